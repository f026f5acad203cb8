"""One attempted step of Radau IIA of order 5 (:mod:`camdyn.integrator.radau`): the
iteration matrices and their factorization (:func:`radau_factor`), the collocation
polynomial as dense output and as the Newton iteration's starting values
(:func:`radau_dense_coefficients`, :func:`radau_dense`, :func:`radau_start`), the
simplified Newton iteration (:func:`newton_begin`, :func:`newton_continue`) and the
embedded error estimate (:func:`radau_error`), composed into one step of a function
``rhs`` by :func:`radau_step`, as in
Hairer and Wanner's RADAU5 (its subroutines RADCOR, SLVRAD, ESTRAD and CONTR5 [1, 2]).
The step-size logic is the caller's (:func:`camdyn.integrator.radau.radau_solve`).

Notation (as in [1], IV.8): one step from ``(t, y)`` of size ``h`` [s] solves the
collocation system for the stage increments ``z_i = Y_i - y`` [state units]

    Z = h (A x I) F(Z),    F(Z)_i = f(t + c_i h, y + z_i),    y_1 = y + z_3,

by the simplified Newton iteration with a Jacobian ``J ~ df/dy`` [1/s] held fixed over
the iteration (and over steps while the iteration converges fast). With
``A^-1 = T Lambda T^-1``, ``Lambda = [[gamma, 0, 0], [0, alpha, beta], [0, -beta, alpha]]``
and ``W = (T^-1 x I) Z``, each iteration solves

    (gamma / h I - J) dW_1 = r_1,
    ((alpha - i beta) / h I - J) (dW_2 + i dW_3) = r_2 + i r_3,

with ``r = (T^-1 x I) F(Z) - h^-1 (Lambda x I) W`` ([1], IV.8, "Simplified Newton
iterations"), so one real and one complex LU factorization per step size serve all
iterations. The coefficients are those of :mod:`camdyn.integrator.radau_tableau`.

References
----------
[1] E. Hairer, G. Wanner, Solving Ordinary Differential Equations II: Stiff and
    Differential-Algebraic Problems, 2nd ed., Springer (1996), section IV.8,
    doi:10.1007/978-3-642-05221-7.
[2] E. Hairer, G. Wanner, radau5.f (Fortran code of RADAU5, version of 1996), described
    in [1], IV.8.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.integrator.inlining import InlinedPipeline
from camdyn.integrator.linalg import lu_factor, lu_solve
from camdyn.integrator.radau_tableau import (
    RADAU_ALPHA,
    RADAU_BETA,
    RADAU_C,
    RADAU_E,
    RADAU_GAMMA,
    RADAU_P,
    RADAU_T,
    RADAU_TI,
)
from camdyn.integrator.tolerances import absolute_tolerance

__all__ = [
    "NEWTON_MAX", "THETA_JACOBIAN", "EPS", "STEP_CONVERGED", "STEP_SLOW", "STEP_DIVERGED", "ITERATE", "RECORD_SIZE",
    "WORK_ROWS", "radau_factor", "radau_dense_coefficients", "radau_dense", "radau_start", "scaled_rms",
    "newton_begin", "newton_continue", "newton_summary", "radau_error", "radau_step",
]

# Newton iteration constants (RADAU5's defaults, [2]).
NEWTON_MAX = 7           # NIT: iterations at most per attempt
THETA_JACOBIAN = 0.001   # THET: a new Jacobian after a step whose contraction exceeded it
EPS = np.finfo(np.float64).eps

# Outcomes of one attempted step.
STEP_CONVERGED = 0
STEP_SLOW = 1            # the iteration converges, too slowly for NEWTON_MAX: h *= factor
STEP_DIVERGED = 2        # contraction >= 0.99, NEWTON_MAX reached, or a non-finite stage


@numba.njit(cache=True, inline="always")
def radau_factor(jacobian, h, lu_real, pivots_real, lu_complex, pivots_complex):
    """Build and factor the two iteration matrices of a step of size ``h`` [s]:
    ``gamma / h I - J`` (real) and ``(alpha - i beta) / h I - J`` (complex), in place
    (:func:`camdyn.integrator.linalg.lu_factor`).

    Parameters
    ----------
    jacobian : ndarray, shape (n, n)
        ``J ~ df/dy`` [1/s], not modified.
    h : float
        Step size [s].
    lu_real, lu_complex : ndarray, shape (n, n), float64 and complex128
        Receive the factorizations.
    pivots_real, pivots_complex : ndarray, shape (n,), int64
        Receive their row swaps.

    Returns
    -------
    singular : bool
        Whether either matrix is singular (the step must then be retried shorter).
    """
    n = jacobian.shape[0]
    shift_real = RADAU_GAMMA / h
    shift_complex = complex(RADAU_ALPHA / h, -RADAU_BETA / h)
    for i in range(n):
        for j in range(n):
            lu_real[i, j] = -jacobian[i, j]
            lu_complex[i, j] = -jacobian[i, j]
        lu_real[i, i] += shift_real
        lu_complex[i, i] += shift_complex
    singular_real = lu_factor(lu_real, pivots_real)
    singular_complex = lu_factor(lu_complex, pivots_complex)
    return singular_real or singular_complex


@numba.njit(cache=True, inline="always")
def radau_dense_coefficients(y0, z, coefficients):
    """Coefficients of the collocation polynomial of a step from ``y0`` with stage
    increments ``z`` (3 x n) into ``coefficients`` (4 x n): row 0 is ``y0``, rows 1-3
    multiply ``theta``, ``theta^2`` and ``theta^3`` (:data:`RADAU_P`)."""
    n = y0.shape[0]
    for i in range(n):
        coefficients[0, i] = y0[i]
        for k in range(3):
            coefficients[k + 1, i] = RADAU_P[0, k] * z[0, i] + RADAU_P[1, k] * z[1, i] + RADAU_P[2, k] * z[2, i]


@numba.njit(cache=True)
def radau_dense(theta, coefficients, out):
    """State at ``t_old + theta h`` from the collocation polynomial of the last step:
    the cubic through the step's start and its three stages, accurate to ``O(h^4)``
    inside the step (the collocation polynomial of an s-stage method: Hairer, Norsett
    and Wanner, ODE I, 2nd ed., II.7). ``theta``
    [-] is in [0, 1] for interpolation; past 1 it extrapolates (the Newton starting
    values of the next step)."""
    for i in range(out.shape[0]):
        out[i] = coefficients[0, i] + theta * (coefficients[1, i] + theta * (coefficients[2, i]
                                                                             + theta * coefficients[3, i]))


@numba.njit(cache=True, inline="always")
def radau_start(h, h_old, y, coefficients, z, have_polynomial):
    """Starting values ``z_i`` of the Newton iteration of a step of ``h`` [s] from ``y``:
    the last step's collocation polynomial (step ``h_old`` [s]) extrapolated to the new
    nodes ``t + c_i h``, minus ``y`` ([1], IV.8, "Starting values"; RADAU5), or zero
    without a polynomial (first step)."""
    n = y.shape[0]
    if not have_polynomial:
        for s in range(3):
            for i in range(n):
                z[s, i] = 0.0
        return
    for s in range(3):
        theta = 1.0 + RADAU_C[s] * h / h_old
        for i in range(n):
            value = coefficients[0, i] + theta * (coefficients[1, i] + theta * (coefficients[2, i]
                                                                                + theta * coefficients[3, i]))
            z[s, i] = value - y[i]


@numba.njit(cache=True)
def scaled_rms(v, y0, y1, rtol, atol, controlled):
    """RMS over the first ``controlled`` components of ``v / (atol + rtol max(|y0|,
    |y1|))`` [-]."""
    acc = 0.0
    for i in range(controlled):
        sc = absolute_tolerance(atol, i) + rtol * max(abs(y0[i]), abs(y1[i]))
        acc += (v[i] / sc) ** 2
    return math.sqrt(acc / controlled)


# Slots of the Newton iteration's record (:func:`newton_begin`, :func:`newton_continue`).
_ITERATIONS = 0       # iterations done
_THETA = 1            # contraction rate [-]
_QUOTIENT_OLD = 2     # the last quotient of successive increment norms [-]
_NORM_OLD = 3         # the last increment norm [-]
_FACCON = 4           # eta [-]
_FACTOR = 5           # RADAU5's reduction of h after a failed iteration [-]
RECORD_SIZE = 6
#: :func:`newton_continue`'s verdict that the iteration goes on: evaluate ``f`` at the
#: new stage states.
ITERATE = -1
#: Rows of the real scratch array ``work`` (9 x n) of a step.
WORK_ROWS = 9
_STAGE_STATES = 3     # rows 3-5: the states y + z_i at which f is evaluated next
_YT = 6               # a right-hand side being solved for
_DW_REAL = 7          # the increment of the real system
_RHS_ERR = 8          # sum_i e_i z_i / h of the error estimate


# The stepping is split so that no function here calls the right-hand side: a caller
# (:func:`radau_step` for a function ``rhs``, camdyn.integrator.implicit for a system of
# the registry) evaluates ``f`` at the stage states each iteration asks for. A compiled
# function that takes another as an argument cannot be cached by numba (its cache keys a
# function argument by its identity, which changes with every process), and neither can
# one that passes a compiled function as a value: the driver, which must be cached,
# calls only these pieces.
@numba.njit(cache=True, inline="always")
def _stage_states(y, z, work):
    """The states ``y + z_i`` of the three stages into ``work[3:6]``."""
    for s in range(3):
        for i in range(y.shape[0]):
            work[_STAGE_STATES + s, i] = y[i] + z[s, i]


@numba.njit(cache=True, inline="always")
def newton_begin(y, z, w, faccon, record, work):
    """Start the simplified Newton iteration of a step from ``y`` at the starting values
    ``z`` (3 x n, :func:`radau_start`): ``W = T^-1 Z`` into ``w``, the ``record``
    (:data:`RECORD_SIZE`) reset with ``eta = max(faccon, eps)^0.8`` ([1], IV.8; RADAU5's
    FACCON), and the stage states at which the caller evaluates ``f`` next into rows 3-5
    of ``work`` (its values at stage ``i`` go into row ``i``: :func:`newton_continue`)."""
    n = y.shape[0]
    for s in range(3):
        for i in range(n):
            w[s, i] = RADAU_TI[s, 0] * z[0, i] + RADAU_TI[s, 1] * z[1, i] + RADAU_TI[s, 2] * z[2, i]
    record[_ITERATIONS] = 0.0
    record[_THETA] = THETA_JACOBIAN
    record[_QUOTIENT_OLD] = 0.0
    record[_NORM_OLD] = 0.0
    record[_FACCON] = max(faccon, EPS) ** 0.8
    record[_FACTOR] = 1.0
    _stage_states(y, z, work)


@numba.njit(cache=True, inline="always")
def _increment(h, w, lu_real, pivots_real, lu_complex, pivots_complex, work, cwork):
    """The simplified Newton increment from the stage values ``F`` in ``work[0:3]``: the
    residuals ``r_1`` and ``r_2 + i r_3`` and the solves of the real and the complex
    system into ``work[7]`` and ``cwork[1]`` ([1], IV.8; RADAU5's SLVRAD)."""
    g = RADAU_GAMMA / h
    a = RADAU_ALPHA / h
    b = RADAU_BETA / h
    yt = work[_YT]
    r_complex = cwork[0]
    for i in range(w.shape[1]):
        t0 = RADAU_TI[0, 0] * work[0, i] + RADAU_TI[0, 1] * work[1, i] + RADAU_TI[0, 2] * work[2, i]
        t1 = RADAU_TI[1, 0] * work[0, i] + RADAU_TI[1, 1] * work[1, i] + RADAU_TI[1, 2] * work[2, i]
        t2 = RADAU_TI[2, 0] * work[0, i] + RADAU_TI[2, 1] * work[1, i] + RADAU_TI[2, 2] * work[2, i]
        yt[i] = t0 - g * w[0, i]                        # r_1
        r_complex[i] = complex(t1 - a * w[1, i] - b * w[2, i],   # r_2 + i r_3
                               t2 + b * w[1, i] - a * w[2, i])
    lu_solve(lu_real, pivots_real, yt, work[_DW_REAL])
    lu_solve(lu_complex, pivots_complex, r_complex, cwork[1])


@numba.njit(cache=True, inline="always")
def newton_continue(y, h, rtol, atol, controlled, newton_tolerance, lu_real, pivots_real, lu_complex,
                    pivots_complex, z, w, record, work, cwork):
    """One iteration of the simplified Newton iteration ([1], IV.8; RADAU5's RADCOR),
    from ``F``, the right-hand side at the stage states, in ``work[0:3]``: the increment,
    its norm and the contraction ``theta``, and ``Z`` and ``W`` updated. It stops when
    ``eta ||dW|| <= kappa Tol`` (``newton_tolerance``), gives up when ``theta`` reaches
    0.99, when ``F`` is not finite or after ``NEWTON_MAX`` iterations, and when
    ``theta`` predicts no convergence within ``NEWTON_MAX`` iterations it gives up with
    RADAU5's reduction of ``h`` (``record``'s factor).

    Returns
    -------
    outcome : int
        :data:`ITERATE` (the next stage states are in ``work[3:6]``),
        ``STEP_CONVERGED``, ``STEP_SLOW`` or ``STEP_DIVERGED``.
    """
    n = y.shape[0]
    for s in range(3):
        for i in range(n):
            if not math.isfinite(work[s, i]):
                record[_FACTOR] = 0.5
                return STEP_DIVERGED
    _increment(h, w, lu_real, pivots_real, lu_complex, pivots_complex, work, cwork)
    dw_real = work[_DW_REAL]
    dw_complex = cwork[1]
    record[_ITERATIONS] += 1.0
    iterations = int(record[_ITERATIONS])
    acc = 0.0   # ||dW||: RMS over the three stages, scaled by the step's start
    for i in range(controlled):
        sc = absolute_tolerance(atol, i) + rtol * abs(y[i])
        acc += (dw_real[i] / sc) ** 2 + (dw_complex[i].real / sc) ** 2 + (dw_complex[i].imag / sc) ** 2
    norm = math.sqrt(acc / (3 * controlled))
    if 1 < iterations < NEWTON_MAX:
        quotient = norm / record[_NORM_OLD]
        theta = quotient if iterations == 2 else math.sqrt(quotient * record[_QUOTIENT_OLD])
        record[_THETA] = theta
        record[_QUOTIENT_OLD] = quotient
        if theta >= 0.99:
            record[_FACTOR] = 0.5
            return STEP_DIVERGED
        record[_FACCON] = theta / (1.0 - theta)
        # predicted ||dW|| after the remaining iterations, against the tolerance
        predicted = record[_FACCON] * norm * theta ** (NEWTON_MAX - 1 - iterations) / newton_tolerance
        if predicted >= 1.0:
            q = max(1e-4, min(20.0, predicted))
            record[_FACTOR] = 0.8 * q ** (-1.0 / (4.0 + NEWTON_MAX - 1 - iterations))
            return STEP_SLOW
    record[_NORM_OLD] = max(norm, EPS)
    for i in range(n):
        w[0, i] += dw_real[i]
        w[1, i] += dw_complex[i].real
        w[2, i] += dw_complex[i].imag
    for s in range(3):   # Z = T W
        for i in range(n):
            z[s, i] = RADAU_T[s, 0] * w[0, i] + RADAU_T[s, 1] * w[1, i] + RADAU_T[s, 2] * w[2, i]
    if record[_FACCON] * norm <= newton_tolerance:
        return STEP_CONVERGED
    if iterations >= NEWTON_MAX:
        record[_FACTOR] = 0.5
        return STEP_DIVERGED
    _stage_states(y, z, work)
    return ITERATE


@numba.njit(cache=True, inline="always")
def newton_summary(record):
    """``(iterations, theta, faccon, factor)`` of a finished iteration: the iterations
    done, the contraction rate [-] (0.001 after a single iteration), ``eta = theta / (1 -
    theta)`` for the next step [-] and the reduction of ``h`` after a failure [-]."""
    return int(record[_ITERATIONS]), record[_THETA], record[_FACCON], record[_FACTOR]


@numba.njit(cache=True, inline="always")
def radau_error(y, f_start, y1, z, h, rtol, atol, controlled, lu_real, pivots_real, err, work):
    """RADAU5's embedded error estimate (ESTRAD) of a converged step into ``err`` [state
    units]: ``err = (gamma/h I - J)^-1 (f_start + sum_i e_i z_i / h)`` with ``f_start =
    f(t, y)``. Returns its scaled RMS norm (``>= 1e-10``) [-].

    Where that rejects the step (after a rejection, or on the first step) RADAU5 filters
    it once more: the same formula with ``f(t, y + err)`` as ``f_start`` tends to the
    correct value also for stiff components where ``h J`` is large."""
    n = y.shape[0]
    yt = work[_YT]
    rhs_err = work[_RHS_ERR]
    for i in range(n):
        rhs_err[i] = (RADAU_E[0] * z[0, i] + RADAU_E[1] * z[1, i] + RADAU_E[2] * z[2, i]) / h
        yt[i] = f_start[i] + rhs_err[i]
    lu_solve(lu_real, pivots_real, yt, err)
    return max(scaled_rms(err, y, y1, rtol, atol, controlled), 1e-10)


# radau_step takes ``rhs`` and is compiled per function passed and not cached (see the
# note above; measured here: the second process recompiled radau_solve, about 10 s on the
# shared 2-core machine); it and radau_solve inline their helpers (``inline="always"``,
# camdyn.integrator.inlining's pipeline removes the inlined arguments'
# reference-counted copies): called, they made radau_solve about 1.5 times slower than
# the same code written in one function (measured on Van der Pol and Robertson at rtol
# 1e-8); inlined, it runs as fast.
@numba.njit(cache=False, pipeline_class=InlinedPipeline)
def radau_step(rhs, t, y, f0, h, p, rtol, atol, controlled, newton_tolerance, faccon, refine,
               lu_real, pivots_real, lu_complex, pivots_complex, z, w, y1, err, work, cwork, record):
    """One attempted Radau IIA step of size ``h`` [s] from ``(t, y)`` with the LU
    factorizations of :func:`radau_factor` for this ``h`` (the step-size logic is the
    caller's: :func:`camdyn.integrator.radau.radau_solve` is RADAU5's).

    Parameters
    ----------
    rhs : numba function
        ``rhs(t, y, p, dydt)``: ``dydt`` [state units/s] receives ``f(t, y)``.
    t, h : float
        Time and step size [s].
    y, f0 : ndarray, shape (n,)
        State and ``f(t, y)``.
    p : ndarray
        Parameters of ``rhs``.
    rtol : float
        Relative tolerance [-].
    atol : float or ndarray
        Absolute tolerance [state units] (:mod:`camdyn.integrator.tolerances`).
    controlled : int
        The error norms are taken over the first ``controlled`` components.
    newton_tolerance : float
        ``kappa Tol`` of the stopping test ``eta ||dW|| <= kappa Tol`` [-].
    faccon : float
        ``eta`` of the last step's iteration [-] (1 at the start of an integration).
    refine : bool
        Whether to evaluate the error estimate a second time from ``f(t, y + err)``
        when the first one rejects the step (after a rejection or on the first step;
        RADAU5's ESTRAD).
    lu_real, pivots_real, lu_complex, pivots_complex
        Factorizations from :func:`radau_factor`.
    z : ndarray, shape (3, n)
        Starting values of the stage increments on entry (:func:`radau_start`), the
        converged increments on exit.
    w : ndarray, shape (3, n)
        Scratch (the transformed increments ``W``).
    y1, err : ndarray, shape (n,)
        Receive ``y + z_3`` and the error estimate [state units].
    work : ndarray, shape (9, n)
        Scratch (:data:`WORK_ROWS`).
    cwork : ndarray, shape (2, n), complex128
        Scratch of the complex system.
    record : ndarray, shape (6,)
        Scratch: the iteration's record (:data:`RECORD_SIZE`).

    Returns
    -------
    outcome : int
        ``STEP_CONVERGED``, ``STEP_SLOW`` or ``STEP_DIVERGED``.
    error : float
        Scaled RMS norm of the error estimate (``>= 1e-10``) [-] if converged.
    iterations : int
        Newton iterations done.
    theta : float
        Contraction rate of the last iterations [-] (0.001 after a single iteration).
    faccon : float
        ``eta = theta / (1 - theta)`` for the next step [-].
    factor : float
        The reduction of ``h`` RADAU5 applies when the iteration is too slow [-].
    calls : int
        Right-hand-side evaluations.
    """
    newton_begin(y, z, w, faccon, record, work)
    outcome = ITERATE
    calls = 0
    while outcome == ITERATE:
        for s in range(3):
            rhs(t + RADAU_C[s] * h, work[_STAGE_STATES + s], p, work[s])
        calls += 3
        outcome = newton_continue(y, h, rtol, atol, controlled, newton_tolerance, lu_real, pivots_real, lu_complex,
                                  pivots_complex, z, w, record, work, cwork)
    iterations, theta, faccon, factor = newton_summary(record)
    if outcome != STEP_CONVERGED:
        return outcome, 0.0, iterations, theta, faccon, factor, calls
    for i in range(y.shape[0]):
        y1[i] = y[i] + z[2, i]
    error = radau_error(y, f0, y1, z, h, rtol, atol, controlled, lu_real, pivots_real, err, work)
    if error >= 1.0 and refine:
        for i in range(y.shape[0]):
            work[_YT, i] = y[i] + err[i]
        rhs(t, work[_YT], p, work[0])
        calls += 1
        error = radau_error(y, work[0], y1, z, h, rtol, atol, controlled, lu_real, pivots_real, err, work)
    return STEP_CONVERGED, error, iterations, theta, faccon, 1.0, calls
