"""Two coupled oscillators, the second against a rigid wall: a test model of the hybrid
integrator with a state of 4 components and one guard.

Unit masses; mass 1 is tied to the ground by ``k1`` and driven by ``A cos(W t)``, mass 2
is tied to mass 1 by ``k2``; both have viscous damping ``c`` to the ground::

    x1'' = -(k1 + k2) x1 + k2 x2 - c x1' + A cos(W t)      (before any impact)
    x2'' = k2 (x1 - x2) - c x2'

At the wall ``x2 = sigma`` the velocity of mass 2 jumps, ``x2'+ = -r x2'-`` (Newton's
law of restitution). Between impacts the motion is linear, so tests compare it with a
matrix-exponential solution. State ``(x1 [m], x1' [m/s], x2 [m], x2' [m/s])``.

Parameter vector ``p``: ``(k1 [1/s^2], k2 [1/s^2], c [1/s], A [m/s^2], W [rad/s],
sigma [m], r [-])`` (stiffness and damping per unit mass).
"""

from __future__ import annotations

import math

import numba

GROUND_STIFFNESS = 0
COUPLING_STIFFNESS = 1
DAMPING = 2
FORCE = 3
FORCING = 4
WALL = 5
RESTITUTION = 6
N_PARAMETERS = 7
STATE_SIZE = 4


@numba.njit(cache=True, inline="always")
def rhs(t, y, p, dydt):
    """The equations of motion above."""
    k1 = p[GROUND_STIFFNESS]
    k2 = p[COUPLING_STIFFNESS]
    c = p[DAMPING]
    dydt[0] = y[1]
    dydt[1] = -(k1 + k2) * y[0] + k2 * y[2] - c * y[1] + p[FORCE] * math.cos(p[FORCING] * t)
    dydt[2] = y[3]
    dydt[3] = k2 * (y[0] - y[2]) - c * y[3]


@numba.njit(cache=True)
def jacobian(p, jac):
    """The constant Jacobian ``d f / d y`` (4 x 4)."""
    k1 = p[GROUND_STIFFNESS]
    k2 = p[COUPLING_STIFFNESS]
    c = p[DAMPING]
    jac[:, :] = 0.0
    jac[0, 1] = 1.0
    jac[1, 0] = -(k1 + k2)
    jac[1, 1] = -c
    jac[1, 2] = k2
    jac[2, 3] = 1.0
    jac[3, 0] = k2
    jac[3, 2] = -k2
    jac[3, 3] = -c


@numba.njit(cache=True)
def guards(t, y, p, values, rates):
    """Guard 0: the gap ``sigma - x2`` [m] to the wall and its rate ``-x2'`` [m/s]."""
    values[0] = p[WALL] - y[2]
    rates[0] = -y[3]


@numba.njit(cache=True)
def reset(y, p):
    """The impact: ``x2'+ = -r x2'-``."""
    y[3] = -p[RESTITUTION] * y[3]
