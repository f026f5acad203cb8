"""Two rocking followers on one cam turning as a rigid body (a drum-brake-like layout).

Each follower obeys the moment balance of the single rocking follower (eq 3.16, 4.13),
evaluated by :func:`camdyn.model.dynamics.evaluate_cam` with its own parameter block
(pivot, spring, contact, friction: :mod:`camdyn.model.layout`). Follower 2 is placed at
its pivot rotated by the angle ``phi`` [rad] counter-clockwise about the cam pivot E: in
its own frame (:mod:`camdyn.model.geometry`, rotated by ``phi``) the cam has turned by
``Theta - phi`` and gravity points along ``-y`` rotated by ``-phi``, so its block holds
``g cos(phi)`` (the model takes gravity along the frame's ``y`` only: the packing
refuses a placement with a gravity component along the bar's ``x``). The shaft, of
inertia ``J`` [kg m^2], takes both reactions (Euler's law about a fixed axis, as
:mod:`camdyn.model.driven_cam`, eq 1-2 there)::

    J Theta_ddot = T_drive - T_bearing + T_contact,1 + T_contact,2          (1)

A moment about E is the same in every frame rotated about E, so each follower's
``T_contact,i`` is :func:`camdyn.model.driven_cam.contact_torque` in its own frame.

State ``(alpha_1 [rad], alpha_1_dot [rad/s], alpha_2 [rad], alpha_2_dot [rad/s],
Theta [rad], Theta_dot [rad/s], z [rad], W_drive [J], W_bearing [J], W_cam,1 [J],
W_cam,2 [J])``: the followers, the shaft, the PI controller's integral, and the works of
the drive, the bearing and the cam on each follower, for the energy bookkeeping.

Coulomb friction has a stick phase (the switch model of :mod:`camdyn.model.stick_slip`,
Leine et al. 1998, doi:10.1023/A:1008289604683): while a follower sticks its sliding
velocity is held at zero (the cam rolls it) by the friction force that
:func:`accelerations` solves for, as long as that force stays within ``mu_s Fn``
(``mu_s >= mu_k``, the static coefficient); it slides again when the force reaches the
cone, and a sliding follower sticks where its sliding velocity crosses zero with the
force it needs inside the cone (else it slides on the other way).

The mode vector holds per follower a cam-follower mode (:mod:`camdyn.model.layout`,
``MODE_*``) and a stick flag, ``MODE_EACH`` slots; the guards are, per follower
(follower 1's first), the cam-follower's three (penetration, sliding velocity,
penetration rate), the stick's two (``mu_s Fn -+ F``) and the sprag margin
(:func:`sprag_margin`), whose zeros are reported as events (the compliant contact lets
the run go on through a self-locking phase, the normal force growing with the wedging).

Parameter vector: the driven cam's (:mod:`camdyn.model.driven_cam`: follower 1's block
and the drive's slots), the placement angle, each follower's ``mu_s``, the mode mirrored
for the guards, then follower 2's block (``L.SIZE`` slots, its motion slots unused).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.model import driven_cam
from camdyn.model import layout as L
from camdyn.model.driven_cam import bearing_torque, contact_torque_parts, drive_torque, shaft_compliance
from camdyn.model.dynamics import evaluate_cam, mode_expected_sign, mode_initial, mode_transition
from camdyn.model.geometry import contact_kinematics_trig, contact_point_rate, contact_rates_trig

PLACEMENT = driven_cam.SIZE + 0   # phi [rad]: follower 2's pivot rotated about E
STATIC = driven_cam.SIZE + 1      # mu_s [-] of follower 1, then of follower 2 (Coulomb friction's stick)
MIRROR = driven_cam.SIZE + 3      # the current mode, mirrored for the guards (MODE_SIZE slots)

FOLLOWERS = 2
STATE_SIZE = 11
CONTROLLED_SIZE = 7
GUARDS_EACH = 6
GUARD_COUNT = FOLLOWERS * GUARDS_EACH
MODE_EACH = L.MODE_SIZE + 2       # a cam-follower mode, the stick flag and the sprag margin's sign
MODE_STICK = L.MODE_SIZE
MODE_SPRAG = L.MODE_SIZE + 1      # +1 while the contact force's moment about P pushes the follower off, else -1
MODE_SIZE = FOLLOWERS * MODE_EACH
SECOND = MIRROR + MODE_SIZE       # first slot of follower 2's block
SIZE = SECOND + L.SIZE

__all__ = ["block", "frame_angle", "accelerations", "rhs", "jacobian", "guards", "expected_sign", "transition",
           "initial_mode", "monitor", "channels", "CHANNELS", "SIZE", "STATE_SIZE", "MODE_SIZE", "GUARD_COUNT"]


@numba.njit(cache=True)
def block(i, p):
    """Follower ``i``'s (0 or 1) cam-follower parameter block (a view of ``p``)."""
    if i == 0:
        return p
    return p[SECOND:SECOND + L.SIZE]


@numba.njit(cache=True)
def follower_mode(i, mode):
    """Follower ``i``'s cam-follower mode (a view of ``mode``, ``L.MODE_SIZE`` slots)."""
    return mode[i * MODE_EACH:i * MODE_EACH + L.MODE_SIZE]


@numba.njit(cache=True)
def frame_angle(i, theta, p):
    """The cam angle [rad] in follower ``i``'s frame: ``Theta`` for follower 1,
    ``Theta - phi`` for follower 2 (module docstring)."""
    if i == 0:
        return theta
    return theta - p[PLACEMENT]


@numba.njit(cache=True)
def follower_terms(i, y, mode, p):
    """Follower ``i``'s forces with its friction force ``F`` [N] left free.

    Returns
    -------
    tuple
        ``(a0 [rad/s^2], k [1/(kg m)], fn [N], f_slip [N], normal_torque [N m],
        lever [m], c0 [m/s^2], c_alpha [m], c_theta [m], power0 [W], vr [m/s])``:
        ``alpha_ddot = a0 + k F``; the moment about E of its reaction on the cam is
        ``normal_torque + lever F`` (eq 2 of :mod:`camdyn.model.driven_cam`); the
        friction of the sliding mode is ``f_slip``; the sliding velocity's rate is
        ``vr_dot = c0 + c_alpha alpha_ddot + c_theta Theta_ddot`` (linear in the
        accelerations, :func:`camdyn.model.geometry.contact_rates_trig`); the cam's power
        to the follower is ``power0 + F u.v_cam`` with ``u.v_cam = -lever Theta_dot``.
    """
    q = block(i, p)
    m = follower_mode(i, mode)
    theta = frame_angle(i, y[4], p)
    alpha = y[2 * i]
    alpha_dot = y[2 * i + 1]
    res = evaluate_cam(theta, y[5], alpha, alpha_dot, m, q, 0.0)
    k = q[L.OFFSET] / q[L.INERTIA]               # the friction's moment +F h about P (camdyn.model.friction)
    if m[L.MODE_CONTACT] < 0.5:
        return res[0], k, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, res[7]
    fn = res[1]
    f_slip = res[2]
    normal_torque, lever = contact_torque_parts(alpha, theta, fn, 1.0, q)
    ca = math.cos(alpha)
    sa = math.sin(alpha)
    ct = math.cos(theta)
    st = math.sin(theta)
    c0 = contact_rates_trig(ca, sa, ct, st, alpha_dot, 0.0, y[5], 0.0, q)[3]
    c_alpha = contact_rates_trig(ca, sa, ct, st, alpha_dot, 1.0, y[5], 0.0, q)[3] - c0
    c_theta = contact_rates_trig(ca, sa, ct, st, alpha_dot, 0.0, y[5], 1.0, q)[3] - c0
    power0 = res[10] + f_slip * lever * y[5]
    return res[0] - k * f_slip, k, fn, f_slip, normal_torque, lever, c0, c_alpha, c_theta, power0, res[7]


@numba.njit(cache=True)
def accelerations(y, mode, p):
    """Accelerations, friction forces and the powers of the state's works.

    A sliding follower's friction is Coulomb's (or the smoothed law's), ``f_slip``; a
    sticking one's is the force that holds its sliding velocity at zero,
    ``vr_dot = 0``, solved with the moment balances (eq 3.16 of each follower, eq 1) in
    closed form: with ``alpha_i'' = a0_i + k_i F_i`` and ``J Theta'' = T0 + sum_j
    lever_j F_j``, each sticking ``i`` gives the row ``c_alpha,i k_i F_i + c_theta,i
    sum_j lever_j F_j / J = -(c0_i + c_alpha,i a0_i + c_theta,i T0 / J)``, each sliding
    one ``F_i = f_slip,i``; the 2 x 2 system is solved by Cramer's rule. (Its matrix on
    the sticking rows is ``-G M^-1 G^T``, negative definite with the compliant normal
    force: a stick never locks the mechanism.)

    Returns
    -------
    tuple
        ``(alpha_1_ddot [rad/s^2], alpha_2_ddot [rad/s^2], theta_ddot [rad/s^2],
        T_drive [N m], T_bearing [N m], T_contact,1 [N m], T_contact,2 [N m],
        P_cam,1 [W], P_cam,2 [W], F_1 [N], F_2 [N], Fn_1 [N], Fn_2 [N])``
    """
    t1 = follower_terms(0, y, mode, p)
    t2 = follower_terms(1, y, mode, p)
    drive = drive_torque(y[5], y[6], p)
    bearing = bearing_torque(y[5], p)
    compliance = shaft_compliance(p)          # 1 / J, or 0 at a prescribed speed
    base = (drive - bearing + t1[4] + t2[4]) * compliance
    rows = np.zeros((2, 3))
    for i in range(FOLLOWERS):
        t = t1 if i == 0 else t2
        if mode[i * MODE_EACH + MODE_STICK] > 0.5:
            rows[i, i] = t[7] * t[1]
            rows[i, 0] += t[8] * t1[5] * compliance
            rows[i, 1] += t[8] * t2[5] * compliance
            rows[i, 2] = -(t[6] + t[7] * t[0] + t[8] * base)
        else:
            rows[i, i] = 1.0
            rows[i, 2] = t[3]
    det = rows[0, 0] * rows[1, 1] - rows[0, 1] * rows[1, 0]
    force1 = (rows[0, 2] * rows[1, 1] - rows[0, 1] * rows[1, 2]) / det
    force2 = (rows[0, 0] * rows[1, 2] - rows[1, 0] * rows[0, 2]) / det
    theta_ddot = base + (t1[5] * force1 + t2[5] * force2) * compliance               # eq (1)
    torque1 = t1[4] + t1[5] * force1
    torque2 = t2[4] + t2[5] * force2
    if p[driven_cam.DRIVE_KIND] == driven_cam.PRESCRIBED:   # the torque that holds the speed (eq 1, Theta_ddot = 0)
        drive = bearing - torque1 - torque2
    power1 = t1[9] - force1 * t1[5] * y[5]
    power2 = t2[9] - force2 * t2[5] * y[5]
    return (t1[0] + t1[1] * force1, t2[0] + t2[1] * force2, theta_ddot, drive, bearing, torque1, torque2,
            power1, power2, force1, force2, t1[2], t2[2])


@numba.njit(cache=True)
def rhs(t, y, mode, p, dydt):
    """Right-hand side ``dy/dt`` of the eleven states (module docstring)."""
    res = accelerations(y, mode, p)
    acc1, acc2, theta_ddot, drive, bearing, torque1, torque2, power1, power2 = res[:9]
    dydt[0] = y[1]
    dydt[1] = acc1
    dydt[2] = y[3]
    dydt[3] = acc2
    dydt[4] = y[5]
    dydt[5] = theta_ddot
    dydt[6] = p[driven_cam.TARGET_SPEED] - y[5]
    dydt[7] = drive * y[5]
    dydt[8] = bearing * y[5]
    dydt[9] = power1
    dydt[10] = power2


@numba.njit(cache=True)
def jacobian(t, y, mode, p, jac):
    """``d f / d y`` (11 x 11) by central differences of :func:`rhs` in the seven dynamic
    states (the works feed back into nothing: their columns are zero), with the relative
    step ``1e-7`` of :func:`camdyn.model.driven_cam.jacobian`."""
    n = y.shape[0]
    jac[:, :] = 0.0
    up = np.empty(n)
    down = np.empty(n)
    probe = y.copy()
    for j in range(CONTROLLED_SIZE):
        step = 1e-7 * max(abs(y[j]), 1.0)
        probe[j] = y[j] + step
        span = probe[j]
        rhs(t, probe, mode, p, up)
        probe[j] = y[j] - step
        span -= probe[j]
        rhs(t, probe, mode, p, down)
        probe[j] = y[j]
        for i in range(n):
            jac[i, j] = (up[i] - down[i]) / span


@numba.njit(cache=True)
def guards(t, y, f, known, p, values, rates):
    """Per follower, five guards and their rates: the cam-follower's ``(delta [m],
    vr [m/s], delta_dot [m/s])`` with their exact rates
    (:func:`camdyn.model.dynamics.guards`) in its frame, NaN where the accelerations in
    ``f`` are not ``known``; and, for the stick, ``mu_s Fn - F`` and ``mu_s Fn + F`` [N]
    (``F`` the friction that holds it in the current mode, which the guards do not
    receive: :func:`transition` mirrors it into the ``MIRROR`` slots of ``p``; their
    rates are left NaN: the driver then brackets them at the step's midpoint); and the
    sprag margin ``chi + mu_k s h`` [m] (:func:`sprag_margin`) with its exact rate."""
    theta_ddot = f[5] if known else math.nan
    mirrored = p[MIRROR:MIRROR + MODE_SIZE]
    held = accelerations(y, mirrored, p)
    for i in range(FOLLOWERS):
        alpha_ddot = f[2 * i + 1] if known else math.nan
        theta = frame_angle(i, y[4], p)
        delta, vr, delta_dot, vr_dot, delta_ddot = contact_rates_trig(
            math.cos(y[2 * i]), math.sin(y[2 * i]), math.cos(theta), math.sin(theta), y[2 * i + 1], alpha_ddot,
            y[5], theta_ddot, block(i, p))
        k = GUARDS_EACH * i
        limit = p[STATIC + i] * held[11 + i]
        values[k] = delta
        values[k + 1] = vr
        values[k + 2] = delta_dot
        values[k + 3] = limit - held[9 + i]
        values[k + 4] = limit + held[9 + i]
        rates[k] = delta_dot
        rates[k + 1] = vr_dot
        rates[k + 2] = delta_ddot
        rates[k + 3] = math.nan
        rates[k + 4] = math.nan
        values[k + 5], rates[k + 5] = sprag_margin(i, y, mirrored, p)


@numba.njit(cache=True)
def sprag_margin(i, y, mode, p):
    """Follower ``i``'s sprag margin [m] and its rate [m/s]: the moment arm about P of its
    contact force per unit normal force, ``chi + mu_k s h`` (the clockwise moment
    ``Fn chi + Ff h`` of eq 3.16 with ``Ff = mu_k s Fn``, ``s`` the sliding sign of the
    mode). Positive, the contact force turns the follower away from the cam; where it
    reaches zero the force's line of action passes through the pivot and beyond it
    friction wedges the follower into the cam (self-locking, sprag-slip: Spurr, "A theory
    of brake squeal", Proc. IMechE Automobile Division, 1961). The rate is ``chi_dot``
    (:func:`camdyn.model.geometry.contact_point_rate`)."""
    q = block(i, p)
    theta = frame_angle(i, y[4], p)
    alpha = y[2 * i]
    chi = contact_kinematics_trig(math.cos(alpha), math.sin(alpha), math.cos(theta), math.sin(theta), 0.0, 0.0,
                                  q)[2]
    slip = mode[i * MODE_EACH + L.MODE_SLIP]
    return chi + q[L.MU] * slip * q[L.OFFSET], contact_point_rate(alpha, y[2 * i + 1], theta, y[5], q)


@numba.njit(cache=True)
def expected_sign(k, mode, p):
    """+1 or -1 for an active guard, 0 for an inactive one: the cam-follower's rule for
    its follower's first three, except the sliding velocity while it sticks; the stick
    guards while it sticks (and touches)."""
    i = k // GUARDS_EACH
    local = k - GUARDS_EACH * i
    m = follower_mode(i, mode)
    stuck = mode[i * MODE_EACH + MODE_STICK] > 0.5
    if local == 5:
        sliding = m[L.MODE_CONTACT] > 0.5 and not stuck and block(i, p)[L.FRICTION_LAW] == 1.0
        return mode[i * MODE_EACH + MODE_SPRAG] if sliding else 0.0
    if local >= 3:
        return 1.0 if stuck and m[L.MODE_CONTACT] > 0.5 else 0.0
    if local == 1 and stuck:
        return 0.0
    return mode_expected_sign(local, m, block(i, p))


@numba.njit(cache=True)
def set_stuck(i, stuck, mode, p):
    """Mark follower ``i`` sticking (``stuck``) or not, in the mode and its mirror in ``p``."""
    mode[i * MODE_EACH + MODE_STICK] = 1.0 if stuck else 0.0
    p[MIRROR:MIRROR + MODE_SIZE] = mode


@numba.njit(cache=True)
def can_stick(i, y, mode, p):
    """Whether follower ``i``, touching the cam under Coulomb friction with ``mu_s``,
    would stay stuck: the friction that holds it (the other follower as it is) is within
    ``mu_s Fn``. A negative ``mu_s`` slot turns the stick phase off."""
    if block(i, p)[L.FRICTION_LAW] != 1.0 or follower_mode(i, mode)[L.MODE_CONTACT] < 0.5 or p[STATIC + i] < 0.0:
        return False
    trial = mode.copy()
    trial[i * MODE_EACH + MODE_STICK] = 1.0
    held = accelerations(y, trial, p)
    return abs(held[9 + i]) <= p[STATIC + i] * held[11 + i]


@numba.njit(cache=True)
def transition(k, t, y, values, mode, p):
    """The mode after guard ``k`` crossed, for its follower: the cam-follower's rule
    (contact onset, separation, peak penetration), except at a zero of the sliding
    velocity, where it sticks if it can (:func:`can_stick`; its velocity is then set
    so that ``vr = 0`` exactly, a correction at the event's rounding) and otherwise
    slides on the other way; from a stick it slides forward (``F`` reached ``mu_s Fn``:
    the cam outruns it, ``vr > 0``) or backward. A sprag margin's zero flips its sign's
    flag only (the event is the report); every other switch sets the flag afresh."""
    i = k // GUARDS_EACH
    local = k - GUARDS_EACH * i
    m = follower_mode(i, mode)
    if local == 5:
        mode[i * MODE_EACH + MODE_SPRAG] = -mode[i * MODE_EACH + MODE_SPRAG]
        p[MIRROR:MIRROR + MODE_SIZE] = mode
        return
    if local == 3 or local == 4:
        m[L.MODE_SLIP] = 1.0 if local == 3 else -1.0
        set_stuck(i, False, mode, p)
    elif local == 1 and can_stick(i, y, mode, p):
        set_stuck(i, True, mode, p)
        hold_sliding_velocity(i, y, p)
    else:
        mode_transition(local, values[GUARDS_EACH * i:GUARDS_EACH * i + 3], m)
        set_stuck(i, mode[i * MODE_EACH + MODE_STICK] > 0.5 and m[L.MODE_CONTACT] > 0.5, mode, p)
    mode[i * MODE_EACH + MODE_SPRAG] = 1.0 if sprag_margin(i, y, mode, p)[0] >= 0.0 else -1.0
    p[MIRROR:MIRROR + MODE_SIZE] = mode


@numba.njit(cache=True)
def hold_sliding_velocity(i, y, p):
    """Set follower ``i``'s angular velocity [rad/s] to roll without sliding:
    ``vr = Theta_dot w - alpha_dot h = 0`` (:func:`camdyn.model.geometry.contact_rates_trig`)."""
    q = block(i, p)
    theta = frame_angle(i, y[4], p)
    ca = math.cos(y[2 * i])
    sa = math.sin(y[2 * i])
    rolling = contact_rates_trig(ca, sa, math.cos(theta), math.sin(theta), 0.0, 0.0, y[5], 0.0, q)[1]
    y[2 * i + 1] = rolling / q[L.OFFSET]


@numba.njit(cache=True)
def initial_mode(t, y, p, mode):
    """The mode at the start: each follower in contact where its penetration is
    positive; sticking where its sliding velocity is zero and it can stick."""
    values = np.empty(GUARD_COUNT)
    rates = np.empty(GUARD_COUNT)
    p[MIRROR:MIRROR + MODE_SIZE] = 0.0
    guards(t, y, y, False, p, values, rates)
    mode[:] = 0.0
    for i in range(FOLLOWERS):
        mode_initial(values[GUARDS_EACH * i:GUARDS_EACH * i + 3], block(i, p), follower_mode(i, mode))
    p[MIRROR:MIRROR + MODE_SIZE] = mode
    for i in range(FOLLOWERS):
        if values[GUARDS_EACH * i + 1] == 0.0 and can_stick(i, y, mode, p):
            set_stuck(i, True, mode, p)
    for i in range(FOLLOWERS):
        mode[i * MODE_EACH + MODE_SPRAG] = 1.0 if sprag_margin(i, y, mode, p)[0] >= 0.0 else -1.0
    p[MIRROR:MIRROR + MODE_SIZE] = mode


@numba.njit(cache=True)
def regime(mode):
    """0 while both followers fly, 1 while either touches the cam."""
    for i in range(FOLLOWERS):
        if mode[i * MODE_EACH + L.MODE_CONTACT] > 0.5:
            return 1
    return 0


@numba.njit(cache=True)
def monitor(t, y, mode, p):
    """The larger normal force [N] of the followers under impact (its peak goes to the
    event log), else 0."""
    peak = 0.0
    for i in range(FOLLOWERS):
        m = follower_mode(i, mode)
        if m[L.MODE_CONTACT] > 0.5 and m[L.MODE_IMPACT] > 0.5:
            peak = max(peak, follower_terms(i, y, mode, p)[2])
    return peak


#: name, unit, long name of each per-follower channel of :func:`channels`.
CHANNELS = (
    ("alpha_ddot", "rad/s^2", "follower angular acceleration"),
    ("contact_torque", "N m", "moment of the follower's reaction on the cam about its pivot"),
    ("Fn", "N", "normal contact force on the follower"),
    ("Ff", "N", "friction force on the follower along its bar (u)"),
    ("sliding_velocity", "m/s", "sliding velocity vr of the cam on the follower along u"),
    ("penetration", "m", "contact penetration delta (negative: gap)"),
    ("in_contact", "1", "1 while the follower touches the cam"),
    ("sticking", "1", "1 while the contact sticks"),
    ("sprag_margin", "m", "moment arm about the pivot of the contact force per unit normal force, chi + mu_k s h"),
)
#: name, unit, long name of each shaft channel of :func:`channels`, after the followers'.
SHAFT_CHANNELS = (
    ("cam_acceleration", "rad/s^2", "cam shaft angular acceleration Theta_ddot"),
    ("drive_torque", "N m", "drive torque on the cam shaft"),
    ("bearing_torque", "N m", "bearing friction torque (opposing the rotation)"),
)


@numba.njit(cache=True)
def channels(y, modes, p):
    """Per-follower channels (n, 2, len(CHANNELS)) and shaft channels (n,
    len(SHAFT_CHANNELS)) at the sampled states ``y`` (n, 11) and modes ``modes``; NaN
    rows where the state is NaN (a run that stopped early)."""
    n = y.shape[0]
    per = np.full((n, FOLLOWERS, len(CHANNELS)), np.nan)
    shaft = np.full((n, len(SHAFT_CHANNELS)), np.nan)
    for r in range(n):
        if math.isnan(y[r, 0]):
            continue
        res = accelerations(y[r], modes[r], p)
        shaft[r, 0] = res[2]
        shaft[r, 1] = res[3]
        shaft[r, 2] = res[4]
        for i in range(FOLLOWERS):
            theta = frame_angle(i, y[r, 4], p)
            kin = contact_rates_trig(math.cos(y[r, 2 * i]), math.sin(y[r, 2 * i]), math.cos(theta), math.sin(theta),
                                     y[r, 2 * i + 1], 0.0, y[r, 5], 0.0, block(i, p))
            row = per[r, i]
            row[0] = res[i]
            row[1] = res[5 + i]
            row[2] = res[11 + i]
            row[3] = res[9 + i]
            row[4] = kin[1]
            row[5] = kin[0]
            row[6] = modes[r, i * MODE_EACH + L.MODE_CONTACT]
            row[7] = modes[r, i * MODE_EACH + MODE_STICK]
            row[8] = sprag_margin(i, y[r], modes[r], p)[0]
    return per, shaft
