"""The variational system of a registered model: its state and its state-transition
matrix, integrated together, with the saltation matrix applied at every event.

For a model of ``n`` states the variational system has ``n + n^2`` states: the model's
``y``, then ``Phi`` (row-major, ``Phi[i, j] = Y[n + i n + j]``) with ``Phi' = J(t, y) Phi``
between events. At an event of guard ``g`` (before: mode ``-``; after: mode ``+``, with the
reset ``y+ = R(y-)``) the matrix jumps by the saltation matrix (Aizerman and Gantmacher
1958; Leine and Nijmeijer 2004, doi:10.1007/978-3-540-44398-8)::

    S = R_y + (f+ - R_y f-) grad(g)^T / (dg/dt)-,      Phi+ = S Phi-

where ``(dg/dt)-`` is the guard's exact rate before the event (the system's own guard
rates), ``grad(g)`` its gradient in ``y`` and ``R_y`` the reset's Jacobian, both by
central differences of the model's guard and transition functions (the guards and resets
are smooth in ``y``). Over one period of a periodic orbit ``Phi`` is the monodromy
matrix, whose eigenvalues are the Floquet multipliers.

Every component is error-controlled (the matrix too); the explicit steppers are used
(:func:`preferred_method` returns DOP853).
"""

from __future__ import annotations

import numba
import numpy as np

from camdyn.systems import models

#: Variational systems have ids ``VARIATIONAL + model id``.
VARIATIONAL = 100
#: Relative step of the central differences of guards and resets [-].
DIFFERENCE_STEP = 1e-7


@numba.njit(cache=True)
def state_size(model):
    n = models.state_size(model)
    return n + n * n


@numba.njit(cache=True)
def rhs(model, t, y, mode, p, dydt):
    """``(f(t, y), J(t, y) Phi)`` into ``dydt``."""
    n = models.state_size(model)
    x = y[:n]
    f = dydt[:n]
    models.rhs(model, t, x, mode, p, f)
    jac = np.empty((n, n))
    models.jacobian(model, t, x, f, mode, p, jac)
    for i in range(n):
        for j in range(n):
            acc = 0.0
            for k in range(n):
                acc += jac[i, k] * y[n + k * n + j]
            dydt[n + i * n + j] = acc


@numba.njit(cache=True)
def jacobian(model, t, y, f0, mode, p, jac):
    """The block-diagonal part ``diag(J, J, ..., J)`` (the term ``d(J Phi)/dy`` left out:
    the variational system is integrated by explicit steppers)."""
    n = models.state_size(model)
    block = np.empty((n, n))
    models.jacobian(model, t, y[:n], f0[:n], mode, p, block)
    jac[:, :] = 0.0
    for b in range(n + 1):
        for i in range(n):
            for j in range(n):
                jac[b * n + i, b * n + j] = block[i, j]


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
def saltation(model, k, t, x, values, mode, p, matrix):
    """The model's transition for guard ``k`` at ``t`` [s] (``x`` and ``mode`` updated in
    place) and its saltation matrix into ``matrix`` (n x n)."""
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
    models.transition(model, k, t, x, values, mode, p)
    f_after = np.empty(n)
    models.rhs(model, t, x, mode, p, f_after)
    jump = f_after - reset @ f_before
    for i in range(n):
        for j in range(n):
            matrix[i, j] = reset[i, j] + jump[i] * grad[j] / rates[k]


@numba.njit(cache=True)
def transition(model, k, t, y, values, mode, p):
    """The model's transition on ``y[:n]`` and ``Phi+ = S Phi-``."""
    n = models.state_size(model)
    salt = np.empty((n, n))
    saltation(model, k, t, y[:n], values, mode, p, salt)
    phi = y[n:].copy()
    for i in range(n):
        for j in range(n):
            acc = 0.0
            for r in range(n):
                acc += salt[i, r] * phi[r * n + j]
            y[n + i * n + j] = acc
