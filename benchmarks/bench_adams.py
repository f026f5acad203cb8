"""Multistep experiment: does an Adams method make camdyn's core faster than LSODA?

Two measurements on the two cases of bench_peers.py (30 cam revolutions sampled at
20 kHz, error as bench_peers defines it: max |alpha - alpha_true| / max |alpha_true|
against its cached SciPy DOP853 truth at rtol 1e-13):

1. ``counts``: right-hand-side calls and steps per revolution of SciPy's
   ``scipy.integrate.ode`` VODE (Adams and BDF, each with functional iteration and with
   a Newton corrector on a finite-difference Jacobian) and LSODA, all with the
   numba-compiled peer right-hand side (benchmarks/peer_models.py, no events), rtol from
   1e-5 to 1e-11, atol as bench_peers gives numbalsoda (rtol * 1e-4). The calls are
   counted in the right-hand side itself (Jacobian columns included). This asks which
   multistep family needs the fewest calls at equal error, without timing Python.
2. ``timing``: camdyn's compiled core (``driver.integrate``) with DOP853, with its
   Adams method (``METHOD_ADAMS``) and with Adams and BDF switched automatically
   (``METHOD_MULTISTEP``), against numbalsoda's LSODA, in one process, interleaved, best
   of 3, at bench_peers' rungs (rtol 1e-4 to 1e-11 in half decades).

Run with the peers' environment (numbalsoda)::

    PYTHONPATH=src:benchmarks .venv-peers/bin/python benchmarks/bench_adams.py [counts] [timing]
    PYTHONPATH=src:benchmarks .venv-peers/bin/python benchmarks/bench_adams.py summary

Writes benchmarks/adams.json (the parts run) and prints the tables (``summary``: the
tables of the stored JSON only).
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
from bench_peers import CASES, RTOLS, TARGETS, Case, measure, numbalsoda_tool, scalar_atol, time_at
from peer_models import compiled_derivative_array
from scipy.integrate import ode

from camdyn.integrator import driver
from camdyn.systems import registry as systems

HERE = Path(__file__).resolve().parent
COUNTED = ("accepted_steps", "rejected_steps", "rhs_calls", "jacobians", "bdf_steps")
REVOLUTIONS = 30
COUNT_RTOLS = (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11)
# name -> (integrator, method, Newton corrector with a finite-difference Jacobian)
MULTISTEP = {"VODE Adams, functional": ("vode", "adams", False), "VODE Adams, Newton": ("vode", "adams", True),
             "VODE BDF, functional": ("vode", "bdf", False), "VODE BDF, Newton": ("vode", "bdf", True),
             "LSODA": ("lsoda", None, True)}


def run_multistep(case, name, rtol):
    """One SciPy ``ode`` run: error [-] and steps, calls and Jacobians per revolution."""
    integrator, method, newton = MULTISTEP[name]
    calls = [0]

    def rhs(t, y):
        calls[0] += 1
        return compiled_derivative_array(t, y, case.p)

    solver = ode(rhs)
    options = {"rtol": rtol, "atol": scalar_atol(rtol), "nsteps": 10 ** 7}
    if integrator == "vode":
        solver.set_integrator("vode", method=method, order=12 if method == "adams" else 5, with_jacobian=newton,
                              **options)
    else:
        solver.set_integrator("lsoda", **options)
    solver.set_initial_value(case.y0.copy(), 0.0)
    alpha = np.empty(case.t.size)
    alpha[0] = case.y0[0]
    for k in range(1, case.t.size):
        alpha[k] = solver.integrate(case.t[k])[0]
        if not solver.successful():
            return {"rtol": rtol, "failure": f"status {solver.get_return_code()}"}
    iwork = solver._integrator.iwork   # VODE and LSODA: IWORK(11..13) = steps, f calls, Jacobians
    per_rev = 1.0 / case.revolutions
    return {"rtol": rtol, "error": case.error(alpha), "steps_per_rev": int(iwork[10]) * per_rev,
            "rhs_per_rev": calls[0] * per_rev, "jacobians_per_rev": int(iwork[12]) * per_rev}


def core(method):
    """A runner of camdyn's compiled core with ``method`` (``driver.METHOD_*``)."""
    def run(case, rtol):
        y, _, _, counters = driver.integrate(
            systems.CAM_FOLLOWER, case.prep.p, case.prep.y0.copy(), 0.0, case.duration, case.t, rtol,
            scalar_atol(rtol), case.period / 32, method, 50_000_000, 64 + 16 * case.revolutions, True, math.inf)
        if counters[driver.COUNT_STATUS] != driver.STATUS_OK:
            raise RuntimeError(driver.STATUS_MESSAGES[int(counters[driver.COUNT_STATUS])])
        return y[:, 0], {name: int(counters[i]) for i, name in enumerate(driver.COUNTER_NAMES)
                         if name in COUNTED}
    return run


def timing(case, rounds=3, rtols=RTOLS):
    """Interleaved best-of-``rounds`` times [ms/rev], errors and counters per revolution
    per rung (bench_peers.measure, no time budget)."""
    from numbalsoda import lsoda
    runners = {"camdyn core DOP853": core(driver.METHOD_DOP853), "camdyn core Adams": core(driver.METHOD_ADAMS),
               "camdyn core Adams/BDF": core(driver.METHOD_MULTISTEP), "numbalsoda LSODA": numbalsoda_tool(lsoda)}
    curves = measure(case, runners, rtols, rounds, math.inf)
    for rows in curves.values():                   # counters per revolution, as adams.json holds them
        for row in rows:
            row.update({k: v / case.revolutions for k, v in row.items()
                        if k in COUNTED})
    return curves


def at_error(rows, target, key):
    """``key`` per revolution at the error ``target`` [-], interpolated in log-log on the error
    envelope as bench_peers.time_at does for the time (a count as ``log(1 + count)``; None if
    never reached)."""
    if key == "ms_per_rev":
        return time_at([r for r in rows if "error" in r], target)
    usable = [dict(r, ms_per_rev=r[key] + 1.0) for r in rows if key in r and "error" in r]   # counts may be 0
    found = time_at(usable, target)
    return None if found is None else found - 1.0


def summary(results):
    """Markdown tables of the parts in ``results``: calls and times at the error targets."""
    lines = []
    text = lambda v: "not reached" if v is None else f"{v:.3g}"
    for label, entry in results.items():
        if label == "settings":
            continue
        if "counts" in entry:
            lines += [f"{label}: right-hand-side calls per revolution at equal error (SciPy ode, numba rhs, no events)",
                      "", "| solver | " + " | ".join(f"rhs/rev at {t:.0e}" for t in TARGETS) + " |",
                      "|---|" + "---|" * len(TARGETS)]
            for name, rows in entry["counts"].items():
                cells = (text(at_error(rows, t, "rhs_per_rev")) for t in TARGETS)
                lines.append(f"| {name} | " + " | ".join(cells) + " |")
            lines.append("")
        if "timing" in entry:
            keys = ("ms_per_rev", "rhs_calls", "accepted_steps", "jacobians", "bdf_steps")
            heads = ("ms/rev", "rhs/rev", "steps/rev", "Jacobians/rev", "BDF steps/rev")
            lines += [f"{label}: per revolution at equal error (interleaved, best of 3)",
                      "", "| tool | " + " | ".join(f"{k} at {t:.0e}" for t in TARGETS for k in heads) + " |",
                      "|---|" + "---|" * (len(heads) * len(TARGETS))]
            for name, rows in entry["timing"].items():
                cells = []
                for t in TARGETS:
                    cells += [text(at_error(rows, t, k)) if any(k in r for r in rows) else "-" for k in keys]
                lines.append(f"| {name} | " + " | ".join(cells) + " |")
            lines.append("")
    return "\n".join(lines)


def main():
    parts = sys.argv[1:] or ["counts", "timing"]
    if parts == ["summary"]:
        print(summary(json.loads((HERE / "adams.json").read_text())))
        return
    path = HERE / "adams.json"
    results = json.loads(path.read_text()) if path.exists() else {}
    results["settings"] = {"revolutions": REVOLUTIONS, "count_rtols": COUNT_RTOLS, "timing_rtols": RTOLS}
    for label, (preset, overrides, speed) in CASES.items():
        case = Case(label, preset, overrides, speed, REVOLUTIONS)
        entry = results.setdefault(label, {})
        if "counts" in parts:
            entry["counts"] = {name: [run_multistep(case, name, rtol) for rtol in COUNT_RTOLS] for name in MULTISTEP}
            for name, rows in entry["counts"].items():
                shown = (f"{r['rtol']:.0e}: {r.get('error', np.nan):.1e}/{r.get('rhs_per_rev', 0):.0f}" for r in rows)
                print(label, name, "(rtol: error/rhs per rev)", " ".join(shown), flush=True)
        if "timing" in parts:
            print(label, flush=True)
            entry["timing"] = timing(case)
            for target in TARGETS:
                print(f"  at error {target:.0e}: " + ", ".join(
                    f"{n}: {time_at(rows, target) or float('nan'):.3g} ms/rev" for n, rows in entry["timing"].items()))
    path.write_text(json.dumps(results, indent=1) + "\n")
    print(summary(results))


if __name__ == "__main__":
    main()
