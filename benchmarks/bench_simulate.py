"""Benchmark: the compiled core against a plain SciPy solve_ivp implementation of the
same model (camdyn.testing.oracle), side by side, at the same accuracy.

Accuracy is measured, not assumed: a SciPy DOP853 run at rtol 1e-12 is the truth;
each SciPy method runs at its tolerance, camdyn runs at a ladder of tolerances, and
camdyn's time is taken at the loosest tolerance whose error in alpha is no larger
than SciPy's. Errors are max |alpha - alpha_true| / max |alpha|.

Usage:  python benchmarks/bench_simulate.py [--quick]   (writes benchmarks/results.json)
"""

from __future__ import annotations

import argparse
import json
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import camdyn
from camdyn.integrator import driver
from camdyn.simulation.limits import step_limits
from camdyn.simulation.runner import METHODS, prepare
from camdyn.systems import registry as systems
from camdyn.testing.oracle import reference_simulate

CASES = {
    "ch4 sliding contact (e/a = 0.1, 11.55 Hz)": ("sundar2014-friction", {"cam.runout": "1.75 mm"}, 11.55, "LSODA"),
    "ch3 impacts (e/rc = 0.2, 16 Hz)": ("sundar2014-impact", {"cam.runout": "3.5 mm"}, 16.0, "DOP853"),
}
SCIPY_RTOL = (1e-6, 1e-8)
CAMDYN_RTOLS = (1e-5, 3e-6, 1e-6, 3e-7, 1e-7, 3e-8, 1e-8, 3e-9, 1e-9, 1e-10)


def best_time(fn, repeat):
    times = []
    out = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def run_case(label, preset, overrides, speed, method, revolutions, quick):
    system = camdyn.load_system(preset, overrides).with_values(**{"motion.speed": speed})
    prep = prepare(system)
    fs = 20e3
    t_end = revolutions / speed
    t = np.arange(int(t_end * fs) + 1) / fs
    _, truth, _ = reference_simulate(system, prep.theta0, prep.y0, t[-1], t, prep.viscous_c,
                                     method="DOP853", rtol=1e-12, atol=1e-14)
    scale = np.max(np.abs(truth[0]))
    camdyn.simulate(system, revolutions=1)  # load the compiled code
    ladder = []
    largest, scan = step_limits(1.0 / speed)   # [s]
    for rtol in CAMDYN_RTOLS:
        sec, ds = best_time(lambda: camdyn.simulate(system, revolutions=revolutions, sample_rate=fs, rtol=rtol,
                                                    atol=1e-12), 3)
        err = float(np.max(np.abs(ds.alpha.values - truth[0])) / scale)
        # the compiled integration alone, returning the state at the same samples as SciPy
        args = (systems.CAM_FOLLOWER, prep.p, prep.y0, 0.0, float(ds.time.values[-1]), ds.time.values, rtol, 1e-12,
                largest, METHODS["auto"], 10 ** 9, 64 + 16 * revolutions, False, scan)
        core, _ = best_time(lambda: driver.integrate(*args), 5)
        ladder.append({"rtol": rtol, "seconds": sec, "core_seconds": core, "error": err,
                       "steps": ds.attrs["solver_accepted_steps"], "rejected": ds.attrs["solver_rejected_steps"],
                       "rhs_calls": ds.attrs["solver_rhs_calls"], "events": ds.attrs["solver_events"]})
    rows = []
    for rtol in SCIPY_RTOL:
        sci_revs = min(revolutions, 3 if quick else revolutions)
        sel = t <= sci_revs / speed + 1e-12
        sec, (tt, y, info) = best_time(lambda: reference_simulate(
            system, prep.theta0, prep.y0, t[sel][-1], t[sel], prep.viscous_c, method=method, rtol=rtol,
            atol=1e-12), 1)
        sec_per_rev = sec / sci_revs
        err = float(np.max(np.abs(y[0] - truth[0][sel])) / scale)
        match = next((r for r in ladder if r["error"] <= err), ladder[-1])
        rows.append({
            "case": label, "scipy_method": method, "scipy_rtol": rtol, "scipy_error": err,
            "scipy_ms_per_rev": 1e3 * sec_per_rev, "scipy_rhs_calls_per_rev": info["nfev"] / sci_revs,
            "scipy_revolutions_timed": sci_revs,
            "camdyn_rtol": match["rtol"], "camdyn_error": match["error"],
            "camdyn_ms_per_rev": 1e3 * match["seconds"] / revolutions,
            "camdyn_core_ms_per_rev": 1e3 * match["core_seconds"] / revolutions,
            "camdyn_steps_per_rev": match["steps"] / revolutions,
            "camdyn_rejected_per_rev": match["rejected"] / revolutions,
            "camdyn_rhs_calls_per_rev": match["rhs_calls"] / revolutions,
            "speedup": sec_per_rev / (match["seconds"] / revolutions),
            "speedup_core": sec_per_rev / (match["core_seconds"] / revolutions),
        })
    return rows, ladder


def second_process_seconds():
    code = ("import time; t0 = time.perf_counter(); import camdyn; "
            "camdyn.simulate(camdyn.load_system('sundar2014-impact'), revolutions=30); "
            "print(time.perf_counter() - t0)")
    subprocess.run([sys.executable, "-c", code], check=True, capture_output=True)  # fills the cache
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)
    return time.perf_counter() - t0, float(out.stdout.strip())


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true", help="time SciPy on 3 revolutions only")
    parser.add_argument("--revolutions", type=int, default=30)
    args = parser.parse_args()
    results = {"machine": platform.processor() or platform.machine(), "python": platform.python_version(),
               "revolutions": args.revolutions, "cases": [], "ladders": {}}
    for label, (preset, overrides, speed, method) in CASES.items():
        rows, ladder = run_case(label, preset, overrides, speed, method, args.revolutions, args.quick)
        results["cases"] += rows
        results["ladders"][label] = ladder
    wall, inside = second_process_seconds()
    results["second_process_wall_s"] = wall
    results["second_process_import_and_simulate_s"] = inside
    Path(__file__).with_name("results.json").write_text(json.dumps(results, indent=2))
    print("| case | SciPy method, rtol | SciPy error | SciPy ms/rev | camdyn rtol | camdyn error "
          "| camdyn core ms/rev | camdyn simulate() ms/rev | camdyn steps/rev | speed-up core | speed-up simulate() |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in results["cases"]:
        print(f"| {r['case']} | {r['scipy_method']} {r['scipy_rtol']:g} | {r['scipy_error']:.1e} | "
              f"{r['scipy_ms_per_rev']:.1f} | {r['camdyn_rtol']:g} | {r['camdyn_error']:.1e} | "
              f"{r['camdyn_core_ms_per_rev']:.3f} | {r['camdyn_ms_per_rev']:.3f} | {r['camdyn_steps_per_rev']:.0f} | "
              f"{r['speedup_core']:.0f}x | {r['speedup']:.0f}x |")
    print(f"\nsecond process (import + 30-revolution simulation, compiled code from the disk cache): "
          f"{wall:.2f} s wall, {inside:.2f} s inside Python")


if __name__ == "__main__":
    main()
