"""Radau IIA (camdyn.integrator.radau) against SciPy's Radau on two stiff problems of
Hairer and Wanner (ODE II, IV.10), at equal tolerances, both with the analytic Jacobian:

* Van der Pol in the scaled form y1' = y2, y2' = ((1 - y1^2) y2 - y1) / eps, eps = 1e-6,
  y(0) = (2, -0.66), t in [0, 2], atol = rtol;
* Robertson's kinetics, y(0) = (1, 0, 0), t in [0, 1e5], atol = 1e-10.

Columns: accepted and rejected steps, right-hand-side calls, Jacobians and LU
decompositions (pairs of real and complex; SciPy's ``nlu`` counts each of its two
factorizations), the final state's error against SciPy's Radau at rtol 1e-12 in units
of the tolerance, max_i |y_i - y_ref,i| / (atol + rtol |y_ref,i|), and the time of one
solve (camdyn: compiled, best of 3; SciPy: one run, Python right-hand side).

Run::

    PYTHONPATH=src .venv/bin/python benchmarks/bench_radau_stiff.py

Prints a markdown table (about 40 s, most of it SciPy's reference runs and numba's
compilation).
"""

from __future__ import annotations

import time

import numba
import numpy as np
from scipy.integrate import solve_ivp

from camdyn.integrator.radau import (
    RADAU_ACCEPTED,
    RADAU_JACOBIANS,
    RADAU_LU,
    RADAU_REJECTED,
    RADAU_RHS,
    RADAU_STATUS,
    radau_solve,
)

VAN_DER_POL, ROBERTSON = 0, 1


@numba.njit(cache=True)
def rhs(t, y, p, dydt):
    if p[0] == VAN_DER_POL:
        dydt[0] = y[1]
        dydt[1] = ((1.0 - y[0] * y[0]) * y[1] - y[0]) * 1e6
    else:
        dydt[0] = -0.04 * y[0] + 1e4 * y[1] * y[2]
        dydt[2] = 3e7 * y[1] * y[1]
        dydt[1] = 0.04 * y[0] - 1e4 * y[1] * y[2] - 3e7 * y[1] * y[1]


@numba.njit(cache=True)
def jac(t, y, p, jacobian):
    if p[0] == VAN_DER_POL:
        jacobian[0, 0] = 0.0
        jacobian[0, 1] = 1.0
        jacobian[1, 0] = (-2.0 * y[0] * y[1] - 1.0) * 1e6
        jacobian[1, 1] = (1.0 - y[0] * y[0]) * 1e6
    else:
        jacobian[0, 0] = -0.04
        jacobian[0, 1] = 1e4 * y[2]
        jacobian[0, 2] = 1e4 * y[1]
        jacobian[1, 0] = 0.04
        jacobian[1, 1] = -1e4 * y[2] - 6e7 * y[1]
        jacobian[1, 2] = -1e4 * y[1]
        jacobian[2, 0] = 0.0
        jacobian[2, 1] = 6e7 * y[1]
        jacobian[2, 2] = 0.0


PROBLEMS = {
    # name: (problem, y0, t_end, atol at rtol, atol of the reference at rtol 1e-12)
    "Van der Pol, eps 1e-6": (VAN_DER_POL, np.array([2.0, -0.66]), 2.0, lambda rtol: rtol, 1e-12),
    "Robertson, [0, 1e5]": (ROBERTSON, np.array([1.0, 0.0, 0.0]), 1e5, lambda rtol: 1e-10, 1e-16),
}
RTOLS = (1e-4, 1e-6, 1e-8)


def scipy_radau(p, y0, t_end, rtol, atol):
    n = y0.shape[0]

    def fun(t, y):
        out = np.empty(n)
        rhs(t, y, p, out)
        return out

    def jacobian(t, y):
        out = np.zeros((n, n))
        jac(t, y, p, out)
        return out

    start = time.perf_counter()
    sol = solve_ivp(fun, (0.0, t_end), y0, method="Radau", rtol=rtol, atol=atol, jac=jacobian)
    elapsed = time.perf_counter() - start
    assert sol.success, sol.message
    return sol.y[:, -1], len(sol.t) - 1, sol.nfev, sol.njev, sol.nlu, elapsed


def main():
    print("| problem | rtol | camdyn steps (rejected) | SciPy steps | ratio | camdyn rhs / jac / LU "
          "| SciPy rhs / jac / LU | camdyn error / tol | SciPy error / tol | camdyn time | SciPy time |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name, (problem, y0, t_end, atol_of, reference_atol) in PROBLEMS.items():
        p = np.array([float(problem)])
        reference = scipy_radau(p, y0, t_end, 1e-12, reference_atol)[0]
        for rtol in RTOLS:
            atol = atol_of(rtol)
            args = (rhs, jac, 0.0, y0, t_end, rtol, atol, 0.0, 10 ** 6, np.array([t_end]), p)
            best = np.inf
            for _ in range(3):
                start = time.perf_counter()
                y_out, counters = radau_solve(*args)
                best = min(best, time.perf_counter() - start)
            assert counters[RADAU_STATUS] == 0
            y_scipy, steps, nfev, njev, nlu, elapsed = scipy_radau(p, y0, t_end, rtol, atol)
            scale = atol + rtol * np.abs(reference)
            error = np.max(np.abs(y_out[-1] - reference) / scale)
            error_scipy = np.max(np.abs(y_scipy - reference) / scale)
            print(f"| {name} | {rtol:.0e} | {counters[RADAU_ACCEPTED]} ({counters[RADAU_REJECTED]}) | {steps} "
                  f"| {counters[RADAU_ACCEPTED] / steps:.2f} "
                  f"| {counters[RADAU_RHS]} / {counters[RADAU_JACOBIANS]} / {counters[RADAU_LU]} "
                  f"| {nfev} / {njev} / {nlu} | {error:.1e} | {error_scipy:.1e} "
                  f"| {best * 1e3:.2f} ms | {elapsed * 1e3:.0f} ms |")


if __name__ == "__main__":
    main()
