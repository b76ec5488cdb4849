"""Markdown table of benches/peers/run.sh's raw lines: medians over rounds of each code's
per-round median thread CPU time, tip errors against the reference tips, and the ratio to
tdcr's time on the same row.

Usage: python3 table.py RAW COMMIT
"""

import json
import platform
import statistics
import sys
import time


def main():
    raw, commit = sys.argv[1], sys.argv[2]
    rows = {}  # (code, settings, case, start) -> list of (ms, error, detail)
    tdcr = {}  # (case, start) -> list of (ms, error, detail)
    for line in open(raw):
        words = line.split()
        if not words:
            continue
        if words[0] == "tdcr":
            for r in json.loads(line[len("tdcr "):]):
                detail = f"{r['intervals']} intervals, {r['newton_steps']} + {r['chord_steps']} steps"
                tdcr.setdefault((r["case"], r["start"]), []).append(
                    (1e3 * r["median_cpu_seconds"], r["tip_error_m"], detail)
                )
        elif "failed" in words:
            continue
        elif words[0] == "peer":
            _, settings, stop, case, start, steps, ms, evals, error = words
            detail = f"{steps} RK4 steps, stop {stop}, {evals} shooting evaluations"
            rows.setdefault(("Till, ContinuumRobotExamples", settings, case, start), []).append(
                (float(ms), float(error), detail)
            )
        elif words[0] == "scipy":
            _, settings, case, start, tol, ms, nodes, error = words
            detail = f"tol {tol}, {nodes} nodes"
            rows.setdefault(("scipy solve_bvp", settings, case, start), []).append(
                (float(ms), float(error), detail)
            )
    med = lambda v: statistics.median(x[0] for x in v)
    rng = lambda v: f"{min(x[0] for x in v):.3g}-{max(x[0] for x in v):.3g}"
    print(f"Measured {time.strftime('%Y-%m-%d', time.gmtime())} on {platform.machine()} "
          f"({platform.processor() or 'processor not exposed'}), "
          f"interleaved rounds: {len(next(iter(tdcr.values())))}; peer commit {commit}.")
    print()
    print("| code | settings | case | start | CPU ms (median; range over rounds) | tip error (m) "
          "| tdcr CPU ms | tdcr tip error (m) | code / tdcr |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for (code, settings, case, start), v in rows.items():
        t = tdcr[(case, start)]
        ratio = med(v) / med(t)
        print(f"| {code} | {settings}: {v[-1][2]} | {case} | {start} | {med(v):.3g} ({rng(v)}) "
              f"| {v[-1][1]:.1e} | {med(t):.3g} ({rng(t)}) | {t[-1][1]:.1e} | {ratio:.0f}x |")


if __name__ == "__main__":
    main()
