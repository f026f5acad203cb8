"""A variable-order, variable-step Adams-Moulton method in Nordsieck form, with its
corrector solved by a modified Newton iteration (the stepper half of the integrator for
``METHOD_ADAMS``).

The history is the Nordsieck array ``z[j] = h^j y^(j) / j!``, ``j = 0..q`` (order ``q``,
1 to :data:`MAX_ORDER`). A step predicts ``z_p = z A`` (``A`` Pascal's triangle), then
finds the correction ``e`` such that ``h f(t + h, z_p[0] + l_0 e) = z_p[1] + e`` by Newton's
method with the matrix ``I - h l_0 J`` (kept while ``h l_0`` changes by less than 30 % and
for at most :data:`JACOBIAN_AGE` steps), and sets ``z_new = z_p + e l``. The coefficients
``l`` of order ``q`` are those of ``Lambda(x) = int_-1^x prod_(i=1)^(q-1) (s + i) / (q-1)! ds``
and the local error is ``C_q e`` with ``C_q = int_-1^0 prod_(i=0)^(q-1) (s + i) ds / q!``
(Byrne and Hindmarsh 1975, ACM TOMS 1(1) 71-96, doi:10.1145/355626.355636; Hindmarsh's
LSODE). The step and order are chosen after ``q + 1`` steps at one step size, from the
error estimates of orders ``q - 1``, ``q`` and ``q + 1`` (the last from the difference of
successive corrections), with LSODE's safety factors 1.3, 1.2 and 1.4.

The continuous extension of a step is the Nordsieck polynomial itself,
``y(t + h + s h) = sum_j z_new[j] s^j`` for ``s`` in [-1, 0]. After an event, or any change of
state the history does not know, the method restarts at order 1.

The driver keeps everything in one array ``history`` of :data:`ROWS` rows of ``n`` columns
(``Z``, ``Z_NEW``, the last correction ``E_LAST``, the current one ``E``, and scalars in
column 0 of the rows from ``SCALARS``), so that it passes through the driver's functions
as the step's ``work`` array.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.polynomial import polynomial as P

from camdyn.integrator.counters import COUNT_JACOBIANS
from camdyn.integrator.linalg import lu_factor, lu_solve
from camdyn.systems import registry as systems

#: Largest order [-].
MAX_ORDER = 12
#: Steps a Newton matrix is kept at most [-].
JACOBIAN_AGE = 20
#: Newton iterations per step at most [-].
NEWTON_ITERATIONS = 4

Z = 0
Z_NEW = MAX_ORDER + 2
E_LAST = 2 * MAX_ORDER + 4
E = E_LAST + 1
SCALARS = E + 1
ORDER = SCALARS          # q [-]
TIME = SCALARS + 1       # time of Z [s]
STEP = SCALARS + 2       # the step Z is scaled to [s]
SINCE = SCALARS + 3      # steps since the last change of step or order [-]
AGE = SCALARS + 4        # steps since the Newton matrix was formed (-1: none) [-]
H_L0 = SCALARS + 5       # h l_0 of the Newton matrix [s]
NEXT_STEP = SCALARS + 6  # proposed next step [s]
NEXT_ORDER = SCALARS + 7 # proposed next order [-]
FAILS = SCALARS + 8      # error test failures in a row [-]
ROWS = SCALARS + 9


def _adams_tables():
    """``l`` vectors (row q) and error constants ``C_q`` for q = 1 .. MAX_ORDER + 1."""
    el = np.zeros((MAX_ORDER + 2, MAX_ORDER + 2))
    error = np.zeros(MAX_ORDER + 2)
    for q in range(1, MAX_ORDER + 2):
        slope = np.array([1.0])
        for i in range(1, q):
            slope = P.polymul(slope, [float(i), 1.0])
        slope = slope / math.factorial(q - 1)
        lam = P.polyint(slope)
        lam[0] -= P.polyval(-1.0, lam)
        if q <= MAX_ORDER:
            el[q, :q + 1] = lam
        c = np.array([1.0])
        for i in range(q):
            c = P.polymul(c, [float(i), 1.0])
        ci = P.polyint(c)
        error[q] = (P.polyval(0.0, ci) - P.polyval(-1.0, ci)) / math.factorial(q)
    return el, error


EL, ERROR_CONSTANT = _adams_tables()


@numba.njit(cache=True)
def _norm(v, y, rtol, atol, controlled):
    """RMS of ``v`` over the controlled components, scaled by ``atol + rtol |y|``."""
    acc = 0.0
    for i in range(controlled):
        acc += (v[i] / (atol + rtol * abs(y[i]))) ** 2
    return math.sqrt(acc / controlled)


@numba.njit(cache=True)
def _rescale(hist, q, ratio):
    """Rescale the history to a step ``ratio`` times longer."""
    r = 1.0
    for j in range(1, q + 1):
        r *= ratio
        for i in range(hist.shape[1]):
            hist[Z + j, i] *= r


@numba.njit(cache=True)
def _prepare(hist, t, y, f, h):
    """Restart at order 1 unless the history is at ``(t, y)``; rescale it to ``h``."""
    n = y.shape[0]
    fresh = hist[TIME, 0] != t
    for i in range(n):
        fresh = fresh or hist[Z, i] != y[i]
    if fresh:
        for j in range(MAX_ORDER + 2):
            for i in range(n):
                hist[Z + j, i] = 0.0
                hist[Z_NEW + j, i] = 0.0
        for i in range(n):
            hist[Z, i] = y[i]
            hist[Z + 1, i] = h * f[i]
            hist[E_LAST, i] = 0.0
        hist[ORDER, 0] = 1.0
        hist[TIME, 0] = t
        hist[STEP, 0] = h
        hist[SINCE, 0] = 0.0
        hist[FAILS, 0] = 0.0
        hist[AGE, 0] = -1.0
    elif hist[STEP, 0] != h:
        _rescale(hist, int(hist[ORDER, 0]), h / hist[STEP, 0])
        hist[STEP, 0] = h
        hist[SINCE, 0] = 0.0


@numba.njit(cache=True)
def _newton_matrix(system, t, y, f, h, q, mode, p, hist, matrix, pivots):
    """Form and factor ``I - h l_0 J`` at ``(t, y)`` unless the last one still serves;
    returns the Jacobians formed (0 or 1)."""
    hl0 = h * EL[q, 0]
    age = hist[AGE, 0]
    if age >= 0.0 and age < JACOBIAN_AGE and abs(hl0 / hist[H_L0, 0] - 1.0) <= 0.3:
        return 0
    n = y.shape[0]
    systems.jacobian(system, t, y, f, mode, p, matrix)
    for i in range(n):
        for k in range(n):
            matrix[i, k] = (1.0 if i == k else 0.0) - hl0 * matrix[i, k]
    lu_factor(matrix, pivots)
    hist[AGE, 0] = 0.0
    hist[H_L0, 0] = hl0
    return 1


@numba.njit(cache=True)
def _correct(system, t, h, q, mode, p, hist, matrix, pivots, y1, f1, work, rtol, atol, controlled):
    """Predict into ``Z_NEW`` and solve the corrector; ``y1`` is the corrected state.
    Returns whether Newton converged and the right-hand-side calls."""
    n = y1.shape[0]
    for j in range(q + 1):
        for i in range(n):
            hist[Z_NEW + j, i] = hist[Z + j, i]
    for k in range(1, q + 1):           # z_p = z A: repeated sums (Pascal's triangle)
        for j in range(q, k - 1, -1):
            for i in range(n):
                hist[Z_NEW + j - 1, i] += hist[Z_NEW + j, i]
    l0 = EL[q, 0]
    for i in range(n):
        hist[E, i] = 0.0
        y1[i] = hist[Z_NEW, i]
    calls = 0
    previous = 0.0
    for iteration in range(NEWTON_ITERATIONS):
        systems.rhs(system, t + h, y1, mode, p, f1)
        calls += 1
        for i in range(n):
            work[i] = h * f1[i] - hist[Z_NEW + 1, i] - hist[E, i]
        lu_solve(matrix, pivots, work, work)
        for i in range(n):
            hist[E, i] += work[i]
            y1[i] = hist[Z_NEW, i] + l0 * hist[E, i]
            work[i] *= l0
        size = _norm(work, y1, rtol, atol, controlled)
        if size <= 0.1 or (iteration > 0 and size * min(1.0, size / previous) <= 0.1):
            return True, calls
        previous = size
    return False, calls


@numba.njit(cache=True)
def _propose(hist, q, h, e_norm, y1, rtol, atol, controlled, work):
    """Next step and order after an accepted step of error norm ``e_norm``: change them
    only after ``q + 1`` steps at one step size, to the order whose estimate allows the
    longest step (Byrne and Hindmarsh 1975)."""
    n = y1.shape[0]
    eta = 1.0
    new_q = q
    if hist[SINCE, 0] + 1.0 > q:
        eta = 1.0 / (1.2 * e_norm ** (1.0 / (q + 1)) + 1e-6)
        if q > 1:
            for i in range(n):
                work[i] = ERROR_CONSTANT[q - 1] * math.gamma(q + 1.0) * hist[Z_NEW + q, i]
            down = 1.0 / (1.3 * _norm(work, y1, rtol, atol, controlled) ** (1.0 / q) + 1e-6)
            if down > eta:
                eta, new_q = down, q - 1
        if q < MAX_ORDER:
            for i in range(n):
                work[i] = ERROR_CONSTANT[q + 1] * (hist[E, i] - hist[E_LAST, i])
            up = 1.0 / (1.4 * _norm(work, y1, rtol, atol, controlled) ** (1.0 / (q + 2)) + 1e-6)
            if up > eta:
                eta, new_q = up, q + 1
        if eta < 1.1:
            eta, new_q = 1.0, q
    hist[NEXT_STEP, 0] = h * min(eta, 5.0)
    hist[NEXT_ORDER, 0] = new_q


@numba.njit(cache=True)
def adams_step(system, t, y, f, h, mode, p, hist, matrix, pivots, y1, f1, work, rtol, atol, counters):
    """One step of ``h`` [s] from ``(t, y)`` (``f`` its rates) into ``y1`` and ``f1``
    (the corrected derivative ``z_new[1] / h``).

    Returns
    -------
    e : float
        Scaled error norm (at most 1 to accept; 1e3 when Newton did not converge).
    order : float
        ``q + 1``, for the driver's step after a refusal.
    calls : int
        Right-hand-side calls (the Jacobians are counted in ``counters``).
    """
    _prepare(hist, t, y, f, h)
    q = int(hist[ORDER, 0])
    controlled = systems.controlled_size(system)
    counters[COUNT_JACOBIANS] += _newton_matrix(system, t, y, f, h, q, mode, p, hist, matrix, pivots)
    converged, calls = _correct(system, t, h, q, mode, p, hist, matrix, pivots, y1, f1, work, rtol, atol,
                                controlled)
    if not converged:
        hist[AGE, 0] = -1.0            # a fresh Newton matrix for the retry
        return 1e3, q + 1.0, calls
    n = y.shape[0]
    for j in range(q + 1):
        for i in range(n):
            hist[Z_NEW + j, i] += EL[q, j] * hist[E, i]
    for i in range(n):
        f1[i] = hist[Z_NEW + 1, i] / h
        work[i] = ERROR_CONSTANT[q] * hist[E, i]
    e_norm = _norm(work, y1, rtol, atol, controlled)
    if e_norm > 1.0:
        hist[FAILS, 0] += 1.0
        if hist[FAILS, 0] >= 2.0 and q > 1:
            hist[ORDER, 0] = q - 1.0
            for i in range(n):
                hist[Z + q, i] = 0.0
        hist[SINCE, 0] = 0.0
    else:
        _propose(hist, q, h, e_norm, y1, rtol, atol, controlled, work)
    return e_norm, q + 1.0, calls


@numba.njit(cache=True)
def adams_accept(hist, t_end_of_step, h):
    """Make the accepted step's history current; returns the next step [s]."""
    q = int(hist[ORDER, 0])
    n = hist.shape[1]
    for j in range(q + 1):
        for i in range(n):
            hist[Z + j, i] = hist[Z_NEW + j, i]
    new_q = int(hist[NEXT_ORDER, 0])
    if new_q == q + 1:
        for i in range(n):
            hist[Z + q + 1, i] = EL[q, q] * hist[E, i] / (q + 1)
    elif new_q == q - 1:
        for i in range(n):
            hist[Z + q, i] = 0.0
    for i in range(n):
        hist[E_LAST, i] = hist[E, i]
    hist[ORDER, 0] = new_q
    hist[TIME, 0] = t_end_of_step
    hist[STEP, 0] = h
    hist[SINCE, 0] = 0.0 if (new_q != q or hist[NEXT_STEP, 0] != h) else hist[SINCE, 0] + 1.0
    hist[FAILS, 0] = 0.0
    hist[AGE, 0] += 1.0
    return hist[NEXT_STEP, 0]


@numba.njit(cache=True)
def nordsieck_dense(tau, hist, n, out):
    """State at the fraction ``tau`` of the last step, from its Nordsieck polynomial."""
    q = int(hist[ORDER, 0])
    s = tau - 1.0
    for i in range(n):
        acc = hist[Z_NEW + q, i]
        for j in range(q - 1, -1, -1):
            acc = acc * s + hist[Z_NEW + j, i]
        out[i] = acc
