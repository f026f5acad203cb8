"""Follower lift laws of one cam segment, compiled: the lift ``s`` [m] and its first three
derivatives in the cam angle, ``s'`` [m/rad], ``s''`` [m/rad^2] and ``s'''`` [m/rad^3].

A segment starts at cam angle ``theta_start`` [rad] and spans ``span`` [rad]; inside it
``u = (theta - theta_start) / span`` runs from 0 to 1. The rise and return laws are
``s = s0 + L f(u)`` with the lift ``L`` [m] (negative for a return) and the standard
normalised forms of cam design (R. L. Norton, *Cam Design and Manufacturing Handbook*,
2nd ed., Industrial Press 2009; H. A. Rothbart, *Cam Design Handbook*,
McGraw-Hill 2004):

- cycloidal:        ``f = u - sin(2 pi u) / (2 pi)``
- simple harmonic:  ``f = (1 - cos(pi u)) / 2``
- 3-4-5 polynomial: ``f = 10 u^3 - 15 u^4 + 6 u^5``
- 4-5-6-7 polynomial: ``f = 35 u^4 - 84 u^5 + 70 u^6 - 20 u^7``

A circular arc of the cam (centre at distance ``d`` [m] from the cam's axis, at polar
angle ``phi_c`` [rad] in the cam's frame, radius ``rho`` [m]) gives, with
``phi = theta - phi_c``,

- for a flat-faced translating follower, the support function of the circle,
  ``h = d cos(phi) + rho`` (Rothbart 2004: the follower face is tangent to the
  arc);
- for a knife-edge in-line follower (or a roller's centre, with ``rho`` the arc's radius
  plus the roller's), the distance from the axis to the circle along the follower's line,
  ``h = d cos(phi) + sqrt(rho^2 - d^2 sin(phi)^2)`` (the law of cosines in the triangle
  axis, arc centre, contact point);

and the lift is ``s = h - r_base`` with the base radius ``r_base`` [m]. A tabulated lift
is a cubic per interval, ``s = c0 + c1 t + c2 t^2 + c3 t^3`` with ``t = theta -
theta_start`` [rad].
"""

from __future__ import annotations

import math

import numba

#: Segment kinds (stored as floats in a profile table).
DWELL = 0
CYCLOIDAL = 1
HARMONIC = 2
POLYNOMIAL_345 = 3
POLYNOMIAL_4567 = 4
ARC = 5
CUBIC = 6
#: Forms of an arc segment: the follower's line crosses the arc (knife-edge, roller
#: centre) or its flat face touches it.
ARC_RAY = 0.0
ARC_FLAT = 1.0


@numba.njit(cache=True)
def normalised(kind, u):
    """The normalised rise ``f(u)`` and its derivatives ``f', f'', f'''`` in ``u`` [-]."""
    if kind == CYCLOIDAL:
        w = 2.0 * math.pi
        return (u - math.sin(w * u) / w, 1.0 - math.cos(w * u), w * math.sin(w * u), w * w * math.cos(w * u))
    if kind == HARMONIC:
        a = math.pi
        return (0.5 * (1.0 - math.cos(a * u)), 0.5 * a * math.sin(a * u), 0.5 * a * a * math.cos(a * u),
                -0.5 * a ** 3 * math.sin(a * u))
    if kind == POLYNOMIAL_345:
        u2 = u * u
        return (u2 * u * (10.0 - 15.0 * u + 6.0 * u2), u2 * (30.0 - 60.0 * u + 30.0 * u2),
                u * (60.0 - 180.0 * u + 120.0 * u2), 60.0 - 360.0 * u + 360.0 * u2)
    if kind == POLYNOMIAL_4567:
        u2 = u * u
        u3 = u2 * u
        return (u3 * u * (35.0 - 84.0 * u + 70.0 * u2 - 20.0 * u3),
                u3 * (140.0 - 420.0 * u + 420.0 * u2 - 140.0 * u3),
                u2 * (420.0 - 1680.0 * u + 2100.0 * u2 - 840.0 * u3),
                u * (840.0 - 5040.0 * u + 8400.0 * u2 - 4200.0 * u3))
    return (0.0, 0.0, 0.0, 0.0)


@numba.njit(cache=True)
def arc(phi, d, rho, form):
    """Distance ``h`` [m] from the cam's axis to an arc along the follower at angle ``phi``
    [rad] from the arc's centre, and its derivatives ``h'``, ``h''``, ``h'''`` in ``phi``."""
    c = math.cos(phi)
    s = math.sin(phi)
    if form == ARC_FLAT:
        return d * c + rho, -d * s, -d * c, d * s
    # q = rho^2 - d^2 sin^2(phi) and its derivatives; h = d cos(phi) + sqrt(q)
    q = rho * rho - d * d * s * s
    q1 = -d * d * 2.0 * s * c
    q2 = -2.0 * d * d * (c * c - s * s)
    q3 = 4.0 * d * d * 2.0 * s * c
    root = math.sqrt(q)
    r1 = q1 / (2.0 * root)
    r2 = q2 / (2.0 * root) - q1 * q1 / (4.0 * root ** 3)
    r3 = q3 / (2.0 * root) - 3.0 * q1 * q2 / (4.0 * root ** 3) + 3.0 * q1 ** 3 / (8.0 * root ** 5)
    return d * c + root, -d * s + r1, -d * c + r2, d * s + r3


@numba.njit(cache=True)
def segment(row, theta):
    """Lift and derivatives ``(s, s', s'', s''')`` of a segment row at ``theta`` [rad]
    inside it.

    ``row`` holds ``(kind, theta_start, span, a0, a1, a2, a3, a4)``: for a dwell ``a0 =
    s0``; for a rise or return ``(s0, L)``; for an arc ``(d, phi_c, rho, form, r_base)``;
    for a cubic ``(c0, c1, c2, c3)``.
    """
    return segment_values(row[0], row[1], row[2], row[3], row[4], row[5], row[6], row[7], theta)


@numba.njit(cache=True)
def segment_values(kind_code, start, span, a0, a1, a2, a3, a4, theta):
    """:func:`segment` from the row's numbers ``(kind, theta_start, span, a0, ..., a4)``
    passed one by one (no array: a caller compiled into the integrator's loop passes
    no array to a call)."""
    kind = int(kind_code)
    t = theta - start
    if kind == DWELL:
        return a0, 0.0, 0.0, 0.0
    if kind == ARC:
        h, h1, h2, h3 = arc(theta - a1, a0, a2, a3)
        return h - a4, h1, h2, h3
    if kind == CUBIC:
        c0, c1, c2, c3 = a0, a1, a2, a3
        return (c0 + t * (c1 + t * (c2 + t * c3)), c1 + t * (2.0 * c2 + 3.0 * c3 * t), 2.0 * c2 + 6.0 * c3 * t,
                6.0 * c3)
    f0, f1, f2, f3 = normalised(kind, t / span)
    lift = a1
    return a0 + lift * f0, lift * f1 / span, lift * f2 / span ** 2, lift * f3 / span ** 3
