"""Coulomb friction at the cam contact of a translating follower
(:mod:`camdyn.model.translating_follower`, rigid law): a knife edge that slides, a flat face
whose friction loads only its guide, and a roller with spin inertia that rolls or slides.

Geometry (the translating follower's frame; the cam turns counter-clockwise at ``omega``
[rad/s] > 0). The follower's reference point (knife tip, roller centre) is at ``C = (eps,
Y)``, ``Y = sqrt(Rp^2 - eps^2) + x`` [m]. In contact its velocity relative to the cam's
material point under it is ``v_rel = omega (Y, s' - eps)`` (with ``x = s``, ``x' = omega
s'``), tangent to the pitch curve; its length is ``omega L``, ``L = sqrt(Y^2 + (s' -
eps)^2)`` [m]. The unit normal (from the cam into the follower) and tangent are ``n =
(-sin phi, cos phi)`` and ``t = (cos phi, sin phi)`` with the pressure angle ``tan phi =
(s' - eps) / Y`` (Norton 2009). The cam pushes the follower with ``N n + F t``: ``N`` [N]
normal, ``F`` [N] the friction along ``t``. Along the follower's line::

    F_line = N cos(phi) + F sin(phi)                                             (1)

where ``F_line`` [N] is the force that sustained rigid contact needs (eq. 3 of the
translating follower, ``m s_ddot + F0 + k s + c s_dot + m g``). The slip velocity [m/s]
of the follower's material point at the contact relative to the cam's (along ``t``)::

    u = omega L + r_r (omega_r - omega)                                          (2)

with ``omega_r`` [rad/s] the roller's spin (absolute; 0 and ``r_r = 0`` for a knife edge,
whose tip slides at ``u = omega L`` > 0). Coulomb's law, static ``mu_s`` and kinetic
``mu_k`` [-]:

- sliding: ``F = -mu_k N sign(u)`` and, by (1), ``N = F_line / (cos phi - mu_k sign(u)
  sin phi)`` (3) (Norton 2009, the normal force of a translating follower with friction);
- the roller's spin ``J_r omega_r' = r_r F`` (4) (the moment of ``F`` about its axle);
- rolling (``u = 0``): ``omega_r = omega (1 - L / r_r)``, so ``omega_r' = -omega^2 L_theta
  / r_r`` with ``L_theta = dL/dtheta = (Y s' + (s' - eps) s'') / L`` [m], the friction the
  spin needs ``F = J_r omega_r' / r_r`` (5) and ``N = (F_line - F sin phi) / cos phi`` (6);
  held while ``|F| <= mu_s N``.
- a flat face: its normal stays along the line (``phi = 0``) and the friction ``mu_k N``,
  normal to the line, loads only the guide: the line's dynamics are those without
  friction; the face slides at ``u = omega (r_base + s)``.

The landing (a Newton impact, or a capture) applies no friction impulse: the roller keeps
its spin through it and then slides until friction has spun it up to rolling (the roller
"skid"). Friction acts in sustained rigid contact only.

State ``(x [m], x' [m/s], omega_r [rad/s], Q [J])``, ``Q`` the heat of friction, ``Q' =
mu_k N |u|`` while sliding; only ``x`` and ``x'`` are error-controlled (so that without
friction the steps, and the results, are the translating follower's). Mode: the
translating follower's (contact, approach, segment, released), then slip: ``sign(u)``
while sliding, 0 while rolling. Guards: the translating follower's (0 the gap, 1 the line
force, 2 the profile's joints), then :data:`SLIP_GUARD` the slip velocity ``u`` (rate
``u' = omega^2 L_theta + r_r omega_r'``, a sliding roller) and :data:`CONE`, ``CONE + 1``
the margins ``mu_s N - F`` and ``mu_s N + F`` (a rolling roller; rates by central
differences in time, the rolling contact being a function of time alone).

**A rocking arm** (:mod:`camdyn.simulation.rocking_friction`) runs on this model with
its lift angle as ``x`` [rad] and the holding moment ``M`` [N m] in place of ``F_line``.
With the arm length ``L_a`` [m] and the pressure angle ``phi`` of the arm (eq. K4 of
:mod:`camdyn.model.rocking_roller`), the cam's force ``N n + F t`` on the roller, passed
to the arm at the roller's axle, has the moment ``N L_a cos(phi) + F L_a sin(phi)``
about the pivot (the normal's and the tangent's levers), so that eq. (1) holds with
``F_line = M / L_a`` and eqs. (2)-(6) with ``L`` the speed, per unit cam speed, of the
roller centre relative to the cam's point under it, ``V(theta)`` [m] (the arm's tables,
read from the block that the slot :data:`ARM` points to: ``L_a``, the start of the table
of ``V``, then the table of ``phi``).

Parameter vector: the translating follower's, then ``(arm, mu_s, mu_k, J_r [kg m^2])``
as its last four slots (read from the end, after the profile table; ``arm`` the start
of a rocking arm's block, 0 for a translating follower).

Reference: R. L. Norton, *Cam Design and Manufacturing Handbook*, 2nd ed., Industrial
Press 2009.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.model import profiles
from camdyn.model import translating_follower as tf

STATE_SIZE = 4
CONTROLLED_SIZE = 2
SLIP_GUARD = tf.GUARD_COUNT       # guard of the slip velocity u, after the translating follower's
CONE = tf.GUARD_COUNT + 1         # guards of the cone margins mu_s N - F and mu_s N + F
GUARD_COUNT = tf.GUARD_COUNT + 3
SLIP = tf.MODE_SIZE               # mode slot: sign of the slip velocity, 0 rolling
MODE_SIZE = tf.MODE_SIZE + 1
FRICTION_SLOTS = 4
ARM = -4                          # slot, from the end of p, of the start of a rocking arm's block (0: none)
FLAT_FACE = 0.0
KNIFE_FACE = 1.0
#: A slip [m/s] below this fraction of ``omega Rp`` at the start of a contact is rolling's
#: rounding (a spin set to rolling's from the geometry).
ROLLING_SLIP = 1e-13
#: Time step [s] of the central differences of the rolling guards' rates, per radian of cam.
RATE_STEP = 1e-6


@numba.njit(cache=True)
def coefficients(p):
    """``(mu_s [-], mu_k [-], J_r [kg m^2])`` from the end of ``p``."""
    n = p.size
    return p[n - 3], p[n - 2], p[n - 1]


@numba.njit(cache=True)
def arm_block(p):
    """The start in ``p`` of a rocking arm's block, 0 for a translating follower."""
    return int(p[p.size + ARM])


@numba.njit(cache=True)
def arm_geometry(theta, line, p):
    """``(sin phi, cos phi, V [m], V_theta [m], M / L_a [N])`` of a rocking arm at the cam
    angle ``theta`` [rad] with the holding moment ``line`` [N m] (module docstring)."""
    b = arm_block(p)
    phi = profiles.evaluate(p, b + 2, theta)[0]
    speed, slope, _, _ = profiles.evaluate(p, int(p[b + 1]), theta)
    return math.sin(phi), math.cos(phi), speed, slope, line / p[b]


@numba.njit(cache=True)
def rolls(p):
    """Whether the follower has a roller whose spin friction drives (``mu_s > 0``)."""
    return p[tf.FACE] == tf.ROLLER_FACE and coefficients(p)[0] > 0.0


@numba.njit(cache=True)
def geometry(t, p):
    """``(sin phi, cos phi, L [m], L_theta [m], F_line [N])`` of sustained contact at ``t``
    [s] (module docstring; a flat face: ``phi = 0``, ``L = r_base + s``)."""
    theta = p[tf.PHASE] + p[tf.SPEED] * t
    s, s1, s2, _ = profiles.evaluate(p, tf.PROFILE, theta)
    w = p[tf.SPEED]
    line = p[tf.MASS] * w * w * s2 + tf.spring_force(s, w * s1, p)   # eq. (3) of the translating follower
    if arm_block(p) != 0:
        return arm_geometry(theta, line, p)
    if p[tf.FACE] == FLAT_FACE:
        return 0.0, 1.0, p[tf.PRIME_RADIUS] + s, s1, line
    big = math.sqrt(p[tf.PRIME_RADIUS] ** 2 - p[tf.OFFSET] ** 2) + s
    a = s1 - p[tf.OFFSET]
    length = math.sqrt(big * big + a * a)
    return a / length, big / length, length, (big * s1 + a * s2) / length, line


@numba.njit(cache=True)
def slip_velocity(t, spin, p):
    """The slip velocity u [m/s] (eq. 2) at ``t`` [s] with the roller's spin [rad/s]."""
    length = geometry(t, p)[2]
    w = p[tf.SPEED]
    if p[tf.FACE] != tf.ROLLER_FACE:
        return w * length
    return w * length + p[tf.ROLLER_RADIUS] * (spin - w)


@numba.njit(cache=True)
def rolling_spin(t, p):
    """The roller's spin [rad/s] of rolling contact, ``omega (1 - L / r_r)`` (eq. 2, u = 0)."""
    return p[tf.SPEED] * (1.0 - geometry(t, p)[2] / p[tf.ROLLER_RADIUS])


@numba.njit(cache=True)
def forces(t, slip, p):
    """``(N [N], F [N], omega_r' [rad/s^2])`` in sustained contact at ``t`` [s], sliding
    with ``slip = sign(u)`` (eqs. 3, 4) or rolling, ``slip = 0`` (eqs. 5, 6)."""
    mu_s, mu_k, inertia = coefficients(p)
    sin, cos, _, l_theta, line = geometry(t, p)
    r = p[tf.ROLLER_RADIUS]
    if p[tf.FACE] == FLAT_FACE:
        return line, -mu_k * line * slip, 0.0   # the friction is normal to the line
    if slip == 0.0:
        w = p[tf.SPEED]
        spin_rate = -w * w * l_theta / r
        friction = inertia * spin_rate / r                     # eq. (5)
        return (line - friction * sin) / cos, friction, spin_rate   # eq. (6)
    normal = line / (cos - mu_k * slip * sin)                  # eq. (3)
    friction = -mu_k * slip * normal
    if p[tf.FACE] != tf.ROLLER_FACE or inertia == 0.0:
        return normal, friction, 0.0
    return normal, friction, r * friction / inertia            # eq. (4)


@numba.njit(cache=True)
def in_contact(mode, p):
    return mode[0] > 0.5 and p[tf.LAW] == tf.RIGID


@numba.njit(cache=True)
def rhs(t, y, mode, p, dydt):
    """The translating follower's eqs. for ``x, x'``; eqs. (4)-(5) for the spin and the
    heat of friction ``mu_k N |u|`` while sliding."""
    tf.rhs(t, y, mode, p, dydt)
    dydt[2] = 0.0
    dydt[3] = 0.0
    if not in_contact(mode, p):
        return
    normal, friction, spin_rate = forces(t, mode[SLIP], p)
    dydt[2] = spin_rate
    if mode[SLIP] != 0.0:   # |F| |u|, written sign(u) u so that it stays smooth up to the event
        dydt[3] = abs(friction) * mode[SLIP] * slip_velocity(t, y[2], p)


@numba.njit(cache=True)
def jacobian(t, y, mode, p, jac):
    """``d f / d y`` (4 x 4): the translating follower's block; the heat rate's slope in
    the spin while a roller slides."""
    tf.jacobian(t, y, mode, p, jac)   # zeroes the whole matrix first
    if in_contact(mode, p) and mode[SLIP] != 0.0 and p[tf.FACE] == tf.ROLLER_FACE:
        friction = forces(t, mode[SLIP], p)[1]
        jac[3, 2] = abs(friction) * p[tf.ROLLER_RADIUS] * mode[SLIP]


@numba.njit(cache=True)
def cone(t, p, values):
    """``mu_s N - F`` and ``mu_s N + F`` [N] of rolling contact at ``t`` [s] into
    ``values[CONE]`` and ``values[CONE + 1]``."""
    normal, friction, _ = forces(t, 0.0, p)
    mu_s = coefficients(p)[0]
    values[CONE] = mu_s * normal - friction
    values[CONE + 1] = mu_s * normal + friction


@numba.njit(cache=True)
def guards(t, y, f, known, p, values, rates):
    """The guards (module docstring) and their rates."""
    tf.guards(t, y, p, values, rates)
    w = p[tf.SPEED]
    values[SLIP_GUARD] = slip_velocity(t, y[2], p)
    rates[SLIP_GUARD] = w * w * geometry(t, p)[3] + p[tf.ROLLER_RADIUS] * (f[2] if known else math.nan)
    if not rolls(p):
        values[CONE] = values[CONE + 1] = rates[CONE] = rates[CONE + 1] = 1.0
        return
    h = RATE_STEP / w
    ahead = np.empty(GUARD_COUNT)
    behind = np.empty(GUARD_COUNT)
    cone(t + h, p, ahead)
    cone(t - h, p, behind)
    cone(t, p, values)
    for k in (CONE, CONE + 1):
        rates[k] = (ahead[k] - behind[k]) / (2.0 * h)


@numba.njit(cache=True)
def expected_sign(k, mode, p):
    """Gap and line force as the translating follower; the slip velocity keeps its sign
    while a roller slides, the cone margins stay positive while it rolls."""
    if k < SLIP_GUARD:
        return tf.expected_sign(k, mode, p)
    if not (rolls(p) and in_contact(mode, p)):
        return 0.0
    if k == SLIP_GUARD:
        return mode[SLIP]
    return 1.0 if mode[SLIP] == 0.0 else 0.0


@numba.njit(cache=True)
def hold_or_slip(t, y, mode, p):
    """At ``u = 0``: rolling, the spin set to rolling's exactly, if the cone holds the
    friction the spin needs (eq. 5), else sliding the way that friction would drive the
    spin (``sign(u) = -sign(F)``, the slip then grows away from zero)."""
    normal, friction, _ = forces(t, 0.0, p)
    if abs(friction) <= coefficients(p)[0] * normal:
        mode[SLIP] = 0.0
        y[2] = rolling_spin(t, p)
    else:
        mode[SLIP] = -1.0 if friction > 0.0 else 1.0


@numba.njit(cache=True)
def settle(t, y, mode, p):
    """The slip mode at the start of sustained contact at ``t`` [s]: the sign of ``u``
    (a roller without inertia spins up at once and rolls), or at ``u = 0`` (to
    :data:`ROLLING_SLIP`) :func:`hold_or_slip`."""
    if not rolls(p):
        mode[SLIP] = 1.0
        return
    u = slip_velocity(t, y[2], p)
    if abs(u) <= ROLLING_SLIP * p[tf.SPEED] * p[tf.PRIME_RADIUS] or coefficients(p)[2] == 0.0:
        hold_or_slip(t, y, mode, p)
        return
    mode[SLIP] = 1.0 if u > 0.0 else -1.0


@numba.njit(cache=True)
def transition(k, t, y, mode, p):
    """The translating follower's guards: its impact, capture, separation and joints (the
    spin kept), then the slip mode of a new contact; :data:`SLIP_GUARD`: the slip velocity
    vanished, rolling if the cone holds (the spin set to rolling's exactly), else a
    reversal; :data:`CONE` and ``CONE + 1``: the cone broke, sliding with ``u < 0`` or
    ``u > 0``."""
    if k < SLIP_GUARD:
        was = mode[0]
        tf.transition(k, t, y, mode, p)
        if mode[0] > 0.5 and was < 0.5:
            settle(t, y, mode, p)
        return
    if k == SLIP_GUARD:
        hold_or_slip(t, y, mode, p)
        return
    mode[SLIP] = -1.0 if k == CONE else 1.0


@numba.njit(cache=True)
def regime(mode):
    """The translating follower's regime (:func:`camdyn.model.translating_follower.regime`)."""
    return tf.regime(mode)


@numba.njit(cache=True)
def initial_mode(t, y, p, mode):
    """The translating follower's contact, then the slip mode."""
    tf.initial_mode(t, y, p, mode)
    mode[SLIP] = 0.0
    if in_contact(mode, p):
        settle(t, y, mode, p)


@numba.njit(cache=True)
def monitor(t, y, mode, p):
    """The normal force N [N] in contact, 0 in flight."""
    if not in_contact(mode, p):
        return 0.0
    return forces(t, mode[SLIP], p)[0]


def pack(head, static, kinetic, inertia, arm=None):
    """The parameter vector: the translating follower's ``head`` (with its profile table),
    a rocking arm's block from ``arm = (L_a [m], table of phi [rad], table of V [m])``
    (profile tables over the cam angle; None for a translating follower), then ``(the
    block's start, mu_s [-], mu_k [-], J_r [kg m^2])``."""
    if arm is None:
        return np.concatenate([head, [0.0, static, kinetic, inertia]])
    length, pressure, speed = arm
    block = [length, head.size + 2.0 + pressure.size]
    return np.concatenate([head, block, pressure, speed, [float(head.size), static, kinetic, inertia]])
