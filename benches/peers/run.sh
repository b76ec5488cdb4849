#!/bin/sh
# Side-by-side: tdcr against John Till's ContinuumRobotExamples and scipy's solve_bvp on cases
# S and H at matched tip accuracy, in interleaved rounds on thread CPU time
# (docs/benchmarks.md, "Side by side"). Run from the repository root:
#
#   benches/peers/run.sh PEER [ROUNDS] [PYTHON]
#
# PEER: a checkout of https://github.com/JohnDTill/ContinuumRobotExamples (a working tree or a
# bare git directory); ROUNDS: interleaved rounds (default 5); PYTHON: an interpreter with
# numpy and scipy for the solve_bvp rows (default: none, rows left out). Writes
# out/peers/table.md and the raw lines beside it.
set -eu
PEER=${1:?usage: benches/peers/run.sh PEER [ROUNDS] [PYTHON]}
ROUNDS=${2:-5}
PYTHON=${3:-}
OUT=out/peers
mkdir -p "$OUT"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

# The peer's headers: from the working tree, or exported from the bare repository.
if [ -d "$PEER/Library" ]; then
    SRC=$PEER
    COMMIT=$(git -C "$PEER" rev-parse HEAD 2>/dev/null || echo unknown)
else
    git --git-dir="$PEER" archive HEAD Library | tar -x -C "$WORK"
    SRC=$WORK
    COMMIT=$(git --git-dir="$PEER" rev-parse HEAD)
fi
echo "peer commit $COMMIT" >&2
g++ -O2 -std=c++14 -I "$SRC/Library" -I "$SRC/Library/eigen" -o "$WORK/till_driver" benches/peers/till_driver.cpp
cargo build --release --quiet --bin tdcr

# Matched accuracy: S on 32 RK4 steps, H on 108, with this LM stop (sum of squares of the
# distal wrench error), about tdcr's default tip error. Shipped: the peer example's own 100
# points (99 steps) and stop.
MATCHED_STOP=1e-18
SHIPPED_STOP=1e-12
RAW=$OUT/raw.txt
: > "$RAW"
for round in $(seq "$ROUNDS"); do
    echo "round $round of $ROUNDS" >&2
    "$WORK/till_driver" S 32 "$MATCHED_STOP" 10 | sed "s/^/peer matched $MATCHED_STOP /" >> "$RAW"
    "$WORK/till_driver" H 108 "$MATCHED_STOP" 4 | sed "s/^/peer matched $MATCHED_STOP /" >> "$RAW"
    "$WORK/till_driver" A 99 "$SHIPPED_STOP" 4 | sed "s/^/peer shipped $SHIPPED_STOP /" >> "$RAW"
    target/release/tdcr bench --format json --repeats 100 | sed 's/^/tdcr /' >> "$RAW"
    if [ -n "$PYTHON" ]; then
        "$PYTHON" benches/peers/scipy_bvp.py 1e-5 3 S 2>/dev/null | sed 's/^/scipy matched /' >> "$RAW"
    fi
done
python3 benches/peers/table.py "$RAW" "$COMMIT" > "$OUT/table.md"
cat "$OUT/table.md"
