"""The mechanisms the compiled driver can integrate, ids 5 and up, each behind one branch
of every function here; :mod:`camdyn.systems.models` sends every mechanism id here in
the first lines of its functions, which have the same meaning as there.

System 5 is the stick-slip oscillator (:mod:`camdyn.model.stick_slip`, 3 states, 3
guards) and system 6 the cam-follower with the cam as a rigid body on a driven shaft
(:mod:`camdyn.model.driven_cam`, 8 states, the cam-follower's 3 guards and modes).
System 7 is the rocking follower on a flexible pivot bearing
(:mod:`camdyn.model.flexible_pivot`, 8 states, the cam-follower's 3 guards and modes).
System 9 is two rocking followers on one driven cam (:mod:`camdyn.model.two_followers`,
11 states, per follower the cam-follower's 3 guards and mode, a stick flag and 2 stick
guards); id 8 is reserved. System 10 is the translating follower with Coulomb friction
at its cam contact (:mod:`camdyn.model.sliding_follower`, 4 states, 5 guards: a knife
edge or flat face that slides, a roller that rolls or slides). Systems 11 and 12 are
systems 6 and 9 with the cam angle as the independent variable
(:mod:`camdyn.model.cam_angle`, the same sizes, guards and modes), whose period map is
the Poincare map of a section at a cam angle: their periodic orbits.
"""

from __future__ import annotations

import numba
import numpy as np

from camdyn.model import cam_angle, driven_cam, dynamics, stick_slip
from camdyn.model import flexible_pivot as pivot
from camdyn.model import layout as L
from camdyn.model import sliding_follower as sliding
from camdyn.model import two_followers as pair

STICK_SLIP = 5
DRIVEN_CAM = 6
FLEXIBLE_PIVOT = 7
TWO_FOLLOWERS = 9
SLIDING_FOLLOWER = 10
DRIVEN_CAM_ANGLE = 11
TWO_FOLLOWERS_ANGLE = 12


@numba.njit(cache=True)
def angle_model(system):
    """0 (the driven cam) or 1 (two followers) for a system in the cam angle, else -1."""
    if system == DRIVEN_CAM_ANGLE:
        return 0
    if system == TWO_FOLLOWERS_ANGLE:
        return 1
    return -1


@numba.njit(cache=True)
def sizes(system):
    """``(state_size, controlled_size, guard_count, mode_size)`` of a mechanism."""
    if system == STICK_SLIP:
        return stick_slip.STATE_SIZE, 2, stick_slip.GUARD_COUNT, 1
    if system == FLEXIBLE_PIVOT:
        return pivot.STATE_SIZE, pivot.CONTROLLED_SIZE, pivot.GUARD_COUNT, L.MODE_SIZE
    if system == TWO_FOLLOWERS or system == TWO_FOLLOWERS_ANGLE:
        return pair.STATE_SIZE, pair.CONTROLLED_SIZE, pair.GUARD_COUNT, pair.MODE_SIZE
    if system == SLIDING_FOLLOWER:
        return sliding.STATE_SIZE, sliding.CONTROLLED_SIZE, sliding.GUARD_COUNT, sliding.MODE_SIZE
    return driven_cam.STATE_SIZE, driven_cam.CONTROLLED_SIZE, driven_cam.GUARD_COUNT, L.MODE_SIZE


@numba.njit(cache=True)
def rhs(system, t, y, mode, p, dydt):
    which = angle_model(system)
    if which >= 0:
        cam_angle.rhs(which, t, y, mode, p, dydt)
        return
    if system == STICK_SLIP:
        stick_slip.rhs(t, y, mode, p, dydt)
    elif system == TWO_FOLLOWERS:
        pair.rhs(t, y, mode, p, dydt)
    elif system == SLIDING_FOLLOWER:
        sliding.rhs(t, y, mode, p, dydt)
    elif system == FLEXIBLE_PIVOT:
        pivot.rhs(t, y, mode, p, dydt)
    else:
        driven_cam.rhs(t, y, mode, p, dydt)


@numba.njit(cache=True)
def jacobian(system, t, y, f0, mode, p, jac):
    which = angle_model(system)
    if which >= 0:
        cam_angle.jacobian(which, t, y, mode, p, jac)
        return
    if system == STICK_SLIP:
        stick_slip.jacobian(t, y, mode, p, jac)
    elif system == TWO_FOLLOWERS:
        pair.jacobian(t, y, mode, p, jac)
    elif system == SLIDING_FOLLOWER:
        sliding.jacobian(t, y, mode, p, jac)
    elif system == FLEXIBLE_PIVOT:
        pivot.jacobian(t, y, mode, p, jac)
    else:
        driven_cam.jacobian(t, y, mode, p, jac)


@numba.njit(cache=True)
def guards(system, t, y, f, known, p, values, rates):
    which = angle_model(system)
    if which >= 0:
        cam_angle.guards(which, t, y, f, known, p, values, rates)
        return
    if system == STICK_SLIP:
        stick_slip.guards(t, y, f, known, p, values, rates)
    elif system == TWO_FOLLOWERS:
        pair.guards(t, y, f, known, p, values, rates)
    elif system == SLIDING_FOLLOWER:
        sliding.guards(t, y, f, known, p, values, rates)
    elif system == FLEXIBLE_PIVOT:
        pivot.guards(t, y, f, known, p, values, rates)
    else:
        driven_cam.guards(t, y, f, known, p, values, rates)


@numba.njit(cache=True)
def expected_sign(system, k, mode, p):
    if system == STICK_SLIP:
        return stick_slip.expected_sign(k, mode, p)
    if system == TWO_FOLLOWERS or system == TWO_FOLLOWERS_ANGLE:
        return pair.expected_sign(k, mode, p)
    if system == SLIDING_FOLLOWER:
        return sliding.expected_sign(k, mode, p)
    # the driven cam and the flexible pivot: the cam-follower's contact modes and rule
    return dynamics.mode_expected_sign(k, mode, p)


@numba.njit(cache=True)
def transition(system, k, t, y, values, mode, p):
    which = angle_model(system)
    if which >= 0:
        cam_angle.transition(which, k, t, y, values, mode, p)
        return
    if system == STICK_SLIP:
        stick_slip.transition(k, t, y, mode, p)
    elif system == TWO_FOLLOWERS:
        pair.transition(k, t, y, values, mode, p)
    elif system == SLIDING_FOLLOWER:
        sliding.transition(k, t, y, mode, p)
    else:   # the driven cam and the flexible pivot: the cam-follower's rule
        dynamics.mode_transition(k, values, mode)


@numba.njit(cache=True)
def initial_mode(system, t, y, p, mode):
    which = angle_model(system)
    if which >= 0:
        cam_angle.initial_mode(which, t, y, p, mode)
        return
    if system == STICK_SLIP:
        stick_slip.initial_mode(t, y, p, mode)
    elif system == TWO_FOLLOWERS:
        pair.initial_mode(t, y, p, mode)
    elif system == SLIDING_FOLLOWER:
        sliding.initial_mode(t, y, p, mode)
    else:   # the driven cam and the flexible pivot: in contact where the penetration is positive
        count = sizes(system)[2]
        values = np.empty(count)
        rates = np.empty(count)
        guards(system, t, y, y, False, p, values, rates)
        dynamics.mode_initial(values, p, mode)


@numba.njit(cache=True)
def regime(system, mode, p):
    """Sticking and slipping (stick-slip), free flight and contact (driven cam, flexible
    pivot, two followers: either in contact)."""
    if system == STICK_SLIP:
        return 0 if mode[0] == 0.0 else 1
    if system == TWO_FOLLOWERS or system == TWO_FOLLOWERS_ANGLE:
        return pair.regime(mode)
    if system == SLIDING_FOLLOWER:
        return sliding.regime(mode)
    return 1 if mode[L.MODE_CONTACT] > 0.5 else 0


@numba.njit(cache=True)
def monitor(system, t, y, mode, p):
    """The extension ``|x|`` [m] (stick-slip); an impact's normal force [N] (driven cam,
    flexible pivot, two followers)."""
    which = angle_model(system)
    if which >= 0:
        return cam_angle.monitor(which, t, y, mode, p)
    if system == STICK_SLIP:
        return abs(y[0])
    if system == FLEXIBLE_PIVOT:
        return pivot.monitor(t, y, mode, p)
    if system == TWO_FOLLOWERS:
        return pair.monitor(t, y, mode, p)
    if system == SLIDING_FOLLOWER:
        return sliding.monitor(t, y, mode, p)
    return driven_cam.monitor(t, y, mode, p)
