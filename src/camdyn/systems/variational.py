"""The variational system of a registered model: its state, its state-transition matrix
and, on request, its derivatives with respect to parameters, integrated together, with the
saltation matrix applied at every event.

For a model of ``n`` states the variational system has ``n + n^2`` states: the model's
``y``, then ``Phi`` (row-major, ``Phi[i, j] = Y[n + i n + j]``) with ``Phi' = J(t, y) Phi``
between events (``J`` from :func:`camdyn.systems.models.variational_jacobian`). At an
event of guard ``g`` (before: mode ``-``; after: mode ``+``, with the
reset ``y+ = R(y-, t)``) the matrix jumps by the saltation matrix (Aizerman and Gantmacher
1958; Leine and Nijmeijer 2004, doi:10.1007/978-3-540-44398-8)::

    S = R_y + (f+ - R_y f- - R_t) grad(g)^T / (dg/dt)-,      Phi+ = S Phi-          (1)

where ``(dg/dt)-`` is the guard's exact rate before the event (the system's own guard
rates), ``grad(g)`` its gradient in ``y``, ``R_y`` the reset's Jacobian and ``R_t`` its
rate in time (a reset onto a moving surface, such as a translating follower's rebound
from its cam, ``x'+ = s_dot(t) - e (x'- - s_dot(t))``; zero for a fixed wall or a mode
change), all by central differences of the model's guard and transition functions (the
guards and resets are smooth in ``y`` and ``t``). Over one period of a periodic orbit ``Phi`` is the monodromy
matrix, whose eigenvalues are the Floquet multipliers.

**Parameter sensitivities.** With ``k`` parameters ``q_j`` the system has ``n k`` more
states, the columns ``Y_j = d y / d q_j`` (``Y[n + n^2 + j n + i]``), with
``Y_j' = J Y_j + df/dq_j`` between events and, at an event (differentiating the event time
``g(y(t*), t*, q) = 0`` with respect to ``q_j``)::

    Y_j+ = S Y_j- + dR/dq_j + (f+ - R_y f- - R_t) (dg/dq_j) / (dg/dt)-             (2)

A parameter is a direction in the parameter vector: its slots ``p[:L]`` move by
``dp/dq_j`` per unit of ``q_j``. The ``k`` directions follow the model's ``L`` slots in
``p``, each as ``(h_j, h_j dp/dq_j)`` (``L + 1`` values); ``df/dq_j`` is the fourth-order central
difference over ``p[:L] + (-2, -1, 1, 2) h_j dp/dq_j``, ``dg/dq_j`` and ``dR/dq_j`` the
second-order one over ``p[:L] +- h_j dp/dq_j`` (guards and resets are evaluated once per
event, the field at every stage). The system id carries ``k``: :func:`system_id`. The derivatives
are taken at a fixed initial state.

**A value carried in the mode.** Under the restitution-parameterised contact laws the
force depends on the approach velocity ``c`` of the current contact, which the model's
transition stores in the mode at contact onset from the state there
(:func:`camdyn.systems.models.carried_slot`), so the flow depends on the state at onset
through ``c`` as well. The variational system carries ``r = dc/d(column)`` for each
column (``Phi``'s ``n``, then the ``k`` parameters') in mode slots after the model's
(:func:`mode_size`), constant between events, and adds to each column's rate::

    Phi_c' = J Phi_c + (df/dc) r_c                                               (3)

with ``df/dc`` by a central difference of the right-hand side in ``c``. At an event the
value after it, ``c+ = T(y-, t*, c-, q)`` (the transition, guard values recomputed from
the state), has (differentiating it with the event time ``dt*``)::

    r+ = T_y (Phi_c + f- dt*) + T_t dt* + T_c r- + T_q,
    dt* = -(grad(g) Phi_c + dg/dq) / (dg/dt)-                                    (4)

(``dg/dq`` and ``T_q`` only in a parameter's column), the partial derivatives of ``T``
by central differences: at an onset ``T_c = 0`` and ``T_y`` is the gradient of the
approach velocity, at any other event ``T_c = 1`` and the rest zero. Under the other
laws the slots stay zero and nothing changes.

Every component is error-controlled (the matrices too); the explicit steppers are used
(:func:`preferred_method` returns DOP853).
"""

from __future__ import annotations

import numba
import numpy as np

from camdyn.systems import models

#: Variational systems have ids ``VARIATIONAL + model id``.
VARIATIONAL = 100
#: With ``k`` parameter sensitivities, ``k PARAMETRIC + VARIATIONAL + model id``.
PARAMETRIC = 1000
#: Relative step of the central differences of guards and resets [-].
DIFFERENCE_STEP = 1e-7


@numba.njit(cache=True)
def system_id(model, count):
    """Id of ``model``'s variational system with ``count`` parameter sensitivities."""
    return count * PARAMETRIC + VARIATIONAL + model


@numba.njit(cache=True)
def split(system):
    """``(model, count)`` of a variational system's id (see :func:`system_id`)."""
    return system % PARAMETRIC - VARIATIONAL, system // PARAMETRIC


@numba.njit(cache=True)
def state_size(model, count):
    n = models.state_size(model)
    return n + n * n + n * count


@numba.njit(cache=True)
def mode_size(model, count):
    """The model's mode slots, then, for a model with a carried mode value
    (:func:`camdyn.systems.models.carried_slot`), that value's derivatives: ``n`` with
    respect to the initial state, then one per parameter (eq. 3)."""
    size = models.mode_size(model)
    if models.carries(model):
        size += models.state_size(model) + count
    return size


@numba.njit(cache=True)
def _offset(n, c):
    """``(first index, stride)`` in the variational state of column ``c``: ``Phi``'s
    column ``c`` for ``c < n``, else parameter ``c - n``'s ``Y_j``."""
    if c < n:
        return n + c, n
    return n + n * n + (c - n) * n, 1


@numba.njit(cache=True)
def _direction(p, count, j):
    """``(L, h_j, first slot of h_j dp/dq_j)`` of parameter ``j`` (see the module's
    docstring)."""
    length = (p.shape[0] - count) // (count + 1)
    slot = length + j * (length + 1)
    return length, p[slot], slot + 1


@numba.njit(cache=True)
def _moved(p, count, j, sign):
    """A copy of ``p`` with ``p[:L]`` moved by ``sign h_j dp/dq_j``, and ``h_j``."""
    length, step, first = _direction(p, count, j)
    moved = p.copy()
    for i in range(length):
        moved[i] += sign * p[first + i]
    return moved, step


@numba.njit(cache=True)
def rhs(model, count, t, y, mode, p, dydt):
    """``(f(t, y), J(t, y) Phi, J Y_j + df/dq_j)`` into ``dydt``."""
    n = models.state_size(model)
    x = y[:n]
    f = dydt[:n]
    models.rhs(model, t, x, mode, p, f)
    jac = np.empty((n, n))
    models.variational_jacobian(model, t, x, f, mode, p, jac)
    for c in range(n + count):
        column = n + c * n if c >= n else n + c   # Phi's column c, or parameter c - n
        stride = 1 if c >= n else n
        for i in range(n):
            acc = 0.0
            for k in range(n):
                acc += jac[i, k] * y[column + k * stride]
            dydt[column + i * stride] = acc
    _carried_field(model, count, t, x, mode, p, dydt)
    if count == 0:
        return
    # df/dq_j by the fourth-order central difference (f(-2h) - 8 f(-h) + 8 f(h) - f(2h)) / 12h:
    # a parameter that moves the cam's angle moves it by h t dTheta/dq, which in a stiff
    # contact is not small against the penetration (the second-order difference's error
    # was 1e-3 of the derivative through an impact of the chapter 3 rig at h = 1e-7 q)
    values = np.empty(n)
    weights = (1.0, -8.0, 8.0, -1.0)
    signs = (-2.0, -1.0, 1.0, 2.0)
    for j in range(count):
        base = n + n * n + j * n
        for r in range(4):
            moved, step = _moved(p, count, j, signs[r])
            models.rhs(model, t, x, mode, moved, values)
            for i in range(n):
                dydt[base + i] += weights[r] * values[i] / (12.0 * step)


@numba.njit(cache=True)
def _carried_field(model, count, t, x, mode, p, dydt):
    """Add ``(df/dc) (dc/d column)`` to the rate of every column (eq. 3): ``c`` the
    carried mode value, ``df/dc`` by a central difference of the model's right-hand side
    in it, ``dc/d column`` from the mode's derivative slots. Nothing while those are all
    zero (no event has set the value yet)."""
    slot = models.carried_slot(model, p)
    if slot < 0:
        return
    n = x.shape[0]
    first = models.mode_size(model)
    active = False
    for c in range(n + count):
        active = active or mode[first + c] != 0.0
    if not active:
        return
    value = mode[slot]
    step = DIFFERENCE_STEP * max(abs(value), 1e-6)
    moved = mode.copy()
    up = np.empty(n)
    down = np.empty(n)
    moved[slot] = value + step
    models.rhs(model, t, x, moved, p, up)
    moved[slot] = value - step
    models.rhs(model, t, x, moved, p, down)
    span = (value + step) - (value - step)   # the step as represented
    for c in range(n + count):
        rate = mode[first + c]
        if rate != 0.0:
            column, stride = _offset(n, c)
            for i in range(n):
                dydt[column + i * stride] += (up[i] - down[i]) / span * rate


@numba.njit(cache=True)
def _carried_value(model, k, t, x, mode, p):
    """The carried mode value after the transition of guard ``k`` at ``(t, x)`` from
    ``mode`` (neither changed), with the guard values taken there as the driver takes
    them."""
    m = models.guard_count(model)
    vals = np.empty(m)
    rates = np.empty(m)
    models.guards(model, t, x, x, False, p, vals, rates)
    after = mode.copy()
    models.transition(model, k, t, x.copy(), vals, after, p)
    return after[models.carried_slot(model, p)]


@numba.njit(cache=True)
def _carried_partials(model, k, t, x, mode, p, partials):
    """Central differences of :func:`_carried_value` in each state component into
    ``partials[:n]``, in time into ``partials[n]`` and in the value before the event into
    ``partials[n + 1]``."""
    n = x.shape[0]
    probe = x.copy()
    moved = mode.copy()
    slot = models.carried_slot(model, p)
    for i in range(n + 2):
        if i < n:
            step = DIFFERENCE_STEP * max(abs(x[i]), 1.0)
            probe[i] = x[i] + step
            up = _carried_value(model, k, t, probe, mode, p)
            span = probe[i]
            probe[i] = x[i] - step
            down = _carried_value(model, k, t, probe, mode, p)
            span -= probe[i]
            probe[i] = x[i]
        elif i == n:
            step = DIFFERENCE_STEP * max(abs(t), 1.0)
            up = _carried_value(model, k, t + step, x, mode, p)
            down = _carried_value(model, k, t - step, x, mode, p)
            span = (t + step) - (t - step)
        else:
            value = mode[slot]
            step = DIFFERENCE_STEP * max(abs(value), 1e-6)
            moved[slot] = value + step
            up = _carried_value(model, k, t, x, moved, p)
            moved[slot] = value - step
            down = _carried_value(model, k, t, x, moved, p)
            span = (value + step) - (value - step)
        partials[i] = (up - down) / span


@numba.njit(cache=True)
def _carried_jump(model, count, k, t, y, mode, p):
    """The derivatives of the carried mode value across the event of guard ``k`` at ``t``
    [s] (eq. 4), into the mode's derivative slots, from the state, its columns and the
    mode before the event (``y``, ``mode``; the model's slots of ``mode`` unchanged)."""
    if models.carried_slot(model, p) < 0:
        return
    n = models.state_size(model)
    m = models.guard_count(model)
    x = y[:n].copy()
    first = models.mode_size(model)
    f_before = np.empty(n)
    models.rhs(model, t, x, mode, p, f_before)
    vals = np.empty(m)
    rates = np.empty(m)
    models.guards(model, t, x, f_before, True, p, vals, rates)
    rate = rates[k]                          # (dg/dt)-, the guard's exact rate before
    grad = np.empty(n)
    _guard_gradient(model, k, t, x, p, grad)
    partials = np.empty(n + 2)
    _carried_partials(model, k, t, x, mode, p, partials)
    along = partials[n]                      # dc+/dt along the flow: c_y f- + c_t
    for i in range(n):
        along += partials[i] * f_before[i]
    after = np.empty(n + count)
    for c in range(n + count):
        column, stride = _offset(n, c)
        shift = 0.0                          # the event time's variation, times -(dg/dt)-
        direct = 0.0                         # the value's own rate in the parameter
        if c >= n:
            plus, step = _moved(p, count, c - n, 1.0)
            minus, step = _moved(p, count, c - n, -1.0)
            models.guards(model, t, x, x, False, plus, vals, rates)
            shift = vals[k]
            models.guards(model, t, x, x, False, minus, vals, rates)
            shift = (shift - vals[k]) / (2.0 * step)
            direct = (_carried_value(model, k, t, x, mode, plus)
                      - _carried_value(model, k, t, x, mode, minus)) / (2.0 * step)
        acc = direct + partials[n + 1] * mode[first + c]
        for i in range(n):
            shift += grad[i] * y[column + i * stride]
            acc += partials[i] * y[column + i * stride]
        after[c] = acc - along * shift / rate
    for c in range(n + count):
        mode[first + c] = after[c]


@numba.njit(cache=True)
def jacobian(model, count, t, y, f0, mode, p, jac):
    """The block-diagonal part: ``J`` on the state and on each column of ``Phi`` and of the
    parameter sensitivities, laid out as :func:`rhs` stores them (``Phi``'s column ``c``
    strided by ``n``, a sensitivity contiguous). The coupling ``d(J Phi)/dy`` and the
    carried field are left out: an implicit stepper's simplified Newton iteration
    converges with this approximation, to the same solution."""
    n = models.state_size(model)
    block = np.empty((n, n))
    models.jacobian(model, t, y[:n], f0[:n], mode, p, block)
    jac[:, :] = 0.0
    for i in range(n):
        for k in range(n):
            jac[i, k] = block[i, k]
    for c in range(n + count):
        column = n + c * n if c >= n else n + c   # as in rhs
        stride = 1 if c >= n else n
        for i in range(n):
            for k in range(n):
                jac[column + i * stride, column + k * stride] = block[i, k]


@numba.njit(cache=True)
def _guard_gradient(model, k, t, x, p, grad):
    """Central differences of guard ``k`` in each state component."""
    n = x.shape[0]
    m = models.guard_count(model)
    vals = np.empty(m)
    rates = np.empty(m)
    probe = x.copy()
    for i in range(n):
        step = DIFFERENCE_STEP * max(abs(x[i]), 1.0)
        probe[i] = x[i] + step
        span = probe[i]
        models.guards(model, t, probe, probe, False, p, vals, rates)
        up = vals[k]
        probe[i] = x[i] - step
        span -= probe[i]   # the step as represented
        models.guards(model, t, probe, probe, False, p, vals, rates)
        grad[i] = (up - vals[k]) / span
        probe[i] = x[i]


@numba.njit(cache=True)
def _reset_jacobian(model, k, t, x, values, mode, p, reset):
    """Central differences of the transition's reset ``R(y)`` (the identity where the
    transition only switches the mode)."""
    n = x.shape[0]
    for i in range(n):
        step = DIFFERENCE_STEP * max(abs(x[i]), 1.0)
        up = x.copy()
        up[i] += step
        down = x.copy()
        down[i] -= step
        span = up[i] - down[i]   # the step as represented: a reset that leaves y gives 1 exactly
        models.transition(model, k, t, up, values, mode.copy(), p)
        models.transition(model, k, t, down, values, mode.copy(), p)
        for r in range(n):
            reset[r, i] = (up[r] - down[r]) / span


@numba.njit(cache=True)
def _reset_rate(model, k, t, x, values, mode, p, rate):
    """Central difference in time of the transition's reset, ``R_t`` of eq. (1) (exactly
    zero for a reset that does not depend on time)."""
    step = DIFFERENCE_STEP * max(abs(t), 1.0)
    up = x.copy()
    down = x.copy()
    models.transition(model, k, t + step, up, values, mode.copy(), p)
    models.transition(model, k, t - step, down, values, mode.copy(), p)
    span = (t + step) - (t - step)   # the step as represented
    for r in range(x.shape[0]):
        rate[r] = (up[r] - down[r]) / span


@numba.njit(cache=True)
def _parameter_jumps(model, count, k, t, x, values, mode, p, reset_rates, guard_rates):
    """Central differences over each parameter ``j`` of the reset, ``dR/dq_j`` into
    ``reset_rates[:, j]``, and of guard ``k``, ``dg/dq_j`` into ``guard_rates[j]``, at the
    state ``x`` before the event."""
    n = x.shape[0]
    m = models.guard_count(model)
    vals = np.empty(m)
    rates = np.empty(m)
    for j in range(count):
        plus, step = _moved(p, count, j, 1.0)
        minus, step = _moved(p, count, j, -1.0)
        models.guards(model, t, x, x, False, plus, vals, rates)
        up = vals[k]
        models.guards(model, t, x, x, False, minus, vals, rates)
        guard_rates[j] = (up - vals[k]) / (2.0 * step)
        after_plus = x.copy()
        after_minus = x.copy()
        models.transition(model, k, t, after_plus, values, mode.copy(), plus)
        models.transition(model, k, t, after_minus, values, mode.copy(), minus)
        for r in range(n):
            reset_rates[r, j] = (after_plus[r] - after_minus[r]) / (2.0 * step)


@numba.njit(cache=True)
def saltation(model, k, t, x, values, mode, p, matrix):
    """The model's transition for guard ``k`` at ``t`` [s] (``x`` and ``mode`` updated in
    place) and its saltation matrix (eq. 1) into ``matrix`` (n x n). Returns the jump of
    the field across the event, ``f+ - R_y f- - R_t``, divided by the guard's rate before
    it."""
    n = x.shape[0]
    m = models.guard_count(model)
    f_before = np.empty(n)
    models.rhs(model, t, x, mode, p, f_before)
    vals = np.empty(m)
    rates = np.empty(m)
    models.guards(model, t, x, f_before, True, p, vals, rates)
    grad = np.empty(n)
    _guard_gradient(model, k, t, x, p, grad)
    reset = np.empty((n, n))
    _reset_jacobian(model, k, t, x, values, mode, p, reset)
    reset_rate = np.empty(n)
    _reset_rate(model, k, t, x, values, mode, p, reset_rate)
    models.transition(model, k, t, x, values, mode, p)
    f_after = np.empty(n)
    models.rhs(model, t, x, mode, p, f_after)
    jump = (f_after - reset @ f_before - reset_rate) / rates[k]
    for i in range(n):
        for j in range(n):
            matrix[i, j] = reset[i, j] + jump[i] * grad[j]
    return jump


@numba.njit(cache=True)
def transition(model, count, k, t, y, values, mode, p):
    """The model's transition on ``y[:n]``, ``Phi+ = S Phi-`` (eq. 1) and each parameter
    column by eq. (2)."""
    n = models.state_size(model)
    reset_rates = np.empty((n, count))
    guard_rates = np.empty(count)
    if count > 0:
        _parameter_jumps(model, count, k, t, y[:n].copy(), values, mode, p, reset_rates, guard_rates)
    _carried_jump(model, count, k, t, y, mode, p)
    salt = np.empty((n, n))
    jump = saltation(model, k, t, y[:n], values, mode, p, salt)
    before = y[n:].copy()
    for c in range(n + count):
        column = c if c < n else n * n + (c - n) * n   # offset in ``before`` of column c
        stride = n if c < n else 1
        for i in range(n):
            acc = 0.0
            for r in range(n):
                acc += salt[i, r] * before[column + r * stride]
            if c >= n:
                acc += reset_rates[i, c - n] + jump[i] * guard_rates[c - n]
            y[n + column + i * stride] = acc
