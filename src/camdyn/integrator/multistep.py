"""The step of the Nordsieck multistep methods (``METHOD_ADAMS`` and ``METHOD_MULTISTEP``):
the BDF corrector by Newton's method, and the automatic switch between the Adams and BDF
families.

**BDF corrector.** The BDF step of order ``q`` solves ``G(e) = h f(t + h, z_p[0] + l_0 e)
- z_p[1] - e = 0`` for the correction ``e`` of ``h y'`` (the history
:mod:`camdyn.integrator.nordsieck` holds, ``l`` BDF's) by modified Newton iterations
``(I - gamma J) d = G(e)``, ``e <- e + d``, ``gamma = h l_0`` [s], ``J`` the system's Jacobian
(:func:`camdyn.systems.registry.jacobian`), the matrix factored by
:func:`camdyn.integrator.linalg.lu_factor`. The matrix is kept across steps and factored
anew, as CVODE does (Hindmarsh et al. 2005, ACM TOMS 31(3) 363-396,
doi:10.1145/1089014.1089020), when ``gamma`` moved by more than :data:`GAMMA_CHANGE` of
the factored one, after :data:`MATRIX_STEPS` steps, and after a switch or a restart; the
Jacobian is kept for :data:`JACOBIAN_STEPS` steps, and evaluated anew when the iteration
fails with an old one (the step is then tried again at once). While ``gamma`` differs from
the factored one the update is scaled by ``2 / (1 + gamma / gamma_factored)``. The
iteration takes at most :data:`NEWTON_ITERATIONS` right-hand sides, stops as the Adams one
does (its last update, times the convergence rate, adds at most a tenth to the error
estimate; the rate is kept from step to step and set to 1 with each new matrix), and fails
when an update grows to twice the last.

**Switching** (``METHOD_MULTISTEP``; after Petzold 1983, SIAM J. Sci. Stat. Comput. 4(1)
136-148, doi:10.1137/0904010, and LSODA). A run starts in the Adams family; every
:data:`SWITCH_STEPS` accepted steps the step compares what either family could do next.
The Adams step is bounded by its region of absolute stability, ``h rho <= S_q`` (LSODA's
``SM1``), ``rho`` the spectral radius of the Jacobian, estimated by
:func:`spectral_radius` (in the Adams family the Jacobian is evaluated for the test, one
per :data:`SWITCH_STEPS` steps; in the BDF family the last one serves). The rule:

- Adams to BDF when the Adams step is held by stability: ``h rho >= S_q / RATIO``. (LSODA
  also asks that BDF's step, from this step's error translated between the families, be
  5 times longer; measured on a stiff linear problem, the error estimate of an Adams
  step held at its stability bound is that of the decaying stiff component, not of the
  solution, and the translated BDF step came out shorter than the Adams step, so the
  test is on stability alone.) The first BDF step is this error's translated step, at
  most :data:`SWITCH_GROWTH` times this one.
- BDF to Adams when the Adams step would be at least as long as the BDF one: the ratio
  ``(6 E)^(-1/(q+1))`` of BDF's error norm ``E`` against the same for the Adams error
  ``E`` translates to, bounded by ``S_q / (RATIO h rho)`` (so that the Adams method would
  not at once count as held by stability again).
- BDF to Adams also when BDF did not pay: its step, at a test, is less than ``RATIO``
  times the Adams step at the switch (a lightly damped oscillation bounds BDF of orders
  3-5 as it bounds Adams: neither is stable along the imaginary axis). The Adams history
  then tests twice as rarely as before (at most :data:`MAX_PATIENCE` times), so that such
  a problem does not alternate between the families; a BDF trial that pays, or a return
  to Adams on accuracy, sets the interval back to :data:`SWITCH_STEPS`.

Errors translate through the families' error constants per ``h^(q+1) y^(q+1)``
(:data:`camdyn.integrator.nordsieck.DERIVATIVE_ERROR`; from an Adams order above 5, BDF's
order-5 error comes from ``z[6]``). A switch keeps the history and the order (at most 5
for BDF).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.integrator.linalg import lu_factor, lu_solve
from camdyn.integrator.nordsieck import (
    ADAMS,
    ADAMS_STEP,
    BDF,
    BDF_MAX_ORDER,
    CURRENT,
    DERIVATIVE_ERROR,
    EL,
    FACTORIAL,
    FAMILY,
    GAMMA,
    JACOBIAN,
    JACOBIAN_AGE,
    MATRIX_AGE,
    NEXT_FAMILY,
    NEXT_ORDER,
    NEXT_STEP,
    PATIENCE,
    RATE,
    ROWS,
    SINCE,
    STIFFNESS,
    THRESHOLD,
    Z_NEW,
    E,
    begin_step,
    count_failure,
    finish_step,
    functional_correct,
)
from camdyn.integrator.tolerances import absolute_tolerance
from camdyn.systems import registry as systems

#: Right-hand-side calls of the Newton iteration per try at most (CVODE's) [-].
NEWTON_ITERATIONS = 3
#: Relative change of ``gamma = h l_0`` beyond which the matrix is factored anew [-].
GAMMA_CHANGE = 0.3
#: Steps after which the matrix is factored anew, and the Jacobian evaluated anew [-].
MATRIX_STEPS, JACOBIAN_STEPS = 20, 50
#: Accepted steps between tests for a switch of family [-].
SWITCH_STEPS = 20
#: The fraction ``1 / RATIO`` of the Adams method's stability bound ``S_q / rho`` at and
#: beyond which its step counts as held by stability; and the least ratio of the BDF step
#: to the Adams step at the switch for which BDF pays [-].
RATIO = 2.0
#: Largest factor of SWITCH_STEPS between the tests of an Adams history [-].
MAX_PATIENCE = 64.0
#: Largest growth of the step at a switch [-].
SWITCH_GROWTH = 10.0
#: Squarings of the Jacobian in the estimate of its spectral radius [-].
SQUARINGS = 6
#: ``S_q``: ``h |lambda|`` within the Adams method's region of absolute stability at order
#: ``q`` (index q; LSODA's ``SM1``) [-].
STABILITY = np.array([0.0, 0.5, 0.575, 0.55, 0.45, 0.35, 0.25, 0.2, 0.15, 0.1, 0.075, 0.05, 0.025, 0.025])


@numba.njit(cache=True)
def history_rows(n):
    """Rows of the history array for ``n`` state components [-]."""
    return ROWS + n


@numba.njit(cache=True, inline="always")
def _weighted_norm(a, y, rtol, atol, controlled):
    """``max_i sum_j |a_ij| w_j / w_i`` over the controlled block, ``w = atol + rtol |y|``."""
    norm = 0.0
    for i in range(controlled):
        row = 0.0
        for j in range(controlled):
            row += abs(a[i, j]) * (absolute_tolerance(atol, j) + rtol * abs(y[j]))
        norm = max(norm, row / (absolute_tolerance(atol, i) + rtol * abs(y[i])))
    return norm


@numba.njit(cache=True)
def spectral_radius(jac, y, rtol, atol, controlled):
    """Estimate of the spectral radius [1/s] of the controlled block of ``jac``:
    ``||J^k||^(1/k)`` for ``k = 2^SQUARINGS`` (Gelfand's formula) in the error-weighted
    norm, by repeated squaring, each power scaled by its norm. It exceeds the spectral
    radius by at most the ``k``-th root of the eigenvector basis' condition number."""
    a = np.empty((controlled, controlled))
    b = np.empty((controlled, controlled))
    for i in range(controlled):
        for j in range(controlled):
            a[i, j] = jac[i, j]
    estimate = _weighted_norm(a, y, rtol, atol, controlled)
    power = 1.0
    for _ in range(SQUARINGS):
        norm = _weighted_norm(a, y, rtol, atol, controlled)
        if norm == 0.0:
            return 0.0   # nilpotent
        if power > 1.0:
            estimate *= norm ** (1.0 / power)
        for i in range(controlled):
            for j in range(controlled):
                acc = 0.0
                for k in range(controlled):
                    acc += a[i, k] * a[k, j]
                b[i, j] = acc / (norm * norm)
        a, b = b, a
        power *= 2.0
    norm = _weighted_norm(a, y, rtol, atol, controlled)
    return estimate * norm ** (1.0 / power)


@numba.njit(cache=True, inline="always")
def _jacobian(system, t, y, f, mode, p, hist, matrix, rtol, atol, controlled):
    """The Jacobian at ``(t, y)`` into the history's ``JACOBIAN`` rows (through ``matrix``),
    and its spectral radius into ``STIFFNESS`` [1/s]."""
    n = y.shape[0]
    systems.jacobian(system, t, y, f, mode, p, matrix)
    for i in range(n):
        for j in range(n):
            hist[JACOBIAN + i, j] = matrix[i, j]
    hist[STIFFNESS, 0] = spectral_radius(matrix, y, rtol, atol, controlled)
    hist[JACOBIAN_AGE, 0] = 0.0


@numba.njit(cache=True, inline="always")
def _factor(hist, gamma, matrix, pivots):
    """Factor ``I - gamma J`` (``J`` from the history) into ``matrix`` and ``pivots``.
    Returns whether it is singular."""
    n = matrix.shape[0]
    for i in range(n):
        for j in range(n):
            matrix[i, j] = -gamma * hist[JACOBIAN + i, j]
        matrix[i, i] += 1.0
    hist[GAMMA, 0] = gamma
    hist[MATRIX_AGE, 0] = 0.0
    hist[RATE, 0] = 1.0
    return lu_factor(matrix, pivots)


@numba.njit(cache=True, inline="always")
def _newton_try(system, t, h, q, mode, p, hist, y1, f1, work, matrix, pivots, rtol, atol, controlled):
    """One try of the Newton iteration from the prediction. Returns whether it converged,
    the right-hand-side calls and the Jacobians evaluated."""
    n = y1.shape[0]
    l0 = EL[BDF, q, 0]
    gamma = h * l0
    for i in range(n):
        hist[E, i] = 0.0
        y1[i] = hist[Z_NEW, i]
    jacobians = 0
    previous = 0.0
    for iteration in range(NEWTON_ITERATIONS):
        systems.rhs(system, t + h, y1, mode, p, f1)
        if iteration == 0 and (hist[MATRIX_AGE, 0] >= MATRIX_STEPS or hist[JACOBIAN_AGE, 0] >= JACOBIAN_STEPS
                               or abs(gamma - hist[GAMMA, 0]) > GAMMA_CHANGE * hist[GAMMA, 0]):
            if hist[JACOBIAN_AGE, 0] >= JACOBIAN_STEPS:
                _jacobian(system, t + h, y1, f1, mode, p, hist, matrix, rtol, atol, controlled)
                jacobians += 1
            if _factor(hist, gamma, matrix, pivots):
                return False, iteration + 1, jacobians
        for i in range(n):
            work[i] = h * f1[i] - hist[Z_NEW + 1, i] - hist[E, i]
        lu_solve(matrix, pivots, work, work)
        scale = 2.0 * hist[GAMMA, 0] / (hist[GAMMA, 0] + gamma)   # a stale gamma's correction
        for i in range(n):
            work[i] *= scale
            hist[E, i] += work[i]
            y1[i] = hist[Z_NEW, i] + l0 * hist[E, i]
        change = 0.0
        for i in range(controlled):
            change += (work[i] / (absolute_tolerance(atol, i) + rtol * abs(y1[i]))) ** 2
        change = math.sqrt(change / controlled)
        if iteration > 0:
            hist[RATE, 0] = max(0.3 * hist[RATE, 0], change / previous)
            if change > 2.0 * previous:
                return False, iteration + 1, jacobians
        if change * min(1.0, hist[RATE, 0]) * CURRENT[BDF, q] <= 0.1:
            return True, iteration + 1, jacobians
        previous = change
    return False, NEWTON_ITERATIONS, jacobians


@numba.njit(cache=True, inline="always")
def _newton(system, t, h, q, mode, p, hist, y1, f1, work, matrix, pivots, rtol, atol, controlled):
    """The BDF corrector: a Newton try, and a second one with a new Jacobian when the first
    failed with an old one. Returns whether it converged, the right-hand-side calls and
    the Jacobians."""
    converged, calls, jacobians = _newton_try(system, t, h, q, mode, p, hist, y1, f1, work, matrix, pivots, rtol,
                                              atol, controlled)
    if not converged and hist[JACOBIAN_AGE, 0] > 0.0:
        hist[JACOBIAN_AGE, 0] = np.inf
        converged, more_calls, more = _newton_try(system, t, h, q, mode, p, hist, y1, f1, work, matrix, pivots,
                                                  rtol, atol, controlled)
        calls += more_calls
        jacobians += more
    return converged, calls, jacobians


@numba.njit(cache=True, inline="always")
def _ratio(error, q):
    """The step ratio an error norm ``error`` of order ``q`` allows [-]."""
    return 1.0 / ((6.0 * error) ** (1.0 / (q + 1)) + 1e-6)


@numba.njit(cache=True, inline="always")
def _consider_switch(system, t, h, q, mode, p, hist, e_norm, y1, f1, work, matrix, rtol, atol, controlled):
    """Every :data:`SWITCH_STEPS` accepted steps, choose the family, order and step that
    follow this accepted step (module docstring). Returns the Jacobians evaluated."""
    family = int(hist[FAMILY, 0])
    if hist[SINCE, 0] < SWITCH_STEPS * (max(1.0, hist[PATIENCE, 0]) if family == ADAMS else 1.0):
        return 0
    hist[SINCE, 0] = 0.0
    jacobians = 0
    if family == ADAMS:
        _jacobian(system, t + h, y1, f1, mode, p, hist, matrix, rtol, atol, controlled)
        jacobians = 1
        if h * hist[STIFFNESS, 0] >= STABILITY[q] / RATIO:
            q_bdf = min(q, BDF_MAX_ORDER)
            if q > BDF_MAX_ORDER:   # BDF's order-5 error from z[6] (Nordsieck: h^6 y^(6) / 6!)
                for i in range(y1.shape[0]):
                    work[i] = DERIVATIVE_ERROR[BDF, q_bdf] * FACTORIAL[q_bdf + 1] * hist[Z_NEW + q_bdf + 1, i]
                e_bdf = 0.0
                for i in range(controlled):
                    e_bdf += (work[i] / (absolute_tolerance(atol, i) + rtol * abs(y1[i]))) ** 2
                e_bdf = math.sqrt(e_bdf / controlled)
            else:
                e_bdf = e_norm * DERIVATIVE_ERROR[BDF, q] / DERIVATIVE_ERROR[ADAMS, q]
            _switch(hist, BDF, q_bdf, h, _ratio(e_bdf, q_bdf))
            hist[ADAMS_STEP, 0] = h
    else:
        e_adams = e_norm * DERIVATIVE_ERROR[ADAMS, q] / DERIVATIVE_ERROR[BDF, q]
        adams = min(_ratio(e_adams, q), STABILITY[q] / (RATIO * h * hist[STIFFNESS, 0] + 1e-300))
        if adams >= _ratio(e_norm, q):
            _switch(hist, ADAMS, q, h, adams)
            hist[PATIENCE, 0] = 1.0
        elif h < RATIO * hist[ADAMS_STEP, 0]:   # BDF did not pay: back, and test less often
            _switch(hist, ADAMS, q, h, adams)
            hist[PATIENCE, 0] = min(2.0 * max(1.0, hist[PATIENCE, 0]), MAX_PATIENCE)
        else:
            hist[PATIENCE, 0] = 1.0
    return jacobians


@numba.njit(cache=True, inline="always")
def _switch(hist, family, q, h, ratio):
    """Have the next step taken by ``family`` at order ``q``, ``ratio`` times ``h``
    [s] long (kept when it is below THRESHOLD, at most SWITCH_GROWTH)."""
    hist[NEXT_FAMILY, 0] = family
    hist[NEXT_ORDER, 0] = q
    hist[NEXT_STEP, 0] = h * (min(ratio, SWITCH_GROWTH) if ratio >= THRESHOLD else 1.0)


@numba.njit(cache=True)
def multistep_step(system, t, y, f, h, mode, p, hist, y1, f1, work, matrix, pivots, rtol, atol, switching):
    """One step of ``h`` [s] from ``(t, y)`` (``f`` its rates) into ``y1`` and ``f1``
    (the rates of the step's polynomial at its end, ``z_new[1] / h``), by the history's
    family; when ``switching``, an accepted step may choose the other family for the next
    (``matrix`` (n, n) and ``pivots`` (n,) hold BDF's factored matrix between steps).

    Compiled on its own and called by the driver, not inlined into it: inlined, it made
    the driver's first compile about 96 s longer (431 s against 335 s of one core for
    the core of ``camdyn simulate``), for multistep runs 1.25-1.28 times faster, methods
    that ``simulate`` does not offer (docs/design-notes/compiled-driver.md).

    Returns
    -------
    e : float
        Scaled error norm (at most 1 to accept; 1e3 when the corrector did not converge).
    order : float
        ``q + 1``, for the driver's step after a refusal.
    calls : int
        Right-hand-side calls.
    jacobians : int
        Jacobians evaluated.
    """
    family, q = begin_step(hist, t, y, f, h)
    controlled = systems.controlled_size(system)
    if family == ADAMS:
        converged, calls = functional_correct(system, t, h, q, mode, p, hist, y1, f1, work, rtol, atol, controlled)
        jacobians = 0
    else:
        converged, calls, jacobians = _newton(system, t, h, q, mode, p, hist, y1, f1, work, matrix, pivots, rtol,
                                              atol, controlled)
    if not converged:
        count_failure(hist, family)
        return 1e3, q + 1.0, calls, jacobians
    e_norm = finish_step(hist, family, q, h, y1, f1, work, rtol, atol, controlled)
    if e_norm <= 1.0 and switching:
        jacobians += _consider_switch(system, t, h, q, mode, p, hist, e_norm, y1, f1, work, matrix, rtol, atol,
                                      controlled)
    return e_norm, q + 1.0, calls, jacobians
