"""Wall time per orbit of harmonic balance against shooting (find_orbit) on the chapter 4
rig ("sundar2014-friction", 11.55 Hz), interleaved in one process, and each one's error in
the orbit's start state against a reference (harmonic balance at H = 32, tail ~1e-14).
"hb cold" is given no guess: it starts from the problem's orbit guess (the follower riding
the cam, pressed in by the static penetration).

Run: .venv/bin/python benchmarks/bench_harmonic_balance.py [repeats]
"""

import sys
import time

import numpy as np

import camdyn
from camdyn.continuation import orbits
from camdyn.continuation.problem import system_problem
from camdyn.steady import harmonic_balance


def main(repeats: int = 5) -> None:
    problem = system_problem(camdyn.load_system("sundar2014-friction"), "motion.speed")
    start = orbits.find_orbit(problem).state                         # warm-up and a start for both
    reference = harmonic_balance(problem, harmonics=32, guess=start).samples[0]
    times = {"hb H=8": [], "hb auto": [], "hb cold": [], "shooting": []}
    errors = {}
    for _ in range(repeats):                                          # interleaved
        t = time.perf_counter()
        hb = harmonic_balance(problem, harmonics=8, guess=start)
        times["hb H=8"].append(time.perf_counter() - t)
        errors["hb H=8"] = np.max(np.abs(hb.samples[0] / reference - 1))
        t = time.perf_counter()
        auto = harmonic_balance(problem, guess=start)
        times["hb auto"].append(time.perf_counter() - t)
        errors["hb auto"] = np.max(np.abs(auto.samples[0] / reference - 1))
        t = time.perf_counter()
        cold = harmonic_balance(problem)                              # no guess: the problem's orbit guess
        times["hb cold"].append(time.perf_counter() - t)
        errors["hb cold"] = np.max(np.abs(cold.samples[0] / reference - 1))
        t = time.perf_counter()
        shot = orbits.find_orbit(problem, start=start)
        times["shooting"].append(time.perf_counter() - t)
        errors["shooting"] = np.max(np.abs(shot.state / reference - 1))
    for name, values in times.items():
        print(f"{name:10s} median {1e3 * np.median(values):9.2f} ms per orbit, relative error {errors[name]:.2e}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 5)
