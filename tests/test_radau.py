"""Radau IIA of order 5 (:mod:`camdyn.integrator.radau`) against things outside its code:
the closed forms of the method's coefficients (Hairer and Wanner, ODE II, IV.5 and
IV.8), closed-form solutions for its orders and its error control, and SciPy's
``solve_ivp(method="Radau")`` (a separate implementation of the same method, [1] of the
module) on two stiff test problems of Hairer and Wanner.

All problems share one right-hand side and one Jacobian, picked by ``p[0]``, so that
numba compiles :func:`radau_solve` once for the whole file (about 10-15 s on the
shared machine; a specialisation per function pair is not cached across processes).
``p[2]`` scales the Jacobian (1: exact).
"""

import math
import time

import numba
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from camdyn.integrator.counters import STATUS_MAX_STEPS, STATUS_OK
from camdyn.integrator.radau import (
    RADAU_A,
    RADAU_ACCEPTED,
    RADAU_ALPHA,
    RADAU_B,
    RADAU_BETA,
    RADAU_C,
    RADAU_E,
    RADAU_GAMMA,
    RADAU_JACOBIANS,
    RADAU_NEWTON,
    RADAU_P,
    RADAU_REJECTED,
    RADAU_STATUS,
    RADAU_T,
    RADAU_TI,
    STEP_CONVERGED,
    radau_dense,
    radau_dense_coefficients,
    radau_factor,
    radau_solve,
    radau_start,
    radau_step,
)

FORCED, OSCILLATOR, VAN_DER_POL, ROBERTSON, RELAXATION = 0, 1, 2, 3, 4


@numba.njit(cache=True)
def rhs(t, y, p, dydt):
    """The test problems: ``y' = -y + sin t``; ``y'' = -w^2 y`` (``w = p[1]`` [rad/s]);
    Van der Pol in Hairer and Wanner's scaled form (``p[1] = 1/eps``); Robertson's
    kinetics; ``y' = -lambda (y - cos t)`` (``lambda = p[1]`` [1/s])."""
    k = int(p[0])
    if k == FORCED:
        dydt[0] = -y[0] + math.sin(t)
    elif k == OSCILLATOR:
        dydt[0] = y[1]
        dydt[1] = -p[1] * p[1] * y[0]
    elif k == VAN_DER_POL:
        dydt[0] = y[1]
        dydt[1] = ((1.0 - y[0] * y[0]) * y[1] - y[0]) * p[1]
    elif k == ROBERTSON:
        dydt[0] = -0.04 * y[0] + 1e4 * y[1] * y[2]
        dydt[2] = 3e7 * y[1] * y[1]
        dydt[1] = 0.04 * y[0] - 1e4 * y[1] * y[2] - 3e7 * y[1] * y[1]
    else:
        dydt[0] = -p[1] * (y[0] - math.cos(t))


@numba.njit(cache=True)
def jac(t, y, p, jacobian):
    """``df/dy`` of :func:`rhs`, times ``p[2]``."""
    k = int(p[0])
    if k == FORCED:
        jacobian[0, 0] = -1.0
    elif k == OSCILLATOR:
        jacobian[0, 0] = 0.0
        jacobian[0, 1] = 1.0
        jacobian[1, 0] = -p[1] * p[1]
        jacobian[1, 1] = 0.0
    elif k == VAN_DER_POL:
        jacobian[0, 0] = 0.0
        jacobian[0, 1] = 1.0
        jacobian[1, 0] = (-2.0 * y[0] * y[1] - 1.0) * p[1]
        jacobian[1, 1] = (1.0 - y[0] * y[0]) * p[1]
    elif k == ROBERTSON:
        jacobian[0, 0] = -0.04
        jacobian[0, 1] = 1e4 * y[2]
        jacobian[0, 2] = 1e4 * y[1]
        jacobian[1, 0] = 0.04
        jacobian[1, 1] = -1e4 * y[2] - 6e7 * y[1]
        jacobian[1, 2] = -1e4 * y[1]
        jacobian[2, 0] = 0.0
        jacobian[2, 1] = 6e7 * y[1]
        jacobian[2, 2] = 0.0
    else:
        jacobian[0, 0] = -p[1]
    n = y.shape[0]
    for i in range(n):
        for j in range(n):
            jacobian[i, j] *= p[2]


def params(problem, value=0.0, jacobian_scale=1.0):
    return np.array([problem, value, jacobian_scale], dtype=float)


def forced_exact(t, y0=1.0):
    """``y' = -y + sin t``: ``y = (y0 + 1/2) e^-t + (sin t - cos t) / 2``."""
    return (y0 + 0.5) * np.exp(-t) + 0.5 * (np.sin(t) - np.cos(t))


def relaxation_exact(t, lam, y0):
    """``y' = -lambda (y - cos t)``: ``y = C e^(-lambda t) + lambda (lambda cos t + sin t)
    / (lambda^2 + 1)``."""
    steady = lam * (lam * np.cos(t) + np.sin(t)) / (lam * lam + 1.0)
    return (y0 - lam * lam / (lam * lam + 1.0)) * np.exp(-lam * t) + steady


def slope(h, err):
    """Least-squares slope of log(err) against log(h): the observed order."""
    return np.polyfit(np.log(h), np.log(err), 1)[0]


def fixed_steps(p, y0, t_end, steps, mid=False):
    """``steps`` Radau steps of ``h = t_end / steps`` (Jacobian and LU at every step; the
    Newton iteration run to ``1e-3`` of a ``1e-12`` scale, far below the
    discretization error). Returns the final state, and with ``mid`` the largest error
    of the dense output at the middle of the steps against :func:`forced_exact`, and
    the Newton iterations."""
    n = y0.shape[0]
    h = t_end / steps
    y, y1, err, f0 = y0.copy(), np.empty(n), np.empty(n), np.empty(n)
    jacobian = np.zeros((n, n))
    lu_r, lu_c = np.empty((n, n)), np.empty((n, n), complex)
    piv_r, piv_c = np.empty(n, np.int64), np.empty(n, np.int64)
    z, w, work, cwork = np.zeros((3, n)), np.empty((3, n)), np.empty((9, n)), np.empty((2, n), complex)
    coefficients, out = np.empty((4, n)), np.empty(n)
    mid_error, iterations, faccon = 0.0, 0, 1.0
    for k in range(steps):
        t = k * h
        rhs(t, y, p, f0)
        jac(t, y, p, jacobian)
        assert not radau_factor(jacobian, h, lu_r, piv_r, lu_c, piv_c)
        radau_start(h, h, y, coefficients, z, k > 0)
        outcome, _, its, _, faccon, _, _ = radau_step(rhs, t, y, f0, h, p, 1e-12, 1e-12, n, 1e-3, faccon, False,
                                                       lu_r, piv_r, lu_c, piv_c, z, w, y1, err, work, cwork,
                                                       np.empty(6))
        assert outcome == STEP_CONVERGED
        iterations += its
        radau_dense_coefficients(y, z, coefficients)
        if mid:
            radau_dense(0.5, coefficients, out)
            mid_error = max(mid_error, abs(out[0] - forced_exact(t + 0.5 * h, y0[0])))
        y[:] = y1
    return y, mid_error, iterations


# --- coefficients against their closed forms ------------------------------------------


def test_coefficients_satisfy_the_order_conditions_and_hairers_closed_forms():
    """Radau IIA's c are the zeros of the Radau polynomial; b = A's last row satisfies
    the quadrature conditions to order 2s - 1 = 5 and A the stage order conditions C(3);
    the eigenvalues of A^-1 are 3 + 3^(2/3) - 3^(1/3) and 3 + (3^(1/3) - 3^(2/3)) / 2
    +- i (3^(5/6) + 3^(7/6)) / 2, and RADAU5's error weights are (-13 -+ 7 sqrt 6) / 3,
    -1/3 (Hairer and Wanner, ODE II, IV.8)."""
    s6 = math.sqrt(6.0)
    assert np.allclose(RADAU_C, [(4 - s6) / 10, (4 + s6) / 10, 1.0], rtol=0, atol=1e-15)
    for k in range(1, 6):
        assert RADAU_B @ RADAU_C ** (k - 1) == pytest.approx(1.0 / k, rel=1e-14)
    assert RADAU_B @ RADAU_C ** 5 != pytest.approx(1.0 / 6, rel=1e-6)   # and not to order 6
    for k in range(1, 4):
        assert np.allclose(RADAU_A @ RADAU_C ** (k - 1), RADAU_C ** k / k, rtol=0, atol=1e-15)
    assert RADAU_GAMMA == pytest.approx(3 + 3 ** (2 / 3) - 3 ** (1 / 3), rel=1e-14)
    assert RADAU_ALPHA == pytest.approx(3 + 0.5 * (3 ** (1 / 3) - 3 ** (2 / 3)), rel=1e-14)
    assert RADAU_BETA == pytest.approx(0.5 * (3 ** (5 / 6) + 3 ** (7 / 6)), rel=1e-14)
    block = np.array([[RADAU_GAMMA, 0, 0], [0, RADAU_ALPHA, RADAU_BETA], [0, -RADAU_BETA, RADAU_ALPHA]])
    assert np.allclose(RADAU_TI @ np.linalg.inv(RADAU_A) @ RADAU_T, block, rtol=0, atol=1e-12)
    assert np.allclose(RADAU_T @ RADAU_TI, np.eye(3), rtol=0, atol=1e-14)
    assert np.allclose(RADAU_E, [(-13 - 7 * s6) / 3, (-13 + 7 * s6) / 3, -1 / 3], rtol=1e-13, atol=0)
    # the dense output's cubic passes through the stages: sum_k P[i, k] c_j^(k+1) = delta_ij
    powers = np.array([[c ** (k + 1) for c in RADAU_C] for k in range(3)])
    assert np.allclose(RADAU_P @ powers, np.eye(3), rtol=0, atol=1e-13)


# --- orders on a closed-form solution -------------------------------------------------


def test_order_five_at_fixed_steps():
    """y' = -y + sin t, y(0) = 1, to t = 4 in 4, 8, 16, 32 steps: the global error falls
    by 2^5 per halving (measured order 4.99; errors 4.7e-5, 1.4e-6, 4.6e-8, 1.5e-9). The
    same on the oscillator y'' = -y over one period (measured 4.95; 7.4e-3 ... 2.5e-7)."""
    y0 = np.array([1.0])
    steps = np.array([4, 8, 16, 32])
    errors = np.array([abs(fixed_steps(params(FORCED), y0, 4.0, m)[0][0] - forced_exact(4.0)) for m in steps])
    order = slope(4.0 / steps, errors)
    assert 4.6 < order < 5.6, (order, errors)
    period = 2 * math.pi
    errors = []
    for m in steps:
        y = fixed_steps(params(OSCILLATOR, 1.0), np.array([1.0, 0.0]), period, m)[0]
        errors.append(math.hypot(y[0] - 1.0, y[1]))
    order = slope(period / steps, np.array(errors))
    assert 4.6 < order < 5.6, (order, errors)


def test_dense_output_order():
    """The collocation cubic in the middle of the steps: its error (the interpolation's
    O(h^4) plus the O(h^5) global error) converges at order 4 (measured: 4.02; errors
    5.4e-4 ... 1.3e-7), and
    ``radau_dense(1)`` is the step's end point."""
    y0 = np.array([1.0])
    steps = np.array([4, 8, 16, 32])
    errors = np.array([fixed_steps(params(FORCED), y0, 4.0, m, mid=True)[1] for m in steps])
    order = slope(4.0 / steps, errors)
    assert 3.5 < order < 4.6, (order, errors)
    z = np.array([[0.1, -0.2], [0.3, 0.1], [0.7, -0.4]])
    coefficients, out = np.empty((4, 2)), np.empty(2)
    radau_dense_coefficients(np.array([1.0, 2.0]), z, coefficients)
    radau_dense(1.0, coefficients, out)
    assert np.allclose(out, [1.7, 1.6], rtol=0, atol=1e-14)
    radau_dense(0.0, coefficients, out)
    assert np.array_equal(out, [1.0, 2.0])


# --- error control ----------------------------------------------------------------------


def _estimate(p, y0, h, refine):
    """The error estimate [state units] and the state after one step of ``h`` [s] from
    ``(0, y0)`` (Jacobian exact, zero starting values, rtol = atol = 1e-6)."""
    n = y0.shape[0]
    f0, y1, err = np.empty(n), np.empty(n), np.empty(n)
    jacobian = np.zeros((n, n))
    lu_r, lu_c = np.empty((n, n)), np.empty((n, n), complex)
    piv_r, piv_c = np.empty(n, np.int64), np.empty(n, np.int64)
    rhs(0.0, y0, p, f0)
    jac(0.0, y0, p, jacobian)
    assert not radau_factor(jacobian, h, lu_r, piv_r, lu_c, piv_c)
    z, w, work, cwork = np.zeros((3, n)), np.empty((3, n)), np.empty((9, n)), np.empty((2, n), complex)
    outcome = radau_step(rhs, 0.0, y0, f0, h, p, 1e-6, 1e-6, n, 1e-6, 1.0, refine,
                         lu_r, piv_r, lu_c, piv_c, z, w, y1, err, work, cwork, np.empty(6))[0]
    assert outcome == STEP_CONVERGED
    return err, y1


def test_error_estimate_orders_and_its_second_filtering_on_a_stiff_transient():
    """One step of y' = -y + sin t from y(0) = 1: the estimate is that of an embedded
    3rd-order formula, O(h^4) (measured slope 3.9 for h = 0.4 ... 0.05, approaching 4),
    and above the true local error, O(h^6). One step of h = 1 of y' = -1e8 (y - cos t)
    from y(0) = 2 (a transient of 1 that the step damps to 3.0e-8): the estimate filtered
    once, (I - h gamma_0 J)^-1 (...), is the whole transient (measured -1.0, 3e7 times
    the true error), so the first step would be rejected again and again; filtered a
    second time through f(t, y + err) (RADAU5, after a rejection or on the first step)
    it is 3.6e-8, the true error within 25 %."""
    steps = np.array([0.4, 0.2, 0.1, 0.05])
    estimates, errors = [], []
    for h in steps:
        err, y1 = _estimate(params(FORCED), np.array([1.0]), h, False)
        estimates.append(abs(err[0]))
        errors.append(abs(y1[0] - forced_exact(h)))
    assert 3.6 < slope(steps, np.array(estimates)) < 4.4, estimates
    assert 5.5 < slope(steps, np.array(errors)) < 6.5, errors
    assert np.all(np.array(estimates) > np.array(errors))
    p = params(RELAXATION, 1e8)
    true_error = _estimate(p, np.array([2.0]), 1.0, False)[1][0] - relaxation_exact(1.0, 1e8, 2.0)
    assert 1e-8 < abs(true_error) < 1e-7
    once = _estimate(p, np.array([2.0]), 1.0, False)[0][0]
    twice = _estimate(p, np.array([2.0]), 1.0, True)[0][0]
    assert abs(once) > 0.5
    assert abs(twice) == pytest.approx(abs(true_error), rel=0.25)



def test_error_control_is_sound_and_tolerance_proportional():
    """The oscillator y'' = -y over 10 s (1.6 periods), rtol = atol in {1e-4, 1e-6,
    1e-8}, error measured on 101 dense outputs: the global error is within a factor 30
    below rtol and never above it (measured error / rtol: 0.43, 0.36, 0.30: the
    estimate neither lets the error past the tolerance nor wastes steps far below it),
    and it falls with rtol, by at least 10x per 100x (measured: 119x and 122x, a slope
    of 1.04 in log-log)."""
    t_out = np.linspace(0.0, 10.0, 101)
    errors = []
    for rtol in (1e-4, 1e-6, 1e-8):
        y_out, counters = radau_solve(rhs, jac, 0.0, np.array([1.0, 0.0]), 10.0, rtol, rtol, 0.0, 100000,
                                      t_out, params(OSCILLATOR, 1.0))
        assert counters[RADAU_STATUS] == STATUS_OK
        error = max(np.max(np.abs(y_out[:, 0] - np.cos(t_out))), np.max(np.abs(y_out[:, 1] + np.sin(t_out))))
        assert rtol / 30 < error < rtol, (rtol, error)
        errors.append(error)
    assert errors[1] < 0.1 * errors[0] and errors[2] < 0.1 * errors[1], errors


# --- stiff problems against SciPy ---------------------------------------------------------


def scipy_solve(p, y0, t_end, rtol, atol):
    """SciPy's Radau with the analytic Jacobian, on the same functions."""
    n = len(y0)

    def fun(t, y):
        out = np.empty(n)
        rhs(t, y, p, out)
        return out

    def jacobian(t, y):
        out = np.zeros((n, n))
        jac(t, y, p, out)
        return out

    sol = solve_ivp(fun, (0.0, t_end), y0, method="Radau", rtol=rtol, atol=atol, jac=jacobian)
    assert sol.success
    return sol.y[:, -1], len(sol.t) - 1


@pytest.mark.parametrize("problem, y0, t_end, rtol, atol, reference, scipy_steps", [
    # Van der Pol, Hairer and Wanner's scaled form y1' = y2, y2' = ((1 - y1^2) y2 - y1) / eps,
    # eps = 1e-6 (mu = 1e6), y(0) = (2, -0.66), t in [0, 2] (ODE II, IV.10). Measured at rtol =
    # atol = 1e-6: camdyn 835 accepted steps (9 rejected), SciPy 1.17.1 859.
    (VAN_DER_POL, [2.0, -0.66], 2.0, 1e-6, 1e-6, [1.706167437543, -0.892810016551], 859),
    # Robertson, y(0) = (1, 0, 0), t in [0, 1e5], rtol = 1e-6, atol = 1e-10: camdyn 175 (5),
    # SciPy 188.
    (ROBERTSON, [1.0, 0.0, 0.0], 1e5, 1e-6, 1e-10, [1.786592114225e-02, 7.274751468500e-08, 9.821340061102e-01], 188),
])
def test_stiff_problems_against_scipy(problem, y0, t_end, rtol, atol, reference, scipy_steps):
    """Accepted steps within 0.75x-1.33x of SciPy's Radau at the same tolerances (measured
    0.92-1.01 at rtol 1e-4, 1e-6 and 1e-8 on both problems: the same method and
    controller, up to RADAU5's details), and the final state within atol + rtol |y| of
    a reference from SciPy's Radau at rtol 1e-10 (recomputed here, 8,156 and 1,776
    steps; its values are written above): the global error is within the tolerance the
    local error was held to (measured: at most 0.0036 of it on Van der Pol, 0.0023 on
    Robertson)."""
    p = params(problem, 1e6 if problem == VAN_DER_POL else 0.0)
    y_out, counters = radau_solve(rhs, jac, 0.0, np.array(y0), t_end, rtol, atol, 0.0, 100000,
                                  np.array([t_end]), p)
    assert counters[RADAU_STATUS] == STATUS_OK
    _, steps = scipy_solve(p, np.array(y0), t_end, rtol, atol)
    assert steps == pytest.approx(scipy_steps, rel=0.1)   # the measurement in the comment above
    ratio = counters[RADAU_ACCEPTED] / steps
    assert 0.75 < ratio < 1.33, (counters[RADAU_ACCEPTED], steps)
    tight, _ = scipy_solve(p, np.array(y0), t_end, 1e-10, 1e-10 * atol / rtol)
    assert np.allclose(tight, reference, rtol=1e-9, atol=1e-14)
    bound = atol + rtol * np.abs(tight)
    assert np.all(np.abs(y_out[-1] - tight) < bound), (y_out[-1] - tight, bound)


# --- stability and robustness ---------------------------------------------------------------


def test_l_stability_on_a_very_stiff_relaxation():
    """y' = -1e8 (y - cos t) from y(0) = 2 (1 off the slow solution): ten steps of h = 1
    (h lambda = -1e8) land on the slow solution: the first damps the transient of 1 to
    R(h lambda) = O(1 / (h lambda)) (measured 3.0e-8), the next ones stay within the
    smooth part's error (measured <= 1.2e-10), with no oscillation about it (an A-stable
    method with R(-inf) = -1, such as the trapezoidal rule, would keep a +-1 transient);
    an adaptive run at rtol 1e-6 needs 47 steps (2 rejected) and ends 2.5e-9 off."""
    lam = 1e8
    p = params(RELAXATION, lam)
    y = np.array([2.0])
    deviations = []
    t = 0.0
    for _ in range(10):
        y1 = _one_step(p, t, y, 1.0)
        t += 1.0
        deviations.append(y1[0] - relaxation_exact(t, lam, 2.0))
        y = y1
    assert abs(deviations[0]) < 1e-7, deviations
    assert np.all(np.abs(deviations[1:]) < 1e-9), deviations
    y_out, counters = radau_solve(rhs, jac, 0.0, np.array([2.0]), 10.0, 1e-6, 1e-6, 0.0, 10000,
                                  np.array([10.0]), p)
    assert counters[RADAU_STATUS] == STATUS_OK
    assert abs(y_out[-1, 0] - relaxation_exact(10.0, lam, 2.0)) < 1e-5
    assert counters[RADAU_ACCEPTED] < 200, counters


def _one_step(p, t, y, h):
    """One Radau step of ``h`` [s] from ``(t, y)``, Jacobian exact, zero starting values."""
    n = y.shape[0]
    f0, y1, err = np.empty(n), np.empty(n), np.empty(n)
    jacobian = np.zeros((n, n))
    lu_r, lu_c = np.empty((n, n)), np.empty((n, n), complex)
    piv_r, piv_c = np.empty(n, np.int64), np.empty(n, np.int64)
    rhs(t, y, p, f0)
    jac(t, y, p, jacobian)
    assert not radau_factor(jacobian, h, lu_r, piv_r, lu_c, piv_c)
    z, w, work, cwork = np.zeros((3, n)), np.empty((3, n)), np.empty((9, n)), np.empty((2, n), complex)
    outcome = radau_step(rhs, t, y, f0, h, p, 1e-12, 1e-12, n, 1e-3, 1.0, False,
                         lu_r, piv_r, lu_c, piv_c, z, w, y1, err, work, cwork, np.empty(6))[0]
    assert outcome == STEP_CONVERGED
    return y1


def test_a_wrong_jacobian_costs_iterations_not_accuracy():
    """y' = -100 (y - cos t), y(0) = 2, to t = 2 at rtol = atol = 1e-6, with the exact
    Jacobian and with half of it: the simplified Newton iteration still converges to the
    same collocation solution (its matrix only sets the contraction rate), so the error
    bound holds for both (measured max errors 2.0e-6 and 5.9e-8 on 41 outputs); the
    wrong one needs more Newton iterations per attempted step (measured 3.5 against
    1.2) and, as the slower contraction fails the iteration on longer steps, more steps
    (81 accepted and 46 rejected against 43 and 0)."""
    lam = 1e2
    t_out = np.linspace(0.0, 2.0, 41)
    exact = relaxation_exact(t_out, lam, 2.0)
    results = []
    for scale in (1.0, 0.5):
        y_out, counters = radau_solve(rhs, jac, 0.0, np.array([2.0]), 2.0, 1e-6, 1e-6, 0.0, 100000, t_out,
                                      params(RELAXATION, lam, scale))
        assert counters[RADAU_STATUS] == STATUS_OK
        error = np.max(np.abs(y_out[:, 0] - exact))
        assert error < 1e-5, (scale, error)
        steps = counters[RADAU_ACCEPTED] + counters[RADAU_REJECTED]
        results.append((error, counters[RADAU_NEWTON] / steps, counters))
    assert results[1][1] > 2.0 * results[0][1], results


def test_outputs_counters_and_per_component_tolerances():
    """``t_out`` at ``t0`` returns ``y0`` as given; a run stopped by ``max_steps`` says so
    and leaves the outputs past the stop NaN; an ``atol`` per component
    (:mod:`camdyn.integrator.tolerances`) equal to the scalar one gives the same step,
    and an infinite one takes its component out of the error norm."""
    p = params(ROBERTSON)
    y0 = np.array([1.0, 0.0, 0.0])
    y_out, counters = radau_solve(rhs, jac, 0.0, y0, 1e5, 1e-6, 1e-10, 0.0, 50, np.array([0.0, 1e5]), p)
    assert np.array_equal(y_out[0], y0)
    assert counters[RADAU_STATUS] == STATUS_MAX_STEPS
    assert counters[RADAU_ACCEPTED] + counters[RADAU_REJECTED] == 50
    assert np.all(np.isnan(y_out[1]))
    y = np.array([0.5, 1e-5, 0.5])
    scalar = _estimate_with_atol(p, y, 1e-10)
    per_component = _estimate_with_atol(p, y, np.full(3, 1e-10))
    assert per_component[0] == scalar[0]
    assert np.array_equal(per_component[1], scalar[1]) and np.array_equal(per_component[2], scalar[2])
    only_first = _estimate_with_atol(p, y, np.array([1e-10, np.inf, np.inf]))
    # (the Newton iteration's norm changes too, so the estimate is this run's own)
    scale = 1e-10 + 1e-6 * max(y[0], abs(only_first[1][0]))
    assert only_first[0] == pytest.approx(abs(only_first[2][0]) / scale / math.sqrt(3), rel=1e-12)
    assert only_first[0] < 1e-3 * scalar[0]   # measured 0.84 against 4550: y2 (1e-5) dominated it


def _estimate_with_atol(p, y0, atol):
    """(error norm, y1, err) of one step of 1e-3 s from ``(0, y0)`` with ``atol``."""
    n = y0.shape[0]
    f0, y1, err = np.empty(n), np.empty(n), np.empty(n)
    jacobian = np.zeros((n, n))
    lu_r, lu_c = np.empty((n, n)), np.empty((n, n), complex)
    piv_r, piv_c = np.empty(n, np.int64), np.empty(n, np.int64)
    rhs(0.0, y0, p, f0)
    jac(0.0, y0, p, jacobian)
    radau_factor(jacobian, 1e-3, lu_r, piv_r, lu_c, piv_c)
    z, w, work, cwork = np.zeros((3, n)), np.empty((3, n)), np.empty((9, n)), np.empty((2, n), complex)
    result = radau_step(rhs, 0.0, y0, f0, 1e-3, p, 1e-6, atol, n, 1e-3, 1.0, False,
                        lu_r, piv_r, lu_c, piv_c, z, w, y1, err, work, cwork, np.empty(6))
    assert result[0] == STEP_CONVERGED
    return result[1], y1.copy(), err.copy()


def test_solve_runs_quickly_once_compiled():
    """The compiled run of Van der Pol at rtol 1e-6 (835 steps) takes milliseconds (a
    guard against a per-step Python fallback or an allocation per step)."""
    p = params(VAN_DER_POL, 1e6)
    args = (rhs, jac, 0.0, np.array([2.0, -0.66]), 2.0, 1e-6, 1e-6, 0.0, 100000, np.array([2.0]), p)
    radau_solve(*args)
    start = time.perf_counter()
    _, counters = radau_solve(*args)
    assert time.perf_counter() - start < 0.2
    assert counters[RADAU_JACOBIANS] < counters[RADAU_ACCEPTED]   # Jacobians are reused
