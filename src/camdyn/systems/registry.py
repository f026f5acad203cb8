"""Registry of the hybrid systems the compiled driver can integrate: the only module of
:mod:`camdyn.systems` that the integrator imports.

A system id below :data:`VARIATIONAL` is a model (:mod:`camdyn.systems.models`, where
the interface each model provides is described and where a new model is added); the id
``VARIATIONAL + model`` is that model's variational system
(:mod:`camdyn.systems.variational`: the state with its state-transition matrix, and the
saltation matrix at every event), and ``k PARAMETRIC + VARIATIONAL + model`` the same
with ``k`` parameter sensitivities. Every function here dispatches on that split; the
driver sizes its arrays from :func:`state_size`, :func:`guard_count` and
:func:`mode_size`.
"""

from __future__ import annotations

import numba
import numpy as np

from camdyn.systems import models, variational
from camdyn.systems.models import (
    CAM_FOLLOWER,
    COUPLED_OSCILLATORS,
    DRIVEN_CAM,
    DRIVEN_CAM_ANGLE,
    FLEXIBLE_PIVOT,
    OSCILLATOR,
    RIGID_IMPACT,
    SLIDING_FOLLOWER,
    STICK_SLIP,
    TRANSLATING_FOLLOWER,
    TWO_FOLLOWERS,
    TWO_FOLLOWERS_ANGLE,
)
from camdyn.systems.variational import PARAMETRIC, VARIATIONAL

__all__ = ["CAM_FOLLOWER", "OSCILLATOR", "RIGID_IMPACT", "COUPLED_OSCILLATORS", "TRANSLATING_FOLLOWER", "STICK_SLIP",
           "DRIVEN_CAM", "FLEXIBLE_PIVOT", "TWO_FOLLOWERS", "SLIDING_FOLLOWER", "DRIVEN_CAM_ANGLE",
           "TWO_FOLLOWERS_ANGLE",
           "VARIATIONAL", "PARAMETRIC", "state_size", "controlled_size",
           "guard_count", "mode_size", "rhs", "rhs_inline", "jacobian", "guards",
           "guard_samples", "grid_values", "expected_sign", "transition", "initial_mode", "regime", "preferred_method",
           "plain_error_estimate", "monitor"]


@numba.njit(cache=True)
def _model(system):
    return variational.split(system)[0] if system >= VARIATIONAL else system


@numba.njit(cache=True)
def state_size(system):
    """Number of state components."""
    if system >= VARIATIONAL:
        model, count = variational.split(system)
        return variational.state_size(model, count)
    return models.state_size(system)


@numba.njit(cache=True)
def controlled_size(system):
    """Number of leading state components under error control (a variational system's
    all: its state and its matrix)."""
    if system >= VARIATIONAL:
        model, count = variational.split(system)
        return variational.state_size(model, count)
    return models.controlled_size(system)


@numba.njit(cache=True)
def guard_count(system):
    """Number of guard functions."""
    return models.guard_count(_model(system))


@numba.njit(cache=True)
def mode_size(system):
    """Number of slots of the mode vector (a variational system's adds the derivatives
    of a carried mode value: :func:`camdyn.systems.variational.mode_size`)."""
    if system >= VARIATIONAL:
        model, count = variational.split(system)
        return variational.mode_size(model, count)
    return models.mode_size(system)


@numba.njit(cache=True)
def rhs(system, t, y, mode, p, dydt):
    if system >= VARIATIONAL:
        model, count = variational.split(system)
        variational.rhs(model, count, t, y, mode, p, dydt)
    else:
        models.rhs(system, t, y, mode, p, dydt)


@numba.njit(cache=True, inline="always")
def rhs_inline(system, t, y, mode, p, dydt):
    """:func:`rhs` compiled into its caller (numba IR inlining): DOP853's stages use it."""
    if system >= VARIATIONAL:
        model, count = variational.split(system)
        variational.rhs(model, count, t, y, mode, p, dydt)
    else:
        models.rhs_inline(system, t, y, mode, p, dydt)


@numba.njit(cache=True)
def jacobian(system, t, y, f0, mode, p, jac):
    """The Jacobian ``jac = d f / d y`` (n x n) at ``(t, y)``, where ``f0 = f(t, y)``."""
    if system >= VARIATIONAL:
        model, count = variational.split(system)
        variational.jacobian(model, count, t, y, f0, mode, p, jac)
    else:
        models.jacobian(system, t, y, f0, mode, p, jac)


@numba.njit(cache=True)
def guards(system, t, y, f, known, p, values, rates):
    """Guard values and their exact rates (NaN where unknown) at ``(t, y)``; ``f`` is
    ``dy/dt`` there when ``known``."""
    if system >= VARIATIONAL:
        model = _model(system)
        n = models.state_size(model)
        models.guards(model, t, y[:n], f[:n], known, p, values, rates)
    else:
        models.guards(system, t, y, f, known, p, values, rates)


@numba.njit(cache=True)
def guard_samples(system, p, times, states, index, out):
    """Guard ``index``'s value at each sampled state ``states[i]`` at ``times[i]`` [s]
    into ``out[i]`` (its unit), as :func:`guards` gives it with the rates unknown."""
    m = guard_count(system)
    values = np.empty(m)
    rates = np.empty(m)
    for i in range(times.shape[0]):
        guards(system, times[i], states[i], states[i], False, p, values, rates)
        out[i] = values[index]


@numba.njit(cache=True)
def grid_values(system, times, states, mode, p, rates, jacs):
    """The rates ``rates[j] = f(t_j, y_j)`` and Jacobians ``jacs[j] = df/dy`` of ``system``
    at every time ``times[j]`` [s] and full state ``states[j]`` in mode ``mode``, in one
    compiled call (harmonic balance's grid, :mod:`camdyn.steady.harmonic_balance`)."""
    f = np.empty(states.shape[1])
    for j in range(times.shape[0]):
        rhs(system, times[j], states[j], mode, p, f)
        jacobian(system, times[j], states[j], f, mode, p, jacs[j])
        rates[j] = f


@numba.njit(cache=True)
def expected_sign(system, k, mode, p):
    """+1 or -1 for an active guard, 0 for an inactive one."""
    return models.expected_sign(_model(system), k, mode, p)


@numba.njit(cache=True)
def transition(system, k, t, y, values, mode, p):
    """The new mode after guard ``k`` crossed, and the state's reset if any."""
    if system >= VARIATIONAL:
        model, count = variational.split(system)
        variational.transition(model, count, k, t, y, values, mode, p)
    else:
        models.transition(system, k, t, y, values, mode, p)


@numba.njit(cache=True)
def initial_mode(system, t, y, p, mode):
    model = _model(system)
    models.initial_mode(model, t, y[:models.state_size(model)], p, mode)


@numba.njit(cache=True)
def regime(system, mode, p):
    """Index (0 or 1) of the dynamic regime of a mode (the driver remembers the last step
    of each)."""
    return models.regime(_model(system), mode, p)


@numba.njit(cache=True)
def plain_error_estimate(system):
    """Whether DOP853 steps of this system are controlled by their 5th-order error
    estimate alone, not Hairer's combination with the 3rd-order one: the cam-follower,
    whose Hertz force has a branch point at separation, near which the combination
    accepted a step with the 5th-order estimate at 41 times the tolerance
    (docs/integrator.md, *Accuracy in sustained contact*); not its variational system."""
    return system == CAM_FOLLOWER


@numba.njit(cache=True)
def preferred_method(system, mode, p):
    """Stepper for automatic selection: 1 Dormand-Prince 5(4), 2 RODAS4, 3 DOP853 (always
    DOP853 for a variational system)."""
    if system >= VARIATIONAL:
        return 3
    return models.preferred_method(system, mode, p)


@numba.njit(cache=True)
def monitor(system, t, y, mode, p):
    """A scalar whose maximum between events is logged."""
    model = _model(system)
    return models.monitor(model, t, y[:models.state_size(model)], mode, p)
