"""The Nordsieck history shared by the two families of variable-order, variable-step
multistep methods of the integrator: Adams-Moulton (orders 1 to :data:`MAX_ORDER`, its
corrector solved by functional iteration, no Jacobian; ``METHOD_ADAMS``) and the backward
differentiation formulas (BDF, orders 1 to :data:`BDF_MAX_ORDER`, corrected by Newton's
method in :mod:`camdyn.integrator.multistep`, which also switches between the families
for ``METHOD_MULTISTEP``). The history row ``FAMILY`` says which family it serves.

The history is the Nordsieck array ``z[j] = h^j y^(j) / j!``, ``j = 0..q`` (order ``q``,
1 to :data:`MAX_ORDER`). A step predicts ``z_p = z A`` (``A`` Pascal's triangle), then
finds the correction ``e`` such that ``h f(t + h, z_p[0] + l_0 e) = z_p[1] + e`` by
fixed-point iteration (at most :data:`ITERATIONS` right-hand-side calls, usually two), and
sets ``z_new = z_p + e l``. The Adams coefficients ``l`` of order ``q`` are those of
``Lambda(x) = int_-1^x prod_(i=1)^(q-1) (s + i) / (q-1)! ds`` and the local error is
``C_q e`` with ``C_q = int_-1^0 prod_(i=0)^(q-1) (s + i) ds / q!`` (Byrne and Hindmarsh
1975, ACM TOMS 1(1) 71-96, doi:10.1145/355626.355636); BDF's are those of
``Lambda(x) = prod_(i=1)^q (1 + x / i)`` divided by its ``x`` coefficient (so that
``l_1 = 1`` in both families, and ``l_0 = 1 / (1 + 1/2 + ... + 1/q)``), with LSODE's error
multipliers ``l_0 / (q + 1)`` of ``e`` (the estimate ``h^(q+1) y^(q+1) / (q + 1)``),
``(q - 1)!`` of ``z[q]`` for order ``q - 1`` and ``l_0 / (q + 2)`` of the change of ``e``
for order ``q + 1`` (its ``TESCO``; Radhakrishnan and Hindmarsh 1993, LSODE report
UCRL-ID-113855, section 3). The iteration stops when its last
change, weighted by the contraction rate, adds at most a tenth to the error estimate, and
the step and order follow CVODE's rules (Hindmarsh et al. 2005, ACM TOMS 31(3) 363-396,
doi:10.1145/1089014.1089020): the order is reconsidered only ``q + 1`` steps after its
last change, from the error estimates of orders ``q - 1``, ``q`` and ``q + 1`` (the last
from the difference of successive corrections), with the biases 6, 6 and 10; the step
changes only when it would grow by a factor of at least :data:`THRESHOLD` or must shrink,
so that the history is rarely rescaled, and never grows in the step after a refusal.

The continuous extension of a step is the Nordsieck polynomial itself,
``y(t + h + s h) = sum_j z_new[j] s^j`` for ``s`` in [-1, 0]. After an event, or any change of
state the history does not know, the driver takes one DOP853 step and starts the history
from that step's continuous extension at order :data:`START_ORDER` (:func:`adams_start`);
the order-1 start of :func:`begin_step` is the fallback.

The driver keeps everything in one array ``history`` of ``ROWS + n`` rows of ``n`` columns
(``Z``, ``Z_NEW``, the correction ``E`` and the one saved for the order-raise estimate
``E_LAST``, scalars in column 0 of the rows from ``SCALARS``, and from row ``JACOBIAN`` the
last Jacobian of the BDF corrector), so that it passes through the driver's functions as
the step's ``work`` array.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.polynomial import polynomial as P

from camdyn.integrator.tolerances import absolute_tolerance
from camdyn.systems import registry as systems

#: Largest order of the Adams family [-].
MAX_ORDER = 12
#: Largest order of the BDF family [-] (BDF of order 6 and above are not zero-stable).
BDF_MAX_ORDER = 5
#: The families, as the history's ``FAMILY`` row holds them.
ADAMS, BDF = 0, 1
#: Right-hand-side calls of the corrector iteration per step at most [-].
ITERATIONS = 3
#: Smallest growth of the step worth rescaling the history for [-].
THRESHOLD = 1.5
#: Largest growth of the step per change [-] below order 3 (the ramp after a start at order
#: 1) and from order 3 on (where a step limited by stability, as in a stiff contact,
#: would fail after a larger one).
GROWTH_LOW, GROWTH = 10.0, 2.0
#: Order of a history started from a DOP853 step [-].
START_ORDER = 5
#: Refusals of one step after which the history is dropped and the driver starts it
#: again from a DOP853 step [-] (near a contact's separation the Hertz force's
#: ``delta^1.5`` has unbounded derivatives, which no history of high order follows).
FAILS_TO_RESTART = 2

Z = 0
Z_NEW = MAX_ORDER + 2
E_LAST = 2 * MAX_ORDER + 4
E = E_LAST + 1
SCALARS = E + 1
ORDER = SCALARS          # q [-]
TIME = SCALARS + 1       # time of Z [s]
STEP = SCALARS + 2       # the step Z is scaled to [s]
WAIT = SCALARS + 3       # accepted steps before the order may change [-]
NEXT_STEP = SCALARS + 4  # proposed next step [s]
NEXT_ORDER = SCALARS + 5 # proposed next order [-]
FAILS = SCALARS + 6      # refusals of the current step [-]
SAVED_STEP = SCALARS + 7 # the step of the correction saved in E_LAST [s]
FAMILY = SCALARS + 8     # ADAMS or BDF [-]
NEXT_FAMILY = SCALARS + 9  # the family of the next step [-]
RELOAD = SCALARS + 10    # 1: the next BDF step restarts at order 1 from the rates [-]
SINCE = SCALARS + 11     # accepted steps since the last test for a switch [-]
STIFFNESS = SCALARS + 12 # weighted norm of the last Jacobian [1/s]
GAMMA = SCALARS + 13     # h l_0 of the factored BDF matrix [s]
RATE = SCALARS + 14      # the Newton iteration's convergence rate [-]
MATRIX_AGE = SCALARS + 15    # steps since the BDF matrix was factored [-]
JACOBIAN_AGE = SCALARS + 16  # steps since the Jacobian was evaluated [-]
PATIENCE = SCALARS + 17  # tests an Adams history skips, after BDF did not pay [-]
ADAMS_STEP = SCALARS + 18    # the Adams step at the last switch to BDF [s]
ROWS = SCALARS + 19
JACOBIAN = ROWS          # first of the n rows of the Jacobian


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
        error[q] = abs(P.polyval(0.0, ci) - P.polyval(-1.0, ci)) / math.factorial(q)
    return el, error


def _bdf_tables():
    """BDF's ``l`` vectors (row q, ``l_1 = 1``) from ``prod_(i=1)^q (1 + x / i)``, and
    LSODE's error multipliers of ``e`` (order q), of ``z[q]`` (order q - 1) and of the
    change of ``e`` (order q + 1), for q = 1 .. BDF_MAX_ORDER."""
    el = np.zeros((MAX_ORDER + 2, MAX_ORDER + 2))
    current, down, up = (np.zeros(MAX_ORDER + 2) for _ in range(3))
    for q in range(1, BDF_MAX_ORDER + 1):
        lam = np.array([1.0])
        for i in range(1, q + 1):
            lam = P.polymul(lam, [1.0, 1.0 / i])
        el[q, :q + 1] = lam / lam[1]
        current[q] = el[q, 0] / (q + 1)
        up[q] = el[q, 0] / (q + 2)
        down[q] = math.factorial(q - 1)
    return el, current, down, up


FACTORIAL = np.array([math.factorial(q) for q in range(MAX_ORDER + 3)], dtype=np.float64)
ADAMS_EL, ERROR_CONSTANT = _adams_tables()
BDF_EL, BDF_CURRENT, BDF_DOWN, BDF_UP = _bdf_tables()
#: ``l`` vectors, ``EL[family, q]``.
EL = np.stack((ADAMS_EL, BDF_EL))
#: Multipliers of ``e`` giving the error estimate of order ``q`` [-], ``CURRENT[family, q]``.
CURRENT = np.stack((ERROR_CONSTANT, BDF_CURRENT))
#: Multipliers of ``z[q]`` giving the error estimate of order ``q - 1`` [-].
DOWN = np.stack((np.append(0.0, ERROR_CONSTANT[:-1]) * FACTORIAL[:MAX_ORDER + 2], BDF_DOWN))
#: Multipliers of the change of ``e`` giving the error estimate of order ``q + 1`` [-].
UP = np.stack((np.append(ERROR_CONSTANT[1:], 0.0), BDF_UP))
#: Local error per ``h^(q+1) y^(q+1)`` [-] (Adams-Moulton's error constant; BDF's as LSODE
#: estimates it, ``1 / (q + 1)``), which translates an error estimate between the families.
DERIVATIVE_ERROR = np.stack((ERROR_CONSTANT, np.array([0.0] + [1.0 / (q + 1) for q in range(1, MAX_ORDER + 2)])))
#: Largest order of each family [-].
TOP = np.array([MAX_ORDER, BDF_MAX_ORDER])
#: ``6 e`` at and above which order ``q``'s step would grow by less than THRESHOLD [-].
KEEP = np.array([(1.0 / THRESHOLD - 1e-6) ** (q + 1) for q in range(MAX_ORDER + 2)])


@numba.njit(cache=True, inline="always")
def _norm(v, y, rtol, atol, controlled):
    """RMS of ``v`` over the controlled components, scaled by ``atol + rtol |y|``
    (``atol`` one number or one per component)."""
    acc = 0.0
    for i in range(controlled):
        acc += (v[i] / (absolute_tolerance(atol, i) + rtol * abs(y[i]))) ** 2
    return math.sqrt(acc / controlled)


@numba.njit(cache=True, inline="always")
def _prepare(hist, t, y, f, h):
    """Restart at order 1 unless the history is at ``(t, y)``; rescale it to ``h``."""
    n = y.shape[0]
    fresh = hist[TIME, 0] != t
    for i in range(n):
        fresh = fresh or hist[Z, i] != y[i]
    if fresh:
        for i in range(n):
            hist[Z, i] = y[i]
            hist[Z + 1, i] = h * f[i]
        hist[ORDER, 0] = 1.0
        hist[TIME, 0] = t
        hist[STEP, 0] = h
        hist[WAIT, 0] = 2.0
        hist[FAILS, 0] = 0.0
    elif hist[STEP, 0] != h:
        q = int(hist[ORDER, 0])
        ratio = h / hist[STEP, 0]
        r = 1.0
        for j in range(1, q + 1):
            r *= ratio
            for i in range(n):
                hist[Z + j, i] *= r
        hist[STEP, 0] = h


@numba.njit(cache=True, inline="always")
def _predict(hist, q, n):
    """``Z_NEW = Z A``: the history carried to the step's end (repeated sums, Pascal's triangle)."""
    for j in range(q + 1):
        for i in range(n):
            hist[Z_NEW + j, i] = hist[Z + j, i]
    for k in range(1, q + 1):
        for j in range(q, k - 1, -1):
            for i in range(n):
                hist[Z_NEW + j - 1, i] += hist[Z_NEW + j, i]


@numba.njit(cache=True, inline="always")
def _correct(system, t, h, q, mode, p, hist, y1, f1, work, rtol, atol, controlled):
    """Solve the corrector by functional iteration; ``y1`` is the corrected state.
    Returns whether it converged and the right-hand-side calls."""
    n = y1.shape[0]
    l0 = EL[ADAMS, q, 0]
    for i in range(n):
        hist[E, i] = 0.0
        y1[i] = hist[Z_NEW, i]
    rate = 1.0
    previous = 0.0
    for iteration in range(ITERATIONS):
        systems.rhs_inline(system, t + h, y1, mode, p, f1)
        for i in range(n):
            e_new = h * f1[i] - hist[Z_NEW + 1, i]
            work[i] = e_new - hist[E, i]
            hist[E, i] = e_new
            y1[i] = hist[Z_NEW, i] + l0 * e_new
        change = _norm(work, y1, rtol, atol, controlled)
        if iteration > 0:
            rate = max(0.3 * rate, change / previous)
            if change > 2.0 * previous:
                return False, iteration + 1
        if change * min(1.0, rate) * CURRENT[ADAMS, q] <= 0.1:
            return True, iteration + 1
        previous = change
    return False, ITERATIONS


@numba.njit(cache=True, inline="always")
def _eta(hist, family, q, h, e_norm, y1, rtol, atol, controlled, work):
    """Ratio of the next step to this one and the next order, after an accepted step of
    error norm ``e_norm`` (CVODE's choice among orders ``q - 1``, ``q``, ``q + 1``)."""
    n = y1.shape[0]
    wait = hist[WAIT, 0] - 1.0
    if wait > 0.0 and (hist[FAILS, 0] > 0.0 or 6.0 * e_norm >= KEEP[q]):
        if wait == 1.0:   # the step stays: no power to take
            for i in range(n):
                hist[E_LAST, i] = hist[E, i]
            hist[SAVED_STEP, 0] = h
        return 1.0, q, wait
    eta = 1.0 / ((6.0 * e_norm) ** (1.0 / (q + 1)) + 1e-6)
    new_q = q
    if wait <= 0.0 and hist[FAILS, 0] > 0.0:
        wait = 2.0
    elif wait <= 0.0:
        if q > 1:
            for i in range(n):
                work[i] = DOWN[family, q] * hist[Z_NEW + q, i]
            down = 1.0 / ((6.0 * _norm(work, y1, rtol, atol, controlled)) ** (1.0 / q) + 1e-6)
            if down > eta:
                eta, new_q = down, q - 1
        if q < TOP[family]:
            scale = (h / hist[SAVED_STEP, 0]) ** (q + 1)   # the saved correction at this step
            for i in range(n):
                work[i] = UP[family, q] * (hist[E, i] - scale * hist[E_LAST, i])
            up = 1.0 / ((10.0 * _norm(work, y1, rtol, atol, controlled)) ** (1.0 / (q + 2)) + 1e-6)
            if up > eta:
                eta, new_q = up, q + 1
        wait = 2.0
    if wait == 1.0:
        for i in range(n):
            hist[E_LAST, i] = hist[E, i]
        hist[SAVED_STEP, 0] = h
    if hist[FAILS, 0] > 0.0:
        eta = min(eta, 1.0)
    if eta < THRESHOLD:
        eta, new_q = 1.0, q
    return min(eta, GROWTH_LOW if q < 3 else GROWTH), new_q, wait


@numba.njit(cache=True, inline="always")
def count_failure(hist, family):
    """Count a failed step; after :data:`FAILS_TO_RESTART` in a row, drop an Adams
    history or have a BDF one restart at order 1."""
    hist[FAILS, 0] += 1.0
    if hist[FAILS, 0] >= FAILS_TO_RESTART:
        if family == ADAMS:
            hist[TIME, 0] = np.nan
        else:
            hist[RELOAD, 0] = 1.0


@numba.njit(cache=True, inline="always")
def _refuse(hist, family, q, e_norm, y1, rtol, atol, controlled, work):
    """After a refused step of error norm ``e_norm``: drop the order when order ``q - 1``
    allows the longer retry (LSODE's rule, Hindmarsh 1983); after :data:`FAILS_TO_RESTART`
    refusals in a row drop an Adams history (the driver starts it again from a DOP853
    step) or restart a BDF one at order 1 from the rates (CVODE's rule; a DOP853 step would
    be held to the stability bound of a stiff problem). Returns the error norm the driver
    sizes the retry from (its ``h * 0.9 e^(-1/(q+1))`` then is the step this choice allows,
    at most 0.9 h)."""
    n = y1.shape[0]
    count_failure(hist, family)
    eta = 1.0 / ((6.0 * e_norm) ** (1.0 / (q + 1)) + 1e-6)
    if q > 1:
        for i in range(n):
            work[i] = DOWN[family, q] * hist[Z_NEW + q, i]
        down = 1.0 / ((6.0 * _norm(work, y1, rtol, atol, controlled)) ** (1.0 / q) + 1e-6)
        if down > eta:
            eta = down
            hist[ORDER, 0] = q - 1.0
            hist[WAIT, 0] = q
    eta = min(eta, 0.9)
    return max((0.9 / eta) ** (q + 1), 1.0 + 1e-9)


@numba.njit(cache=True, inline="always")
def begin_step(hist, t, y, f, h):
    """Carry the history to the step ``h`` [s] from ``(t, y)`` (``f`` its rates), restarting
    a BDF history at order 1 from the rates after repeated refusals, and predict.
    Returns the family and the order of the step."""
    _prepare(hist, t, y, f, h)
    if hist[RELOAD, 0] > 0.0:
        for i in range(y.shape[0]):
            hist[Z + 1, i] = h * f[i]
        hist[ORDER, 0] = 1.0
        hist[WAIT, 0] = 2.0
        hist[RELOAD, 0] = 0.0
    q = int(hist[ORDER, 0])
    _predict(hist, q, y.shape[0])
    return int(hist[FAMILY, 0]), q


@numba.njit(cache=True, inline="always")
def functional_correct(system, t, h, q, mode, p, hist, y1, f1, work, rtol, atol, controlled):
    """The Adams corrector: :func:`_correct` (whether it converged, right-hand-side calls)."""
    return _correct(system, t, h, q, mode, p, hist, y1, f1, work, rtol, atol, controlled)


@numba.njit(cache=True, inline="always")
def finish_step(hist, family, q, h, y1, f1, work, rtol, atol, controlled):
    """After the corrector converged: the new history ``z_p + e l``, the rates ``f1`` of its
    polynomial at the step's end (``z_new[1] / h``), the error test, and the next step and
    order (accepted) or the retry's error norm (refused). Returns the scaled error norm."""
    n = y1.shape[0]
    for j in range(q + 1):
        for i in range(n):
            hist[Z_NEW + j, i] += EL[family, q, j] * hist[E, i]
    for i in range(n):
        f1[i] = hist[Z_NEW + 1, i] / h
        work[i] = CURRENT[family, q] * hist[E, i]
    e_norm = _norm(work, y1, rtol, atol, controlled)
    if e_norm > 1.0:
        return _refuse(hist, family, q, e_norm, y1, rtol, atol, controlled, work)
    eta, new_q, wait = _eta(hist, family, q, h, e_norm, y1, rtol, atol, controlled, work)
    hist[NEXT_STEP, 0] = h * eta
    hist[NEXT_ORDER, 0] = new_q
    hist[NEXT_FAMILY, 0] = family
    hist[WAIT, 0] = wait if new_q == q else new_q + 1.0
    return e_norm


@numba.njit(cache=True, inline="always")
def adams_accept(hist, t_end_of_step, h):
    """Make the accepted step's history current, in the family chosen for the next step
    (a switch keeps the order, at most :data:`BDF_MAX_ORDER` for BDF, and waits
    ``q + 1`` steps before changing it); returns the next step [s]."""
    q = int(hist[ORDER, 0])
    family = int(hist[FAMILY, 0])
    n = hist.shape[1]
    for j in range(q + 1):
        for i in range(n):
            hist[Z + j, i] = hist[Z_NEW + j, i]
    new_q = int(hist[NEXT_ORDER, 0])
    if new_q == q + 1:
        for i in range(n):
            hist[Z + q + 1, i] = EL[family, q, q] * hist[E, i] / (q + 1)
    hist[SINCE, 0] += 1.0
    hist[MATRIX_AGE, 0] += 1.0
    hist[JACOBIAN_AGE, 0] += 1.0
    if hist[NEXT_FAMILY, 0] != family:
        family = int(hist[NEXT_FAMILY, 0])
        new_q = min(new_q, TOP[family])
        hist[FAMILY, 0] = family
        hist[WAIT, 0] = new_q + 1.0
        hist[MATRIX_AGE, 0] = np.inf   # factor the BDF matrix anew
    hist[ORDER, 0] = new_q
    hist[TIME, 0] = t_end_of_step
    hist[STEP, 0] = h
    hist[FAILS, 0] = 0.0
    return hist[NEXT_STEP, 0]


@numba.njit(cache=True, inline="always")
def nordsieck_dense(tau, hist, n, out):
    """State at the fraction ``tau`` of the last step, from its Nordsieck polynomial."""
    q = int(hist[ORDER, 0])
    s = tau - 1.0
    for i in range(n):
        acc = hist[Z_NEW + q, i]
        for j in range(q - 1, -1, -1):
            acc = acc * s + hist[Z_NEW + j, i]
        out[i] = acc


@numba.njit(cache=True, inline="always")
def _times_tau(hist, degree, n, shift_only):
    """Multiply the polynomial in ``u`` held in the rows ``Z..Z+degree`` by ``1 + u``, or
    by ``-u`` when ``shift_only``."""
    for j in range(degree + 1, 0, -1):
        for i in range(n):
            hist[Z + j, i] = -hist[Z + j - 1, i] if shift_only else hist[Z + j, i] + hist[Z + j - 1, i]
    if shift_only:
        for i in range(n):
            hist[Z, i] = 0.0


@numba.njit(cache=True)
def adams_start(hist, coefficients, y1, t1, h, rtol, atol, controlled, work):
    """Start the history at the end ``t1`` [s] of a DOP853 step of ``h`` [s] to ``y1``, at
    order :data:`START_ORDER`: ``z[j]`` (``j >= 1``) are the Taylor coefficients about
    ``tau = 1`` of the step's 7th-order continuous extension ``y(t1 - h + tau h)``
    (coefficients ``coefficients[0:7]``, see :func:`camdyn.integrator.steppers.dense`),
    which are the Nordsieck array at the step ``h``. Returns the first Adams step [s],
    from the local error of that order that the extension's next coefficient predicts."""
    n = y1.shape[0]
    for j in range(9):
        for i in range(n):
            hist[Z + j, i] = 0.0
    for i in range(n):
        hist[Z, i] = coefficients[6, i]
    degree = 0
    for k in range(5, -1, -1):   # ((((((F6 tau + F5) s + F4) tau + F3) s + ... + F0) tau, tau = 1 + u, s = -u
        _times_tau(hist, degree, n, k % 2 == 0)
        degree += 1
        for i in range(n):
            hist[Z, i] += coefficients[k, i]
    _times_tau(hist, degree, n, False)
    family = int(hist[FAMILY, 0])
    q = min(START_ORDER, TOP[family])
    for i in range(n):
        hist[Z, i] = y1[i]
        work[i] = DERIVATIVE_ERROR[family, q] * FACTORIAL[q + 1] * hist[Z + q + 1, i]
    eta = 1.0 / ((6.0 * _norm(work, y1, rtol, atol, controlled)) ** (1.0 / (q + 1)) + 1e-6)
    hist[ORDER, 0] = q
    hist[TIME, 0] = t1
    hist[STEP, 0] = h
    hist[WAIT, 0] = q + 1.0
    hist[FAILS, 0] = 0.0
    hist[RELOAD, 0] = 0.0
    hist[MATRIX_AGE, 0] = np.inf      # the mode may have changed: a new BDF matrix,
    hist[JACOBIAN_AGE, 0] = np.inf    # from a new Jacobian
    return h * min(eta, 1.0)


@numba.njit(cache=True, inline="always")
def adams_ready(hist, t, y):
    """Whether the history is at ``(t, y)`` (else the next step starts it again)."""
    ready = hist[TIME, 0] == t
    for i in range(y.shape[0]):
        ready = ready and hist[Z, i] == y[i]
    return ready
