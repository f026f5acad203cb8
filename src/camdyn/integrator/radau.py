"""Radau IIA of order 5: a fully implicit, L-stable, stiffly accurate three-stage
collocation method, implemented as in Hairer and Wanner's RADAU5 [1, 2].

The method is in three modules, this one the entry point that re-exports the other two:
its coefficients and the transformation that splits its Newton iteration into one real
and one complex ``n x n`` linear system (:mod:`camdyn.integrator.radau_tableau`); one
attempted step (:func:`radau_step`, for a driver that owns the step-size logic) and the
collocation polynomial as dense output (:func:`radau_dense`), in
:mod:`camdyn.integrator.radau_newton`, whose docstring gives the notation; and here
RADAU5's step-size controller and a driver-free integration routine
(:func:`radau_solve`, for tests and benchmarks). It is not wired into
:mod:`camdyn.integrator.driver`.

The tolerances mean what they mean for the other steppers of camdyn
(:mod:`camdyn.integrator.tolerances`): the embedded error estimate of a step is kept
below ``atol + rtol max(|y|, |y_1|)`` in the RMS norm. RADAU5 itself transforms the
user's tolerances first (``rtol' = 0.1 rtol^(2/3)``, [2], subroutine RADAU5) so that the
global error comes out proportional to ``rtol``; this module does not (as SciPy's
``Radau`` does not), so that its step counts compare with SciPy's at equal tolerances.

References
----------
[1] E. Hairer, G. Wanner, Solving Ordinary Differential Equations II: Stiff and
    Differential-Algebraic Problems, 2nd ed., Springer (1996), section IV.8,
    doi:10.1007/978-3-642-05221-7.
[2] E. Hairer, G. Wanner, radau5.f (Fortran code of RADAU5, version of 1996, with its
    subroutines RADCOR, SLVRAD, ESTRAD and CONTR5), described in [1], IV.8.
[3] K. Gustafsson, Control-theoretic techniques for stepsize selection in implicit
    Runge-Kutta methods, ACM Trans. Math. Softw. 20 (1994) 496-517,
    doi:10.1145/198429.198437.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.integrator.counters import STATUS_MAX_STEPS, STATUS_NOT_FINITE, STATUS_OK, STATUS_STEP_UNDERFLOW
from camdyn.integrator.inlining import InlinedPipeline
from camdyn.integrator.radau_newton import (
    EPS,
    NEWTON_MAX,
    RECORD_SIZE,
    STEP_CONVERGED,
    STEP_DIVERGED,
    STEP_SLOW,
    THETA_JACOBIAN,
    WORK_ROWS,
    radau_dense,
    radau_dense_coefficients,
    radau_factor,
    radau_start,
    radau_step,
    scaled_rms,
)
from camdyn.integrator.radau_tableau import (
    RADAU_A,
    RADAU_ALPHA,
    RADAU_B,
    RADAU_BETA,
    RADAU_C,
    RADAU_E,
    RADAU_GAMMA,
    RADAU_P,
    RADAU_T,
    RADAU_TI,
)

__all__ = [
    "RADAU_A", "RADAU_B", "RADAU_C", "RADAU_T", "RADAU_TI", "RADAU_GAMMA", "RADAU_ALPHA", "RADAU_BETA",
    "RADAU_E", "RADAU_P", "RADAU_COUNTER_NAMES", "radau_factor", "radau_step", "radau_start",
    "radau_dense_coefficients", "radau_dense", "radau_solve", "predictive_quotient", "KEEP_LOW", "KEEP_HIGH",
    "STEP_CONVERGED", "STEP_SLOW", "STEP_DIVERGED",
]

# Controller constants (RADAU5's defaults, [2]).
SAFETY = 0.9             # SAFE
FACTOR_MAX = 8.0         # 1 / FACR: the largest growth of a step
FACTOR_MIN = 0.2         # 1 / FACL: the largest reduction from the error estimate
KEEP_LOW, KEEP_HIGH = 1.0, 1.2   # QUOT1, QUOT2: keep h (and the LU) for a new step within

# Counters returned by radau_solve.
RADAU_ACCEPTED = 0
RADAU_REJECTED = 1
RADAU_RHS = 2
RADAU_JACOBIANS = 3
RADAU_LU = 4
RADAU_NEWTON = 5
RADAU_STATUS = 6
RADAU_COUNTER_SIZE = 7
RADAU_COUNTER_NAMES = ("accepted_steps", "rejected_steps", "rhs_calls", "jacobians", "lu_decompositions",
                       "newton_iterations", "status")


# --- the step-size controller -----------------------------------------------------------


@numba.njit(cache=True, inline="always")
def _controller(h, outcome, factor, error, iterations, first, predictive, h_accepted, error_accepted):
    """RADAU5's verdict on a step of ``h`` [s] and the next step [s]: ``(accepted,
    h_new)``. A Newton iteration that failed (``outcome``) gives ``h`` times its
    ``factor``; an error norm ``error`` [-] of 1 or more rejects the step, and a rejected
    first step is retried ten times shorter; otherwise ``h_new = h / q`` with ``q =
    clip(err^(1/4) / fac, 1/8, 5)`` and the safety factor ``fac = 0.9 (2 NIT + 1) / (2 NIT
    + k)`` after ``k`` Newton ``iterations``. With ``predictive`` (an accepted step after
    an accepted one), ``q`` is at least Gustafsson's ``(h_acc / h) (err^2 /
    err_acc)^(1/4) / 0.9`` [3], from the last accepted step ``h_accepted`` and its error
    ``error_accepted``."""
    if outcome != STEP_CONVERGED:
        return False, h * factor
    if error >= 1.0 and first:
        return False, h * 0.1
    fac = min(SAFETY, SAFETY * (1 + 2 * NEWTON_MAX) / (iterations + 2 * NEWTON_MAX))
    quotient = max(1.0 / FACTOR_MAX, min(1.0 / FACTOR_MIN, error ** 0.25 / fac))
    if error < 1.0 and predictive:
        quotient = max(quotient, predictive_quotient(h, error, h_accepted, error_accepted))
    return error < 1.0, h / quotient


@numba.njit(cache=True, inline="always")
def predictive_quotient(h, error, h_accepted, error_accepted):
    """Gustafsson's predictive quotient ``h / h_new`` [-] after an accepted step of ``h``
    [s] with error norm ``error`` [-] that followed an accepted step of ``h_accepted``
    [s] with ``error_accepted`` [-]: ``(h_acc / h) (err^2 / err_acc)^(1/4) / 0.9`` [3],
    clipped to ``[1/8, 5]`` as RADAU5 clips its quotients."""
    gustafsson = (h_accepted / h) * (error * error / error_accepted) ** 0.25 / SAFETY
    return max(1.0 / FACTOR_MAX, min(1.0 / FACTOR_MIN, gustafsson))


@numba.njit(cache=True, inline="always")
def _next_step(t, h, h_new, h_max, t_end, rejected, theta):
    """The step [s] after an accepted one of ``h`` [s] that ended at ``t`` [s], from the
    controller's ``h_new`` [s]: at most ``h_max``, and at most ``h`` right after a
    rejection; the rest of the interval if ``h_new`` reaches ``t_end``; ``h`` kept (and
    with it the LU factorizations) when ``h_new / h`` is in [1, 1.2] and the last
    iteration contracted by at most ``THETA_JACOBIAN``, and a new Jacobian when a new
    ``h`` follows a slower contraction. Returns ``(h, last, need_lu, need_jacobian)``."""
    h_new = min(h_new, h_max)
    if rejected:
        h_new = min(h_new, h)
    last = False
    need_lu = False
    if t + h_new >= t_end:
        h = t_end - t
        last = True
        need_lu = True
    else:
        ratio = h_new / h
        if not (theta <= THETA_JACOBIAN and KEEP_LOW <= ratio <= KEEP_HIGH):
            h = h_new
            need_lu = True
    return h, last, need_lu, need_lu and theta > THETA_JACOBIAN


@numba.njit(cache=True, inline="always")
def _stop_status(t, h, attempts, max_steps):
    """``STATUS_MAX_STEPS`` after ``max_steps`` attempts, ``STATUS_STEP_UNDERFLOW`` when
    ``h`` [s] is lost in the rounding of ``t`` [s] (or not positive), else
    ``STATUS_OK``."""
    if attempts >= max_steps:
        return STATUS_MAX_STEPS
    if 0.1 * abs(h) <= abs(t) * EPS or h <= 0.0:
        return STATUS_STEP_UNDERFLOW
    return STATUS_OK


# The functions that take ``rhs`` or ``jac`` are compiled per function passed and not
# cached, and the helpers are inlined into radau_solve (see the note in
# camdyn.integrator.radau_newton).
@numba.njit(cache=False)
def _initial_step(rhs, t, y, f0, t_end, p, rtol, atol, yt, f1):
    """Starting step [s] of Hairer, Norsett and Wanner (ODE I, II.4) for an error
    estimate of order 3; one right-hand-side call."""
    n = y.shape[0]
    d0 = scaled_rms(y, y, y, rtol, atol, n)
    d1 = scaled_rms(f0, y, y, rtol, atol, n)
    h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    h0 = min(h0, t_end - t)
    for i in range(n):
        yt[i] = y[i] + h0 * f0[i]
    rhs(t + h0, yt, p, f1)
    for i in range(n):
        f1[i] = f1[i] - f0[i]
    d2 = scaled_rms(f1, y, y, rtol, atol, n) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** 0.25
    return min(100.0 * h0, h1, t_end - t)


@numba.njit(cache=False)
def _start(rhs, t, y, f0, t_end, p, rtol, atol, first_step, work, counters):
    """``f0 = f(t, y)`` at the start and the first step [s]: ``first_step`` if positive,
    else :func:`_initial_step`'s estimate, cut to the interval (right-hand-side calls
    counted). Returns ``(h, last)``, ``last`` when it reaches ``t_end``."""
    rhs(t, y, p, f0)
    counters[RADAU_RHS] += 1
    if first_step > 0.0:
        h = min(first_step, t_end - t)
    else:
        h = _initial_step(rhs, t, y, f0, t_end, p, rtol, atol, work[0], work[1])
        counters[RADAU_RHS] += 1
    if t + h >= t_end:
        return t_end - t, True
    return h, False


@numba.njit(cache=False, inline="always")
def _iteration_matrices(jac, t, y, p, h, need_jacobian, jacobian, lu_real, pivots_real, lu_complex,
                        pivots_complex, counters):
    """A new Jacobian at ``(t, y)`` if ``need_jacobian``, then the factorizations of the
    iteration matrices for ``h`` [s] (:func:`radau_factor`), counted. Returns whether
    either matrix is singular."""
    if need_jacobian:
        jac(t, y, p, jacobian)
        counters[RADAU_JACOBIANS] += 1
    counters[RADAU_LU] += 1
    return radau_factor(jacobian, h, lu_real, pivots_real, lu_complex, pivots_complex)


# --- the output samples -----------------------------------------------------------------


@numba.njit(cache=True)
def _sample_start(t0, y0, t_out, y_out):
    """``y0`` at the output times up to ``t0`` [s]; returns the index of the next output."""
    k_out = 0
    while k_out < t_out.shape[0] and t_out[k_out] <= t0:
        y_out[k_out] = y0
        k_out += 1
    return k_out


@numba.njit(cache=True, inline="always")
def _sample_step(t_old, t, h, coefficients, t_out, k_out, y_out):
    """The collocation polynomial (:func:`radau_dense`) of the step of ``h`` [s] from
    ``t_old`` to ``t`` [s] at the output times from index ``k_out`` up to ``t``; returns
    the index of the next output."""
    while k_out < t_out.shape[0] and t_out[k_out] <= t:
        radau_dense((t_out[k_out] - t_old) / h, coefficients, y_out[k_out])
        k_out += 1
    return k_out


@numba.njit(cache=False, inline="always")
def _advance(rhs, p, t, h, t_end, last, y, y1, z, f0, coefficients, t_out, k_out, y_out, counters):
    """Take an accepted step of ``h`` [s] from ``t`` [s]: the end time (``t_end`` for the
    last step, and for one that lands on it up to rounding), the step's collocation
    polynomial into ``coefficients``, ``y`` set to ``y1``, the outputs inside the step,
    and ``f0 = f(t, y)`` at the new point (counted). Returns ``(t, last, k_out,
    status)``, ``status`` ``STATUS_NOT_FINITE`` if the new state or its ``f`` is not
    finite, else ``STATUS_OK``."""
    t_old = t
    t = t_end if last else t + h
    if t_end - t <= 16.0 * EPS * max(1.0, abs(t_end)):
        t = t_end   # landed on the end up to rounding: no step of a few ulp after it
        last = True
    radau_dense_coefficients(y, z, coefficients)
    n = y.shape[0]
    for i in range(n):
        y[i] = y1[i]
    k_out = _sample_step(t_old, t, h, coefficients, t_out, k_out, y_out)
    rhs(t, y, p, f0)
    counters[RADAU_RHS] += 1
    status = STATUS_OK
    for i in range(n):
        if not math.isfinite(y[i]) or not math.isfinite(f0[i]):
            status = STATUS_NOT_FINITE
    return t, last, k_out, status


# --- the integration ----------------------------------------------------------------------


@numba.njit(cache=False, pipeline_class=InlinedPipeline)
def radau_solve(rhs, jac, t0, y0, t_end, rtol, atol, first_step, max_steps, t_out, p):
    """Integrate ``y' = f(t, y)`` from ``t0`` to ``t_end`` [s] (forward) with Radau IIA
    of order 5 and RADAU5's step-size and Jacobian-reuse strategy ([1], IV.8; [2]).

    Step size: RADAU5's controller with Gustafsson's predictive one after the second
    accepted step (:func:`_controller`); a step right after a rejection is not longer
    than the rejected one, and a new step keeps ``h`` and the LU factorizations when
    ``h_new / h`` is in [1, 1.2] and the last iteration contracted by at most 0.001
    (:func:`_next_step`). The Jacobian is recomputed only when it contracted more slowly,
    or after a rejection with an old Jacobian. A failed Newton iteration halves ``h`` (or
    reduces it as RADAU5's convergence prediction says); a rejected first step is
    retried ten times shorter.

    Parameters
    ----------
    rhs : numba function
        ``rhs(t, y, p, dydt)`` writes ``f(t, y)`` [state units/s] into ``dydt``.
    jac : numba function
        ``jac(t, y, p, J)`` writes ``df/dy`` [1/s] into ``J`` (n x n); an approximation
        slows the Newton iteration but does not change the solution it converges to.
    t0, t_end : float
        Start and end [s], ``t_end > t0``.
    y0 : ndarray, shape (n,)
        Initial state.
    rtol : float
        Relative tolerance [-].
    atol : float or ndarray, shape (n,)
        Absolute tolerance [state units].
    first_step : float
        First step [s]; 0 or less picks one (Hairer, Norsett and Wanner's estimate).
    max_steps : int
        The most steps (accepted and rejected) before stopping.
    t_out : ndarray, shape (m,)
        Increasing output times in [t0, t_end] [s]; the states there come from the
        collocation polynomials of the steps.
    p : ndarray
        Parameters passed to ``rhs`` and ``jac``.

    Returns
    -------
    y_out : ndarray, shape (m, n)
        States at ``t_out`` (NaN past a stop).
    counters : ndarray, shape (7,), int64
        Indexed by ``RADAU_*`` (:data:`RADAU_COUNTER_NAMES`): accepted and rejected
        steps, right-hand-side calls, Jacobians, LU decompositions (pairs of real and
        complex), Newton iterations, and a ``STATUS_*`` code of
        :mod:`camdyn.integrator.counters`.
    """
    n = y0.shape[0]
    counters, y_out = np.zeros(RADAU_COUNTER_SIZE, dtype=np.int64), np.full((t_out.shape[0], n), np.nan)
    y, y1, err, f0 = y0.copy(), np.empty(n), np.empty(n), np.empty(n)
    jacobian, lu_real, lu_complex = np.zeros((n, n)), np.empty((n, n)), np.empty((n, n), dtype=np.complex128)
    pivots_real, pivots_complex = np.empty(n, dtype=np.int64), np.empty(n, dtype=np.int64)
    z, w, cwork = np.zeros((3, n)), np.empty((3, n)), np.empty((2, n), dtype=np.complex128)
    work, record = np.empty((WORK_ROWS, n)), np.empty(RECORD_SIZE)
    coefficients = np.empty((4, n))
    t, k_out = t0, _sample_start(t0, y0, t_out, y_out)
    h, last = _start(rhs, t, y, f0, t_end, p, rtol, atol, first_step, work, counters)
    newton_tolerance = max(10.0 * EPS / rtol, min(0.03, math.sqrt(rtol)))
    need_jacobian = need_lu = first = True
    fresh_jacobian = False    # RADAU5's CALJAC: J was computed at the current (t, y)
    rejected = have_polynomial = False
    faccon, theta, h_old, h_accepted, error_accepted = 1.0, THETA_JACOBIAN, h, h, 1.0
    while True:
        status = _stop_status(t, h, counters[RADAU_ACCEPTED] + counters[RADAU_REJECTED], max_steps)
        if status != STATUS_OK:
            break
        if not last and t + h >= t_end:   # a retried step reaching the end (RADAU5 checks after acceptances only)
            h, last, need_lu = t_end - t, True, True
        h_new = 0.5 * h   # RADAU5's unexpected rejection: a singular iteration matrix
        accepted = singular = False
        if need_lu or need_jacobian:
            fresh_jacobian = fresh_jacobian or need_jacobian
            singular = _iteration_matrices(jac, t, y, p, h, need_jacobian, jacobian, lu_real, pivots_real,
                                           lu_complex, pivots_complex, counters)
            need_jacobian = need_lu = False
        if not singular:
            radau_start(h, h_old, y, coefficients, z, have_polynomial and not first)
            outcome, error, iterations, theta, faccon, factor, calls = radau_step(
                rhs, t, y, f0, h, p, rtol, atol, n, newton_tolerance, faccon, first or rejected,
                lu_real, pivots_real, lu_complex, pivots_complex, z, w, y1, err, work, cwork, record)
            counters[RADAU_RHS] += calls
            counters[RADAU_NEWTON] += iterations
            accepted, h_new = _controller(h, outcome, factor, error, iterations, first, counters[RADAU_ACCEPTED] > 0,
                                          h_accepted, error_accepted)
        if not accepted:
            counters[RADAU_REJECTED] += 1
            h, rejected, last, need_lu, need_jacobian = h_new, True, False, True, not fresh_jacobian
            continue
        first = False
        counters[RADAU_ACCEPTED] += 1
        h_accepted, error_accepted, h_old, have_polynomial, fresh_jacobian = h, max(1e-2, error), h, True, False
        t, last, k_out, status = _advance(rhs, p, t, h, t_end, last, y, y1, z, f0, coefficients, t_out, k_out,
                                          y_out, counters)
        if status != STATUS_OK or last:
            break
        h, last, need_lu, need_jacobian = _next_step(t, h, h_new, t_end - t0, t_end, rejected, theta)
        rejected = False
    counters[RADAU_STATUS] = status
    return y_out, counters
