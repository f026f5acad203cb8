"""The cam as a rigid body: the cam-follower of :mod:`camdyn.model.dynamics` with the
cam shaft's rotation a state instead of a prescribed motion.

The follower obeys the same moment balance (eq 3.16, 4.13), evaluated at the cam angle
``Theta`` and speed ``Theta_dot`` of the state by :func:`camdyn.model.dynamics.evaluate_cam`.
The shaft, of inertia ``J`` [kg m^2] about the cam pivot E, turns counter-clockwise
(the sense of ``Theta``) under Euler's law for a rigid body about a fixed axis::

    J Theta_ddot = T_drive - T_bearing + T_contact                       (1)
    T_contact    = Fn n.(z x (Xc - E)) - Ff u.(z x (Xc - E))             (2)

(2) is the moment about E of the follower's reaction on the cam, ``+Fn n - Ff u`` at the
contact point ``Xc`` (the follower feels ``-Fn n + Ff u``, the convention of
:func:`camdyn.model.outputs.pivot_reaction`); by construction
``T_contact Theta_dot = -P_cam``, the power the cam delivers to the follower
(:mod:`camdyn.model.dynamics`), so the energy of the whole mechanism balances.

Drive torques ``T_drive`` [N m] (``DRIVE_KIND``):

0. constant, ``T0``;
1. a DC motor's torque-speed line, ``T_stall (1 - Theta_dot / omega_free)`` (a permanent
   magnet motor at constant voltage: Hughes and Drury, *Electric Motors and Drives*,
   5th ed., 2019, section 3.6);
2. a PI speed controller with feed-forward, ``T0 + Kp (omega_ref - Theta_dot) + Ki z``,
   ``z' = omega_ref - Theta_dot`` (Astrom and Murray, *Feedback Systems*, 2008, eq 10.6);
3. a prescribed speed: the drive holds ``Theta_dot`` at its starting value whatever the
   load, ``Theta_ddot = 0`` and ``T_drive = T_bearing - T_contact`` (the limit
   ``J -> infinity`` of (1)): the cam of the rocking follower, turning at constant speed.

Bearing friction ``T_bearing = c_b Theta_dot + T_c tanh(Theta_dot / omega_b)`` [N m]:
viscous plus a Coulomb torque smoothed over the speed ``omega_b`` (the tanh
regularisation of :mod:`camdyn.model.friction`).

State ``(alpha [rad], alpha_dot [rad/s], Theta [rad], Theta_dot [rad/s], z [rad],
W_drive [J], W_bearing [J], W_cam [J])``: the follower, the shaft, the controller's
integral, and three works integrated for the energy bookkeeping (the drive's input
``T_drive Theta_dot``, the bearing's loss ``T_bearing Theta_dot`` and the cam's power to
the follower ``P_cam``). The mode vector and guards are the cam-follower's
(:mod:`camdyn.model.layout`): contact, sliding sign, compression and approach velocity.

The parameter vector is the cam-follower's (:func:`camdyn.model.layout.pack`, whose
motion slots are unused) followed by the slots below.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.model import layout as L
from camdyn.model.dynamics import evaluate_cam
from camdyn.model.geometry import contact_kinematics_trig, contact_rates_trig

SHAFT_INERTIA = L.SIZE + 0     # J [kg m^2]
DRIVE_KIND = L.SIZE + 1        # 0 constant torque, 1 DC motor line, 2 PI speed controller, 3 prescribed
DRIVE_TORQUE = L.SIZE + 2      # T0 [N m]: the constant torque, or the controller's feed-forward
STALL_TORQUE = L.SIZE + 3      # T_stall [N m]
FREE_SPEED = L.SIZE + 4        # omega_free [rad/s]
PROPORTIONAL = L.SIZE + 5      # Kp [N m s/rad]
INTEGRAL = L.SIZE + 6          # Ki [N m/rad]
TARGET_SPEED = L.SIZE + 7      # omega_ref [rad/s]
BEARING_VISCOUS = L.SIZE + 8   # c_b [N m s/rad]
BEARING_COULOMB = L.SIZE + 9   # T_c [N m]
BEARING_SPEED = L.SIZE + 10    # omega_b [rad/s]
SIZE = L.SIZE + 11

DRIVE_KINDS = {"constant": 0, "motor": 1, "controller": 2, "prescribed": 3}
#: The prescribed speed's drive kind (``Theta_ddot = 0``).
PRESCRIBED = 3.0

STATE_SIZE = 8
CONTROLLED_SIZE = 5
GUARD_COUNT = 3

__all__ = ["drive_torque", "bearing_torque", "contact_torque", "contact_torque_parts", "channels", "CHANNELS",
           "accelerations", "rhs", "jacobian", "guards", "monitor", "SIZE", "STATE_SIZE", "DRIVE_KINDS"]


@numba.njit(cache=True)
def drive_torque(theta_dot, integral, p):
    """Drive torque ``T_drive`` [N m] at shaft speed ``theta_dot`` [rad/s] with the
    controller's integral ``integral`` [rad] (module docstring, kinds 0-2; 0 for the
    prescribed speed, kind 3, whose torque :func:`accelerations` solves from the load)."""
    kind = p[DRIVE_KIND]
    if kind == PRESCRIBED:
        return 0.0
    if kind == 0.0:
        return p[DRIVE_TORQUE]
    if kind == 1.0:
        return p[STALL_TORQUE] * (1.0 - theta_dot / p[FREE_SPEED])
    return p[DRIVE_TORQUE] + p[PROPORTIONAL] * (p[TARGET_SPEED] - theta_dot) + p[INTEGRAL] * integral


@numba.njit(cache=True)
def shaft_compliance(p):
    """``1 / J`` [1/(kg m^2)], the factor of eq (1); 0 for a prescribed speed (kind 3)."""
    if p[DRIVE_KIND] == PRESCRIBED:
        return 0.0
    return 1.0 / p[SHAFT_INERTIA]


@numba.njit(cache=True)
def bearing_torque(theta_dot, p):
    """Bearing friction torque ``c_b Theta_dot + T_c tanh(Theta_dot / omega_b)`` [N m],
    opposing the rotation."""
    torque = p[BEARING_VISCOUS] * theta_dot
    if p[BEARING_COULOMB] != 0.0:
        torque += p[BEARING_COULOMB] * math.tanh(theta_dot / p[BEARING_SPEED])
    return torque


@numba.njit(cache=True)
def contact_torque_parts(alpha, theta, fn, ff, p):
    """The two terms of eq (2) [N m]: the counter-clockwise moments about the cam pivot E
    of the normal reaction ``+Fn n`` and of the friction reaction ``-Ff u`` on the cam,
    for a normal force ``fn`` [N] and a friction force ``ff`` [N] on the follower along
    ``u``. The lever arms are the cam's material velocity at the contact point for a unit
    shaft speed (:func:`camdyn.model.geometry.contact_kinematics_trig`)."""
    ca = math.cos(alpha)
    sa = math.sin(alpha)
    delta, delta_dot, chi, rho_c, vr, n_arm, u_arm = contact_kinematics_trig(
        ca, sa, math.cos(theta), math.sin(theta), 0.0, 1.0, p)
    return fn * n_arm, -ff * u_arm


@numba.njit(cache=True)
def contact_torque(alpha, theta, fn, ff, p):
    """Counter-clockwise moment about the cam pivot E [N m] of the follower's reaction on
    the cam, eq (2) (the sum of :func:`contact_torque_parts`)."""
    normal, friction = contact_torque_parts(alpha, theta, fn, ff, p)
    return normal + friction


@numba.njit(cache=True)
def accelerations(y, mode, p):
    """Follower and shaft accelerations and the powers of the state's works.

    Returns
    -------
    tuple
        ``(alpha_ddot [rad/s^2], theta_ddot [rad/s^2], T_drive [N m], T_bearing [N m],
        T_contact [N m], P_cam [W], Fn [N], Ff [N])``
    """
    res = evaluate_cam(y[2], y[3], y[0], y[1], mode, p, 0.0)
    fn = res[1]
    ff = res[2]
    torque = 0.0
    if mode[L.MODE_CONTACT] > 0.5:
        torque = contact_torque(y[0], y[2], fn, ff, p)
    drive = drive_torque(y[3], y[4], p)
    bearing = bearing_torque(y[3], p)
    if p[DRIVE_KIND] == PRESCRIBED:          # the torque that holds the speed: eq (1) with Theta_ddot = 0
        drive = bearing - torque
    theta_ddot = (drive - bearing + torque) * shaft_compliance(p)     # eq (1)
    return res[0], theta_ddot, drive, bearing, torque, res[10], fn, ff


@numba.njit(cache=True)
def rhs(t, y, mode, p, dydt):
    """Right-hand side ``dy/dt`` of the eight states (module docstring)."""
    alpha_ddot, theta_ddot, drive, bearing, torque, power, fn, ff = accelerations(y, mode, p)
    dydt[0] = y[1]
    dydt[1] = alpha_ddot
    dydt[2] = y[3]
    dydt[3] = theta_ddot
    dydt[4] = p[TARGET_SPEED] - y[3]
    dydt[5] = drive * y[3]
    dydt[6] = bearing * y[3]
    dydt[7] = power


@numba.njit(cache=True)
def jacobian(t, y, mode, p, jac):
    """``d f / d y`` (8 x 8) by central differences of :func:`rhs` in the five dynamic
    states (the works feed back into nothing: their columns are zero). The relative step
    ``1e-7`` moves the penetration by about ``chi 1e-7`` [m], far above its rounding."""
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
    """The cam-follower's guards ``(delta [m], vr [m/s], delta_dot [m/s])`` and their exact
    rates (:func:`camdyn.model.dynamics.guards`), at the state's cam angle and speed; the
    rates of ``vr`` and ``delta_dot`` need the accelerations ``f[1]``, ``f[3]`` and are NaN
    when they are not ``known``."""
    alpha_ddot = f[1] if known else math.nan
    theta_ddot = f[3] if known else math.nan
    delta, vr, delta_dot, vr_dot, delta_ddot = contact_rates_trig(
        math.cos(y[0]), math.sin(y[0]), math.cos(y[2]), math.sin(y[2]), y[1], alpha_ddot, y[3], theta_ddot, p)
    values[0] = delta
    values[1] = vr
    values[2] = delta_dot
    rates[0] = delta_dot
    rates[1] = vr_dot
    rates[2] = delta_ddot


# The contact modes, their guards' expected signs, transitions and the initial mode are the
# cam-follower's (camdyn.model.dynamics: mode_*), applied by camdyn.systems.mechanisms.
@numba.njit(cache=True)
def monitor(t, y, mode, p):
    """Normal force [N] during an impact (its peak goes to the event log), else 0."""
    if mode[L.MODE_CONTACT] > 0.5 and mode[L.MODE_IMPACT] > 0.5:
        return evaluate_cam(y[2], y[3], y[0], y[1], mode, p, 0.0)[1]
    return 0.0


#: name, unit, long name of each derived channel of :func:`channels`, in column order.
CHANNELS = (
    ("alpha_ddot", "rad/s^2", "follower angular acceleration"),
    ("cam_acceleration", "rad/s^2", "cam shaft angular acceleration Theta_ddot"),
    ("drive_torque", "N m", "drive torque on the cam shaft"),
    ("bearing_torque", "N m", "bearing friction torque (opposing the rotation)"),
    ("contact_torque", "N m", "moment of the follower's reaction on the cam about its pivot"),
    ("friction_torque", "N m", "moment of the contact friction on the cam about its pivot (part of contact_torque)"),
    ("Fn", "N", "normal contact force on the follower"),
    ("Ff", "N", "friction force on the follower along the bar (u)"),
    ("penetration", "m", "contact penetration delta (negative: gap)"),
    ("in_contact", "1", "1 while the follower touches the cam"),
)


@numba.njit(cache=True)
def channels(y, modes, p):
    """Channels of :data:`CHANNELS` at the sampled states ``y`` (n, 8) and modes ``modes``
    (n, mode size); NaN rows where the state is NaN (a run that stopped early)."""
    n = y.shape[0]
    out = np.full((n, len(CHANNELS)), np.nan)
    for i in range(n):
        if math.isnan(y[i, 0]):
            continue
        alpha_ddot, theta_ddot, drive, bearing, torque, power, fn, ff = accelerations(y[i], modes[i], p)
        row = out[i]
        row[0] = alpha_ddot
        row[1] = theta_ddot
        row[2] = drive
        row[3] = bearing
        row[4] = torque
        row[5] = contact_torque_parts(y[i, 0], y[i, 2], fn, ff, p)[1]
        row[6] = fn
        row[7] = ff
        row[8] = evaluate_cam(y[i, 2], y[i, 3], y[i, 0], y[i, 1], modes[i], p, 0.0)[5]
        row[9] = modes[i, L.MODE_CONTACT]
    return out
