"""The rocking follower on a flexible pivot: the cam-follower of
:mod:`camdyn.model.dynamics` whose pivot bearing is a spring and a damper in ``x`` and
``y``, two more degrees of freedom.

Generalized coordinates ``q = (alpha [rad], u [m], v [m])``: the follower angle
(clockwise, as in docs/model.md §1) and the displacement ``P = (u, v)`` of the follower
pivot from its rest position, where the bearing force vanishes. With ``n = (sin alpha,
cos alpha)`` and ``u_hat = (cos alpha, -sin alpha)`` the centre of gravity G sits at
``P + l_cg u_hat`` and moves at ``v_G = P' - l_cg alpha' n``; the kinetic energy is::

    T = 1/2 m |P'|^2 - m l_cg alpha' n.P' + 1/2 I_P alpha'^2                      (1)

so that Lagrange's equations give the mass matrix and the velocity terms::

        | I_P               -m l_cg sin(alpha)   -m l_cg cos(alpha) |
    M = | -m l_cg sin(alpha)        m                    0           |            (2)
        | -m l_cg cos(alpha)        0                    m           |

    M q'' = Q + (0, m l_cg alpha'^2 cos(alpha), -m l_cg alpha'^2 sin(alpha))      (3)

(the ``alpha`` row has no velocity term: ``d/dt dT/dalpha' = dT/dalpha`` cancels it).
Eliminating ``P''`` from (3) leaves Euler's law about G and Newton's law for G::

    (I_P - m l_cg^2) alpha'' = Q_alpha + l_cg n.Q_P                               (4)
    P'' = Q_P / m + l_cg (alpha'' n + alpha'^2 u_hat)                             (5)

``Q_alpha`` [N m] is the clockwise moment about the moving pivot and ``Q_P = (Q_u, Q_v)``
[N] the resultant of the forces on the follower:

- gravity: ``Q_alpha = m g l_cg cos(alpha)``, ``Q_P = (0, -m g)``;
- the bearing: ``Q_P = -kp (u, v) - cp (u', v')``, the bearing force ``(Nx, Ny)``;
- the contact, at the follower's contact point ``P + chi u_hat + h n``, force
  ``-Fn n + Ff u_hat`` (docs/model.md §3.5, §3.8): ``Q_alpha = Fn chi + Ff h`` (eq 3.16,
  4.13), ``Q_P = -Fn n + Ff u_hat``;
- the spring (below).

The contact geometry is the cam-follower's with the cam pivot at ``E0 - P`` from the
follower pivot (:func:`camdyn.model.geometry.contact_point_from`); the follower's
material velocity gains ``P'``, so the penetration rate gains ``+n.P'`` and the sliding
velocity ``-u_hat.P'``::

    delta' = -alpha' chi - n.v_cam(Xc) + n.P'                                     (6)
    vr     = u_hat.v_cam(Xc) - alpha' h - u_hat.P'                                (7)

The spring's ground end is fixed; its follower end moves with the body, so a translation
``P`` shortens it along its axis ``d = (sin sigma, cos sigma)`` by ``s = d.P`` [m]. Its
potential is the rigid pivot's, ``V_r(alpha)`` with ``-V_r' = M_s(alpha)`` the moment of
eq 3.10 / 4.14 (:func:`camdyn.model.dynamics.spring_moment`), plus the work of that
shortening against the force ``Fs(alpha)`` of eq 3.10 / 4.44::

    V_s = V_r(alpha) - Fs(alpha) s + 1/2 ks s^2                                   (8)
    Q_alpha = M_s(alpha) + Fs'(alpha) s ,   Q_P = (Fs(alpha) - ks s) d            (9)

(9) is the force of the shortened spring, ``Fs - ks s``, along its axis, and the change
of its moment to first order in ``s`` (at ``alpha = 0``, ``Fs' s = ks dx s``, the lever
``dx`` times the change of force); the rigid pivot is ``s = 0`` exactly. Written from a
potential, the model conserves energy: without damping or friction::

    T + V_s + V_g + 1/2 kp |P|^2 + V_contact - W_cam = const                    (10)

with ``V_g = m g (v - l_cg sin(alpha))``, ``V_contact`` the Hertz potential and
``W_cam`` the cam's work (:mod:`camdyn.model.dynamics`); bearing damping removes
``W_bearing = integral cp |P'|^2 dt``.

State ``(alpha [rad], alpha_dot [rad/s], u [m], u_dot [m/s], v [m], v_dot [m/s],
W_cam [J], W_bearing [J])``. The mode vector, guards and mode rules are the
cam-follower's (:mod:`camdyn.model.layout`, :func:`camdyn.model.dynamics.mode_transition`).
The parameter vector is the cam-follower's (:func:`camdyn.model.layout.pack`) followed by
the slots below.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.model import layout as L
from camdyn.model.contact import contact_force
from camdyn.model.dynamics import spring_force_trig, spring_moment_trig
from camdyn.model.friction import friction_coefficient
from camdyn.model.geometry import cam_acceleration, cam_angle, contact_kinematics_from, contact_rates_from

PIVOT_STIFFNESS = L.SIZE + 0   # kp [N/m]
PIVOT_DAMPING = L.SIZE + 1     # cp [N s/m]
SIZE = L.SIZE + 2

STATE_SIZE = 8
CONTROLLED_SIZE = 6
GUARD_COUNT = 3

__all__ = ["spring_force_slope", "evaluate", "rhs", "jacobian", "guards", "monitor", "channels", "CHANNELS",
           "SIZE", "STATE_SIZE", "PIVOT_STIFFNESS", "PIVOT_DAMPING"]


@numba.njit(cache=True)
def spring_force_slope(ca, sa, p):
    """``dFs/dalpha`` [N/rad] of the spring force of eq 3.10 / 4.44 at ``cos(alpha)``,
    ``sin(alpha)``: ``ks (dx sec^2 + 0.5 wb sec tan)`` times the tilt factor
    ``f = cos(alpha) / cos(alpha - sigma)``, plus the compression times
    ``f' = -sin(sigma) / cos^2(alpha - sigma)``."""
    inv_c = 1.0 / ca
    compression = p[L.LS] - p[L.DY] + (p[L.DX] * sa + 0.5 * p[L.WIDTH]) * inv_c
    slope = (p[L.DX] + 0.5 * p[L.WIDTH] * sa) * inv_c * inv_c
    if p[L.TILT] == 0.0:
        return p[L.KS] * slope
    tilted = ca * math.cos(p[L.TILT]) + sa * math.sin(p[L.TILT])     # cos(alpha - sigma)
    factor = ca / tilted
    return p[L.KS] * (slope * factor - compression * math.sin(p[L.TILT]) / (tilted * tilted))


@numba.njit(cache=True)
def evaluate(theta, theta_dot, y, mode, p, elastic, everywhere):
    """Forces and accelerations at one instant, cam at ``theta`` [rad], ``theta_dot``
    [rad/s]; ``elastic`` drops the contact damping (the static equilibrium);
    ``everywhere`` computes the contact kinematics in free flight too (else they are 0
    there).

    Returns
    -------
    tuple
        ``(alpha_ddot [rad/s^2], u_ddot [m/s^2], v_ddot [m/s^2], Fn [N], Ff [N], Fs [N],
        Nx [N], Ny [N], delta [m], delta_dot [m/s], vr [m/s], chi [m], P_cam [W], Fk [N])``,
        ``Fs`` the force of the shortened spring, ``(Nx, Ny)`` the bearing's force on
        the follower.
    """
    alpha, alpha_dot, u, u_dot, v, v_dot = y[0], y[1], y[2], y[3], y[4], y[5]
    ca = math.cos(alpha)
    sa = math.sin(alpha)
    m = p[L.MASS]
    lcg = p[L.CG]
    # spring, eq (8)-(9)
    dsx = math.sin(p[L.TILT])
    dsy = math.cos(p[L.TILT])
    shortening = dsx * u + dsy * v
    fs0 = spring_force_trig(ca, sa, p)
    fs = fs0 - p[L.KS] * shortening
    q_alpha = m * p[L.GRAVITY] * lcg * ca + spring_moment_trig(ca, sa, fs0, p) + \
        spring_force_slope(ca, sa, p) * shortening
    nx = -p[PIVOT_STIFFNESS] * u - p[PIVOT_DAMPING] * u_dot
    ny = -p[PIVOT_STIFFNESS] * v - p[PIVOT_DAMPING] * v_dot
    qx = fs * dsx + nx
    qy = fs * dsy + ny - m * p[L.GRAVITY]
    fn = 0.0
    ff = 0.0
    fk = 0.0
    power = 0.0
    delta = delta_dot = vr = chi = 0.0
    contact = mode[L.MODE_CONTACT] > 0.5
    if contact or everywhere:
        delta, delta_dot, chi, rho_c, vr, n_v, u_v = contact_kinematics_from(
            ca, sa, math.cos(theta), math.sin(theta), alpha_dot, theta_dot, p[L.PIVOT_X] - u, p[L.PIVOT_Y] - v, p)
        delta_dot += sa * u_dot + ca * v_dot            # eq (6): + n.P'
        vr -= ca * u_dot - sa * v_dot                   # eq (7): - u_hat.P'
    if contact:
        fn, fk = contact_force(delta, 0.0 if elastic else delta_dot, rho_c, mode[L.MODE_APPROACH], p)
        ff = friction_coefficient(vr, mode[L.MODE_SLIP], p) * fn
        q_alpha += fn * chi + ff * p[L.OFFSET]      # eq 3.16, 4.13
        qx += -fn * sa + ff * ca                    # -Fn n + Ff u_hat
        qy += -fn * ca - ff * sa
        power = -fn * n_v + ff * u_v
    alpha_ddot = (q_alpha + lcg * (sa * qx + ca * qy)) / (p[L.INERTIA] - m * lcg * lcg)        # eq (4)
    w2 = alpha_dot * alpha_dot
    u_ddot = qx / m + lcg * (alpha_ddot * sa + w2 * ca)                                      # eq (5)
    v_ddot = qy / m + lcg * (alpha_ddot * ca - w2 * sa)
    return alpha_ddot, u_ddot, v_ddot, fn, ff, fs, nx, ny, delta, delta_dot, vr, chi, power, fk


@numba.njit(cache=True)
def rhs(t, y, mode, p, dydt):
    """Right-hand side ``dy/dt`` of the eight states (module docstring)."""
    theta, theta_dot = cam_angle(t, p)
    res = evaluate(theta, theta_dot, y, mode, p, False, False)
    dydt[0] = y[1]
    dydt[1] = res[0]
    dydt[2] = y[3]
    dydt[3] = res[1]
    dydt[4] = y[5]
    dydt[5] = res[2]
    dydt[6] = res[12]
    dydt[7] = p[PIVOT_DAMPING] * (y[3] * y[3] + y[5] * y[5])


@numba.njit(cache=True)
def jacobian(t, y, mode, p, jac):
    """``d f / d y`` (8 x 8) by central differences of :func:`rhs` in the six dynamic
    states (the works feed back into nothing: their columns are zero); relative steps of
    ``1e-7``, with a floor of ``1e-7`` in the angle and its rate and ``1e-12`` [m, m/s]
    in the pivot's displacement and velocity."""
    n = y.shape[0]
    jac[:, :] = 0.0
    up = np.empty(n)
    down = np.empty(n)
    probe = y.copy()
    for j in range(CONTROLLED_SIZE):
        floor = 1.0 if j < 2 else 1e-5
        step = 1e-7 * max(abs(y[j]), floor)
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
    rates: those of a pivot at rest (:func:`camdyn.model.geometry.contact_rates_from`)
    plus the pivot's motion, from (6) and (7) with ``n' = alpha' u_hat``,
    ``u_hat' = -alpha' n``::

        delta'' += 2 alpha' u_hat.P' + n.P''      vr' += alpha' n.P' - u_hat.P''

    The rates of ``vr`` and ``delta_dot`` need the accelerations ``f[1]``, ``f[3]``,
    ``f[5]`` and are NaN when they are not ``known``."""
    ca = math.cos(y[0])
    sa = math.sin(y[0])
    theta, theta_dot = cam_angle(t, p)
    alpha_dot = y[1]
    alpha_ddot = f[1] if known else math.nan
    u_ddot = f[3] if known else math.nan
    v_ddot = f[5] if known else math.nan
    delta, vr, delta_dot, vr_dot, delta_ddot = contact_rates_from(
        ca, sa, math.cos(theta), math.sin(theta), alpha_dot, alpha_ddot, theta_dot, cam_acceleration(t, p),
        p[L.PIVOT_X] - y[2], p[L.PIVOT_Y] - y[4], p)
    n_vel = sa * y[3] + ca * y[5]          # n . P'
    u_vel = ca * y[3] - sa * y[5]          # u_hat . P'
    n_acc = sa * u_ddot + ca * v_ddot
    u_acc = ca * u_ddot - sa * v_ddot
    values[0] = delta
    values[1] = vr - u_vel
    values[2] = delta_dot + n_vel
    rates[0] = values[2]
    rates[1] = vr_dot + alpha_dot * n_vel - u_acc
    rates[2] = delta_ddot + 2.0 * alpha_dot * u_vel + n_acc


# The contact modes, their guards' expected signs, transitions and the initial mode are the
# cam-follower's (camdyn.model.dynamics: mode_*), applied by camdyn.systems.mechanisms.
@numba.njit(cache=True)
def monitor(t, y, mode, p):
    """Normal force [N] during an impact (its peak goes to the event log), else 0."""
    if mode[L.MODE_CONTACT] > 0.5 and mode[L.MODE_IMPACT] > 0.5:
        theta, theta_dot = cam_angle(t, p)
        return evaluate(theta, theta_dot, y, mode, p, False, False)[3]
    return 0.0


@numba.njit(cache=True)
def static_residual(x, theta, theta_dot, mode, p):
    """Accelerations ``(alpha'', u'', v'')`` [rad/s^2, m/s^2, m/s^2] of the follower at
    rest at ``x = (alpha [rad], u [m], v [m])``, the contact damping dropped, the cam at
    ``theta`` [rad] turning at ``theta_dot`` [rad/s] (which sets the friction's
    direction); zero at the static equilibrium."""
    y = np.array([x[0], 0.0, x[1], 0.0, x[2], 0.0])
    res = evaluate(theta, theta_dot, y, mode, p, True, True)
    return np.array([res[0], res[1], res[2]])


#: name, unit, long name of each derived channel of :func:`channels`, in column order.
CHANNELS = (
    ("alpha_ddot", "rad/s^2", "follower angular acceleration"),
    ("u_ddot", "m/s^2", "horizontal acceleration of the follower pivot"),
    ("v_ddot", "m/s^2", "vertical acceleration of the follower pivot"),
    ("Fn", "N", "normal contact force on the follower"),
    ("Ff", "N", "friction force on the follower along the bar (u)"),
    ("Fs", "N", "spring force (compression)"),
    ("Nx", "N", "bearing force on the follower, horizontal (bearing spring and damper)"),
    ("Ny", "N", "bearing force on the follower, vertical (bearing spring and damper)"),
    ("penetration", "m", "contact penetration delta (negative: gap)"),
    ("penetration_rate", "m/s", "penetration rate delta_dot"),
    ("sliding_velocity", "m/s", "sliding velocity vr of the cam relative to the follower"),
    ("moment_arm", "m", "moment arm chi of the normal force about the moving pivot"),
    ("cam_angle", "rad", "cam angle Theta"),
    ("in_contact", "1", "1 while the follower touches the cam"),
)


@numba.njit(cache=True)
def channels(t, y, modes, p):
    """Channels of :data:`CHANNELS` at the sampled times ``t`` [s], states ``y`` (n, 8) and
    modes ``modes`` (n, mode size); NaN rows where the state is NaN (a run that stopped
    early)."""
    n = y.shape[0]
    out = np.full((n, len(CHANNELS)), np.nan)
    for i in range(n):
        if math.isnan(y[i, 0]):
            continue
        theta, theta_dot = cam_angle(t[i], p)
        res = evaluate(theta, theta_dot, y[i], modes[i], p, False, True)
        row = out[i]
        for k in range(12):
            row[k] = res[k]
        row[12] = theta
        row[13] = modes[i, L.MODE_CONTACT]
    return out
