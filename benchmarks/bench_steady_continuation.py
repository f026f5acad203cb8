"""Wall time of a frequency-response curve on the chapter 4 rig ("sundar2014-friction",
5-17 Hz): harmonic balance (camdyn.steady.continue_harmonic, H auto) against shooting's
pseudo-arclength continuation (camdyn.continuation.continue_orbits), each with its largest
step set so that the curve has about 200 points; median of the repeats, interleaved, after
a warm-up (numba compiles). Then the contact loss at e/a 0.1 and 0.05 located by harmonic
balance at H = 16, 32 and auto against shooting's.

Run: OMP_NUM_THREADS=1 .venv/bin/python benchmarks/bench_steady_continuation.py [repeats]
(without it, on a loaded machine the BLAS threads of the eigenvalue and linear solves at
H = 64 compete and each one can take tens of times longer).
"""

import sys
import time

import numpy as np

import camdyn
from camdyn.continuation.branches import continue_orbits
from camdyn.continuation.orbits import find_orbit
from camdyn.continuation.problem import system_problem
from camdyn.steady import continue_harmonic


def _timed(function):
    t = time.perf_counter()
    result = function()
    return result, time.perf_counter() - t


def curves(repeats: int) -> None:
    problem = system_problem(camdyn.load_system("sundar2014-friction", {"motion.speed": "5 Hz"}), "motion.speed")
    continue_harmonic(problem, 5.0, 5.5)                              # warm-up
    start = find_orbit(problem)
    continue_orbits(problem, start, 5.5)
    times = {"harmonic balance": [], "shooting": []}
    for _ in range(repeats):
        hb, t = _timed(lambda: continue_harmonic(problem, 5.0, 17.0, max_step=0.0165, max_points=400))
        times["harmonic balance"].append((t, len(hb.parameters), hb.branch.stopped))
        shot, t = _timed(lambda: continue_orbits(problem, start, 17.0, step=0.01, max_step=0.0165, max_points=400))
        times["shooting"].append((t, len(shot.orbits), shot.stopped))
    for name, runs in times.items():
        seconds = float(np.median([r[0] for r in runs]))
        points = runs[-1][1]
        print(f"{name:17s} {points} points in {seconds:.3f} s median, {1e3 * seconds / points:.2f} ms per point; "
              f"{runs[-1][2]}")


def contact_losses() -> None:
    for runout, lo, hi in (("1.75 mm", 17.8, 18.1), ("0.875 mm", 24.1, 24.45)):
        problem = system_problem(camdyn.load_system("sundar2014-friction",
                                                    {"cam.runout": runout, "motion.speed": f"{lo} Hz"}), "motion.speed")
        shot, ts = _timed(lambda: continue_orbits(problem, find_orbit(problem, start=continue_harmonic(
            problem, lo, lo + 0.01).branch.orbits[0].state), hi, step=0.005, max_step=0.01, max_points=40))
        expected = [b.parameter for b in shot.bifurcations if b.kind == "contact-loss"][0]
        print(f"e/a {'0.1' if runout == '1.75 mm' else '0.05'}: shooting contact loss {expected:.7f} Hz ({ts:.2f} s)")
        for harmonics in (16, 32, "auto"):
            try:
                hb, t = _timed(lambda: continue_harmonic(problem, lo, hi, harmonics=harmonics))
            except camdyn.errors.CamdynError as error:
                print(f"  H = {harmonics}: {error}")
                continue
            found = [b.parameter for b in hb.branch.bifurcations if b.kind == "contact-loss"]
            top = max(h.harmonics for h in hb.harmonic_orbits)
            print(f"  H = {harmonics} (up to {top}): {found[0]:.7f} Hz, relative error "
                  f"{abs(found[0] / expected - 1):.1e}, {t:.2f} s")


if __name__ == "__main__":
    curves(int(sys.argv[1]) if len(sys.argv) > 1 else 3)
    contact_losses()
