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

With ``--workers 2`` the segments and windows run in two processes, as the sweep does:
the wall time is then that of the two, and the CPU time both the sum of the items' own
and the processes' whole (their start and compilation included).

Usage:  python benchmarks/bench_continuation.py [--repeat N] [--skip-sweep] [--workers N]
        (writes benchmarks/continuation.json)
"""

from __future__ import annotations

import argparse
import json
import math
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
                                         period / 32.0, driver.METHOD_DOP853, 50_000_000, 100_000, True, math.inf)
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


def _window(system, speed: float, periods: int, down: float, up: float, step: float = 5e-4, max_step: float = 2e-3,
            max_points: int = 60, levels: int = 0, downwards: dict | None = None) -> dict:
    """A window's period-``periods`` branch: the orbit at ``speed`` [Hz] from a
    400-revolution plain run from rest (the brute-force diagram's state), continued down
    to ``down`` and up to ``up`` [Hz] (by default in short steps, scaled units; the
    settings ``downwards`` replace them downwards), with its doublings switched onto down
    to ``levels``; points, ends, bifurcations and CPU time [s]."""
    from camdyn.continuation.orbits import transient_state
    from camdyn.continuation.results import switch_doublings
    t, c = time.perf_counter(), time.process_time()
    problem = system_problem(system.with_values(**{"motion.speed": speed}), "motion.speed")
    orbit = find_orbit(problem, start=transient_state(problem, 400), periods=periods)
    upwards = {"step": step, "max_step": max_step, "max_points": max_points}
    branches = [continue_orbits(problem, orbit, down, **{**upwards, **(downwards or {})}),
                continue_orbits(problem, orbit, up, **upwards)]
    branches += switch_doublings(problem, branches[1], up, levels=levels, step=step, max_points=max_points)
    return {"speed_hz": speed, "periods": periods, "wall_s": time.perf_counter() - t, "cpu_s": time.process_time() - c,
            "branches": [{"points": len(b.orbits), "periods": b.orbits[-1].periods,
                          "from_hz": min(o.parameter for o in b.orbits), "to_hz": max(o.parameter for o in b.orbits),
                          "stopped": b.stopped, "bifurcations": [(x.kind, x.parameter) for x in b.bifurcations]}
                         for b in branches]}


#: The other windows of the brute-force diagram (speed [Hz], period, down to, up to, and
#: settings): 7.29 Hz (3 impacts per revolution), 9.2 Hz (period 2), 9.55 Hz (period 3),
#: 20.0 Hz (period 2), 20.7 Hz (period 4), 29.0 Hz (period 3 and its period-6 branch),
#: then the narrowest: period 3 at 8.9 Hz, 5 at 9.0 Hz, 2 at 19.1 Hz, 8 at 19.3 Hz, 2 at
#: 19.4 Hz, 4 at 19.6 Hz and 6 at 19.7 Hz.
WIDE = {"step": 0.02, "max_step": 0.1, "max_points": 200}
WINDOWS = [(7.28, 1, 7.25, 7.32, {"step": 0.002, "max_step": 0.01, "max_points": 200, "levels": 1}),
           (9.2, 2, 9.0, 9.45, {**WIDE, "levels": 1}),
           (9.55, 3, 9.45, 9.7, {**WIDE, "max_points": 100}),
           (20.0, 2, 19.7, 20.5, {**WIDE, "levels": 1}),
           (20.7, 4, 20.4, 20.9, WIDE),
           (29.0, 3, 28.8, 29.3, {**WIDE, "levels": 1}),
           (8.9, 3, 8.8, 8.92, {"downwards": {"step": 0.02, "max_step": 0.1, "max_points": 12}}),
           (9.0, 5, 8.9, 9.1, {}),
           (19.1, 2, 19.0, 19.2, {}), (19.3, 8, 19.2, 19.302, {}), (19.4, 2, 19.3, 19.5, {}),
           (19.6, 4, 19.5, 19.7, {"max_step": 0.005}), (19.7, 6, 19.6, 19.8, {})]


#: The seven segments of the chapter 3 rig (from, to [Hz], settings), as in the docs' table.
SEGMENTS = [(5.0, 30.0, {}), (8.2, 7.85, {}), (8.2, 8.5, {}), (14.0, 9.5, {}), (14.0, 17.45, {"levels": 2}),
            (24.0, 20.9, {"periods": 2}), (24.0, 28.6, {"periods": 2})]
_SYSTEM = []


def _warm() -> None:
    """Load the chapter 3 rig and compile (or load from the cache) what continuation runs."""
    from camdyn.continuation.results import trace_branch
    if not _SYSTEM:
        _SYSTEM.append(camdyn.load_system("sundar2014-impact"))
        trace_branch(_SYSTEM[0], "motion.speed", 5.0, 5.5, transient=50, max_points=3)


def _job(job: tuple) -> dict:
    """One segment (``("segment", first, last, settings)``) or window (``("window", speed,
    periods, down, up, settings)``) of the chapter 3 rig, in this process."""
    _warm()
    kind, *args, settings = job
    return (_segment if kind == "segment" else _window)(_SYSTEM[0], *args, **settings)


def chapter3(skip_sweep: bool, workers: int = 1) -> dict:
    """The chapter 3 rig's segments and windows, in this process (``workers`` 1) or spread
    over ``workers`` processes (each item's CPU time measured in its process, and the
    processes' whole CPU time from ``getrusage``, their start and compilation included),
    then the brute-force sweep on 2 workers."""
    import resource
    from concurrent.futures import ProcessPoolExecutor

    jobs = [("segment", first, last, settings) for first, last, settings in SEGMENTS]
    jobs += [("window", speed, periods, down, up, settings) for speed, periods, down, up, settings in WINDOWS]
    if workers == 1:
        _warm()
        t = time.perf_counter()
        results = [_job(job) for job in jobs]
        out = {"workers": 1, "wall_s": time.perf_counter() - t}
    else:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t = time.perf_counter()
        with ProcessPoolExecutor(max_workers=workers, initializer=_warm) as pool:
            results = list(pool.map(_job, jobs))
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        out = {"workers": workers, "wall_s": time.perf_counter() - t,
               "workers_cpu_s": (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)}
    out["segments"], out["windows"] = results[:len(SEGMENTS)], results[len(SEGMENTS):]
    out["total_wall_s"] = sum(item["wall_s"] for item in results)
    out["total_cpu_s"] = sum(item["cpu_s"] for item in results)
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
    parser.add_argument("--workers", type=int, default=1,
                        help="processes for the chapter 3 segments and windows (default 1: this process)")
    parser.add_argument("--out", default=str(HERE / "continuation.json"))
    args = parser.parse_args()
    result = {"machine": platform.machine(), "python": platform.python_version(), "camdyn": camdyn.__version__,
              "one_orbit": one_orbit(args.repeat), "chapter3_5_to_30_Hz": chapter3(args.skip_sweep, args.workers)}
    Path(args.out).write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
