"""Stick-slip of a mass on a spring dragged by a moving belt: a hybrid model with a
sticking mode, two slipping modes, and events that switch between them.

A mass ``m`` [kg] is tied to the ground by a spring ``k`` [N/m] and a damper ``c``
[N s/m] and rests on a belt that moves at the constant speed ``v`` [m/s]. The normal
force is the weight, ``N = m g`` [N]; the friction of the belt on the mass follows
Coulomb's law with a static coefficient ``mu_s`` and a kinetic one ``mu_k <= mu_s``
(Popp and Stelter 1990, doi:10.1098/rsta.1990.0098; Leine et al. 1998,
doi:10.1023/A:1008289604683, the "switch model")::

    m x'' = -k x - c x' + F                                       (1)
    slip  (x' != v):  F = -mu_k N sign(x' - v)                     (2)
    stick (x' = v):   F = k x + c v,   held while |F| <= mu_s N    (3)

``x`` [m] is the spring's extension. The mode ``mode[0]`` is the sign of the relative
velocity ``x' - v`` while slipping (+1 or -1), and 0 while sticking.

Guards, each with its exact time derivative:

0. the relative velocity ``x' - v`` [m/s] (active while slipping; rate ``x''``): at
   zero the mass sticks if the force needed to hold it, eq (3), is within
   ``mu_s N``, and otherwise slips on in the other direction (a reversal);
1. ``mu_s N - (k x + c x')`` [N] (active while sticking; rate ``-(k x' + c x'')``):
   the belt can no longer hold the mass back, which falls behind (mode -1);
2. ``mu_s N + (k x + c x')`` [N] (active while sticking): the mass is pushed ahead of
   the belt (mode +1).

The state is ``(x [m], x' [m/s], Q [J])`` with ``Q`` the heat dissipated by friction,
``dQ/dt = mu_k N |x' - v|`` while slipping (zero while sticking).

Parameter vector ``p``: ``(m [kg], k [N/m], c [N s/m], v [m/s], mu_s [-], mu_k [-],
g [m/s^2])``.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.errors import ParameterError

MASS = 0
STIFFNESS = 1
DAMPING = 2
BELT_SPEED = 3
STATIC = 4
KINETIC = 5
GRAVITY = 6
N_PARAMETERS = 7
STATE_SIZE = 3
GUARD_COUNT = 3

STICK = 0.0

__all__ = ["pack", "rhs", "jacobian", "guards", "expected_sign", "transition", "initial_mode",
           "holding_force", "STATE_SIZE", "GUARD_COUNT"]


def pack(mass: float, stiffness: float, belt_speed: float, static_friction: float, kinetic_friction: float,
         damping: float = 0.0, gravity: float = 9.80665) -> np.ndarray:
    """Parameter vector of the stick-slip model, checked.

    Parameters
    ----------
    mass : float
        Mass ``m`` [kg], positive.
    stiffness : float
        Spring stiffness ``k`` [N/m], positive.
    belt_speed : float
        Belt speed ``v`` [m/s], finite.
    static_friction, kinetic_friction : float
        Coefficients ``mu_s >= mu_k >= 0`` [-].
    damping : float
        Viscous damping ``c`` [N s/m], non-negative.
    gravity : float
        Gravitational acceleration ``g`` [m/s^2], positive.

    Raises
    ------
    ParameterError
        If a value is not finite, out of range, or ``mu_k > mu_s``.
    """
    values = {"mass": mass, "stiffness": stiffness, "belt speed": belt_speed, "static friction": static_friction,
              "kinetic friction": kinetic_friction, "damping": damping, "gravity": gravity}
    for name, value in values.items():
        if not math.isfinite(value):
            raise ParameterError(f"stick-slip: the {name} must be finite, got {value!r}")
    for name in ("mass", "stiffness", "gravity"):
        if values[name] <= 0.0:
            raise ParameterError(f"stick-slip: the {name} must be positive, got {values[name]!r}")
    for name in ("kinetic friction", "damping"):
        if values[name] < 0.0:
            raise ParameterError(f"stick-slip: the {name} must not be negative, got {values[name]!r}")
    if static_friction < kinetic_friction:
        raise ParameterError(f"stick-slip: the static friction coefficient ({static_friction}) must not be "
                             f"below the kinetic one ({kinetic_friction})")
    return np.array([mass, stiffness, damping, belt_speed, static_friction, kinetic_friction, gravity])


@numba.njit(cache=True)
def holding_force(x, x_dot, p):
    """Friction force [N] the belt must exert to keep the mass at zero acceleration,
    ``k x + c x'`` (eq 3 with ``x' = v``)."""
    return p[STIFFNESS] * x + p[DAMPING] * x_dot


@numba.njit(cache=True, inline="always")
def rhs(t, y, mode, p, dydt):
    """Right-hand side of eqs (1)-(3): ``(x', x'', dQ/dt)``."""
    if mode[0] == STICK:
        dydt[0] = p[BELT_SPEED]
        dydt[1] = 0.0
        dydt[2] = 0.0
        return
    normal = p[MASS] * p[GRAVITY]
    slip = mode[0]
    force = -p[KINETIC] * normal * slip                                        # eq (2)
    dydt[0] = y[1]
    dydt[1] = (force - p[STIFFNESS] * y[0] - p[DAMPING] * y[1]) / p[MASS]     # eq (1)
    dydt[2] = p[KINETIC] * normal * slip * (y[1] - p[BELT_SPEED])              # mu_k N |x' - v|


@numba.njit(cache=True)
def jacobian(t, y, mode, p, jac):
    """The Jacobian ``d f / d y`` (3 x 3) of :func:`rhs` in the current mode."""
    jac[:, :] = 0.0
    if mode[0] == STICK:
        return
    jac[0, 1] = 1.0
    jac[1, 0] = -p[STIFFNESS] / p[MASS]
    jac[1, 1] = -p[DAMPING] / p[MASS]
    jac[2, 1] = p[KINETIC] * p[MASS] * p[GRAVITY] * mode[0]


@numba.njit(cache=True)
def guards(t, y, f, known, p, values, rates):
    """Guards 0-2 of the module docstring and their rates (NaN where they need the
    acceleration ``f[1]`` [m/s^2] and it is not ``known``)."""
    x_ddot = f[1] if known else math.nan
    limit = p[STATIC] * p[MASS] * p[GRAVITY]
    held = holding_force(y[0], y[1], p)
    held_rate = p[STIFFNESS] * y[1] + (p[DAMPING] * x_ddot if p[DAMPING] != 0.0 else 0.0)
    values[0] = y[1] - p[BELT_SPEED]
    rates[0] = x_ddot
    values[1] = limit - held
    rates[1] = -held_rate
    values[2] = limit + held
    rates[2] = held_rate


@numba.njit(cache=True)
def expected_sign(k, mode, p):
    """+1 or -1 for an active guard, 0 for an inactive one."""
    if mode[0] == STICK:
        return 0.0 if k == 0 else 1.0
    return mode[0] if k == 0 else 0.0


@numba.njit(cache=True)
def transition(k, t, y, mode, p):
    """The mode after guard ``k`` crossed; at sticking the velocity is set to the belt's
    exactly (the event is located to rounding, and eq 3 holds it there)."""
    if k == 0:
        held = holding_force(y[0], p[BELT_SPEED], p)
        if abs(held) <= p[STATIC] * p[MASS] * p[GRAVITY]:
            mode[0] = STICK
            y[1] = p[BELT_SPEED]
        else:
            # a reversal: slipping on with sign s needs s x'' > 0, i.e. s (k x + c v) < -mu_k N
            # by eqs (1)-(2), so s = -sign(k x + c v) when |k x + c v| > mu_s N >= mu_k N
            mode[0] = -1.0 if held > 0.0 else 1.0
    elif k == 1:
        mode[0] = -1.0
    else:
        mode[0] = 1.0


@numba.njit(cache=True)
def initial_mode(t, y, p, mode):
    """Sticking if the mass moves with the belt and the belt can hold it, else slipping
    in the direction of the relative velocity (or of the net spring force at rest on
    the belt)."""
    relative = y[1] - p[BELT_SPEED]
    if relative != 0.0:
        mode[0] = 1.0 if relative > 0.0 else -1.0
        return
    held = holding_force(y[0], y[1], p)
    limit = p[STATIC] * p[MASS] * p[GRAVITY]
    if abs(held) <= limit:
        mode[0] = STICK
    else:
        mode[0] = -1.0 if held > 0.0 else 1.0
