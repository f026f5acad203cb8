"""How many harmonics harmonic balance would need on the impact rig: the Fourier truncation
error of the exact periodic orbit of the chapter 3 rig ("sundar2014-impact", one impact per
cam revolution), found by shooting, against the harmonic count H.

A harmonic-balance solution with H harmonics cannot be closer to the orbit than the orbit's
own Fourier series cut at H; this prints that distance for alpha [rad] and alpha_ddot
[rad/s^2] (largest deviation over one period, relative to the channel's range), from one
period simulated from the shooting orbit at 2^16 samples (rtol 1e-11), with the cost of the
linear algebra harmonic balance would then face (a dense (2 (2H + 1))^2 Newton matrix,
factored once per iteration, and Hill's eigenvalues of the same size).

Run: .venv/bin/python benchmarks/bench_hb_impact_spectrum.py
"""

from __future__ import annotations

import time

import numpy as np

import camdyn
from camdyn.continuation.orbits import find_orbit
from camdyn.continuation.problem import system_problem

SAMPLES = 2 ** 16                     # per cam period
HARMONICS = (8, 16, 32, 64, 128, 256, 512, 1024, 2048, 4096)


def truncation_errors(x: np.ndarray) -> dict[int, float]:
    """max |x - x_H| / (max x - min x) for the Fourier series of the periodic samples x cut at H."""
    spectrum = np.fft.rfft(x)
    span = float(np.ptp(x))
    out = {}
    for h in HARMONICS:
        cut = spectrum.copy()
        cut[h + 1:] = 0.0
        out[h] = float(np.max(np.abs(np.fft.irfft(cut, n=x.size) - x))) / span
    return out


def linear_algebra_seconds(h: int) -> tuple[float, float]:
    """Seconds of one LU factorization and of one eigenvalue solve of a random dense matrix
    of harmonic balance's size at H (u = 2 unknowns), measured here up to H = 256 and
    extrapolated as n^3 beyond."""
    n = 2 * (2 * h + 1)
    m = min(n, 2 * (2 * 256 + 1))
    a = np.random.default_rng(0).standard_normal((m, m))
    start = time.perf_counter()
    np.linalg.solve(a, a[:, 0])
    lu = time.perf_counter() - start
    start = time.perf_counter()
    np.linalg.eigvals(a)
    eig = time.perf_counter() - start
    scale = (n / m) ** 3
    return lu * scale, eig * scale


def main() -> None:
    system = camdyn.load_system("sundar2014-impact")
    problem = system_problem(system, "motion.speed")
    orbit = find_orbit(problem)
    speed = system.motion.speed                                                  # [Hz]
    ds = camdyn.simulate(system, revolutions=1.0, initial_state=orbit.state[:2], sample_rate=SAMPLES * speed,
                         rtol=1e-11)
    alpha, acc = ds["alpha"].values[:SAMPLES], ds["alpha_ddot"].values[:SAMPLES]
    print(f"chapter 3 rig at {speed} Hz: {orbit.impacts_per_period} impact(s) per period; the orbit's end "
          f"returns to its start within {abs(ds['alpha'].values[-1] - alpha[0]):.1e} rad")
    errors = {"alpha": truncation_errors(alpha), "alpha_ddot": truncation_errors(acc)}
    print("| H | alpha: truncation error / range | alpha_ddot: truncation error / range | "
          "one LU of the Newton matrix | Hill's eigenvalues |")
    print("|---|---|---|---|---|")
    for h in HARMONICS:
        lu, eig = linear_algebra_seconds(h)
        print(f"| {h} | {errors['alpha'][h]:.1e} | {errors['alpha_ddot'][h]:.1e} | {lu:.2g} s | {eig:.2g} s |")


if __name__ == "__main__":
    main()
