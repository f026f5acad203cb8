"""Where the CPU time of the chapter 3 continuation benchmark goes.

Runs the segments and windows of ``bench_continuation.py`` (all, or those named by
``--items``, indices into its jobs: the 7 segments, then the 13 windows) in this
process, with every call of the integrator counted by kind (plain runs, variational runs
sampled and unsampled, with their steps, right-hand-side calls and CPU time) and by the
continuation's caller (chord corrector, Newton fallback, a point's linearization,
location of bifurcations, branch switching, start), and a cProfile of the whole (its
cumulative times of the continuation's functions). CPU times are ``process_time``.

Usage:  python benchmarks/profile_continuation.py [--items 0,7,8] [--out profile.json]
"""

from __future__ import annotations

import argparse
import cProfile
import json
import pstats
import sys
import time
from collections import defaultdict
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import bench_continuation as bench  # noqa: E402

from camdyn.integrator import driver  # noqa: E402
from camdyn.systems import registry as systems  # noqa: E402

#: The continuation's functions a run is attributed to, innermost first.
CALLERS = ("_locate", "switch_branch", "_iterate", "point", "find_orbit", "transient_state", "_half_distance")


def _caller() -> str:
    """The innermost of :data:`CALLERS` on the stack, with the corrector's kind."""
    frame = sys._getframe(2)
    names = []
    while frame is not None:
        names.append((frame.f_code.co_name, frame.f_locals))
        frame = frame.f_back
    for name, local in names:
        if name == "_iterate":
            kind = "newton" if local.get("jac", 0) is None else "chord"
            within = next((n for n, _ in names if n in ("_locate", "switch_branch", "find_orbit")), "step")
            return f"{kind} ({within})"
        if name in ("point", "find_orbit", "transient_state", "_half_distance", "switch_branch", "_locate"):
            return name
    return "other"


def counted(table: dict):
    """A wrapper of ``driver.integrate`` that adds each call to ``table``."""
    original = driver.integrate

    def integrate(system, p, y_start, t_start, t_end, t_out, *rest):
        c = time.process_time()
        out = original(system, p, y_start, t_start, t_end, t_out, *rest)
        spent = time.process_time() - c
        counters = out[3]
        kind = ("variational sampled" if t_out.size > 2 else "variational") if system >= systems.VARIATIONAL \
            else "plain"
        for key in (kind, f"{kind} <- {_caller()}"):
            row = table[key]
            row["calls"] += 1
            row["cpu_s"] += spent
            row["steps"] += int(counters[driver.COUNT_ACCEPTED] + counters[driver.COUNT_REJECTED])
            row["rejected"] += int(counters[driver.COUNT_REJECTED])
            row["rhs"] += int(counters[driver.COUNT_RHS])
            row["events"] += int(counters[driver.COUNT_EVENTS])
        return out
    return integrate


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--items", default="", help="comma-separated job indices (default all)")
    parser.add_argument("--out", default="")
    args = parser.parse_args()
    jobs = [("segment", first, last, settings) for first, last, settings in bench.SEGMENTS]
    jobs += [("window", speed, periods, down, up, settings) for speed, periods, down, up, settings in bench.WINDOWS]
    if args.items:
        jobs = [jobs[int(i)] for i in args.items.split(",")]
    bench._warm()
    table = defaultdict(lambda: defaultdict(float))
    driver.integrate = counted(table)
    profile = cProfile.Profile()
    results = []
    c = time.process_time()
    profile.enable()
    for job in jobs:
        results.append(bench._job(job))
        item = results[-1]
        print(f"{job[:3]}: {item['cpu_s']:.2f} s CPU", flush=True)
    profile.disable()
    total = time.process_time() - c
    print(f"total {total:.2f} s CPU")
    for key in sorted(table, key=lambda k: -table[k]["cpu_s"]):
        row = table[key]
        print(f"{key:45s} {row['calls']:7.0f} calls {row['cpu_s']:8.2f} s {row['steps']:10.0f} steps "
              f"{row['rhs']:11.0f} rhs {row['events']:8.0f} events")
    stats = pstats.Stats(profile)
    stats.sort_stats("cumulative").print_stats(r"continuation|numpy.linalg", 30)
    if args.out:
        Path(args.out).write_text(json.dumps({"total_cpu_s": total, "runs": table, "results": results}, indent=1,
                                             default=float) + "\n")


if __name__ == "__main__":
    main()
