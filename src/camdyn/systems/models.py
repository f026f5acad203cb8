"""The models the compiled driver can integrate, each behind one branch of every function
here (the per-model half of :mod:`camdyn.systems.registry`, which adds the variational
systems and is what the integrator imports).

Each system provides, for a state ``y`` of ``state_size`` components, ``guard_count``
guards and a mode vector of ``mode_size`` slots:

- ``rhs(t, y, mode, p, dydt)`` and ``jacobian(t, y, f0, mode, p, jac)`` (``jac`` is the
  full ``n x n`` matrix ``d f / d y``);
- ``controlled_size``: how many leading state components the error control watches
  (the rest, such as quadratures that feed back into nothing, are integrated only);
- ``guards(t, y, f, known, p, values, rates)``: event functions and their time
  derivatives (NaN where unknown), given the state's rates ``f = dy/dt`` at ``(t, y)``
  when ``known``; a guard crossing its expected sign is an event;
- ``expected_sign(k, mode, p)``: +1 or -1 for an active guard, 0 for an inactive one;
- ``transition(k, t, y, values, mode, p)``: the new mode after guard ``k`` crossed, and
  the state's reset (an impact's velocity jump) where the system has one;
- ``preferred_method(mode, p)``: the stepper automatic selection uses;
- ``monitor(t, y, mode, p)``: a scalar whose maximum between events is logged.

System 0 is the cam-follower (:mod:`camdyn.model.dynamics`); system 1 is a forced
linear oscillator with a closed-form solution, and system 2 the same oscillator against
a rigid wall with Newton's restitution (:mod:`camdyn.model.impact_oscillator`), whose
impacts reset the state in :func:`transition`; system 3 is two coupled oscillators, the
second against a wall (:mod:`camdyn.model.coupled_oscillator`, 4 states, 1 guard). The
three test the integrator. System 4 is a translating follower on a cam of any profile,
with rigid (Newton restitution, sustained contact) or compliant contact
(:mod:`camdyn.model.translating_follower`, 2 states, 3 guards: gap, force, joints). The mechanisms, ids 5
and up, are dispatched by :mod:`camdyn.systems.mechanisms`, each function here sending
them there in its first lines: system 5 is the stick-slip oscillator
(:mod:`camdyn.model.stick_slip`, 3 states, 3 guards) and system 6 the cam-follower with
the cam as a rigid body on a driven shaft (:mod:`camdyn.model.driven_cam`, 8 states, the
cam-follower's 3 guards and modes); system 7 the rocking follower on a flexible pivot
bearing (:mod:`camdyn.model.flexible_pivot`, 8 states, the same guards and modes);
system 9 two rocking followers on one driven cam (:mod:`camdyn.model.two_followers`,
11 states, per follower the cam-follower's guards and mode with a stick phase); system 10
the translating follower with friction at its cam contact
(:mod:`camdyn.model.sliding_follower`, 4 states, 5 guards); systems 11 and 12 the driven
cam and two followers with the cam angle as the independent variable
(:mod:`camdyn.model.cam_angle`), for their periodic orbits.

A new model gets an id here (or, for a mechanism, in :mod:`camdyn.systems.mechanisms`)
and a branch in each function; these two modules are the only ones that import the
models.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.model import contact, coupled_oscillator, dynamics, impact_oscillator
from camdyn.model import layout as L
from camdyn.model import translating_follower as translating
from camdyn.systems import mechanisms

CAM_FOLLOWER = 0
OSCILLATOR = 1
RIGID_IMPACT = 2
COUPLED_OSCILLATORS = 3
TRANSLATING_FOLLOWER = 4
# --- mechanisms (ids 5 and up; their branches are the blocks marked "mechanisms" below)
STICK_SLIP = mechanisms.STICK_SLIP
DRIVEN_CAM = mechanisms.DRIVEN_CAM
FLEXIBLE_PIVOT = mechanisms.FLEXIBLE_PIVOT
TWO_FOLLOWERS = mechanisms.TWO_FOLLOWERS
SLIDING_FOLLOWER = mechanisms.SLIDING_FOLLOWER
DRIVEN_CAM_ANGLE = mechanisms.DRIVEN_CAM_ANGLE
TWO_FOLLOWERS_ANGLE = mechanisms.TWO_FOLLOWERS_ANGLE


@numba.njit(cache=True)
def state_size(system):
    """Number of state components."""
    if system >= STICK_SLIP:   # mechanisms
        return mechanisms.sizes(system)[0]
    if system == COUPLED_OSCILLATORS:
        return coupled_oscillator.STATE_SIZE
    if system == TRANSLATING_FOLLOWER:
        return translating.STATE_SIZE
    return 3


@numba.njit(cache=True)
def controlled_size(system):
    """Number of leading state components under error control: the cam-follower's and
    the oscillators' third component is a quadrature that feeds back into nothing."""
    if system >= STICK_SLIP:   # mechanisms
        return mechanisms.sizes(system)[1]
    if system == COUPLED_OSCILLATORS:
        return coupled_oscillator.STATE_SIZE
    if system == TRANSLATING_FOLLOWER:
        return translating.STATE_SIZE
    return 2


@numba.njit(cache=True)
def guard_count(system):
    """Number of guard functions."""
    if system >= STICK_SLIP:   # mechanisms
        return mechanisms.sizes(system)[2]
    if system == CAM_FOLLOWER:
        return 3
    if system == TRANSLATING_FOLLOWER:
        return translating.GUARD_COUNT
    return 1


@numba.njit(cache=True)
def mode_size(system):
    """Number of slots of the mode vector."""
    if system >= STICK_SLIP:   # mechanisms
        return mechanisms.sizes(system)[3]
    if system == CAM_FOLLOWER:
        return L.MODE_SIZE
    if system == TRANSLATING_FOLLOWER:
        return translating.MODE_SIZE
    return 1


@numba.njit(cache=True)
def variational_jacobian(system, t, y, f0, mode, p, jac):
    """The Jacobian for the variational system (:mod:`camdyn.systems.variational`), which
    integrates ``Phi' = J Phi`` under error control: the cam-follower's by central
    differences (:func:`camdyn.model.dynamics.central_jacobian`, whose noise is far below
    the forward differences' that :func:`jacobian` keeps for the Rosenbrock steps); every
    other model's is :func:`jacobian`."""
    if system == CAM_FOLLOWER:
        jac[:, :] = 0.0
        jac[0, 1] = 1.0
        dynamics.central_jacobian(t, y, f0, mode, p, jac)
        return
    jacobian(system, t, y, f0, mode, p, jac)


@numba.njit(cache=True)
def carried_slot(system, p):
    """The mode slot that holds a value of the state at the last event on which the
    right-hand side depends under the parameters ``p`` (the approach velocity [m/s] of
    the restitution-parameterised contact laws, set at contact onset), or -1 for none.
    The variational system carries that value's derivatives
    (:mod:`camdyn.systems.variational`). Two followers on one cam keep one such slot per
    follower and are not covered (-1)."""
    if system == CAM_FOLLOWER or system == DRIVEN_CAM or system == FLEXIBLE_PIVOT or system == DRIVEN_CAM_ANGLE:
        return L.MODE_APPROACH if p[L.DAMPING_LAW] >= contact.FIRST_RESTITUTION_CODE else -1
    if system == TRANSLATING_FOLLOWER:
        return 1 if p[translating.DAMPING_LAW] >= contact.FIRST_RESTITUTION_CODE else -1
    return -1


@numba.njit(cache=True)
def carries(system):
    """Whether the mode of ``system`` can hold a value carried from an event
    (:func:`carried_slot` for some parameters)."""
    return (system == CAM_FOLLOWER or system == DRIVEN_CAM or system == FLEXIBLE_PIVOT or system == TRANSLATING_FOLLOWER
            or system == DRIVEN_CAM_ANGLE)


# --- forced linear oscillator: y'' + 2 zeta w y' + w^2 y = A cos(W t); p = (w, zeta, A, W, stiff)
@numba.njit(cache=True)
def _osc_rhs(t, y, p, dydt):
    dydt[0] = y[1]
    dydt[1] = p[2] * math.cos(p[3] * t) - 2.0 * p[1] * p[0] * y[1] - p[0] * p[0] * y[0]
    dydt[2] = y[0]


@numba.njit(cache=True)
def rhs(system, t, y, mode, p, dydt):
    if system >= STICK_SLIP:   # mechanisms
        mechanisms.rhs(system, t, y, mode, p, dydt)
        return
    if system == CAM_FOLLOWER:
        dynamics.rhs(t, y, mode, p, dydt)
    elif system == COUPLED_OSCILLATORS:
        coupled_oscillator.rhs(t, y, p, dydt)
    elif system == TRANSLATING_FOLLOWER:
        translating.rhs(t, y, mode, p, dydt)
    else:
        _osc_rhs(t, y, p, dydt)


@numba.njit(cache=True, inline="always")
def rhs_inline(system, t, y, mode, p, dydt):
    """:func:`rhs` compiled into its caller (numba IR inlining). DOP853's stages use it:
    it saves a call and the reference counting of its array arguments per evaluation,
    about a fifth of a DOP853 step; the other callers keep the call, which compiles
    faster."""
    if system >= STICK_SLIP:   # mechanisms
        mechanisms.rhs(system, t, y, mode, p, dydt)
        return
    if system == CAM_FOLLOWER:
        dynamics.rhs(t, y, mode, p, dydt)
    elif system == COUPLED_OSCILLATORS:
        coupled_oscillator.rhs(t, y, p, dydt)
    elif system == TRANSLATING_FOLLOWER:
        translating.rhs(t, y, mode, p, dydt)
    else:
        _osc_rhs(t, y, p, dydt)


@numba.njit(cache=True)
def jacobian(system, t, y, f0, mode, p, jac):
    """The Jacobian ``jac = d f / d y`` (n x n) at ``(t, y)``, where ``f0 = f(t, y)``."""
    if system >= STICK_SLIP:   # mechanisms
        mechanisms.jacobian(system, t, y, f0, mode, p, jac)
        return
    if system == COUPLED_OSCILLATORS:
        coupled_oscillator.jacobian(p, jac)
        return
    if system == TRANSLATING_FOLLOWER:
        translating.jacobian(t, y, mode, p, jac)
        return
    jac[:, :] = 0.0
    jac[0, 1] = 1.0   # second-order systems in first-order form; the quadrature's column is zero
    if system == CAM_FOLLOWER:
        dynamics.jacobian(t, y, f0, mode, p, jac)
    else:
        w, z = p[0], p[1]
        jac[1, 0] = -w * w
        jac[1, 1] = -2.0 * z * w
        jac[2, 0] = 1.0


@numba.njit(cache=True)
def guards(system, t, y, f, known, p, values, rates):
    if system >= STICK_SLIP:   # mechanisms
        mechanisms.guards(system, t, y, f, known, p, values, rates)
        return
    if system == CAM_FOLLOWER:
        dynamics.guards(t, y, f[1] if known else math.nan, p, values, rates)
    elif system == RIGID_IMPACT:
        impact_oscillator.guards(t, y, p, values, rates)
    elif system == COUPLED_OSCILLATORS:
        coupled_oscillator.guards(t, y, p, values, rates)
    elif system == TRANSLATING_FOLLOWER:
        translating.guards(t, y, p, values, rates)
    else:
        values[0] = y[0]
        rates[0] = y[1]


@numba.njit(cache=True)
def expected_sign(system, k, mode, p):
    if system >= STICK_SLIP:   # mechanisms
        return mechanisms.expected_sign(system, k, mode, p)
    if system == CAM_FOLLOWER:
        return dynamics.mode_expected_sign(k, mode, p)
    if system == RIGID_IMPACT or system == COUPLED_OSCILLATORS:
        return 1.0   # the gap to the wall stays positive in flight
    if system == TRANSLATING_FOLLOWER:
        return translating.expected_sign(k, mode, p)
    if k == 0:
        return mode[0]
    return 0.0


@numba.njit(cache=True)
def transition(system, k, t, y, values, mode, p):
    if system >= STICK_SLIP:   # mechanisms
        mechanisms.transition(system, k, t, y, values, mode, p)
        return
    if system == CAM_FOLLOWER:
        dynamics.mode_transition(k, values, mode)
    elif system == RIGID_IMPACT:
        impact_oscillator.reset(y, p)   # the state jumps; the mode stays
    elif system == COUPLED_OSCILLATORS:
        coupled_oscillator.reset(y, p)
    elif system == TRANSLATING_FOLLOWER:
        translating.transition(k, t, y, mode, p)
    else:
        mode[0] = -mode[0]


@numba.njit(cache=True)
def initial_mode(system, t, y, p, mode):
    if system >= STICK_SLIP:   # mechanisms
        mechanisms.initial_mode(system, t, y, p, mode)
        return
    values = np.empty(guard_count(system))
    rates = np.empty(guard_count(system))
    guards(system, t, y, y, False, p, values, rates)
    if system == CAM_FOLLOWER:
        dynamics.mode_initial(values, p, mode)
    elif system == TRANSLATING_FOLLOWER:
        translating.initial_mode(t, y, p, mode)
    else:
        mode[0] = 1.0 if values[0] >= 0.0 else -1.0


@numba.njit(cache=True)
def regime(system, mode, p):
    """Index (0 or 1) of the dynamic regime of a mode; the driver remembers the last step
    size of each regime, so that a step after an event starts at the right scale."""
    if system >= STICK_SLIP:   # mechanisms
        return mechanisms.regime(system, mode, p)
    if system == CAM_FOLLOWER:
        return 1 if mode[L.MODE_CONTACT] > 0.5 else 0
    if system == TRANSLATING_FOLLOWER:
        return translating.regime(mode)
    return 0


@numba.njit(cache=True)
def preferred_method(system, mode, p):
    """Stepper for automatic selection: 1 Dormand-Prince 5(4), 2 RODAS4, 3 DOP853."""
    if system >= STICK_SLIP:   # mechanisms
        return 3
    if system == CAM_FOLLOWER:
        # Measured (docs/integrator.md): on the sustained, lightly damped contact of the
        # chapter 4 rig RODAS4 suffers order reduction at |h omega_contact| ~ 1 and needs
        # more steps than the explicit methods at equal accuracy, and impacts are not
        # stiff; DOP853 needs the fewest right-hand-side calls in both regimes.
        return 3
    if system == RIGID_IMPACT or system == COUPLED_OSCILLATORS or system == TRANSLATING_FOLLOWER:
        return 3
    return 2 if p[4] > 0.5 else 1


@numba.njit(cache=True)
def monitor(system, t, y, mode, p):
    if system >= STICK_SLIP:   # mechanisms
        return mechanisms.monitor(system, t, y, mode, p)
    if system == CAM_FOLLOWER:
        # peak force of impacts only (the impact table); free flight and sustained
        # contact cost nothing
        if mode[L.MODE_CONTACT] > 0.5 and mode[L.MODE_IMPACT] > 0.5:
            return dynamics.evaluate(t, y[0], y[1], mode, p)[1]
        return 0.0
    if system == TRANSLATING_FOLLOWER:
        return translating.contact_force(t, y, mode, p)   # the largest force of a contact
    return abs(y[0])
