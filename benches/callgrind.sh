#!/bin/bash
# Instruction counts (callgrind) of the rows docs/benchmarks.md reports, for one build tree.
#   bash benches/callgrind.sh [TREE] [ROWS...]      (TREE: a checkout with a release build,
#   `cargo build --release --all-targets`; default: this checkout)
# ROWS: sc sw hc hw (solve_cost S/H cold/warm, per solve), smc smw (S with a dead tip moment),
# row (a prototype batch row: (200 rows - 20 rows) / 180, one thread), fs fh (friction solve of
# S and H and its frictionless twin, `collocation::solve`), jac (the control Jacobian against a
# warm solve), h21 h101 (whole 21- and 101-step up-down histories). VALGRIND names the
# valgrind to use (default `valgrind`; AVX2 builds need valgrind >= 3.24, docs/benchmarks.md).
# Inputs are made afresh in a scratch folder: the prototype (`tdcr example`), the same with
# friction 0.1 and stiffness 2000 N on tendon 1 for the histories, and tables of four random
# tensions in [0, 3] N (seed 16).
set -euo pipefail
W=$(cd "${1:-$(dirname "$0")/..}" && pwd); shift || true
ROWS=${*:-sc sw hc hw smc smw row fs fh jac}
VG=${VALGRIND:-valgrind}
B=$W/target/release
D=$(mktemp -d); trap 'rm -rf "$D"' EXIT
$B/tdcr example > $D/robot.toml
python3 - "$D" <<'PY'
import random, sys
d = sys.argv[1]
s = open(d + "/robot.toml").read()
s = s.replace("tension = 2.94                   # N, >= 0\n", "tension = 2.94                   # N, >= 0\nfriction = 0.1\nstiffness = 2000.0\n", 1)
open(d + "/proto.toml", "w").write(s)
for n in (200, 20):
    r = random.Random(16)
    with open(d + "/T%d.csv" % n, "w") as o:
        o.write("tension.1,tension.2,tension.3,tension.4\n")
        for _ in range(n):
            o.write(",".join("%.6f" % r.uniform(0, 3) for _ in range(4)) + "\n")
PY
cg() {
    $VG --tool=callgrind --callgrind-out-file=$D/cg.out "$@" >/dev/null 2>$D/cg.err || true
    grep -o "Collected : [0-9]*" $D/cg.err | awk '{print $3}' | grep . ||
        { echo "callgrind counted nothing ($VG; an AVX2 build needs valgrind >= 3.24): $(tail -3 $D/cg.err)" >&2; exit 1; }
}
sc() { cg --toggle-collect='solve_cost::measured' --toggle-collect='solve_cost::uncounted' $B/examples/solve_cost $1 $2 10; }
for r in $ROWS; do case $r in
 sc) v=$(sc S cold); echo "S cold $(echo "$v/10000000"|bc -l|cut -c1-6) M";;
 sw) v=$(sc S warm); echo "S warm $(echo "$v/10000000"|bc -l|cut -c1-6) M";;
 hc) v=$(sc H cold); echo "H cold $(echo "$v/10000000"|bc -l|cut -c1-6) M";;
 hw) v=$(sc H warm); echo "H warm $(echo "$v/10000000"|bc -l|cut -c1-6) M";;
 smc) v=$(sc SM cold); echo "SM cold $(echo "$v/10000000"|bc -l|cut -c1-6) M";;
 smw) v=$(sc SM warm); echo "SM warm $(echo "$v/10000000"|bc -l|cut -c1-6) M";;
 row) a=$(RAYON_NUM_THREADS=1 cg $B/tdcr batch --robot $D/robot.toml $D/T200.csv --out $D/out.csv); b=$(RAYON_NUM_THREADS=1 cg $B/tdcr batch --robot $D/robot.toml $D/T20.csv --out $D/out.csv); echo "batch row $(echo "($a-$b)/180000000"|bc -l|cut -c1-6) M";;
 fs) f=$(cg --toggle-collect='tdcr::collocation::solve' $B/tdcr solve $D/robot.toml --friction 1=0.1); z=$(cg --toggle-collect='tdcr::collocation::solve' $B/tdcr solve $D/robot.toml); echo "friction S $(echo "$f/1000000"|bc -l|cut -c1-6) M / frictionless $(echo "$z/1000000"|bc -l|cut -c1-6) M = $(echo "$f/$z"|bc -l|cut -c1-5)x";;
 fh) H="--tension 1=0 --tension 5=4.91 --tip-force 0,0,-0.196"; f=$(cg --toggle-collect='tdcr::collocation::solve' $B/tdcr solve $D/robot.toml $H --friction 5=0.1); z=$(cg --toggle-collect='tdcr::collocation::solve' $B/tdcr solve $D/robot.toml $H); echo "friction H $(echo "$f/1000000"|bc -l|cut -c1-6) M / frictionless $(echo "$z/1000000"|bc -l|cut -c1-6) M = $(echo "$f/$z"|bc -l|cut -c1-5)x";;
 h21) v=$(cg $B/tdcr sweep $D/proto.toml --tension 1=0:4.91:11 --history up-down --out $D/out.csv); echo "history21 $(echo "$v/1000000"|bc -l|cut -c1-7) M";;
 h101) v=$(cg $B/tdcr sweep $D/proto.toml --tension 1=0:4.91:51 --history up-down --out $D/out.csv); echo "history101 $(echo "$v/1000000"|bc -l|cut -c1-7) M";;
 jac) for c in S H; do w=$(cg --toggle-collect='jacobian_cost::measured' $B/examples/jacobian_cost $c warm 5); kw=$(cg --toggle-collect='jacobian_cost::measured' $B/examples/jacobian_cost $c kept-warm 5); kt=$(cg --toggle-collect='jacobian_cost::measured' $B/examples/jacobian_cost $c kept-tensions 5); t=$(cg --toggle-collect='jacobian_cost::measured' $B/examples/jacobian_cost $c tensions 5); echo "jac $c warm $(echo "$w/5000000"|bc -l|cut -c1-6) M tensions $(echo "$t/5000000"|bc -l|cut -c1-6) M kept ratio $(echo "100*($kt+$kw-$w)/$w"|bc -l|cut -c1-5) %"; done;;
esac; done
