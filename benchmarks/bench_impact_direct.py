"""Benchmark: the direct impact-damping estimate (restoring-force regression) against the
thesis's residue method on the same record: the chapter 3 rig at 15 Hz, runout 3.5 mm,
21 revolutions at 204.8 kHz with 1 % noise (20 impacts), n free.

The residue method runs twice: with no bootstrap (its point estimate alone) and with the
command line's default 64 replicates. Everything runs in this one process, each method
once to warm up (compiled code loaded), then ``--repeat`` rounds interleaved; the best
round of each counts. CPU time is the figure of merit (the machine may be shared); the
wall time is kept beside it. Targets: direct at most 0.2 s, and at least 10 times faster
than the residue method; output-error (started from the direct estimate, included in its
time) at most 10 s.

Usage:  python benchmarks/bench_impact_direct.py [--repeat N]   (writes benchmarks/impact_direct.json)
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import camdyn
from camdyn.identification.impact_damping import estimate_impact_damping
from camdyn.identification.impact_direct import estimate_impact_damping_direct
from camdyn.identification.impact_output_error import estimate_impact_damping_output_error
from camdyn.records.synthesis import synthesize

HERE = Path(__file__).resolve().parent
BETA, N = 24.7e9, 1.5        # the preset's law [N s/m^2.5], [-]


def timed(call):
    """CPU and wall time [s] of one call, and what it returned."""
    c, w = time.process_time(), time.perf_counter()
    out = call()
    return time.process_time() - c, time.perf_counter() - w, out


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--out", default=str(HERE / "impact_direct.json"))
    args = parser.parse_args()
    rig = camdyn.load_system("sundar2014-impact", {"cam.runout": "3.5 mm"})
    record = synthesize(rig, 15.0, revolutions=21, sample_rate=204.8e3, noise=0.01, settle=100)
    methods = {
        "direct": lambda: estimate_impact_damping_direct(rig, record),
        "output_error": lambda: estimate_impact_damping_output_error(rig, record),
        "residue_no_bootstrap": lambda: estimate_impact_damping(rig, record, bootstrap=0),
        "residue_bootstrap_64": lambda: estimate_impact_damping(rig, record, bootstrap=64),
    }
    for call in methods.values():
        call()                                        # warm-up
    runs = {name: [] for name in methods}
    found = {}
    for _ in range(args.repeat):
        for name, call in methods.items():
            cpu, wall, est = timed(call)
            runs[name].append({"cpu_s": cpu, "wall_s": wall})
            found[name] = {"n": est.exponent, "beta": est.beta, "damping_at_peak": est.damping_at_peak,
                           "peak_penetration": est.peak_penetration, "impacts": est.impacts_used,
                           "damping_at_peak_error": est.damping_at_peak / (BETA * est.peak_penetration ** N) - 1,
                           "n_error": est.exponent / N - 1}
            print(f"{name:22s} {cpu:.3f} s CPU, {wall:.3f} s wall", flush=True)
    best = {name: min(r["cpu_s"] for r in rows) for name, rows in runs.items()}
    result = {"machine": platform.processor() or platform.machine(), "python": platform.python_version(),
              "record": f"sundar2014-impact, runout 3.5 mm, 15 Hz, 21 revolutions, 204.8 kHz, 1 % noise, "
                        f"{record.sizes['time']} samples",
              "best_cpu_s": best, "speedup_vs_residue_no_bootstrap": best["residue_no_bootstrap"] / best["direct"],
              "speedup_vs_residue_bootstrap_64": best["residue_bootstrap_64"] / best["direct"],
              "found": found, "runs": runs}
    for key in ("best_cpu_s", "speedup_vs_residue_no_bootstrap", "speedup_vs_residue_bootstrap_64"):
        print(f"{key}: {result[key]}")
    Path(args.out).write_text(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
