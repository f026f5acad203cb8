"""Benchmark: the chapter 3 rig's range covered by continuation against the brute-force
bifurcation diagram over the same range.

The coverage (``camdyn continue sundar2014-impact --from 5Hz --to 30Hz``: the branch from
5 Hz, the restarts past where branches end, the period-doubled branches) and the
400-speed brute-force sweep (300 cam periods each, 200 discarded, as ``camdyn
bifurcation`` runs it) run in this one process, inline (no worker processes), one after
the other and ``--repeat`` times interleaved, after one warm-up of each (the compiled
code loaded). The figure of merit is the CPU time of this process: on a machine shared
with other work the wall time grows, the CPU time much less.

Usage:  python benchmarks/bench_coverage.py [--repeat N]   (writes benchmarks/coverage.json)
"""

from __future__ import annotations

import argparse
import json
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

import camdyn
from camdyn.continuation.coverage import STALL_POINTS, covered_branches
from camdyn.continuation.results import trace_branch
from camdyn.sweeps import run_sweep, spec_from_dict

HERE = Path(__file__).resolve().parent
RUNOUT = "3.5 mm"


def coverage() -> dict:
    """Cover 5-30 Hz; the counts of what it found."""
    rig = camdyn.load_system("sundar2014-impact", {"cam.runout": RUNOUT})
    problem, branch = trace_branch(rig, "motion.speed", 5.0, 30.0, stall=STALL_POINTS)   # as the command
    cover, branches = covered_branches(problem, branch, 5.0, 30.0, 0.02, 200, 50, doublings=1)
    return {"branches": len(branches), "orbits": sum(len(b.orbits) for b in branches),
            "gaps": [[g.start, g.stop] for g in cover.gaps],
            "period_doublings_hz": sorted(d.parameter for b in branches for d in b.bifurcations
                                          if d.kind == "period-doubling" and 15.0 < d.parameter < 17.0)}


def brute_force() -> dict:
    """The 400-speed diagram over 5-30 Hz, inline."""
    with tempfile.TemporaryDirectory() as folder:
        table = {"system": {"source": "sundar2014-impact", "set": {"cam.runout": RUNOUT}},
                 "vary": [{"key": "motion.speed", "values": [float(v) for v in np.linspace(5.0, 30.0, 400)]}],
                 "run": {"revolutions": 300, "discard": 200}, "metrics": {"names": ["poincare"]},
                 "output": {"path": str(Path(folder) / "diagram.nc")}}
        run_sweep(spec_from_dict(table, name="diagram"), workers=0, progress=False).close()
    return {"speeds": 400}


def timed(call) -> tuple[float, float, dict]:
    """CPU and wall time [s] of one call, and what it returned."""
    c, w = time.process_time(), time.perf_counter()
    found = call()
    return time.process_time() - c, time.perf_counter() - w, found


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--out", default=str(HERE / "coverage.json"))
    args = parser.parse_args()
    coverage()                                    # warm-up: the compiled code loaded
    brute_force()
    runs = {"coverage": [], "brute_force": []}
    found = {}
    for _ in range(args.repeat):
        for name, call in (("coverage", coverage), ("brute_force", brute_force)):
            cpu, wall, found[name] = timed(call)
            runs[name].append({"cpu_s": cpu, "wall_s": wall})
            print(f"{name}: {cpu:.1f} s CPU, {wall:.1f} s wall", flush=True)
    best = {name: min(r["cpu_s"] for r in rows) for name, rows in runs.items()}
    result = {"machine": platform.processor() or platform.machine(), "python": platform.python_version(),
              "rig": f"sundar2014-impact, cam.runout = {RUNOUT}, 5-30 Hz", "runs": runs, "found": found,
              "best_cpu_s": best, "ratio_coverage_to_brute_force": best["coverage"] / best["brute_force"]}
    Path(args.out).write_text(json.dumps(result, indent=2) + "\n", encoding="utf-8")
    print(f"coverage / brute force CPU time: {result['ratio_coverage_to_brute_force']:.2f}")


if __name__ == "__main__":
    main()
