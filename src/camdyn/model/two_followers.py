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

The mode vector holds one cam-follower mode (:mod:`camdyn.model.layout`, ``MODE_*``)
per follower, ``L.MODE_SIZE`` slots each; the guards are the cam-follower's three
(penetration, sliding velocity, penetration rate) per follower, follower 1's first.

Parameter vector: the driven cam's (:mod:`camdyn.model.driven_cam`: follower 1's block
and the drive's slots), the placement angle, then follower 2's block (``L.SIZE`` slots,
its drive-and-motion slots unused).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.model import driven_cam
from camdyn.model import layout as L
from camdyn.model.driven_cam import bearing_torque, contact_torque, drive_torque
from camdyn.model.dynamics import evaluate_cam, mode_expected_sign, mode_initial, mode_transition
from camdyn.model.geometry import contact_rates_trig

PLACEMENT = driven_cam.SIZE + 0   # phi [rad]: follower 2's pivot rotated about E
SECOND = driven_cam.SIZE + 1      # first slot of follower 2's block
SIZE = SECOND + L.SIZE

FOLLOWERS = 2
STATE_SIZE = 11
CONTROLLED_SIZE = 7
GUARDS_EACH = 3
GUARD_COUNT = FOLLOWERS * GUARDS_EACH
MODE_SIZE = FOLLOWERS * L.MODE_SIZE

__all__ = ["block", "frame_angle", "accelerations", "rhs", "jacobian", "guards", "expected_sign", "transition",
           "initial_mode", "monitor", "channels", "CHANNELS", "SIZE", "STATE_SIZE", "MODE_SIZE", "GUARD_COUNT"]


@numba.njit(cache=True)
def block(i, p):
    """Follower ``i``'s (0 or 1) cam-follower parameter block (a view of ``p``)."""
    if i == 0:
        return p
    return p[SECOND:SECOND + L.SIZE]


@numba.njit(cache=True)
def frame_angle(i, theta, p):
    """The cam angle [rad] in follower ``i``'s frame: ``Theta`` for follower 1,
    ``Theta - phi`` for follower 2 (module docstring)."""
    if i == 0:
        return theta
    return theta - p[PLACEMENT]


@numba.njit(cache=True)
def follower_forces(i, y, mode, p):
    """Follower ``i``'s evaluation (:func:`camdyn.model.dynamics.evaluate_cam`'s tuple)
    and its reaction torque on the cam about E [N m]."""
    q = block(i, p)
    m = mode[i * L.MODE_SIZE:(i + 1) * L.MODE_SIZE]
    theta = frame_angle(i, y[4], p)
    res = evaluate_cam(theta, y[5], y[2 * i], y[2 * i + 1], m, q, 0.0)
    torque = 0.0
    if m[L.MODE_CONTACT] > 0.5:
        torque = contact_torque(y[2 * i], theta, res[1], res[2], q)
    return res, torque


@numba.njit(cache=True)
def accelerations(y, mode, p):
    """Accelerations and the powers of the state's works.

    Returns
    -------
    tuple
        ``(alpha_1_ddot [rad/s^2], alpha_2_ddot [rad/s^2], theta_ddot [rad/s^2],
        T_drive [N m], T_bearing [N m], T_contact,1 [N m], T_contact,2 [N m],
        P_cam,1 [W], P_cam,2 [W])``
    """
    first, torque1 = follower_forces(0, y, mode, p)
    second, torque2 = follower_forces(1, y, mode, p)
    drive = drive_torque(y[5], y[6], p)
    bearing = bearing_torque(y[5], p)
    theta_ddot = (drive - bearing + torque1 + torque2) / p[driven_cam.SHAFT_INERTIA]     # eq (1)
    return first[0], second[0], theta_ddot, drive, bearing, torque1, torque2, first[10], second[10]


@numba.njit(cache=True)
def rhs(t, y, mode, p, dydt):
    """Right-hand side ``dy/dt`` of the eleven states (module docstring)."""
    acc1, acc2, theta_ddot, drive, bearing, torque1, torque2, power1, power2 = accelerations(y, mode, p)
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
    """Per follower, the cam-follower's guards ``(delta [m], vr [m/s], delta_dot [m/s])``
    and their exact rates (:func:`camdyn.model.dynamics.guards`) in its frame; the rates
    of ``vr`` and ``delta_dot`` need the accelerations in ``f`` and are NaN when they are
    not ``known``."""
    theta_ddot = f[5] if known else math.nan
    for i in range(FOLLOWERS):
        alpha_ddot = f[2 * i + 1] if known else math.nan
        theta = frame_angle(i, y[4], p)
        delta, vr, delta_dot, vr_dot, delta_ddot = contact_rates_trig(
            math.cos(y[2 * i]), math.sin(y[2 * i]), math.cos(theta), math.sin(theta), y[2 * i + 1], alpha_ddot,
            y[5], theta_ddot, block(i, p))
        k = GUARDS_EACH * i
        values[k] = delta
        values[k + 1] = vr
        values[k + 2] = delta_dot
        rates[k] = delta_dot
        rates[k + 1] = vr_dot
        rates[k + 2] = delta_ddot


@numba.njit(cache=True)
def expected_sign(k, mode, p):
    """+1 or -1 for an active guard, 0 for an inactive one (the cam-follower's rule, for
    the follower the guard belongs to)."""
    i = k // GUARDS_EACH
    return mode_expected_sign(k - GUARDS_EACH * i, mode[i * L.MODE_SIZE:(i + 1) * L.MODE_SIZE], block(i, p))


@numba.njit(cache=True)
def transition(k, values, mode):
    """The mode after guard ``k`` crossed (the cam-follower's rule, for its follower)."""
    i = k // GUARDS_EACH
    mode_transition(k - GUARDS_EACH * i, values[GUARDS_EACH * i:GUARDS_EACH * (i + 1)],
                    mode[i * L.MODE_SIZE:(i + 1) * L.MODE_SIZE])


@numba.njit(cache=True)
def initial_mode(t, y, p, mode):
    """The mode at the start: each follower in contact where its penetration is positive."""
    values = np.empty(GUARD_COUNT)
    rates = np.empty(GUARD_COUNT)
    guards(t, y, y, False, p, values, rates)
    for i in range(FOLLOWERS):
        mode_initial(values[GUARDS_EACH * i:GUARDS_EACH * (i + 1)], block(i, p),
                     mode[i * L.MODE_SIZE:(i + 1) * L.MODE_SIZE])


@numba.njit(cache=True)
def regime(mode):
    """0 while both followers fly, 1 while either touches the cam."""
    for i in range(FOLLOWERS):
        if mode[i * L.MODE_SIZE + L.MODE_CONTACT] > 0.5:
            return 1
    return 0


@numba.njit(cache=True)
def monitor(t, y, mode, p):
    """The larger normal force [N] of the followers under impact (its peak goes to the
    event log), else 0."""
    peak = 0.0
    for i in range(FOLLOWERS):
        m = mode[i * L.MODE_SIZE:(i + 1) * L.MODE_SIZE]
        if m[L.MODE_CONTACT] > 0.5 and m[L.MODE_IMPACT] > 0.5:
            peak = max(peak, follower_forces(i, y, mode, p)[0][1])
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
        acc1, acc2, theta_ddot, drive, bearing, torque1, torque2, power1, power2 = accelerations(y[r], modes[r], p)
        shaft[r, 0] = theta_ddot
        shaft[r, 1] = drive
        shaft[r, 2] = bearing
        for i in range(FOLLOWERS):
            res, torque = follower_forces(i, y[r], modes[r], p)
            row = per[r, i]
            row[0] = res[0]
            row[1] = torque
            row[2] = res[1]
            row[3] = res[2]
            row[4] = res[7]
            row[5] = res[5]
            row[6] = modes[r, i * L.MODE_SIZE + L.MODE_CONTACT]
    return per, shaft
