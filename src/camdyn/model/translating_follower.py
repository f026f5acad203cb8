"""A translating follower on a cam of any profile (:mod:`camdyn.model.profiles`): a mass on
a preloaded spring, pushed by the cam, free to leave it and to land on it again.

The follower's position ``x`` [m] is measured along its line from where it rests on the
base circle, as the lift ``s`` is; the cam turns at constant speed, ``theta = theta0 +
omega t``. In free flight (the single-degree-of-freedom model of a spring-loaded
follower, as in R. L. Norton, *Cam Design and Manufacturing Handbook*, 2009)::

    m x'' = -F0 - k x - c x' - m g                                             (1)

with the spring's preload ``F0`` [N] at ``x = 0``, its stiffness ``k`` [N/m], viscous
damping ``c`` [N s/m] and gravity ``g`` [m/s^2] along ``-x``. The gap to the cam is
``x - s(theta)`` and its rate ``x' - omega s'``.

Two contact laws:

- **rigid** (law 0), as in the cam-follower example of the Siconos project after M. di
  Bernardo, G. Osorio and S. Santini: the follower lands on the cam with Newton's
  restitution, ``x'+ = s_dot - e (x'- - s_dot)`` with ``s_dot = omega s'`` (2). An impact
  slower than the capture velocity [m/s] (the end of an accumulation of impacts) puts
  the follower into sustained contact, where it follows the cam, ``x = s``, and the cam
  pushes with ``N = m omega^2 s'' + c omega s' + F0 + k s + m g`` (3, eq. 1 with ``x =
  s``); it leaves the cam where ``N`` falls to zero. Guard 0 is the gap, watched in
  flight; guard 1 the force ``N`` that sustained contact needs, with its rate ``N' = m
  omega^3 s''' + c omega^2 s'' + k omega s'``, watched in contact.
- **compliant** (law 1): a linear spring-dashpot (Kelvin-Voigt) penalty while the cam
  penetrates the follower by ``delta = s - x > 0``, ``N = kc delta + cc delta'`` added to
  eq. (1). For a single impact of the follower's mass alone it restitutes ``e =
  exp(-zeta pi / sqrt(1 - zeta^2))`` with ``zeta = cc / (2 sqrt(kc m))`` (the damped
  half-period of the contact oscillator), the relation used to match it to a Newton
  restitution. The force is left unclipped (it pulls briefly before separation), so that
  the relation holds exactly.

State ``(x [m], x' [m/s])``; mode ``(contact,)``, 0 in flight, 1 in contact.

Parameter vector ``p``: the slots below, then the profile table from :data:`PROFILE`.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.errors import ParameterError
from camdyn.model import profiles

MASS = 0            # m [kg]
STIFFNESS = 1       # k [N/m]
PRELOAD = 2         # F0 [N]
DAMPING = 3         # c [N s/m]
SPEED = 4           # omega [rad/s]
PHASE = 5           # theta0 [rad]
GRAVITY = 6         # g [m/s^2]
LAW = 7             # 0 rigid, 1 compliant
RESTITUTION = 8     # e [-]
CAPTURE = 9         # capture velocity [m/s]
CONTACT_STIFFNESS = 10  # kc [N/m]
CONTACT_DAMPING = 11    # cc [N s/m]
PROFILE = 12
RIGID = 0.0
COMPLIANT = 1.0
STATE_SIZE = 2
GUARD_COUNT = 2
MODE_SIZE = 1


@numba.njit(cache=True)
def cam(t, p):
    """Cam angle theta [rad] and the lift's ``(s [m], s_dot [m/s], s_ddot [m/s^2], s_dddot
    [m/s^3])`` in time at ``t`` [s]."""
    w = p[SPEED]
    theta = p[PHASE] + w * t
    s, s1, s2, s3 = profiles.evaluate(p, PROFILE, theta)
    return theta, s, w * s1, w * w * s2, w * w * w * s3


@numba.njit(cache=True)
def follower_state(t, y, mode, p):
    """The follower's position [m] and velocity [m/s]: the state, or in rigid contact the
    cam's lift and lift rate (which the state follows to the integration's accuracy)."""
    if p[LAW] == RIGID and mode[0] > 0.5:
        _, s, sd, _, _ = cam(t, p)
        return s, sd
    return y[0], y[1]


@numba.njit(cache=True)
def spring_force(x, v, p):
    """Force of spring, damper and gravity on the follower along ``-x`` [N] (eq. 1)."""
    return p[PRELOAD] + p[STIFFNESS] * x + p[DAMPING] * v + p[MASS] * p[GRAVITY]


@numba.njit(cache=True)
def contact_force(t, y, mode, p):
    """The cam's force on the follower N [N]: eq. (3) in rigid contact, the penalty in
    compliant contact, 0 in flight."""
    if mode[0] < 0.5:
        return 0.0
    _, s, sd, sdd, _ = cam(t, p)
    if p[LAW] == RIGID:
        return p[MASS] * sdd + spring_force(s, sd, p)
    return p[CONTACT_STIFFNESS] * (s - y[0]) + p[CONTACT_DAMPING] * (sd - y[1])


@numba.njit(cache=True)
def rhs(t, y, mode, p, dydt):
    """Eq. (1), plus the penalty in compliant contact. In rigid contact the follower moves
    with the cam, ``x' = s_dot``, ``x'' = s_ddot`` (the outputs take the cam's state itself,
    :func:`follower_state`). The integration in contact also makes the step control see
    the joints of the profile, where ``s''`` and so the contact force jump: a step across
    a joint is shortened, so that a contact force dipping below zero just after a joint
    is not stepped over. (At rtol 1e-12 or tighter the jumps of ``s''`` of a simple
    harmonic or circular-arc cam can then shrink the step below the resolution of
    time.)"""
    if p[LAW] == RIGID and mode[0] > 0.5:
        _, _, sd, sdd, _ = cam(t, p)
        dydt[0] = sd
        dydt[1] = sdd
        return
    dydt[0] = y[1]
    dydt[1] = (contact_force(t, y, mode, p) - spring_force(y[0], y[1], p)) / p[MASS]


@numba.njit(cache=True)
def jacobian(t, y, mode, p, jac):
    """``d f / d y`` (2 x 2)."""
    jac[:, :] = 0.0
    if p[LAW] == RIGID and mode[0] > 0.5:
        return
    m = p[MASS]
    jac[0, 1] = 1.0
    jac[1, 0] = -p[STIFFNESS] / m
    jac[1, 1] = -p[DAMPING] / m
    if mode[0] > 0.5:
        jac[1, 0] -= p[CONTACT_STIFFNESS] / m
        jac[1, 1] -= p[CONTACT_DAMPING] / m


@numba.njit(cache=True)
def guards(t, y, p, values, rates):
    """Guard 0: the gap ``x - s`` [m] and its rate [m/s]; guard 1: the force N [N] of
    sustained rigid contact (eq. 3) and its rate [N/s]."""
    _, s, sd, sdd, sddd = cam(t, p)
    values[0] = y[0] - s
    rates[0] = y[1] - sd
    values[1] = p[MASS] * sdd + spring_force(s, sd, p)
    rates[1] = p[MASS] * sddd + p[STIFFNESS] * sd + p[DAMPING] * sdd


@numba.njit(cache=True)
def expected_sign(k, mode, p):
    """The gap (guard 0) stays positive in flight and negative in compliant contact; the
    force of rigid contact (guard 1) stays positive while in contact."""
    contact = mode[0] > 0.5
    if k == 0:
        if not contact:
            return 1.0
        return -1.0 if p[LAW] == COMPLIANT else 0.0
    return 1.0 if contact and p[LAW] == RIGID else 0.0


@numba.njit(cache=True)
def transition(k, t, y, mode, p):
    """The mode after guard ``k`` crossed at ``t`` [s], and the reset of the state."""
    if p[LAW] == COMPLIANT:
        mode[0] = 1.0 - mode[0]
        return
    _, s, sd, sdd, _ = cam(t, p)
    if k == 1:   # the contact force fell to zero: separation, from the cam's state
        mode[0] = 0.0
        y[0] = s
        y[1] = sd
        return
    approach = y[1] - sd
    if -approach > p[CAPTURE]:
        y[1] = sd - p[RESTITUTION] * approach   # eq. (2)
        return
    y[0] = s
    y[1] = sd
    if p[MASS] * sdd + spring_force(s, sd, p) > 0.0:   # captured: the cam holds it
        mode[0] = 1.0


@numba.njit(cache=True)
def initial_mode(t, y, p, mode):
    """Contact where the follower starts on (or, compliant, in) the cam and, rigid, the
    cam pushes it."""
    _, s, sd, sdd, _ = cam(t, p)
    gap = y[0] - s
    mode[0] = 0.0
    if p[LAW] == COMPLIANT:
        if gap < 0.0:
            mode[0] = 1.0
    elif gap <= 0.0 and p[MASS] * sdd + spring_force(s, sd, p) > 0.0:
        mode[0] = 1.0


def pack(profile, mass, stiffness, preload, speed, damping=0.0, phase=0.0, gravity=0.0, law=RIGID,
         restitution=0.0, capture=0.0, contact_stiffness=0.0, contact_damping=0.0):
    """The parameter vector ``p`` (slots above, units there) with the profile's table."""
    head = np.zeros(PROFILE)
    head[[MASS, STIFFNESS, PRELOAD, DAMPING, SPEED, PHASE, GRAVITY, LAW, RESTITUTION, CAPTURE,
          CONTACT_STIFFNESS, CONTACT_DAMPING]] = (mass, stiffness, preload, damping, speed, phase, gravity, law,
                                                  restitution, capture, contact_stiffness, contact_damping)
    return np.concatenate([head, profile.table])


def penalty_damping(restitution, contact_stiffness, mass):
    """The dashpot cc [N s/m] of the compliant law that restitutes ``e`` in a single impact
    of ``mass`` [kg] on ``contact_stiffness`` [N/m]: ``zeta = -ln e / sqrt(pi^2 +
    ln^2 e)``, ``cc = 2 zeta sqrt(kc m)`` (the inverse of the relation above)."""
    if not 0.0 < restitution <= 1.0:
        raise ParameterError(f"the restitution must be in (0, 1], not {restitution}")
    log = math.log(restitution)
    zeta = -log / math.sqrt(math.pi ** 2 + log * log)
    return 2.0 * zeta * math.sqrt(contact_stiffness * mass)
