"""A rigid-impact linear oscillator: a test model of the hybrid integrator with resets.

``x'' + 2 zeta w x' + w^2 x = A cos(W t)`` while ``x < sigma``; at the wall ``x = sigma``
the velocity jumps, ``x'+ = -r x'-`` (Newton's law of restitution). Its periodic impacting
orbits have closed forms (the free motion between impacts is the linear oscillator's), so
it tests event location and state resets without any cam. The third state component is
``integral of x dt`` [m s], as for the forced oscillator.

Parameter vector ``p``: ``(w [rad/s], zeta [-], A [m/s^2], W [rad/s], sigma [m], r [-])``.
"""

from __future__ import annotations

import numba

NATURAL = 0
DAMPING = 1
FORCE = 2
FORCING = 3
WALL = 4
RESTITUTION = 5
N_PARAMETERS = 6


@numba.njit(cache=True)
def guards(t, y, p, values, rates):
    """Guard 0 (the only one): the gap ``sigma - x`` [m] to the wall and its rate
    ``-x'`` [m/s]."""
    values[0] = p[WALL] - y[0]
    rates[0] = -y[1]


@numba.njit(cache=True)
def reset(y, p):
    """The impact: ``x'+ = -r x'-``."""
    y[1] = -p[RESTITUTION] * y[1]
