"""Cam-follower geometry and kinematics in closed form (docs/model.md §1-2).

Frames: origin at the follower pivot P, ``x`` towards the cam pivot, ``y`` up. The
follower angle ``alpha`` is clockwise from ``x``; ``u = (cos alpha, -sin alpha)`` runs
along the bar and ``n = (sin alpha, cos alpha)`` points from the follower to the cam.
The cam (semi-axes ``a >= b``, pivot E on the major axis at distance ``e`` from the
centroid) turns counter-clockwise by ``Theta``.

With the support function ``s(n) = sqrt(a^2 (n.e1)^2 + b^2 (n.e2)^2)`` the contact
point, penetration and moment arm follow without root finding, unlike the thesis's
slope matching (eqs 4.11-4.12). A cam given by a profile table (slot ``CAM_SHAPE`` of
:mod:`camdyn.model.layout`) takes the same quantities from its tabulated support function
(:mod:`camdyn.model.rocking_profile`).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.errors import GeometryError
from camdyn.model import layout as L
from camdyn.model.rocking_profile import (
    contact_point_profile,
    contact_point_rate_profile,
    contact_rates_profile,
    lift_extent,
    reference_angle,
)

__all__ = ["cam_angle", "cam_acceleration", "contact_kinematics", "contact_point", "zero_state", "contact_point_rate",
           "contact_rates_trig", "penetrations", "rigid_angles", "pressed_angles", "contact_point_from",
           "contact_kinematics_from", "contact_rates_from"]


@numba.njit(cache=True)
def cam_angle(t, p):
    """Cam angle ``Theta`` [rad] and speed ``Theta_dot`` [rad/s] at time ``t`` [s].

    Constant motion ``Theta0 + Omega t``; oscillating motion
    ``Theta0 + 0.5 Theta_p sin(omega_c t)`` (thesis 2.7.2); a ramp from ``Omega0`` to
    ``Omega`` over ``T``: ``Theta0 + Omega0 t + 0.5 (Omega - Omega0) t^2 / T`` until ``T``,
    then ``Theta0 + 0.5 (Omega0 + Omega) T + Omega (t - T)`` (uniform acceleration).
    """
    if p[L.MOTION_KIND] == 0.0:
        return p[L.THETA0] + p[L.OMEGA] * t, p[L.OMEGA]
    if p[L.MOTION_KIND] == 2.0:
        return _ramp_angle(t, p)
    if p[L.MOTION_KIND] == 3.0:
        angle, speed, acceleration = _table_angle(t, p)
        return angle, speed
    half = 0.5 * p[L.SWING]
    w = p[L.OMEGA_C]
    return p[L.THETA0] + half * math.sin(w * t), half * w * math.cos(w * t)


@numba.njit(cache=True)
def _ramp_angle(t, p):
    """Cam angle [rad] and speed [rad/s] of the ramp of :func:`cam_angle`."""
    start = p[L.START_OMEGA]
    end = p[L.OMEGA]
    duration = p[L.RAMP_TIME]
    if t < duration:
        return p[L.THETA0] + start * t + 0.5 * (end - start) * t * t / duration, start + (end - start) * t / duration
    return p[L.THETA0] + 0.5 * (start + end) * duration + end * (t - duration), end


@numba.njit(cache=True)
def _table_angle(t, p):
    """Cam angle [rad], speed [rad/s] and acceleration [rad/s^2] of a tabulated motion:
    ``Theta(t) = g(t) + W t`` with ``W`` the mean speed and ``g`` a periodic cubic spline
    of period ``T`` on uniform knots; the coefficients of its power form in each interval,
    ``g = a0 + a1 s + a2 s^2 + a3 s^3`` with ``s`` the time from the interval's start,
    follow one another from slot ``p[TABLE_START]`` of ``p``."""
    period = p[L.TABLE_PERIOD]
    intervals = int(p[L.TABLE_INTERVALS])
    step = period / intervals
    tau = t - period * math.floor(t / period)
    i = min(int(tau / step), intervals - 1)
    s = tau - i * step
    c = int(p[L.TABLE_START]) + 4 * i
    a0, a1, a2, a3 = p[c], p[c + 1], p[c + 2], p[c + 3]
    drift = p[L.TABLE_DRIFT]
    return (a0 + s * (a1 + s * (a2 + s * a3)) + drift * t, a1 + s * (2.0 * a2 + 3.0 * a3 * s) + drift,
            2.0 * a2 + 6.0 * a3 * s)


@numba.njit(cache=True)
def cam_acceleration(t, p):
    """Cam angular acceleration ``Theta_ddot`` [rad/s^2] at time ``t`` [s]."""
    if p[L.MOTION_KIND] == 0.0:
        return 0.0
    if p[L.MOTION_KIND] == 2.0:
        return (p[L.OMEGA] - p[L.START_OMEGA]) / p[L.RAMP_TIME] if t < p[L.RAMP_TIME] else 0.0
    if p[L.MOTION_KIND] == 3.0:
        return _table_angle(t, p)[2]
    w = p[L.OMEGA_C]
    return -0.5 * p[L.SWING] * w * w * math.sin(w * t)


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


@numba.njit(cache=True, inline="always")
def contact_point_trig(ca, sa, ct, st, p):
    """:func:`contact_point` from ``cos/sin`` of ``alpha`` and ``Theta`` (computed once by
    the right-hand side and shared with the spring and gravity terms)."""
    if p[L.CAM_SHAPE] != L.ELLIPSE:
        return contact_point_profile(ca, sa, ct, st, p)
    return contact_point_from(ca, sa, ct, st, p[L.PIVOT_X], p[L.PIVOT_Y], p)


@numba.njit(cache=True, inline="always")
def contact_point_from(ca, sa, ct, st, ex, ey, p):
    """:func:`contact_point_trig` with the cam pivot E at ``(ex, ey)`` [m] from the
    follower pivot instead of ``p``'s ``(PE_x, PE_y)`` (a follower whose pivot moves,
    :mod:`camdyn.model.flexible_pivot`; an ellipse only)."""
    a = p[L.SEMI_A]
    b = p[L.SEMI_B]
    e = p[L.RUNOUT]
    gx = ex - e * ct          # centroid Gc = E - e e1
    gy = ey - e * st
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
def penetrations(alphas, theta, p):
    """Penetration ``delta`` [m] at each follower angle ``alphas`` [rad], cam at ``theta``
    [rad] (a scan in one compiled call)."""
    out = np.empty(alphas.size)
    ct = math.cos(theta)
    st = math.sin(theta)
    for i in range(alphas.size):
        out[i] = contact_point_trig(math.cos(alphas[i]), math.sin(alphas[i]), ct, st, p)[0]
    return out


@numba.njit(cache=True)
def contact_kinematics(alpha, alpha_dot, theta, theta_dot, p):
    """Penetration, its rate, moment arm and sliding velocity (docs/model.md §2).

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


@numba.njit(cache=True, inline="always")
def contact_kinematics_trig(ca, sa, ct, st, alpha_dot, theta_dot, p):
    """:func:`contact_kinematics` from ``cos/sin`` of ``alpha`` and ``Theta``."""
    return contact_kinematics_from(ca, sa, ct, st, alpha_dot, theta_dot, p[L.PIVOT_X], p[L.PIVOT_Y], p)


@numba.njit(cache=True, inline="always")
def contact_kinematics_from(ca, sa, ct, st, alpha_dot, theta_dot, ex, ey, p):
    """:func:`contact_kinematics_trig` with the cam pivot E at ``(ex, ey)`` [m] from the
    follower pivot (:func:`contact_point_from`; a profile table's cam turns about ``p``'s
    pivot); the rates are those of a pivot at rest."""
    if p[L.CAM_SHAPE] != L.ELLIPSE:
        delta, chi, rho_c, xc, yc = contact_point_profile(ca, sa, ct, st, p)
    else:
        delta, chi, rho_c, xc, yc = contact_point_from(ca, sa, ct, st, ex, ey, p)
    vx = -theta_dot * (yc - ey)   # v_cam = Theta_dot z x (Xc - E)
    vy = theta_dot * (xc - ex)
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
    See :func:`contact_rates_trig` for the closed form.
    """
    ca = math.cos(alpha)
    sa = math.sin(alpha)
    ct = math.cos(theta)
    st = math.sin(theta)
    if p[L.CAM_SHAPE] != L.ELLIPSE:
        return contact_point_rate_profile(ca, sa, ct, st, alpha_dot, theta_dot, p)
    n1 = sa * ct + ca * st
    n2 = -sa * st + ca * ct
    a = p[L.SEMI_A]
    b = p[L.SEMI_B]
    s = math.sqrt(a * a * n1 * n1 + b * b * n2 * n2)
    rho_c = a * a * b * b / (s * s * s)
    n_e = sa * p[L.PIVOT_X] + ca * p[L.PIVOT_Y]
    return -alpha_dot * n_e + (alpha_dot + theta_dot) * (p[L.RUNOUT] * n1 + s - rho_c)


@numba.njit(cache=True, inline="always")
def contact_rates_trig(ca, sa, ct, st, alpha_dot, alpha_ddot, theta_dot, theta_ddot, p):
    """The guards of the compiled core and their exact time derivatives.

    With ``phi = alpha + Theta``, the normal's cam-frame components are
    ``n1 = sin(phi)``, ``n2 = cos(phi)``, and ``n . (Xc - E) = -(e n1 + s)``, so

    - ``vr = Theta_dot w - alpha_dot h`` with ``w = e n1 + s``;
    - ``chi_dot = -alpha_dot n.E + phi_dot (w - rho_c)`` (the support function's
      identity ``(a^2 n2^2 + b^2 n1^2) s^2 - n1^2 n2^2 (a^2 - b^2)^2 = a^2 b^2``);
    - ``delta_dot = -alpha_dot chi - Theta_dot (chi - u.E)``.

    Returns
    -------
    tuple
        ``(delta [m], vr [m/s], delta_dot [m/s], vr_dot [m/s^2], delta_ddot [m/s^2])``;
        the rates are NaN when ``alpha_ddot`` is NaN (unknown).
    """
    if p[L.CAM_SHAPE] != L.ELLIPSE:
        return contact_rates_profile(ca, sa, ct, st, alpha_dot, alpha_ddot, theta_dot, theta_ddot, p)
    return contact_rates_from(ca, sa, ct, st, alpha_dot, alpha_ddot, theta_dot, theta_ddot,
                              p[L.PIVOT_X], p[L.PIVOT_Y], p)


@numba.njit(cache=True, inline="always")
def contact_rates_from(ca, sa, ct, st, alpha_dot, alpha_ddot, theta_dot, theta_ddot, ex, ey, p):
    """:func:`contact_rates_trig` with the cam pivot E at ``(ex, ey)`` [m] from the
    follower pivot (:func:`contact_point_from`; an ellipse only); the rates are those of
    a pivot at rest."""
    delta, chi, rho_c, xc, yc = contact_point_from(ca, sa, ct, st, ex, ey, p)
    a = p[L.SEMI_A]
    b = p[L.SEMI_B]
    e = p[L.RUNOUT]
    n1 = sa * ct + ca * st
    n2 = -sa * st + ca * ct
    s = math.sqrt(a * a * n1 * n1 + b * b * n2 * n2)
    w = e * n1 + s
    n_e = sa * ex + ca * ey     # n . E
    u_e = ca * ex - sa * ey     # u . E
    phi_dot = alpha_dot + theta_dot
    vr = theta_dot * w - alpha_dot * p[L.OFFSET]
    delta_dot = -alpha_dot * chi - theta_dot * (chi - u_e)
    vr_dot = (theta_ddot * w + theta_dot * phi_dot * n2 * (e + n1 * (a * a - b * b) / s)
              - alpha_ddot * p[L.OFFSET])
    chi_dot = -alpha_dot * n_e + phi_dot * (w - rho_c)
    delta_ddot = (-alpha_ddot * chi - phi_dot * chi_dot - theta_ddot * (chi - u_e)
                  - theta_dot * alpha_dot * n_e)
    return delta, vr, delta_dot, vr_dot, delta_ddot


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


@numba.njit(cache=True)
def pressed_angles(times, p, alpha_start, pressed):
    """Follower angles [rad] at ``times`` [s] with the follower pressed ``pressed`` [m]
    into the cam (``delta = pressed``; 0: rigid contact), the cam at its prescribed angle
    (:func:`cam_angle`), by Newton's method from ``alpha_start`` [rad] as
    :func:`rigid_angles`."""
    out = np.empty_like(times)
    a = alpha_start
    for i in range(times.size):
        theta = cam_angle(times[i], p)[0]
        for _ in range(60):
            delta, chi, rho_c, xc, yc = contact_point(a, theta, p)
            step = (delta - pressed) / chi
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

    ``system.motion.zero_state`` chooses: ``"maximum-lift"`` is the first convention
    (thesis eqs 3.3-3.4), ``"runout-parallel"`` the second (eqs 4.3-4.4, for a circle
    ``h + rc`` with no runout in the touching condition), ``"auto"`` the first for a
    circle and the second for an ellipse.

    A cam given by a profile (``system.profile``): the follower touches the cam where
    its support function is ``h(theta*)``, ``PEx sin a0 + PEy cos a0 = h + h(theta*)``, and
    ``Theta0 = theta* + pi/2 - a0`` (:mod:`camdyn.model.rocking_profile`, eq R1), with
    ``theta*`` the maximum lift (``"maximum-lift"``, and ``"auto"``) or ``-pi/2``
    (``"runout-parallel"``: the eccentric circle's runout along the follower); both give
    the circle's 0-states for :func:`camdyn.model.profiles.eccentric_circle`.

    Raises
    ------
    GeometryError
        If no follower angle lets the follower touch the cam.
    """
    c, f = system.cam, system.follower
    h = f.surface_offset
    if system.profile is not None:
        return _profile_zero_state(system)
    lift = system.motion.zero_state == "maximum-lift" or (system.motion.zero_state == "auto" and c.is_circle)
    rhs = h + c.semi_major + c.runout if lift else h + c.semi_minor
    r = math.hypot(c.pivot_x, c.pivot_y)
    if rhs > r:
        raise GeometryError(
            f"the cam cannot reach the follower: the cam pivot is {r*1e3:.3g} mm from the follower pivot, "
            f"but contact needs {rhs*1e3:.3g} mm (surface offset + cam size + runout)")
    phase = math.atan2(c.pivot_y, c.pivot_x)   # PEx sin a + PEy cos a = r sin(a + phase)
    a0 = math.asin(rhs / r) - phase             # the root with the bar nearest horizontal
    theta0 = math.pi / 2 - a0 if lift else -a0
    return a0, theta0


def _profile_zero_state(system) -> tuple[float, float]:
    """:func:`zero_state` of a cam given by a profile."""
    c, profile = system.cam, system.profile
    theta_star = reference_angle(profile, system.motion.zero_state != "runout-parallel")
    rhs = system.follower.surface_offset + profile.base_radius + float(profile.lift(theta_star)[0][0])
    r = math.hypot(c.pivot_x, c.pivot_y)
    if rhs > r:
        raise GeometryError(
            f"the cam cannot reach the follower: the cam pivot is {r*1e3:.3g} mm from the follower pivot, "
            f"but contact needs {rhs*1e3:.3g} mm (surface offset + the profile's base radius and lift)")
    phase = math.atan2(c.pivot_y, c.pivot_x)
    a0 = math.asin(rhs / r) - phase
    return a0, (theta_star + math.pi / 2) - a0


def profile_reach(profile) -> tuple[float, float, float]:
    """``(lift range [m], lowest h' [m/rad], highest h' [m/rad])`` of a cam profile: how
    far its support function and so the moment arm (``chi = u.E - h'``, eq R3 of
    :mod:`camdyn.model.rocking_profile`) move over a revolution."""
    h_min, h_max, slope_min, slope_max = lift_extent(profile)
    return h_max - h_min, slope_min, slope_max
