"""Cam-follower geometry and kinematics in closed form (MODEL.md §1-2).

Frames: origin at the follower pivot P, ``x`` towards the cam pivot, ``y`` up. The
follower angle ``alpha`` is clockwise from ``x``; ``u = (cos alpha, -sin alpha)`` runs
along the bar and ``n = (sin alpha, cos alpha)`` points from the follower to the cam.
The cam (semi-axes ``a >= b``, pivot E on the major axis at distance ``e`` from the
centroid) turns counter-clockwise by ``Theta``.

With the support function ``s(n) = sqrt(a^2 (n.e1)^2 + b^2 (n.e2)^2)`` the contact
point, penetration and moment arm follow without root finding, unlike the thesis's
slope matching (eqs 4.11-4.12).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.errors import GeometryError
from camdyn.model import layout as L

__all__ = ["cam_angle", "contact_kinematics", "contact_point", "zero_state", "contact_point_rate", "rigid_angles"]


@numba.njit(cache=True)
def cam_angle(t, p):
    """Cam angle ``Theta`` [rad] and speed ``Theta_dot`` [rad/s] at time ``t`` [s].

    Constant motion ``Theta0 + Omega t``; oscillating motion
    ``Theta0 + 0.5 Theta_p sin(omega_c t)`` (thesis 2.7.2).
    """
    if p[L.MOTION_KIND] == 0.0:
        return p[L.THETA0] + p[L.OMEGA] * t, p[L.OMEGA]
    half = 0.5 * p[L.SWING]
    w = p[L.OMEGA_C]
    return p[L.THETA0] + half * math.sin(w * t), half * w * math.cos(w * t)


@numba.njit(cache=True)
def contact_point(alpha, theta, p):
    """Closest cam point to the follower surface.

    Returns
    -------
    delta : float
        Penetration [m], positive in contact (``-psi_i`` of the thesis).
    chi : float
        Moment arm of the normal force about P, ``u . Xc`` [m].
    rho_c : float
        Cam radius of curvature at the contact point [m].
    xc, yc : float
        Contact point ``Xc`` on the cam [m].
    """
    return contact_point_trig(math.cos(alpha), math.sin(alpha), math.cos(theta), math.sin(theta), p)


@numba.njit(cache=True)
def contact_point_trig(ca, sa, ct, st, p):
    """:func:`contact_point` from ``cos/sin`` of ``alpha`` and ``Theta`` (computed once by
    the right-hand side and shared with the spring and gravity terms)."""
    a = p[L.SEMI_A]
    b = p[L.SEMI_B]
    e = p[L.RUNOUT]
    gx = p[L.PIVOT_X] - e * ct          # centroid Gc = E - e e1
    gy = p[L.PIVOT_Y] - e * st
    n1 = sa * ct + ca * st              # n . e1
    n2 = -sa * st + ca * ct             # n . e2
    s = math.sqrt(a * a * n1 * n1 + b * b * n2 * n2)
    inv_s = 1.0 / s
    delta = p[L.OFFSET] + s - (sa * gx + ca * gy)
    q1 = a * a * n1 * inv_s
    q2 = b * b * n2 * inv_s
    xc = gx - (q1 * ct - q2 * st)
    yc = gy - (q1 * st + q2 * ct)
    chi = ca * xc - sa * yc
    rho_c = a * a * b * b * inv_s * inv_s * inv_s
    return delta, chi, rho_c, xc, yc


@numba.njit(cache=True)
def contact_kinematics(alpha, alpha_dot, theta, theta_dot, p):
    """Penetration, its rate, moment arm and sliding velocity (MODEL.md §2).

    Returns
    -------
    delta : float
        Penetration [m].
    delta_dot : float
        ``-alpha_dot chi - n . v_cam(Xc)`` [m/s] (envelope theorem).
    chi : float
        Moment arm [m].
    rho_c : float
        Cam radius of curvature at the contact [m].
    vr : float
        Sliding velocity ``(v_cam(Xc) - v_fol) . u`` [m/s]: the cam surface relative
        to the follower, along the bar.
    n_vcam, u_vcam : float
        Normal and tangential components of the cam's material velocity at Xc [m/s].
    """
    return contact_kinematics_trig(math.cos(alpha), math.sin(alpha), math.cos(theta), math.sin(theta),
                                   alpha_dot, theta_dot, p)


@numba.njit(cache=True)
def contact_kinematics_trig(ca, sa, ct, st, alpha_dot, theta_dot, p):
    """:func:`contact_kinematics` from ``cos/sin`` of ``alpha`` and ``Theta``."""
    delta, chi, rho_c, xc, yc = contact_point_trig(ca, sa, ct, st, p)
    vx = -theta_dot * (yc - p[L.PIVOT_Y])   # v_cam = Theta_dot z x (Xc - E)
    vy = theta_dot * (xc - p[L.PIVOT_X])
    n_v = sa * vx + ca * vy
    u_v = ca * vx - sa * vy
    delta_dot = -alpha_dot * chi - n_v
    vr = u_v - alpha_dot * p[L.OFFSET]       # u . v_fol = alpha_dot h
    return delta, delta_dot, chi, rho_c, vr, n_v, u_v


@numba.njit(cache=True)
def contact_point_rate(alpha, alpha_dot, theta, theta_dot, p):
    """Rate ``chi_dot`` [m/s] at which the contact point moves along the bar.

    The follower's surface moves relative to the contact point at ``u_b = -chi_dot``;
    the cam's at ``u_c = vr + u_b``; the sum velocity is ``ve = u_c + u_b`` (eq 4.26).
    """
    ca = math.cos(alpha)
    sa = math.sin(alpha)
    ct = math.cos(theta)
    st = math.sin(theta)
    a = p[L.SEMI_A]
    b = p[L.SEMI_B]
    e = p[L.RUNOUT]
    gx = p[L.PIVOT_X] - e * ct
    gy = p[L.PIVOT_Y] - e * st
    n1 = sa * ct + ca * st
    n2 = -sa * st + ca * ct
    s = math.sqrt(a * a * n1 * n1 + b * b * n2 * n2)
    q1 = -a * a * n1 / s                    # Xc = Gc + q1 e1 + q2 e2
    q2 = -b * b * n2 / s
    ux, uy = ca, -sa
    e1x, e1y = ct, st
    e2x, e2y = -st, ct
    n1_dot = alpha_dot * (ux * e1x + uy * e1y) + theta_dot * n2   # dn/dt = alpha_dot u
    n2_dot = alpha_dot * (ux * e2x + uy * e2y) - theta_dot * n1   # de1/dt = Theta_dot e2
    s_dot = (a * a * n1 * n1_dot + b * b * n2 * n2_dot) / s
    q1_dot = -a * a * (n1_dot * s - n1 * s_dot) / (s * s)
    q2_dot = -b * b * (n2_dot * s - n2 * s_dot) / (s * s)
    xc = gx + q1 * e1x + q2 * e2x
    yc = gy + q1 * e1y + q2 * e2y
    # dXc/dt = dGc/dt + q1_dot e1 + q2_dot e2 + Theta_dot (q1 e2 - q2 e1)
    gx_dot = e * theta_dot * st
    gy_dot = -e * theta_dot * ct
    xc_dot = gx_dot + q1_dot * e1x + q2_dot * e2x + theta_dot * (q1 * e2x - q2 * e1x)
    yc_dot = gy_dot + q1_dot * e1y + q2_dot * e2y + theta_dot * (q1 * e2y - q2 * e1y)
    # chi = u . Xc, du/dt = -alpha_dot n
    return -alpha_dot * (sa * xc + ca * yc) + ux * xc_dot + uy * yc_dot


@numba.njit(cache=True)
def rigid_angles(thetas, p, alpha_start):
    """Follower angles [rad] with ``delta = 0`` (rigid contact) at each cam angle
    ``thetas`` [rad], by Newton's method from ``alpha_start`` [rad] (``d delta / d alpha
    = -chi`` exactly, the envelope theorem)."""
    out = np.empty_like(thetas)
    a = alpha_start
    for i in range(thetas.size):
        for _ in range(60):
            delta, chi, rho_c, xc, yc = contact_point(a, thetas[i], p)
            step = delta / chi
            a += step
            if abs(step) < 1e-15:
                break
        out[i] = a
    return out


def zero_state(system) -> tuple[float, float]:
    """The thesis's 0-state: follower angle ``a0`` and cam angle ``Theta0`` [rad].

    Circle (a = b): the follower just touches the cam with the centroid offset
    along the follower normal, i.e. at the cam's lowest point (maximum lift):
    ``PEx sin a0 + PEy cos a0 = h + rc + e`` and ``Theta0 = pi/2 - a0``.

    Ellipse (a > b): as in the thesis (4.3), the major axis is parallel to the
    follower, ``Theta0 = -a0``, so ``PEx sin a0 + PEy cos a0 = h + b``.

    Raises
    ------
    GeometryError
        If no follower angle lets the follower touch the cam.
    """
    c, f = system.cam, system.follower
    h = f.surface_offset
    rhs = h + c.semi_major + c.runout if c.is_circle else h + c.semi_minor
    r = math.hypot(c.pivot_x, c.pivot_y)
    if rhs > r:
        raise GeometryError(
            f"the cam cannot reach the follower: the cam pivot is {r*1e3:.3g} mm from the follower pivot, "
            f"but contact needs {rhs*1e3:.3g} mm (surface offset + cam size + runout)")
    phase = math.atan2(c.pivot_y, c.pivot_x)   # PEx sin a + PEy cos a = r sin(a + phase)
    a0 = math.asin(rhs / r) - phase             # the root with the bar nearest horizontal
    theta0 = math.pi / 2 - a0 if c.is_circle else -a0
    return a0, theta0
