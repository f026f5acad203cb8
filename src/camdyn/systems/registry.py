"""Registry of the hybrid systems the compiled driver can integrate.

Each system provides, for a state ``y`` of 3 components and a mode vector:

- ``rhs(t, y, mode, p, dydt)`` and ``jacobian(t, y, f0, mode, p, jac)``;
- ``guards(t, y, accel, p, values, rates)``: event functions and their time derivatives
  (NaN where unknown), given the acceleration ``accel = dy1/dt`` at ``(t, y)`` (NaN
  when not known); a guard crossing its expected sign is an event;
- ``expected_sign(k, mode, p)``: +1 or -1 for an active guard, 0 for an inactive one;
- ``transition(k, t, y, values, mode, p)``: the new mode after guard ``k`` crossed;
- ``preferred_method(mode, p)``: the stepper automatic selection uses;
- ``monitor(t, y, mode, p)``: a scalar whose maximum between events is logged.

System 0 is the cam-follower (:mod:`camdyn.model.dynamics`); system 1 is a forced
linear oscillator with a closed-form solution, and system 2 the same oscillator against
a rigid wall with Newton's restitution (:mod:`camdyn.model.impact_oscillator`), whose
impacts reset the state in :func:`transition`; both test the integrator.
"""

from __future__ import annotations

import math

import numba

from camdyn.model import dynamics, impact_oscillator
from camdyn.model import layout as L

CAM_FOLLOWER = 0
OSCILLATOR = 1
RIGID_IMPACT = 2
N_GUARDS = 3


# --- forced linear oscillator: y'' + 2 zeta w y' + w^2 y = A cos(W t); p = (w, zeta, A, W, stiff)
@numba.njit(cache=True)
def _osc_rhs(t, y, p, dydt):
    dydt[0] = y[1]
    dydt[1] = p[2] * math.cos(p[3] * t) - 2.0 * p[1] * p[0] * y[1] - p[0] * p[0] * y[0]
    dydt[2] = y[0]


@numba.njit(cache=True)
def rhs(system, t, y, mode, p, dydt):
    if system == CAM_FOLLOWER:
        dynamics.rhs(t, y, mode, p, dydt)
    else:
        _osc_rhs(t, y, p, dydt)


@numba.njit(cache=True, inline="always")
def rhs_inline(system, t, y, mode, p, dydt):
    """:func:`rhs` compiled into its caller (numba IR inlining). DOP853's stages use it:
    it saves a call and the reference counting of its array arguments per evaluation,
    about a fifth of a DOP853 step; the other callers keep the call, which compiles
    faster."""
    if system == CAM_FOLLOWER:
        dynamics.rhs(t, y, mode, p, dydt)
    else:
        _osc_rhs(t, y, p, dydt)


@numba.njit(cache=True)
def jacobian(system, t, y, f0, mode, p, jac):
    """``jac = (d f1/d y0, d f1/d y1, d f2/d y0, d f2/d y1)``; row 0 is (0, 1, 0) by form."""
    if system == CAM_FOLLOWER:
        dynamics.jacobian(t, y, f0, mode, p, jac)
    else:
        w, z = p[0], p[1]
        jac[0] = -w * w
        jac[1] = -2.0 * z * w
        jac[2] = 1.0
        jac[3] = 0.0


@numba.njit(cache=True)
def guards(system, t, y, accel, p, values, rates):
    if system == CAM_FOLLOWER:
        dynamics.guards(t, y, accel, p, values, rates)
    elif system == RIGID_IMPACT:
        impact_oscillator.guards(t, y, p, values, rates)
    else:
        values[0] = y[0]
        rates[0] = y[1]
        values[1] = 1.0
        rates[1] = math.nan
        values[2] = 1.0
        rates[2] = math.nan


@numba.njit(cache=True)
def expected_sign(system, k, mode, p):
    if system == CAM_FOLLOWER:
        contact = mode[L.MODE_CONTACT] > 0.5
        if k == 0:
            return 1.0 if contact else -1.0
        if not contact:
            return 0.0
        if k == 1:
            return mode[L.MODE_SLIP] if p[L.FRICTION_LAW] == 1.0 else 0.0
        # peak penetration of an impact, for the impact table (laws D and E switch on
        # the sign of delta_dot inside the force law and need no event)
        if mode[L.MODE_IMPACT] > 0.5:
            return 1.0 if mode[L.MODE_COMPRESSING] > 0.5 else -1.0
        return 0.0
    if system == RIGID_IMPACT:
        return 1.0 if k == 0 else 0.0   # the gap to the wall stays positive in flight
    if k == 0:
        return mode[0]
    return 0.0


@numba.njit(cache=True)
def transition(system, k, t, y, values, mode, p):
    if system == CAM_FOLLOWER:
        if k == 0:
            if mode[L.MODE_CONTACT] > 0.5:
                mode[L.MODE_CONTACT] = 0.0
            else:
                mode[L.MODE_CONTACT] = 1.0
                mode[L.MODE_IMPACT] = 1.0
                mode[L.MODE_APPROACH] = values[2]
                mode[L.MODE_SLIP] = 1.0 if values[1] >= 0.0 else -1.0
                mode[L.MODE_COMPRESSING] = 1.0 if values[2] > 0.0 else 0.0
        elif k == 1:
            mode[L.MODE_SLIP] = -mode[L.MODE_SLIP]
        else:
            mode[L.MODE_COMPRESSING] = 1.0 - mode[L.MODE_COMPRESSING]
            if mode[L.MODE_COMPRESSING] < 0.5:
                # the impact's peak is passed (its force peaks at or before it): stop
                # watching delta_dot, which in sustained stiff contact hovers at zero and
                # would cross it on rounding noise alone
                mode[L.MODE_IMPACT] = 0.0
    elif system == RIGID_IMPACT:
        impact_oscillator.reset(y, p)   # the state jumps; the mode stays
    else:
        mode[0] = -mode[0]


@numba.njit(cache=True)
def initial_mode(system, t, y, p, mode):
    values = mode.copy()
    rates = mode.copy()
    guards(system, t, y, math.nan, p, values, rates)
    if system == CAM_FOLLOWER:
        mode[L.MODE_CONTACT] = 1.0 if values[0] > 0.0 else 0.0
        mode[L.MODE_SLIP] = 1.0 if values[1] >= 0.0 else -1.0
        mode[L.MODE_COMPRESSING] = 1.0 if values[2] > 0.0 else 0.0
        mode[L.MODE_APPROACH] = p[L.V_REFERENCE]
        mode[L.MODE_IMPACT] = 0.0
    else:
        mode[0] = 1.0 if values[0] >= 0.0 else -1.0


@numba.njit(cache=True)
def regime(system, mode, p):
    """Index (0 or 1) of the dynamic regime of a mode; the driver remembers the last step
    size of each regime, so that a step after an event starts at the right scale."""
    if system == CAM_FOLLOWER:
        return 1 if mode[L.MODE_CONTACT] > 0.5 else 0
    return 0


@numba.njit(cache=True)
def preferred_method(system, mode, p):
    """Stepper for automatic selection: 1 Dormand-Prince 5(4), 2 RODAS4, 3 DOP853."""
    if system == CAM_FOLLOWER:
        # Measured (docs/integrator.md): on the sustained, lightly damped contact of the
        # chapter 4 rig RODAS4 suffers order reduction at |h omega_contact| ~ 1 and needs
        # more steps than the explicit methods at equal accuracy, and impacts are not
        # stiff; DOP853 needs the fewest right-hand-side calls in both regimes.
        return 3
    if system == RIGID_IMPACT:
        return 3
    return 2 if p[4] > 0.5 else 1


@numba.njit(cache=True)
def monitor(system, t, y, mode, p):
    if system == CAM_FOLLOWER:
        # peak force of impacts only (the impact table); free flight and sustained
        # contact cost nothing
        if mode[L.MODE_CONTACT] > 0.5 and mode[L.MODE_IMPACT] > 0.5:
            return dynamics.evaluate(t, y[0], y[1], mode, p)[1]
        return 0.0
    return abs(y[0])
