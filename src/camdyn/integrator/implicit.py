"""Radau IIA inside the hybrid driver, and the switch to it in sustained contact.

:mod:`camdyn.integrator.radau_newton` holds one attempted step of Radau IIA of order 5
(Hairer and Wanner's RADAU5 [1, 2]) for any ``rhs(t, y, p, dydt)``; this module runs it
on a registered system in a given hybrid mode (:func:`implicit_step`), keeps what RADAU5
keeps between steps (the Jacobian, the LU factorizations and their step, the Newton
iteration's contraction, the last accepted step's collocation polynomial for the next
step's starting values), and decides when the driver's switching method
(``METHOD_SWITCHING``) leaves DOP853 for it (:func:`stiffness_test`).

**The Jacobian** is the system's (:func:`camdyn.systems.registry.jacobian`). As in
RADAU5 it is computed again only after an accepted step whose Newton iteration
contracted slowly (``theta > 0.001``), after a refused step whose Jacobian was not
computed at its start, and at every change of mode or of stepper (the state array's
``JAC_VALID``); the simplified Newton iteration converges to the collocation solution
with an approximate Jacobian too, only more slowly.

**The switch** (after LSODA's comparison of the step with the Jacobian's size, [4]).
DOP853 runs through impacts and the contact's ringing; every :data:`STIFF_STEPS`
accepted DOP853 steps since the last event, the Jacobian at the step's end gives the
size of the fastest mode, its spectral radius ``rho`` (:func:`spectral_radius`). When
``h rho`` exceeds :data:`STIFF_BOUND`, DOP853's steps are as short as the fastest
mode's time scale although that mode is at rest (in sustained contact the follower
angle holds 4e-11 of its amplitude above 500 Hz on the chapter 4 rig), and the driver
switches to Radau IIA until the next event (a contact switch, impact or sliding
reversal: the mode changes, and DOP853 takes over again). Hairer's own test in DOP853,
``h ||f(y_1) - f(y_12)|| / ||y_1 - y_12|| > 6.1`` from its last two stages, measures
the fast mode only where the step has excited it, and never fired on the settled rig
(measured: docs/integrator.md, *Radau IIA in the driver*).

References
----------
[1] E. Hairer, G. Wanner, Solving Ordinary Differential Equations II: Stiff and
    Differential-Algebraic Problems, 2nd ed., Springer (1996), doi:10.1007/978-3-642-05221-7.
[2] E. Hairer, G. Wanner, radau5.f (Fortran code of RADAU5, version of 1996).
[3] E. Hairer, S. P. Norsett, G. Wanner, Solving Ordinary Differential Equations I:
    Nonstiff Problems, 2nd ed., Springer (1993), doi:10.1007/978-3-540-78862-1; the
    stiffness detection of its code DOP853.
[4] L. Petzold, Automatic selection of methods for solving stiff and nonstiff systems
    of ordinary differential equations, SIAM J. Sci. Stat. Comput. 4 (1983) 136-148,
    doi:10.1137/0904010 (LSODA).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.integrator.radau import KEEP_HIGH, KEEP_LOW, predictive_quotient
from camdyn.integrator.radau_newton import (
    EPS,
    ITERATE,
    RECORD_SIZE,
    STEP_CONVERGED,
    THETA_JACOBIAN,
    WORK_ROWS,
    newton_begin,
    newton_continue,
    newton_summary,
    radau_dense_coefficients,
    radau_error,
    radau_factor,
    radau_start,
)
from camdyn.integrator.radau_tableau import RADAU_C
from camdyn.systems import registry as systems

__all__ = ["STIFF_BOUND", "STIFF_STEPS", "STATE_SIZE", "spectral_radius", "implicit_workspace", "implicit_reset",
           "implicit_step", "implicit_proposal", "stiffness_test", "is_stiff", "JACOBIAN_THETA"]

#: ``h rho(J)`` [-] (DOP853's step times the Jacobian's spectral radius) above which the
#: switching method leaves DOP853. The contact mode's eigenvalues are nearly imaginary
#: (about ``-120 +- 6000i`` 1/s on the chapter 4 rig), where DOP853's error control
#: holds its step near ``h rho ~ 1`` (0.8 at rtol 1e-8, 1.8 at 1e-6), below its
#: stability boundary (Hairer's DOP853 tests ``h rho > 6.1``, which never fires there).
STIFF_BOUND = 0.5
#: Accepted DOP853 steps between two checks (the first that many after an event).
STIFF_STEPS = 15

# the state array's slots
_STIFF = 0        # 1 while the switching method runs Radau IIA
_STIFF_COUNT = 1  # accepted DOP853 steps since the last check
_JAC_VALID = 2    # the Jacobian belongs to this mode and this stretch of Radau steps
_JAC_FRESH = 3    # ... and was computed at the current step's start
_H_LU = 4         # the step [s] the LU factorizations were made for (0: none)
_FACCON = 5       # eta of the last Newton iteration [-]
_THETA = 6        # its contraction [-]
_POLY_END = 7     # where the stored polynomial's step ended [s] (NaN: none)
_POLY_H = 8       # that step [s]
_TRIAL_END = 9    # the end [s] of the last converged trial step (NaN: none)
_TRIAL_H = 10     # its step [s]
_LAST_T = 11      # the start [s] of the last trial step
_H_ACCEPTED = 12  # the last accepted step [s] since the last event (NaN: none)
_E_ACCEPTED = 13  # its error norm [-]
STATE_SIZE = 14

#: Contraction rate [-] of the Newton iteration above which a new Jacobian is computed at
#: the next step (RADAU5's THET, whose default 0.001 suits costly iterations: here a
#: Newton iteration costs three right-hand sides and a Jacobian about five, measured
#: in docs/integrator.md, *Radau IIA in the driver*).
JACOBIAN_THETA = 0.1


@numba.njit(cache=True)
def implicit_workspace(n):
    """The arrays Radau IIA keeps for a state of ``n`` components: the state array
    (``STATE_SIZE``, reset) and a tuple of the Jacobian (n x n), the real and complex LU
    factorizations with their pivots, the stage increments ``Z`` and ``W`` (3 x n),
    real and complex scratch (9 x n, 2 x n), the last accepted step's collocation
    polynomial (4 x n) and the Newton iteration's record."""
    state = np.empty(STATE_SIZE)
    implicit_reset(state)
    arrays = (np.zeros((n, n)), np.empty((n, n)), np.empty(n, dtype=np.int64),
              np.empty((n, n), dtype=np.complex128), np.empty(n, dtype=np.int64), np.zeros((3, n)),
              np.empty((3, n)), np.empty((WORK_ROWS, n)), np.empty((2, n), dtype=np.complex128), np.empty((4, n)),
              np.empty(RECORD_SIZE))
    return state, arrays


@numba.njit(cache=True, inline="always")
def implicit_reset(state):
    """Back to DOP853 with nothing kept: at the start and after every event (the mode
    changed, so the Jacobian and the polynomial belong to another right-hand side)."""
    state[_STIFF] = 0.0
    state[_STIFF_COUNT] = 0.0
    state[_JAC_VALID] = 0.0
    state[_JAC_FRESH] = 0.0
    state[_H_LU] = 0.0
    state[_FACCON] = 1.0
    state[_THETA] = THETA_JACOBIAN
    state[_POLY_END] = math.nan
    state[_POLY_H] = math.nan
    state[_TRIAL_END] = math.nan
    state[_TRIAL_H] = math.nan
    state[_LAST_T] = math.nan
    state[_H_ACCEPTED] = math.nan
    state[_E_ACCEPTED] = math.nan


@numba.njit(cache=True, inline="always")
def is_stiff(state):
    """Whether the switching method runs Radau IIA now."""
    return state[_STIFF] > 0.5


@numba.njit(cache=True, inline="always")
def spectral_radius(jacobian, v, u):
    """An estimate of the spectral radius of ``jacobian`` (n x n) [1/s]: the mean growth
    per power iteration from ``x = (1, ..., 1)``, ``(||J^16 x|| / ||J^8 x||)^(1/8)``
    (renormalized each step; ``v`` and ``u`` are n-vectors of scratch). For the complex
    pair of a lightly damped contact mode the direction does not converge but the growth
    rate does; skipping the first 8 iterations removes the eigenvectors' conditioning
    from it (``||J^8 x||^(1/8)`` alone gave 13,200 1/s for the 6,000 1/s of the chapter 4
    rig's contact mode, this estimate 6,500)."""
    n = jacobian.shape[0]
    for i in range(n):
        v[i] = 1.0 / math.sqrt(n)
    log_growth = 0.0
    for k in range(16):
        norm = 0.0
        for i in range(n):
            acc = 0.0
            for j in range(n):
                acc += jacobian[i, j] * v[j]
            u[i] = acc
            norm += acc * acc
        norm = math.sqrt(norm)
        if norm == 0.0 or not math.isfinite(norm):
            return 0.0 if norm == 0.0 else math.inf
        if k >= 8:
            log_growth += math.log(norm)
        for i in range(n):
            v[i] = u[i] / norm
    return math.exp(log_growth / 8.0)


@numba.njit(cache=True, inline="always")
def stiffness_test(system, t, y1, f1, h, mode, p, state, arrays):
    """Count an accepted DOP853 step of ``h`` [s] ending at ``(t, y1)`` (``f1 = f(t,
    y1)``) and, every :data:`STIFF_STEPS` of them since the last event, check whether
    ``h`` times the spectral radius of the Jacobian there (:func:`spectral_radius`)
    exceeds :data:`STIFF_BOUND`; if it does, the switching method runs Radau IIA from
    the next step to the next event. Returns the Jacobians computed (0 or 1)."""
    state[_STIFF_COUNT] += 1.0
    if state[_STIFF_COUNT] < STIFF_STEPS:
        return 0
    state[_STIFF_COUNT] = 0.0
    jacobian = arrays[0]
    systems.jacobian(system, t, y1, f1, mode, p, jacobian)
    if h * spectral_radius(jacobian, arrays[7][0], arrays[7][1]) > STIFF_BOUND:
        state[_STIFF] = 1.0
        state[_JAC_VALID] = 1.0   # computed here, at the next step's start
        state[_JAC_FRESH] = 1.0
        state[_LAST_T] = t - h     # the next step is not a retry
        state[_POLY_END] = math.nan
        state[_TRIAL_END] = math.nan
    return 1


@numba.njit(cache=True, inline="always")
def _keep_polynomial(t, state, arrays, coefficients):
    """At the start of a step from ``t`` [s]: if the last converged trial step ended
    there, it was accepted and taken whole, so its collocation polynomial (still in
    ``coefficients``) becomes the one the starting values extrapolate."""
    if t == state[_TRIAL_END]:
        poly = arrays[9]
        for r in range(4):
            for i in range(poly.shape[1]):
                poly[r, i] = coefficients[r, i]
        state[_POLY_END] = t
        state[_POLY_H] = state[_TRIAL_H]


@numba.njit(cache=True, inline="always")
def implicit_step(system, t, y, f0, h, mode, p, rtol, atol, controlled, state, arrays, coefficients, y1, err):
    """One attempted Radau IIA step of ``h`` [s] from ``(t, y)`` (``f0 = f(t, y)``) in
    ``mode``: ``y1`` receives the end state, ``err`` the embedded error estimate
    [state units], ``coefficients`` (at least 4 x n) the step's collocation polynomial
    (read by :func:`camdyn.integrator.steppers.dense`). ``state`` and ``arrays`` come from
    :func:`implicit_workspace`.

    Returns
    -------
    e : float
        Scaled error norm [-] (at most 1 to accept; of order 4 for the step-size
        control). A Newton iteration that failed gives the norm for which the driver's
        control ``0.9 e^(-1/4)`` is RADAU5's reduction of ``h`` (a half, or less when the
        iteration converged too slowly); a singular iteration matrix gives infinity.
    calls : int
        Right-hand-side calls.
    jacobians : int
        Jacobians computed (0 or 1).
    """
    jacobian, lu_real, pivots_real, lu_complex, pivots_complex, z, w, work, cwork, poly, record = arrays
    _keep_polynomial(t, state, arrays, coefficients)
    retry = t == state[_LAST_T]
    if not retry:
        state[_JAC_FRESH] = 0.0
    need_jacobian = state[_JAC_VALID] < 0.5 or (state[_JAC_FRESH] < 0.5
                                                and (retry or state[_THETA] > JACOBIAN_THETA))
    jacobians = 0
    if need_jacobian:
        systems.jacobian(system, t, y, f0, mode, p, jacobian)
        state[_JAC_VALID] = 1.0
        state[_JAC_FRESH] = 1.0
        jacobians = 1
    state[_LAST_T] = t
    state[_TRIAL_END] = math.nan
    if need_jacobian or h != state[_H_LU]:
        state[_H_LU] = h
        if radau_factor(jacobian, h, lu_real, pivots_real, lu_complex, pivots_complex):
            state[_H_LU] = 0.0
            return math.inf, 0, jacobians
    have_polynomial = t == state[_POLY_END]
    radau_start(h, state[_POLY_H], y, poly, z, have_polynomial)
    newton_tolerance = max(10.0 * EPS / rtol, min(0.03, math.sqrt(rtol)))
    newton_begin(y, z, w, state[_FACCON], record, work)
    outcome = ITERATE
    calls = 0
    while outcome == ITERATE:   # f at the stages the iteration asks for (radau_newton's note)
        for s in range(3):
            systems.rhs_inline(system, t + RADAU_C[s] * h, work[3 + s], mode, p, work[s])
        calls += 3
        outcome = newton_continue(y, h, rtol, atol, controlled, newton_tolerance, lu_real, pivots_real, lu_complex,
                                  pivots_complex, z, w, record, work, cwork)
    _, state[_THETA], state[_FACCON], factor = newton_summary(record)
    if outcome != STEP_CONVERGED:
        for i in range(y1.shape[0]):
            y1[i] = y[i]
        return (0.9 / factor) ** 4, calls, jacobians
    for i in range(y.shape[0]):
        y1[i] = y[i] + z[2, i]
    error = radau_error(y, f0, y1, z, h, rtol, atol, controlled, lu_real, pivots_real, err, work)
    if error >= 1.0 and (retry or not have_polynomial):   # RADAU5's second, filtered estimate
        for i in range(y.shape[0]):
            work[6, i] = y[i] + err[i]
        systems.rhs(system, t, work[6], mode, p, work[0])
        calls += 1
        error = radau_error(y, work[0], y1, z, h, rtol, atol, controlled, lu_real, pivots_real, err, work)
    radau_dense_coefficients(y, z, coefficients)
    state[_TRIAL_END] = t + h
    state[_TRIAL_H] = h
    return error, calls, jacobians


@numba.njit(cache=True, inline="always")
def implicit_proposal(state, h, e, h_new):
    """The step [s] after an accepted Radau IIA step of ``h`` [s] and error norm ``e``
    [-], for which the driver's control proposed ``h_new`` [s]: RADAU5's [2] predictive
    control (Gustafsson's, [1] IV.8) where a step accepted since the last event gives its
    ``(h_acc, e_acc)``, ``h / max(h / h_new, (h_acc / h) (e^2 / e_acc)^(1/4) / 0.9)``; and
    ``h`` itself (keeping the LU factorizations) where that is within RADAU5's
    ``[KEEP_LOW, KEEP_HIGH]`` times ``h`` and the Newton iteration contracted fast."""
    e = max(e, 1e-10)
    if state[_H_ACCEPTED] == state[_H_ACCEPTED]:   # not NaN
        h_new = min(h_new, h / predictive_quotient(h, e, state[_H_ACCEPTED], state[_E_ACCEPTED]))
    state[_H_ACCEPTED] = h
    state[_E_ACCEPTED] = max(1e-2, e)
    if state[_THETA] <= THETA_JACOBIAN and KEEP_LOW <= h_new / h <= KEEP_HIGH:
        return h
    return h_new
