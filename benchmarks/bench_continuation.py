"""Benchmark of periodic orbits and continuation.

One orbit: the chapter 4 rig (``sundar2014-friction``, e/a = 0.05, 11.55 Hz) found by
:func:`camdyn.continuation.find_orbit` from a start on the orbit (the case of a
continuation step: one plain run to check the residual, one sampled variational run for
the multipliers) and from a one-revolution transient; the cost of its parts (the plain
shooting run, the variational run) with their step counts; and the cost per point of a
continuation from 11.55 to 20 Hz. Wall time and this process's CPU time, best of
``--repeat``: on a machine shared with other work the wall time grows, the CPU time much
less.

Branches against brute force: the chapter 3 rig (``sundar2014-impact``, e/rc = 0.2) by
continuation, each branch from a transient at a speed inside a periodic window of the
brute-force diagram, with the bifurcations located and the period-doubled branches
switched onto at the period doublings (``switch_doublings``): from 5 Hz towards 30 Hz (it
stops at the loss of contact near 6.9 Hz); the two-impact branch from 8.2 Hz down past its
fold and up past its doubling; the one-impact branch from 14 Hz down to its grazing near
9.57 Hz and up to 17.45 Hz with two levels of doublings; the period-2 branch (one impact
per two revolutions) from 24 Hz down to 20.9 Hz and up to 28.6 Hz with its doubling;
against the 400-speed brute-force diagram from 5 to 30 Hz (300 revolutions each, 200
discarded, as ``camdyn bifurcation`` and benchmarks/bench_sweep.py run it) on 2 local
workers (their CPU time from ``getrusage``).

Usage:  python benchmarks/bench_continuation.py [--repeat N] [--skip-sweep]   (writes benchmarks/continuation.json)
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
from camdyn.continuation import continue_orbits, find_orbit, system_problem
from camdyn.continuation.orbits import flow, shoot
from camdyn.integrator import driver
from camdyn.systems import registry as systems

HERE = Path(__file__).resolve().parent


def _best(call, repeat):
    """Best wall and CPU time [s] of ``repeat`` calls."""
    wall, cpu = [], []
    for _ in range(repeat):
        t, c = time.perf_counter(), time.process_time()
        call()
        wall.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
    return min(wall), min(cpu)


def _steps(problem, orbit, variational):
    """Accepted and rejected steps of one run over the orbit's period."""
    p, period = problem.build(problem.value)
    rtol, atol = problem.matrix_tolerances() if variational else (problem.rtol, problem.atol)
    start = np.concatenate([orbit.full_state, np.eye(3).ravel()]) if variational else orbit.full_state.copy()
    system_id = systems.VARIATIONAL + problem.system_id if variational else problem.system_id
    _, _, _, counters = driver.integrate(system_id, p, start, 0.0, period, np.array([period]), rtol, atol,
                                         period / 32.0, driver.METHOD_DOP853, 50_000_000, 100_000, True)
    return int(counters[driver.COUNT_ACCEPTED]), int(counters[driver.COUNT_REJECTED])


def one_orbit(repeat: int) -> dict:
    system = camdyn.load_system("sundar2014-friction").with_values(**{"cam.runout": 0.05 * 17.5e-3})
    problem = system_problem(system, "motion.speed")
    orbit = find_orbit(problem, transient=1)                     # compiles, and the start below
    out = {"rig": "sundar2014-friction, e/a = 0.05, 11.55 Hz", "rtol": problem.rtol,
           "matrix_rtol": problem.matrix_tolerances()[0]}
    for name, call in (("find_orbit_on_orbit", lambda: find_orbit(problem, start=orbit.state)),
                       ("find_orbit_transient_1", lambda: find_orbit(problem, transient=1)),
                       ("plain_run", lambda: shoot(problem, orbit.state, problem.value)),
                       ("variational_run_sampled", lambda: flow(problem, orbit.state, None, 1, 256))):
        wall, cpu = _best(call, repeat)
        out[name] = {"wall_ms": 1e3 * wall, "cpu_ms": 1e3 * cpu}
    out["newton_iterations_from_transient_1"] = find_orbit(problem, transient=1).iterations
    out["plain_steps_accepted_rejected"] = _steps(problem, orbit, False)
    out["variational_steps_accepted_rejected"] = _steps(problem, orbit, True)
    t, c = time.perf_counter(), time.process_time()
    branch = continue_orbits(problem, orbit, 20.0, step=0.02)
    points = len(branch.orbits)
    out["continuation_11_55_to_20_Hz"] = {"points": points,
                                          "wall_ms_per_point": 1e3 * (time.perf_counter() - t) / points,
                                          "cpu_ms_per_point": 1e3 * (time.process_time() - c) / points}
    return out


def _segment(system, first: float, last: float, periods: int = 1, levels: int = 1) -> dict:
    """The period-``periods`` branch from ``first`` to ``last`` [Hz] as far as continuation
    follows it, with the period-doubled branches switched onto at its doublings (down to
    ``levels`` doublings): points, where and why it stopped, its bifurcations, and the
    wall and CPU time [s]."""
    from camdyn.continuation.results import switch_doublings, trace_branch
    t, c = time.perf_counter(), time.process_time()
    problem, branch = trace_branch(system, "motion.speed", first, last, periods=periods, transient=100, step=0.02,
                                   max_points=500)
    doubled = switch_doublings(problem, branch, last, levels=levels, max_points=500)
    return {"from_hz": first, "to_hz": last, "periods": periods, "wall_s": time.perf_counter() - t,
            "cpu_s": time.process_time() - c,
            "points": len(branch.orbits), "reached_hz": branch.orbits[-1].parameter, "stopped": branch.stopped,
            "bifurcations": [(b.kind, b.parameter) for b in branch.bifurcations],
            "doubled_branches": [{"points": len(b.orbits), "periods": b.orbits[0].periods,
                                  "from_hz": b.orbits[0].parameter, "to_hz": b.orbits[-1].parameter,
                                  "stopped": b.stopped,
                                  "bifurcations": [(x.kind, x.parameter) for x in b.bifurcations]}
                                 for b in doubled]}


def chapter3(skip_sweep: bool) -> dict:
    import resource

    from camdyn.continuation.results import trace_branch
    system = camdyn.load_system("sundar2014-impact")
    trace_branch(system, "motion.speed", 5.0, 5.5, transient=50, max_points=3)        # compiled once
    out = {"segments": [_segment(system, 5.0, 30.0), _segment(system, 8.2, 7.85), _segment(system, 8.2, 8.5),
                        _segment(system, 14.0, 9.5), _segment(system, 14.0, 17.45, levels=2),
                        _segment(system, 24.0, 20.9, periods=2), _segment(system, 24.0, 28.6, periods=2)]}
    out["total_wall_s"] = sum(item["wall_s"] for item in out["segments"])
    out["total_cpu_s"] = sum(item["cpu_s"] for item in out["segments"])
    if not skip_sweep:
        from camdyn.sweeps import run_sweep, spec_from_dict
        with tempfile.TemporaryDirectory() as folder:
            table = {"system": {"source": "sundar2014-impact", "set": {}},
                     "vary": [{"key": "motion.speed", "values": [float(v) for v in np.linspace(5.0, 30.0, 400)]}],
                     "run": {"revolutions": 300, "discard": 200}, "metrics": {"names": ["poincare"]},
                     "output": {"path": str(Path(folder) / "diagram.nc")}}
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            t = time.perf_counter()
            run_sweep(spec_from_dict(table, name="diagram"), workers=2, progress=False).close()
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            out["brute_force_400_speeds_2_workers"] = {
                "wall_s": time.perf_counter() - t,
                "workers_cpu_s": (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)}
    return out


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--skip-sweep", action="store_true")
    args = parser.parse_args()
    result = {"machine": platform.machine(), "python": platform.python_version(), "camdyn": camdyn.__version__,
              "one_orbit": one_orbit(args.repeat), "chapter3_5_to_30_Hz": chapter3(args.skip_sweep)}
    (HERE / "continuation.json").write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
