"""The driven cam (:mod:`camdyn.model.driven_cam`) and two followers on a driven shaft
(:mod:`camdyn.model.two_followers`) with the cam angle ``Theta`` [rad] as the independent
variable instead of the time, for their periodic orbits.

A mechanism whose shaft turns under a torque, a motor or a controller is autonomous: its
steady state repeats in the cam angle, over a period (the time the cam takes to turn
``2 pi k``) that is an unknown. Taking the cam angle as the independent variable (Seydel
2010, *Practical Bifurcation and Stability Analysis*, sec. 7.1, doi:10.1007/978-1-4419-1740-9;
the Poincare section ``Theta = Theta_0``, Kuznetsov 2004, *Elements of Applied
Bifurcation Theory*, sec. 1.5, doi:10.1007/978-1-4757-3978-7) turns it into a system
forced with the fixed period ``2 pi`` in ``Theta``, whose period map is the Poincare
map of the section. While the cam turns forward (``Theta_dot > 0``) the chain rule gives,
for every other state ``x`` of the time-domain model ``dx/dt = g(x, Theta)``::

    dx/dTheta = g(x, Theta) / Theta_dot,      dt/dTheta = 1 / Theta_dot              (1)

The state is the time-domain model's with the cam angle taken out and the time put in
after the shaft's speed and the controller's integral: for the driven cam
``(alpha [rad], alpha_dot [rad/s], Theta_dot [rad/s], z [rad], t [s], W_drive [J],
W_bearing [J], W_cam [J])``, for two followers ``(alpha_1, alpha_1_dot, alpha_2,
alpha_2_dot, Theta_dot, z, t, W_drive, W_bearing, W_cam,1, W_cam,2)`` in the same units.
The time feeds back into nothing (the time-domain models do not read it): like the works
it is a quadrature, and its advance over one orbit is the orbit's period [s].

The guards are the time-domain model's, evaluated at the state's cam angle; their rates
are divided by ``Theta_dot`` (rates in ``Theta``, eq 1); transitions (mode changes, a
stick's velocity correction) are the model's on the time-domain state. The argument
``which`` is 0 for the driven cam and 1 for two followers.
"""

from __future__ import annotations

import numba
import numpy as np

from camdyn.model import driven_cam, dynamics
from camdyn.model import two_followers as pair

#: Slot of the cam angle in each time-domain state (driven cam, two followers).
ANGLE_SLOTS = (2, 4)
#: Relative step of the central differences of :func:`jacobian` [-], as the time-domain models'.
DIFFERENCE_STEP = 1e-7

__all__ = ["rhs", "jacobian", "guards", "transition", "initial_mode", "monitor", "to_time", "to_angle",
           "clock_slot", "controlled_size", "ANGLE_SLOTS"]


@numba.njit(cache=True)
def angle_slot(which):
    """Slot of ``Theta`` in the time-domain state of model ``which``."""
    return ANGLE_SLOTS[0] if which == 0 else ANGLE_SLOTS[1]


@numba.njit(cache=True)
def clock_slot(which):
    """Slot of the time ``t`` [s] in the cam-angle state: after ``Theta_dot`` and ``z``."""
    return angle_slot(which) + 2


@numba.njit(cache=True)
def controlled_size(which):
    """Leading components under error control: the time-domain model's dynamic states
    with the time in the cam angle's place (the works are left out, as there)."""
    return angle_slot(which) + 3


@numba.njit(cache=True)
def to_time(s, theta, which, y):
    """The time-domain state into ``y`` from the cam-angle state ``s`` at ``theta``
    [rad] (module docstring); returns the time [s]."""
    a = angle_slot(which)
    y[:a] = s[:a]
    y[a] = theta
    y[a + 1] = s[a]
    y[a + 2] = s[a + 1]
    y[a + 3:] = s[a + 3:]
    return s[a + 2]


@numba.njit(cache=True)
def to_angle(y, t, which, s):
    """The cam-angle state into ``s`` from the time-domain state ``y`` at time ``t`` [s]."""
    a = angle_slot(which)
    s[:a] = y[:a]
    s[a] = y[a + 1]
    s[a + 1] = y[a + 2]
    s[a + 2] = t
    s[a + 3:] = y[a + 3:]


@numba.njit(cache=True)
def _time_rhs(which, t, y, mode, p, dydt):
    if which == 0:
        driven_cam.rhs(t, y, mode, p, dydt)
    else:
        pair.rhs(t, y, mode, p, dydt)


@numba.njit(cache=True)
def rhs(which, theta, s, mode, p, dsdtheta):
    """``ds/dTheta`` (eq 1). A shaft that stops or turns back (``Theta_dot <= 0``) has no
    cam-angle form: the rates are then NaN and the integrator's run fails."""
    n = s.shape[0]
    y = np.empty(n)
    t = to_time(s, theta, which, y)
    dydt = np.empty(n)
    _time_rhs(which, t, y, mode, p, dydt)
    speed = y[angle_slot(which) + 1]
    scale = 1.0 / speed if speed > 0.0 else np.nan     # dt/dTheta, eq (1)
    to_angle(dydt, 1.0, which, dsdtheta)    # the time's rate dt/dt = 1 in its slot, scaled below
    for i in range(n):
        dsdtheta[i] *= scale                            # dx/dTheta = (dx/dt) (dt/dTheta), eq (1)


@numba.njit(cache=True)
def jacobian(which, theta, s, mode, p, jac):
    """``d(ds/dTheta)/ds`` by central differences of :func:`rhs` in the controlled states
    (the works' columns are zero, and so is the time's: nothing reads it)."""
    n = s.shape[0]
    jac[:, :] = 0.0
    up = np.empty(n)
    down = np.empty(n)
    probe = s.copy()
    clock = clock_slot(which)
    for j in range(controlled_size(which)):
        if j == clock:
            continue
        step = DIFFERENCE_STEP * max(abs(s[j]), 1.0)
        probe[j] = s[j] + step
        span = probe[j]
        rhs(which, theta, probe, mode, p, up)
        probe[j] = s[j] - step
        span -= probe[j]
        rhs(which, theta, probe, mode, p, down)
        probe[j] = s[j]
        for i in range(n):
            jac[i, j] = (up[i] - down[i]) / span


@numba.njit(cache=True)
def guards(which, theta, s, f, known, p, values, rates):
    """The time-domain model's guards at the state's cam angle, their rates in ``Theta``
    (divided by ``Theta_dot``); ``f`` is ``ds/dTheta`` when ``known``."""
    n = s.shape[0]
    y = np.empty(n)
    t = to_time(s, theta, which, y)
    speed = y[angle_slot(which) + 1]
    g = np.empty(n)
    if known:
        to_time(f, 1.0, which, g)          # dx/dt = speed dx/dTheta; dTheta/dt = speed
        for i in range(n):
            g[i] *= speed
    else:
        g[:] = y
    if which == 0:
        driven_cam.guards(t, y, g, known, p, values, rates)
    else:
        pair.guards(t, y, g, known, p, values, rates)
    for k in range(rates.shape[0]):
        rates[k] /= speed                               # dg/dTheta = (dg/dt) / Theta_dot, eq (1)


@numba.njit(cache=True)
def transition(which, k, theta, s, values, mode, p):
    """The time-domain model's transition for guard ``k`` (its reset mapped back)."""
    if which == 0:
        dynamics.mode_transition(k, values, mode)
        return
    n = s.shape[0]
    y = np.empty(n)
    t = to_time(s, theta, which, y)
    pair.transition(k, t, y, values, mode, p)
    to_angle(y, t, which, s)


@numba.njit(cache=True)
def initial_mode(which, theta, s, p, mode):
    """The time-domain model's mode at the start."""
    n = s.shape[0]
    y = np.empty(n)
    t = to_time(s, theta, which, y)
    if which == 0:
        values = np.empty(driven_cam.GUARD_COUNT)
        rates = np.empty(driven_cam.GUARD_COUNT)
        driven_cam.guards(t, y, y, False, p, values, rates)
        dynamics.mode_initial(values, p, mode)
    else:
        pair.initial_mode(t, y, p, mode)


@numba.njit(cache=True)
def monitor(which, theta, s, mode, p):
    """The time-domain model's monitor (an impact's normal force [N])."""
    n = s.shape[0]
    y = np.empty(n)
    t = to_time(s, theta, which, y)
    if which == 0:
        return driven_cam.monitor(t, y, mode, p)
    return pair.monitor(t, y, mode, p)
