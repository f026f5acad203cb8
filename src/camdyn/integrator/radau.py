"""Radau IIA of order 5: a fully implicit, L-stable, stiffly accurate three-stage
collocation method, implemented as in Hairer and Wanner's RADAU5 [1, 2].

The module holds the method's coefficients and the transformation that splits its
Newton iteration into one real and one complex ``n x n`` linear system, one attempted
step (:func:`radau_step`, for a driver that owns the step-size logic), the collocation
polynomial as dense output (:func:`radau_dense`), RADAU5's step-size controller and a
driver-free integration routine (:func:`radau_solve`, for tests and benchmarks). It is
not wired into :mod:`camdyn.integrator.driver`.

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
iterations.

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
from camdyn.integrator.linalg import lu_factor, lu_solve
from camdyn.integrator.tolerances import absolute_tolerance

__all__ = [
    "RADAU_A", "RADAU_B", "RADAU_C", "RADAU_T", "RADAU_TI", "RADAU_GAMMA", "RADAU_ALPHA", "RADAU_BETA",
    "RADAU_E", "RADAU_P", "RADAU_COUNTER_NAMES", "radau_factor", "radau_step", "radau_start",
    "radau_dense_coefficients", "radau_dense", "radau_solve",
]

# ---------------------------------------------------------------------------------------
# Coefficients ([1], IV.5: the Radau IIA method of order 5, s = 3).
_S6 = math.sqrt(6.0)
RADAU_C = np.array([(4.0 - _S6) / 10.0, (4.0 + _S6) / 10.0, 1.0])
RADAU_A = np.array([
    [(88.0 - 7.0 * _S6) / 360.0, (296.0 - 169.0 * _S6) / 1800.0, (-2.0 + 3.0 * _S6) / 225.0],
    [(296.0 + 169.0 * _S6) / 1800.0, (88.0 + 7.0 * _S6) / 360.0, (-2.0 - 3.0 * _S6) / 225.0],
    [(16.0 - _S6) / 36.0, (16.0 + _S6) / 36.0, 1.0 / 9.0],
])
RADAU_B = RADAU_A[2].copy()   # stiffly accurate: b is A's last row, y_1 = y + z_3


def _transformation():
    """``T``, ``T^-1`` and ``gamma, alpha, beta`` of ``A^-1 = T Lambda T^-1`` ([1], IV.8):
    the eigenvector of ``A^-1``'s real eigenvalue ``gamma`` and the real and imaginary
    parts ``u, w`` of the eigenvector of ``alpha + i beta`` (``A^-1 (u + i w) =
    (alpha + i beta)(u + i w)``), each scaled to a last component of 1 (so that ``w``'s
    last component is 0, as in RADAU5)."""
    a_inv = np.linalg.inv(RADAU_A)
    values, vectors = np.linalg.eig(a_inv)
    real = int(np.argmin(np.abs(values.imag)))
    pair = int(np.argmax(values.imag))           # alpha + i beta with beta > 0
    v_real = (vectors[:, real] / vectors[2, real]).real
    v_pair = vectors[:, pair] / vectors[2, pair]
    t = np.column_stack([v_real, v_pair.real, v_pair.imag])
    ti = np.linalg.inv(t)
    lam = ti @ a_inv @ t
    return (np.ascontiguousarray(t), np.ascontiguousarray(ti),
            float(lam[0, 0]), float(lam[1, 1]), float(lam[1, 2]))


RADAU_T, RADAU_TI, RADAU_GAMMA, RADAU_ALPHA, RADAU_BETA = _transformation()


def _error_weights():
    """``e`` of the embedded error estimate ([1], IV.8, "Error estimation"; RADAU5's
    ``DD1..DD3``): the third-order formula ``y^_1 = y + h (gamma_0 f(t, y) + sum_i
    b^_i F_i)`` with ``gamma_0 = 1 / gamma`` (the real eigenvalue of ``A``) gives
    ``y^_1 - y_1 = gamma_0 (h f(t, y) + sum_i e_i z_i)``, with ``e^T = (b^ - b)^T A^-1 /
    gamma_0`` since ``h F = (A^-1 x I) Z``."""
    gamma0 = 1.0 / RADAU_GAMMA
    # order conditions sum b^_i c_i^(k-1) = 1/k - gamma_0 [k = 1], k = 1, 2, 3
    vander = np.vstack([RADAU_C ** k for k in range(3)])
    rhs = np.array([1.0 - gamma0, 0.5, 1.0 / 3.0])
    b_hat = np.linalg.solve(vander, rhs)
    return np.ascontiguousarray((b_hat - RADAU_B) @ np.linalg.inv(RADAU_A) / gamma0)


RADAU_E = _error_weights()


def _dense_weights():
    """``P`` of the collocation polynomial ``u(t + theta h) = y + sum_i z_i sum_k P[i, k]
    theta^(k+1)``: the cubic through ``(0, y)`` and ``(c_i, y + z_i)`` (Lagrange basis
    polynomials of the nodes ``c_i`` that vanish at 0) ([1], IV.8, "Starting values for
    the Newton iteration"; RADAU5's CONTR5 evaluates the same polynomial in Newton form)."""
    vander = np.array([[c ** (k + 1) for k in range(3)] for c in RADAU_C])   # rows: nodes
    # polynomial i's coefficients q_i satisfy vander @ q_i = e_i
    return np.ascontiguousarray(np.linalg.inv(vander).T)


RADAU_P = _dense_weights()

# Newton iteration and controller constants (RADAU5's defaults, [2]).
NEWTON_MAX = 7           # NIT: iterations at most per attempt
SAFETY = 0.9             # SAFE
FACTOR_MAX = 8.0         # 1 / FACR: the largest growth of a step
FACTOR_MIN = 0.2         # 1 / FACL: the largest reduction from the error estimate
THETA_JACOBIAN = 0.001   # THET: a new Jacobian after a step whose contraction exceeded it
KEEP_LOW, KEEP_HIGH = 1.0, 1.2   # QUOT1, QUOT2: keep h (and the LU) for a new step within
EPS = np.finfo(np.float64).eps

# Outcomes of one attempted step.
STEP_CONVERGED = 0
STEP_SLOW = 1            # the iteration converges, too slowly for NEWTON_MAX: h *= factor
STEP_DIVERGED = 2        # contraction >= 0.99, NEWTON_MAX reached, or a non-finite stage

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


@numba.njit(cache=True)
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


@numba.njit(cache=True)
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


@numba.njit(cache=True)
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
def _scaled_rms(v, y0, y1, rtol, atol, controlled):
    """RMS over the first ``controlled`` components of ``v / (atol + rtol max(|y0|,
    |y1|))`` [-]."""
    acc = 0.0
    for i in range(controlled):
        sc = absolute_tolerance(atol, i) + rtol * max(abs(y0[i]), abs(y1[i]))
        acc += (v[i] / sc) ** 2
    return math.sqrt(acc / controlled)


# The functions that take ``rhs`` and ``jac`` are compiled per pair of functions and not
# cached: numba keys a cached specialisation on the function arguments' dispatchers,
# whose identity changes with every process, so each run would compile again anyway and
# leave one more file in __pycache__ (numba issues #2956 and #6264; measured here: the
# second process recompiled radau_solve, about 10 s on the shared 2-core machine).
@numba.njit(cache=False)
def radau_step(rhs, t, y, f0, h, p, rtol, atol, controlled, newton_tolerance, faccon, refine,
               lu_real, pivots_real, lu_complex, pivots_complex, z, w, y1, err, work, cwork):
    """One attempted Radau IIA step of size ``h`` [s] from ``(t, y)`` with the LU
    factorizations of :func:`radau_factor` for this ``h`` (the step-size logic is the
    caller's: :func:`radau_solve` is RADAU5's).

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
        ``eta`` of the last step's iteration [-] (1 at the start of an integration);
        this step starts from ``max(eta, eps)^0.8`` ([1], IV.8; RADAU5's FACCON).
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
    work : ndarray, shape (6, n)
        Scratch: stage values ``F`` (rows 0-2), the stage state, the increment of the real
        system and the filtered estimate's right-hand side.
    cwork : ndarray, shape (2, n), complex128
        Scratch of the complex system.

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
    n = y.shape[0]
    fs = work[0:3]
    yt = work[3]
    dw_real = work[4]
    rhs_err = work[5]
    r_complex = cwork[0]
    dw_complex = cwork[1]
    g = RADAU_GAMMA / h
    a = RADAU_ALPHA / h
    b = RADAU_BETA / h
    for s in range(3):   # W = T^-1 Z
        for i in range(n):
            w[s, i] = RADAU_TI[s, 0] * z[0, i] + RADAU_TI[s, 1] * z[1, i] + RADAU_TI[s, 2] * z[2, i]
    faccon = max(faccon, EPS) ** 0.8
    theta = THETA_JACOBIAN
    theta_quotient_old = 0.0
    norm_old = 0.0
    calls = 0
    iterations = 0
    while True:
        if iterations >= NEWTON_MAX:
            return STEP_DIVERGED, 0.0, iterations, theta, faccon, 0.5, calls
        finite = True
        for s in range(3):
            for i in range(n):
                yt[i] = y[i] + z[s, i]
            rhs(t + RADAU_C[s] * h, yt, p, fs[s])
            calls += 1
            for i in range(n):
                if not math.isfinite(fs[s, i]):
                    finite = False
        if not finite:
            return STEP_DIVERGED, 0.0, iterations, theta, faccon, 0.5, calls
        for i in range(n):
            t0 = RADAU_TI[0, 0] * fs[0, i] + RADAU_TI[0, 1] * fs[1, i] + RADAU_TI[0, 2] * fs[2, i]
            t1 = RADAU_TI[1, 0] * fs[0, i] + RADAU_TI[1, 1] * fs[1, i] + RADAU_TI[1, 2] * fs[2, i]
            t2 = RADAU_TI[2, 0] * fs[0, i] + RADAU_TI[2, 1] * fs[1, i] + RADAU_TI[2, 2] * fs[2, i]
            yt[i] = t0 - g * w[0, i]                        # r_1
            r_complex[i] = complex(t1 - a * w[1, i] - b * w[2, i],   # r_2 + i r_3
                                   t2 + b * w[1, i] - a * w[2, i])
        lu_solve(lu_real, pivots_real, yt, dw_real)
        lu_solve(lu_complex, pivots_complex, r_complex, dw_complex)
        iterations += 1
        acc = 0.0   # ||dW||: RMS over the three stages, scaled by the step's start
        for i in range(controlled):
            sc = absolute_tolerance(atol, i) + rtol * abs(y[i])
            acc += (dw_real[i] / sc) ** 2 + (dw_complex[i].real / sc) ** 2 + (dw_complex[i].imag / sc) ** 2
        norm = math.sqrt(acc / (3 * controlled))
        if 1 < iterations < NEWTON_MAX:
            quotient = norm / norm_old
            theta = quotient if iterations == 2 else math.sqrt(quotient * theta_quotient_old)
            theta_quotient_old = quotient
            if theta < 0.99:
                faccon = theta / (1.0 - theta)
                # predicted ||dW|| after the remaining iterations, against the tolerance
                predicted = faccon * norm * theta ** (NEWTON_MAX - 1 - iterations) / newton_tolerance
                if predicted >= 1.0:
                    q = max(1e-4, min(20.0, predicted))
                    factor = 0.8 * q ** (-1.0 / (4.0 + NEWTON_MAX - 1 - iterations))
                    return STEP_SLOW, 0.0, iterations, theta, faccon, factor, calls
            else:
                return STEP_DIVERGED, 0.0, iterations, theta, faccon, 0.5, calls
        norm_old = max(norm, EPS)
        for i in range(n):
            w[0, i] += dw_real[i]
            w[1, i] += dw_complex[i].real
            w[2, i] += dw_complex[i].imag
        for s in range(3):   # Z = T W
            for i in range(n):
                z[s, i] = RADAU_T[s, 0] * w[0, i] + RADAU_T[s, 1] * w[1, i] + RADAU_T[s, 2] * w[2, i]
        if faccon * norm <= newton_tolerance:
            break
    for i in range(n):
        y1[i] = y[i] + z[2, i]
    # Error estimate (RADAU5's ESTRAD): err = (gamma/h I - J)^-1 (f(t, y) + sum_i e_i z_i / h)
    #                                       = (I - h gamma_0 J)^-1 (gamma_0 h f(t, y) + gamma_0 sum_i e_i z_i)
    for i in range(n):
        rhs_err[i] = (RADAU_E[0] * z[0, i] + RADAU_E[1] * z[1, i] + RADAU_E[2] * z[2, i]) / h
        yt[i] = f0[i] + rhs_err[i]
    lu_solve(lu_real, pivots_real, yt, err)
    error = max(_scaled_rms(err, y, y1, rtol, atol, controlled), 1e-10)
    if error >= 1.0 and refine:
        # the estimate filtered once more, through f(t, y + err) in place of f(t, y): it
        # tends to the correct value also for stiff components where h J is large
        for i in range(n):
            yt[i] = y[i] + err[i]
        rhs(t, yt, p, fs[0])
        calls += 1
        for i in range(n):
            yt[i] = fs[0, i] + rhs_err[i]
        lu_solve(lu_real, pivots_real, yt, err)
        error = max(_scaled_rms(err, y, y1, rtol, atol, controlled), 1e-10)
    return STEP_CONVERGED, error, iterations, theta, faccon, 1.0, calls


@numba.njit(cache=False)
def _initial_step(rhs, t, y, f0, t_end, p, rtol, atol, yt, f1):
    """Starting step [s] of Hairer, Norsett and Wanner (ODE I, II.4) for an error
    estimate of order 3; one right-hand-side call."""
    n = y.shape[0]
    d0 = _scaled_rms(y, y, y, rtol, atol, n)
    d1 = _scaled_rms(f0, y, y, rtol, atol, n)
    h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    h0 = min(h0, t_end - t)
    for i in range(n):
        yt[i] = y[i] + h0 * f0[i]
    rhs(t + h0, yt, p, f1)
    for i in range(n):
        f1[i] = f1[i] - f0[i]
    d2 = _scaled_rms(f1, y, y, rtol, atol, n) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** 0.25
    return min(100.0 * h0, h1, t_end - t)


@numba.njit(cache=False)
def radau_solve(rhs, jac, t0, y0, t_end, rtol, atol, first_step, max_steps, t_out, p):
    """Integrate ``y' = f(t, y)`` from ``t0`` to ``t_end`` [s] (forward) with Radau IIA
    of order 5 and RADAU5's step-size and Jacobian-reuse strategy ([1], IV.8; [2]).

    Step size: ``h_new = h / q`` with ``q = clip(err^(1/4) / fac, 1/8, 5)`` and the
    safety factor ``fac = 0.9 (2 NIT + 1) / (2 NIT + k)`` after ``k`` Newton
    iterations; after the second accepted step ``q`` is at least Gustafsson's
    predictive ``(h_acc / h) (err^2 / err_acc)^(1/4) / 0.9`` [3]. A step right after a
    rejection is not longer than the rejected one. A new step keeps ``h`` and the LU
    factorizations when ``h_new / h`` is in [1, 1.2] and the last iteration contracted
    by at most 0.001; the Jacobian is recomputed only when it contracted more slowly, or
    after a rejection with an old Jacobian. A failed Newton iteration halves ``h`` (or
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
    m = t_out.shape[0]
    counters = np.zeros(RADAU_COUNTER_SIZE, dtype=np.int64)
    y_out = np.full((m, n), np.nan)
    y = y0.copy()
    y1 = np.empty(n)
    err = np.empty(n)
    f0 = np.empty(n)
    jacobian = np.zeros((n, n))
    lu_real = np.empty((n, n))
    lu_complex = np.empty((n, n), dtype=np.complex128)
    pivots_real = np.empty(n, dtype=np.int64)
    pivots_complex = np.empty(n, dtype=np.int64)
    z = np.zeros((3, n))
    w = np.empty((3, n))
    work = np.empty((6, n))
    cwork = np.empty((2, n), dtype=np.complex128)
    coefficients = np.empty((4, n))
    t = t0
    k_out = 0
    while k_out < m and t_out[k_out] <= t0:
        y_out[k_out] = y0
        k_out += 1
    rhs(t, y, p, f0)
    counters[RADAU_RHS] += 1
    newton_tolerance = max(10.0 * EPS / rtol, min(0.03, math.sqrt(rtol)))
    h_max = t_end - t0
    if first_step > 0.0:
        h = min(first_step, h_max)
    else:
        h = _initial_step(rhs, t, y, f0, t_end, p, rtol, atol, work[0], work[1])
        counters[RADAU_RHS] += 1
    last = False
    if t + h >= t_end:
        h = t_end - t
        last = True
    need_jacobian = True
    need_lu = True
    fresh_jacobian = False    # RADAU5's CALJAC: J was computed at the current (t, y)
    first = True
    rejected = False
    faccon = 1.0
    theta = THETA_JACOBIAN
    h_old = h
    h_accepted = h
    error_accepted = 1.0
    have_polynomial = False
    status = STATUS_OK
    while True:
        if counters[RADAU_ACCEPTED] + counters[RADAU_REJECTED] >= max_steps:
            status = STATUS_MAX_STEPS
            break
        if 0.1 * abs(h) <= abs(t) * EPS or h <= 0.0:
            status = STATUS_STEP_UNDERFLOW
            break
        if not last and t + h >= t_end:   # a retried step reaching the end (RADAU5 checks after acceptances only)
            h = t_end - t
            last = True
            need_lu = True
        if need_jacobian:
            jac(t, y, p, jacobian)
            counters[RADAU_JACOBIANS] += 1
            fresh_jacobian = True
            need_jacobian = False
            need_lu = True
        if need_lu:
            singular = radau_factor(jacobian, h, lu_real, pivots_real, lu_complex, pivots_complex)
            counters[RADAU_LU] += 1
            need_lu = False
            if singular:   # RADAU5's unexpected rejection
                h *= 0.5
                rejected = True
                last = False
                need_lu = True
                need_jacobian = not fresh_jacobian
                counters[RADAU_REJECTED] += 1
                continue
        radau_start(h, h_old, y, coefficients, z, have_polynomial and not first)
        outcome, error, iterations, theta_step, faccon, factor, calls = radau_step(
            rhs, t, y, f0, h, p, rtol, atol, n, newton_tolerance, faccon, first or rejected,
            lu_real, pivots_real, lu_complex, pivots_complex, z, w, y1, err, work, cwork)
        counters[RADAU_RHS] += calls
        counters[RADAU_NEWTON] += iterations
        theta = theta_step
        if outcome != STEP_CONVERGED:
            counters[RADAU_REJECTED] += 1
            h *= factor
            rejected = True
            last = False
            need_lu = True
            need_jacobian = not fresh_jacobian
            continue
        fac = min(SAFETY, SAFETY * (1 + 2 * NEWTON_MAX) / (iterations + 2 * NEWTON_MAX))
        quotient = max(1.0 / FACTOR_MAX, min(1.0 / FACTOR_MIN, error ** 0.25 / fac))
        h_new = h / quotient
        if error < 1.0:
            first = False
            counters[RADAU_ACCEPTED] += 1
            if counters[RADAU_ACCEPTED] > 1:   # Gustafsson's predictive controller [3]
                predictive = (h_accepted / h) * (error * error / error_accepted) ** 0.25 / SAFETY
                predictive = max(1.0 / FACTOR_MAX, min(1.0 / FACTOR_MIN, predictive))
                quotient = max(quotient, predictive)
                h_new = h / quotient
            h_accepted = h
            error_accepted = max(1e-2, error)
            t_old = t
            t = t_end if last else t + h
            if t_end - t <= 16.0 * EPS * max(1.0, abs(t_end)):
                t = t_end   # landed on the end up to rounding: no step of a few ulp after it
                last = True
            h_old = h
            radau_dense_coefficients(y, z, coefficients)
            have_polynomial = True
            for i in range(n):
                y[i] = y1[i]
            while k_out < m and t_out[k_out] <= t:
                radau_dense((t_out[k_out] - t_old) / h, coefficients, y_out[k_out])
                k_out += 1
            fresh_jacobian = False
            rhs(t, y, p, f0)
            counters[RADAU_RHS] += 1
            finite = True
            for i in range(n):
                if not math.isfinite(y[i]) or not math.isfinite(f0[i]):
                    finite = False
            if not finite:
                status = STATUS_NOT_FINITE
                break
            if last:
                break
            h_new = min(h_new, h_max)
            if rejected:
                h_new = min(h_new, h)
            rejected = False
            if t + h_new >= t_end:
                h = t_end - t
                last = True
                need_lu = True
            else:
                ratio = h_new / h
                if not (theta <= THETA_JACOBIAN and KEEP_LOW <= ratio <= KEEP_HIGH):
                    h = h_new
                    need_lu = True
            if need_lu and theta > THETA_JACOBIAN:
                need_jacobian = True
        else:
            counters[RADAU_REJECTED] += 1
            rejected = True
            last = False
            if first:
                h *= 0.1
            else:
                h = h_new
            need_lu = True
            need_jacobian = not fresh_jacobian
    counters[RADAU_STATUS] = status
    return y_out, counters
