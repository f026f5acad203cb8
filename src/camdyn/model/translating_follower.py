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
- **Hertz** (law 2): the compliant contact with the Hertz stiffness of the materials and
  the geometry (:mod:`camdyn.model.contact`; K. L. Johnson, *Contact Mechanics*, 1985),
  ``N = F_k(delta) + c(delta) delta'``, ``1/E* = (1-nu_c^2)/Y_c + (1-nu_f^2)/Y_f`` (4).
  Line contact (a flat face, or a cylindrical roller, on a cam of width ``l``):
  ``F_k = (pi/4) E* l delta`` (5). Point contact (a crowned roller, or a knife edge with a
  tip radius ``r_f``): ``F_k = (4/3) E* sqrt(rho_e) delta^1.5`` (6) with ``1/rho_e =
  1/rho_cam + 1/r_f``, ``rho_cam`` the radius of curvature of the cam's surface at the
  contact (signed, negative where concave): the pitch curve's for a knife edge, the
  pitch curve's less the roller's radius for a roller (7). The damping ``c`` is one of
  the laws of :mod:`camdyn.model.contact`: none, viscous (``c`` = ``cc``), or a
  restitution law ``c = chi(e) F_k / v_approach``, so ``F_d = chi(e) F_k delta' /
  v_approach`` (Hunt and Crossley 1975, doi:10.1115/1.3423596; Lankarani and Nikravesh
  1990, doi:10.1115/1.2912617) with
  ``v_approach`` the approach velocity ``s_dot - x'`` at the contact's onset, kept in the
  mode. The force is left unclipped, as the linear law's. The penetration is measured
  along the follower's line (as for the linear law), so for a knife edge or roller the
  pressure angle is neglected in the contact law; the kinematics of a knife edge stay
  those of a sharp edge (its tip radius enters the stiffness only).

**A rocking arm** runs on this model with the arm's lift angle as ``x`` [rad] and the
contact angle as the lift ``s`` [rad] (:mod:`camdyn.simulation.rocking_roller`). Its Hertz
law then reads two more tables beside the profile's, sampled over the cam angle: the lever
``L_n(theta)`` [m] of the contact normal about the pivot and, for point contact, the
curvature ``kappa_cam(theta)`` [1/m] of the cam's surface at the contact (taking the place
of eq. 7's). To first order in the penetration the normal penetration, its rate and the
approach velocity are::

    delta_n = L_n delta,  delta_n' = L_n delta' + omega L_n' delta,  v_n = L_n (s_dot - x')   (8)

with ``delta = s - x`` [rad] and ``L_n' = dL_n/dtheta`` [m/rad]; the normal force ``N(delta_n,
delta_n')`` [N] of eqs. (4)-(7) acts on the arm with the moment::

    M = L_n N                                                                  (9)

[N m], the ``contact_force`` of this model. The slots ``LEVER`` and ``CURVATURE`` hold
where the two tables start in ``p`` (0 without them: a translating follower, whose
results they leave unchanged).


**Joints.** A profile of more than one segment that is not a spline (circular arcs,
rises and returns) has joints, the segments' start angles, where ``s''`` (and so the rigid
contact's force N, and the gap's acceleration) may jump. Guard 2 makes each joint an
event, so that no step straddles one: with ``u`` [rad] the cam angle past the start of
the segment under it, ``L`` [rad] the segment's span and ``j`` the segment's index counted
over revolutions (``index + n revolution`` of ``n`` segments), the guard is
``(-1)^j u (L - u) / L`` [rad], zero at both joints of the segment, of the segment's
sign inside it, with its exact rate ``(-1)^j omega (L - 2u) / L`` [rad/s]; the mode
keeps ``j``, and the guard's expected sign is ``(-1)^j``, so it crosses where the cam
passes the next joint. At the event the model re-decides: in rigid sustained contact
the follower separates at the joint, with the cam's state, if the force N (eq. 3) on the
far side of the joint is at most zero, else it stays; otherwise only the segment's index
moves on (and the step restarts). In rigid contact the state follows the law of the
mode's segment, continued past its end, so that a step reaching past the joint stays
smooth until the guard ends it there. Splines (``s''`` continuous) and one-segment
profiles have no joint guard. After a separation the gap starts at zero with zero rate (and at a
joint a positive acceleration ``-N/m``): a smooth motion on the contact's time scale, so
on a profile with joints the flight that follows takes the contact's step size
(:func:`regime`) until the next impact; with the step of the last flight, which ended
in an accumulation of impacts, the gap could stay below its rounding noise (a chain of
grazes that collapses the step). Profiles without joints keep the flight's step, so
that their runs stay those of the model without joint events.

State ``(x [m], x' [m/s])``; mode ``(contact, approach, segment, released)``: 0 in
flight, 1 in contact; the approach velocity [m/s] of the current contact (Hertz law);
the index ``j`` of the cam's segment counted over revolutions (profiles with joints,
else 0); 1 in a flight that began with a separation (profiles with joints), else 0.

Parameter vector ``p``: the slots below, then the profile table from :data:`PROFILE`.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.errors import ParameterError
from camdyn.model import contact as hertz
from camdyn.model import lift_laws, profiles

MASS = 0            # m [kg]
STIFFNESS = 1       # k [N/m]
PRELOAD = 2         # F0 [N]
DAMPING = 3         # c [N s/m]
SPEED = 4           # omega [rad/s]
PHASE = 5           # theta0 [rad]
GRAVITY = 6         # g [m/s^2]
LAW = 7             # 0 rigid, 1 compliant (linear), 2 Hertz
RESTITUTION = 8     # e [-]
CAPTURE = 9         # capture velocity [m/s]
CONTACT_STIFFNESS = 10  # kc [N/m]
CONTACT_DAMPING = 11    # cc [N s/m]; the viscous c of the Hertz law
CONTACT_KIND = 12   # Hertz: 0 point, 1 line (as camdyn.model.layout)
MODULUS = 13        # E* [Pa]
WIDTH = 14          # l [m] of line contact
FOLLOWER_RADIUS = 15    # r_f [m] of point contact: the roller's or the knife edge's tip radius
DAMPING_LAW = 16    # code of the damping law (camdyn.params.laws.TABLE)
V_REFERENCE = 17    # smallest approach velocity of the restitution laws [m/s]
FACE = 18           # 0 flat, 1 knife, 2 roller
PRIME_RADIUS = 19   # r_base + r_r [m]
OFFSET = 20         # epsilon [m]
ROLLER_RADIUS = 21  # r_r [m]
LEVER = 22          # start in p of the normal's lever table of a rocking arm (0: none, a translating follower)
CURVATURE = 23      # start in p of the arm's cam-curvature table (0: none)
PROFILE = 24
RIGID = 0.0
COMPLIANT = 1.0
HERTZ = 2.0
FACES = {"flat": 0.0, "knife": 1.0, "roller": 2.0}
ROLLER_FACE = 2.0
STATE_SIZE = 2
GUARD_COUNT = 3
MODE_SIZE = 4
JOINT = 2           # the joint guard's index
SEGMENT = 2         # the mode's slot of the segment index j (counted over revolutions)
RELEASED = 3        # the mode's slot: 1 in flight after a separation (profiles with joints), until an impact


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
def equivalent_curvature(theta, p):
    """``1/rho_e`` [1/m] of point contact at the cam angle ``theta`` [rad]: ``kappa_cam +
    1/r_f`` (eq. 7), the cam surface's curvature ``kappa_cam`` [1/m] from the pitch curve's
    ``kappa_p`` (a roller's surface is the pitch curve's inner offset by ``r_r``:
    ``kappa_cam = kappa_p / (1 - r_r kappa_p)``); for a rocking arm, ``kappa_cam`` from
    its curvature table."""
    if p[CURVATURE] != 0.0:   # a rocking arm: the cam surface's curvature sampled at its contact
        return profiles.evaluate(p, int(p[CURVATURE]), theta)[0] + 1.0 / p[FOLLOWER_RADIUS]
    s, s1, s2, _ = profiles.evaluate(p, PROFILE, theta)
    speed_cubed, cross = profiles.pitch_curvature_terms(theta, s, s1, s2, p[PRIME_RADIUS], p[OFFSET])
    kappa = cross / speed_cubed
    if p[FACE] == ROLLER_FACE:
        kappa = kappa / (1.0 - p[ROLLER_RADIUS] * kappa)
    return kappa + 1.0 / p[FOLLOWER_RADIUS]


@numba.njit(cache=True)
def equivalent_radius(theta, p):
    """``rho_e`` [m] of point contact at the cam angle ``theta`` [rad] (eq. 7)."""
    return 1.0 / equivalent_curvature(theta, p)


@numba.njit(cache=True)
def hertz_force(theta, delta, rate, approach, p):
    """The Hertz law's force N [N] (eqs. 4-7) at the penetration ``delta`` [m], its rate
    [m/s], the cam angle ``theta`` [rad] and the contact's approach velocity [m/s]; for a
    rocking arm (a lever table in ``p``) the moment ``L_n N`` [N m] (eqs. 8-9) at the
    angular penetration ``delta`` [rad] and its rate [rad/s], the approach velocity the
    normal one [m/s]."""
    line = p[CONTACT_KIND] != 0.0
    rho_e = 0.0 if line else equivalent_radius(theta, p)
    if p[LEVER] == 0.0:
        kd = hertz.stiffness_at(line, p[MODULUS], rho_e, p[WIDTH], delta)
        return hertz.damped_force(delta, rate, kd, approach, int(p[DAMPING_LAW]), p[CONTACT_DAMPING], 0.0, 0.0,
                                  p[RESTITUTION], p[V_REFERENCE], False)[0]
    # a rocking arm: the normal penetration L_n delta and its rate (eq. 8), the moment L_n N (eq. 9)
    lever, slope, _, _ = profiles.evaluate(p, int(p[LEVER]), theta)
    normal = lever * delta
    normal_rate = lever * rate + p[SPEED] * slope * delta
    kd = hertz.stiffness_at(line, p[MODULUS], rho_e, p[WIDTH], normal)
    return lever * hertz.damped_force(normal, normal_rate, kd, approach, int(p[DAMPING_LAW]), p[CONTACT_DAMPING],
                                      0.0, 0.0, p[RESTITUTION], p[V_REFERENCE], False)[0]


@numba.njit(cache=True)
def approach_velocity(t, y, p):
    """The approach velocity [m/s] of a penalty contact starting at ``t`` [s]: ``s_dot -
    x'``, times the normal's lever ``L_n`` [m] for a rocking arm (eq. 8)."""
    theta, _, sd, _, _ = cam(t, p)
    if p[LEVER] == 0.0:
        return sd - y[1]
    return profiles.evaluate(p, int(p[LEVER]), theta)[0] * (sd - y[1])


@numba.njit(cache=True)
def contact_force(t, y, mode, p):
    """The cam's force on the follower N [N]: eq. (3) in rigid contact, the penalty in
    compliant contact (linear, or Hertz eqs. 4-7), 0 in flight."""
    if mode[0] < 0.5:
        return 0.0
    theta, s, sd, sdd, _ = cam(t, p)
    if p[LAW] == RIGID:
        return p[MASS] * sdd + spring_force(s, sd, p)
    if p[LAW] == HERTZ:
        return hertz_force(theta, s - y[0], sd - y[1], mode[1], p)
    return p[CONTACT_STIFFNESS] * (s - y[0]) + p[CONTACT_DAMPING] * (sd - y[1])


@numba.njit(cache=True)
def rhs(t, y, mode, p, dydt):
    """Eq. (1), plus the penalty in compliant contact. In rigid contact the follower moves
    with the cam, ``x' = s_dot``, ``x'' = s_ddot`` (the outputs take the cam's state itself,
    :func:`follower_state`). On a profile with joints it follows the law of the mode's
    segment, continued past the segment's end (:func:`far_side`): a step that reaches
    past a joint integrates a smooth function, so the step control does not shrink the
    steps towards the joint before the joint guard (guard 2) can end the step there
    (with the cam's own jumping ``s''`` it did, down to picoseconds)."""
    if p[LAW] == RIGID and mode[0] > 0.5:
        if has_joints(p):
            _, sd, sdd = far_side(t, mode[SEGMENT], p)
        else:
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
    if mode[0] < 0.5:
        return
    if p[LAW] == COMPLIANT:
        jac[1, 0] -= p[CONTACT_STIFFNESS] / m
        jac[1, 1] -= p[CONTACT_DAMPING] / m
        return
    # the Hertz law by central differences in delta and its rate (N grows with both)
    theta, s, sd, _, _ = cam(t, p)
    delta = s - y[0]
    rate = sd - y[1]
    d = 1e-6 * max(abs(delta), 1e-12)
    v = 1e-6 * max(abs(rate), 1e-9)
    dn_delta = (hertz_force(theta, delta + d, rate, mode[1], p) - hertz_force(theta, delta - d, rate, mode[1], p))
    dn_rate = (hertz_force(theta, delta, rate + v, mode[1], p) - hertz_force(theta, delta, rate - v, mode[1], p))
    jac[1, 0] -= dn_delta / (2.0 * d) / m
    jac[1, 1] -= dn_rate / (2.0 * v) / m


@numba.njit(cache=True)
def has_joints(p):
    """Whether the profile has joints (more than one segment, not a spline)."""
    return p[PROFILE] > 1.5 and p[PROFILE + 1] != lift_laws.CUBIC


@numba.njit(cache=True)
def segment_at(theta, p):
    """The segment under the cam angle ``theta`` [rad]: its index ``j`` counted over
    revolutions (``index + n revolution``), the angle ``u`` [rad] past its start and its
    span ``L`` [rad]."""
    angle = theta % profiles.TWO_PI
    turns = round((theta - angle) / profiles.TWO_PI)
    index = profiles.segment_index(p, PROFILE, angle)
    row = PROFILE + 1 + index * profiles.ROW
    return index + p[PROFILE] * turns, angle - p[row + 1], p[row + 2]


@numba.njit(cache=True)
def joint_guard(t, p):
    """The joint guard ``(-1)^j u (L - u) / L`` [rad] and its rate [rad/s] at ``t`` [s]
    (see the module's docstring); 0 for a profile without joints."""
    if not has_joints(p):
        return 0.0, 0.0
    j, u, span = segment_at(p[PHASE] + p[SPEED] * t, p)
    sign = 1.0 if int(j) % 2 == 0 else -1.0
    return sign * u * (span - u) / span, sign * p[SPEED] * (span - 2.0 * u) / span


@numba.njit(cache=True)
def far_side(t, j, p):
    """The cam's lift [m], lift rate [m/s] and acceleration [m/s^2] at ``t`` [s] by the
    law of segment ``j`` (counted over revolutions) continued to ``t`` (before its start
    or past its end, whichever is nearer): on the far side of the joint at its start, as
    the cam is once it has passed it, and in contact until the joint at its end is
    taken."""
    n = int(p[PROFILE])
    row = PROFILE + 1 + (int(j) % n) * profiles.ROW
    w = p[SPEED]
    angle = (p[PHASE] + w * t) % profiles.TWO_PI
    past = angle - p[row + 1]
    if past < 0.0:
        past += profiles.TWO_PI
    if past > 0.5 * (p[row + 2] + profiles.TWO_PI):   # nearer the start than the end: before it
        past -= profiles.TWO_PI
    s, s1, s2, _ = lift_laws.segment(p[row:row + profiles.ROW], p[row + 1] + past)
    return s, w * s1, w * w * s2


@numba.njit(cache=True)
def guards(t, y, p, values, rates):
    """Guard 0: the gap ``x - s`` [m] and its rate [m/s]; guard 1: the force N [N] of
    sustained rigid contact (eq. 3) and its rate [N/s]; guard 2: the joints [rad] and
    the rate [rad/s] (:func:`joint_guard`)."""
    _, s, sd, sdd, sddd = cam(t, p)
    values[0] = y[0] - s
    rates[0] = y[1] - sd
    values[1] = p[MASS] * sdd + spring_force(s, sd, p)
    rates[1] = p[MASS] * sddd + p[STIFFNESS] * sd + p[DAMPING] * sdd
    values[JOINT], rates[JOINT] = joint_guard(t, p)


@numba.njit(cache=True)
def expected_sign(k, mode, p):
    """The gap (guard 0) stays positive in flight and negative in compliant contact; the
    force of rigid contact (guard 1) stays positive while in contact; the joint guard
    (guard 2) has the sign ``(-1)^j`` of the segment ``j`` the mode holds."""
    contact = mode[0] > 0.5
    if k == JOINT:
        if not has_joints(p):
            return 0.0
        return 1.0 if int(mode[SEGMENT]) % 2 == 0 else -1.0
    if k == 0:
        if not contact:
            return 1.0
        return -1.0 if p[LAW] != RIGID else 0.0
    return 1.0 if contact and p[LAW] == RIGID else 0.0


@numba.njit(cache=True)
def transition(k, t, y, mode, p):
    """The mode after guard ``k`` crossed at ``t`` [s], and the reset of the state."""
    if k == JOINT:
        joint_transition(t, y, mode, p)
        return
    if p[LAW] != RIGID:   # a penalty law: contact onset (with its approach velocity) or end
        mode[0] = 1.0 - mode[0]
        mode[1] = approach_velocity(t, y, p) if mode[0] > 0.5 else 0.0
        return
    theta, s, sd, sdd, _ = cam(t, p)
    if k == 1:   # the contact force fell to zero: separation, from the cam's state
        mode[0] = 0.0
        y[0] = s
        y[1] = sd
        if has_joints(p):   # the force may have jumped below zero at a joint not yet taken
            mode[SEGMENT] = segment_at(theta, p)[0]
            mode[RELEASED] = 1.0
        return
    approach = y[1] - sd
    if -approach > p[CAPTURE]:
        y[1] = sd - p[RESTITUTION] * approach   # eq. (2)
        mode[RELEASED] = 0.0
        return
    y[0] = s
    y[1] = sd
    if p[MASS] * sdd + spring_force(s, sd, p) > 0.0:   # captured: the cam holds it
        mode[0] = 1.0
        mode[RELEASED] = 0.0


@numba.njit(cache=True)
def joint_transition(t, y, mode, p):
    """The cam passed the joint at the start of segment ``j + 1`` at ``t`` [s]: the mode
    moves on to it; in rigid sustained contact the follower separates there, with the
    cam's state on the far side, if the force N (eq. 3) there is at most zero."""
    j = mode[SEGMENT] + 1.0
    mode[SEGMENT] = j
    if p[LAW] != RIGID or mode[0] < 0.5:
        return
    s, sd, sdd = far_side(t, j, p)
    if p[MASS] * sdd + spring_force(s, sd, p) <= 0.0:
        mode[0] = 0.0
        mode[RELEASED] = 1.0
        y[0] = s
        y[1] = sd


@numba.njit(cache=True)
def initial_mode(t, y, p, mode):
    """Contact where the follower starts on (or, compliant, in) the cam and, rigid, the
    cam pushes it."""
    _, s, sd, sdd, _ = cam(t, p)
    gap = y[0] - s
    mode[0] = 0.0
    mode[1] = 0.0   # no approach under way: the restitution laws use the reference velocity
    mode[SEGMENT] = segment_at(p[PHASE] + p[SPEED] * t, p)[0] if has_joints(p) else 0.0
    mode[RELEASED] = 0.0
    if p[LAW] != RIGID:
        if gap < 0.0:
            mode[0] = 1.0
    elif gap <= 0.0 and p[MASS] * sdd + spring_force(s, sd, p) > 0.0:
        mode[0] = 1.0


@numba.njit(cache=True)
def regime(mode):
    """The driver's regime of the mode (its last step size starts the next after an
    event): 1 in contact and in the flight after a separation (profiles with joints),
    else 0."""
    return 1 if mode[0] > 0.5 or mode[RELEASED] > 0.5 else 0


def pack(profile, mass, stiffness, preload, speed, damping=0.0, phase=0.0, gravity=0.0, law=RIGID,
         restitution=0.0, capture=0.0, contact_stiffness=0.0, contact_damping=0.0, hertz_law=None, lever=None,
         curvature=None):
    """The parameter vector ``p`` (slots above, units there) with the profile's table.

    ``hertz_law`` is a dict of the Hertz law's slots (``CONTACT_KIND``, ``MODULUS``,
    ``WIDTH``, ``FOLLOWER_RADIUS``, ``DAMPING_LAW``, ``V_REFERENCE``: slot -> value), for law 2.
    ``lever`` and ``curvature`` are a rocking arm's tables of ``L_n`` [m] and ``kappa_cam``
    [1/m] over the cam angle (in the profile table's format), appended after the profile's
    with their starts in the slots ``LEVER`` and ``CURVATURE``."""
    head = np.zeros(PROFILE)
    head[[MASS, STIFFNESS, PRELOAD, DAMPING, SPEED, PHASE, GRAVITY, LAW, RESTITUTION, CAPTURE,
          CONTACT_STIFFNESS, CONTACT_DAMPING]] = (mass, stiffness, preload, damping, speed, phase, gravity, law,
                                                  restitution, capture, contact_stiffness, contact_damping)
    head[[FACE, PRIME_RADIUS, OFFSET, ROLLER_RADIUS]] = (FACES[profile.follower], profile.prime_radius,
                                                         profile.offset, profile.roller_radius)
    for slot, value in (hertz_law or {}).items():
        head[slot] = value
    parts = [head, profile.table]
    for slot, table in ((LEVER, lever), (CURVATURE, curvature)):
        if table is not None:
            head[slot] = sum(part.size for part in parts)
            parts.append(np.asarray(table, dtype=float))
    return np.concatenate(parts)


def penalty_damping(restitution, contact_stiffness, mass):
    """The dashpot cc [N s/m] of the compliant law that restitutes ``e`` in a single impact
    of ``mass`` [kg] on ``contact_stiffness`` [N/m]: ``zeta = -ln e / sqrt(pi^2 +
    ln^2 e)``, ``cc = 2 zeta sqrt(kc m)`` (the inverse of the relation above)."""
    if not 0.0 < restitution <= 1.0:
        raise ParameterError(f"the restitution must be in (0, 1], not {restitution}")
    log = math.log(restitution)
    zeta = -log / math.sqrt(math.pi ** 2 + log * log)
    return 2.0 * zeta * math.sqrt(contact_stiffness * mass)
