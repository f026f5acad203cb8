"""The rocking follower's cam given by a profile table (:mod:`camdyn.model.profiles`)
instead of the ellipse's closed form: the contact geometry of :mod:`camdyn.model.geometry`
from the cam's support function about its rotation centre E.

Frames as in :mod:`camdyn.model.geometry`: the follower's normal ``n = (sin alpha, cos
alpha)`` points from the follower to the cam, ``u = (cos alpha, -sin alpha)`` runs along
the bar, and ``phi = alpha + Theta`` is the normal's angle in the cam's frame
(``n . e1 = sin phi``, ``n . e2 = cos phi``).

**The angle mapping.** A profile gives the flat-faced translating follower's lift
``s(theta)`` [m] at the cam angle ``theta`` [rad]; its support function about the cam's
axis is ``h(theta) = r_base + s(theta)`` (Rothbart 2004), with ``theta`` the polar angle,
in the profile's own frame, of the cam's outward normal at the contact. The rocking cam's
outward normal at the contact is ``-n``. The profile is placed so that

    theta = phi - pi / 2                                                        (R1)

so that (i) the cam turning counter-clockwise (``Theta`` growing, the rocking model's
positive sense) runs through the lift in the profile's order, as the translating
follower's ``theta = theta0 + omega t`` does, and (ii) the eccentric circle of
:func:`camdyn.model.profiles.eccentric_circle` (its centre at ``theta = 0``) is the
rocking model's circle (its centroid at ``-e e1``): ``h = e cos(theta) + R = e sin(phi) +
R``, the closed form's ``w = e n1 + s``. (R1) mirrors the profile's frame into the cam's
(a profile point at polar angle ``theta`` lies at ``pi - theta`` in the cam's frame),
because the translating follower's ``theta`` grows where the cam turns clockwise.

**The contact.** With ``h, h', h''`` at ``theta`` of (R1) (primes: d/d theta), the
contact point on the cam is ``Xc = E - h n - h' u`` (the support function's tangent
point, ``d/d theta`` of (R1) turning ``-n`` towards ``-u``), so

    delta = h_off + h - n.E                                                     (R2)
    chi   = u.Xc = u.E - h'                                                     (R3)
    rho_c = h + h''                                                             (R4)

and, with ``phi_dot = alpha_dot + Theta_dot``, ``v_cam(Xc) = Theta_dot z x (Xc - E)``:

    vr        = Theta_dot h - alpha_dot h_off,    n.v_cam = -Theta_dot h'       (R5)
    delta_dot = -alpha_dot chi + Theta_dot h'                                   (R6)
    chi_dot   = -alpha_dot n.E - phi_dot h''                                    (R7)
    vr_dot    = Theta_ddot h + Theta_dot phi_dot h' - alpha_ddot h_off          (R8)

which are the closed form's (:func:`camdyn.model.geometry.contact_rates_trig`) with
``w = h``, ``chi - u.E = -h'`` and ``w - rho_c = -h''``.

Reference: H. A. Rothbart, *Cam Design Handbook*, McGraw-Hill 2004 (support function and
radius of curvature of a flat-faced follower's cam).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.errors import GeometryError
from camdyn.model import layout as L
from camdyn.model.lift_laws import segment_values
from camdyn.model.profiles import ROW, TWO_PI

__all__ = ["lift_at", "support", "contact_point_profile", "contact_rates_profile", "contact_point_rate_profile",
           "reference_angle", "lift_extent"]

HALF_PI = 0.5 * math.pi


@numba.njit(cache=True, inline="always")
def lift_at(p, start, theta):
    """:func:`camdyn.model.profiles.evaluate` of the table at ``p[start:]``, compiled into
    its caller: the lift [m] and its first three derivatives in the cam angle at
    ``theta`` [rad]. The table's numbers go to the segment one by one, so that the
    integrator's inlined loop passes no array to a call (which cost the ellipse's path
    its reference counting: 10 %, measured)."""
    n = int(p[start])
    angle = theta % TWO_PI
    lo = 0
    hi = n - 1
    while lo < hi:   # the last row whose start is <= angle
        mid = (lo + hi + 1) // 2
        if p[start + 1 + mid * ROW + 1] <= angle:
            lo = mid
        else:
            hi = mid - 1
    r = start + 1 + lo * ROW
    return segment_values(p[r], p[r + 1], p[r + 2], p[r + 3], p[r + 4], p[r + 5], p[r + 6], p[r + 7], angle)


@numba.njit(cache=True, inline="always")
def support(ca, sa, ct, st, p):
    """Support function ``h`` [m] of the cam about E and its derivatives ``h'`` [m/rad],
    ``h''`` [m/rad^2] at the normal's angle ``phi = alpha + Theta``, through (R1), from
    ``cos/sin`` of ``alpha`` and ``Theta``."""
    n1 = sa * ct + ca * st              # n . e1 = sin(phi)
    n2 = -sa * st + ca * ct             # n . e2 = cos(phi)
    theta = math.atan2(n1, n2) - HALF_PI   # (R1)
    s, s1, s2, s3 = lift_at(p, int(p[L.PROFILE_START]), theta)
    return p[L.BASE_RADIUS] + s, s1, s2


@numba.njit(cache=True, inline="always")
def contact_point_profile(ca, sa, ct, st, p):
    """``(delta [m], chi [m], rho_c [m], xc [m], yc [m])`` of
    :func:`camdyn.model.geometry.contact_point_trig` for a cam of shape
    :data:`~camdyn.model.layout.PROFILE_TABLE`: eqs (R2)-(R4)."""
    h, h1, h2 = support(ca, sa, ct, st, p)
    px = p[L.PIVOT_X]
    py = p[L.PIVOT_Y]
    delta = p[L.OFFSET] + h - (sa * px + ca * py)     # (R2)
    chi = (ca * px - sa * py) - h1                     # (R3)
    xc = px - h * sa - h1 * ca                         # Xc = E - h n - h' u
    yc = py - h * ca + h1 * sa
    return delta, chi, h + h2, xc, yc                  # (R4)


@numba.njit(cache=True, inline="always")
def contact_rates_profile(ca, sa, ct, st, alpha_dot, alpha_ddot, theta_dot, theta_ddot, p):
    """The guards and their rates of :func:`camdyn.model.geometry.contact_rates_trig` for
    a cam of shape :data:`~camdyn.model.layout.PROFILE_TABLE`: eqs (R5)-(R8); the same
    returns ``(delta [m], vr [m/s], delta_dot [m/s], vr_dot [m/s^2], delta_ddot [m/s^2])``."""
    h, h1, h2 = support(ca, sa, ct, st, p)
    px = p[L.PIVOT_X]
    py = p[L.PIVOT_Y]
    n_e = sa * px + ca * py
    u_e = ca * px - sa * py
    delta = p[L.OFFSET] + h - n_e                      # (R2)
    chi = u_e - h1                                     # (R3)
    phi_dot = alpha_dot + theta_dot
    vr = theta_dot * h - alpha_dot * p[L.OFFSET]       # (R5)
    delta_dot = -alpha_dot * chi + theta_dot * h1      # (R6)
    vr_dot = theta_ddot * h + theta_dot * phi_dot * h1 - alpha_ddot * p[L.OFFSET]   # (R8)
    chi_dot = -alpha_dot * n_e - phi_dot * h2          # (R7)
    delta_ddot = (-alpha_ddot * chi - phi_dot * chi_dot + theta_ddot * h1
                  - theta_dot * alpha_dot * n_e)       # d/dt of (R6) with (R7)
    return delta, vr, delta_dot, vr_dot, delta_ddot


@numba.njit(cache=True, inline="always")
def contact_point_rate_profile(ca, sa, ct, st, alpha_dot, theta_dot, p):
    """``chi_dot`` [m/s] of :func:`camdyn.model.geometry.contact_point_rate` for a cam of
    shape :data:`~camdyn.model.layout.PROFILE_TABLE`: eq (R7)."""
    h, h1, h2 = support(ca, sa, ct, st, p)
    n_e = sa * p[L.PIVOT_X] + ca * p[L.PIVOT_Y]
    return -alpha_dot * n_e - (alpha_dot + theta_dot) * h2


def lift_extent(profile, points: int = 3600):
    """``(h_min, h_max, slope_min, slope_max)``: the smallest and largest support
    function ``h = r_base + s`` [m] and slope ``h'`` [m/rad] of ``profile`` over one
    revolution, sampled at ``points`` angles and refined at the extremes of ``h`` by
    Newton's method on ``h' = 0``."""
    grid = np.linspace(0.0, 2.0 * math.pi, points, endpoint=False)
    s, s1, _, _ = profile.lift(grid)
    low = _stationary(profile, grid[int(np.argmin(s))])
    high = _stationary(profile, grid[int(np.argmax(s))])
    r = profile.base_radius
    h_low = r + float(profile.lift(low)[0][0])
    h_high = r + float(profile.lift(high)[0][0])
    return min(h_low, r + s.min()), max(h_high, r + s.max()), float(s1.min()), float(s1.max())


def _stationary(profile, start: float, reach: float = 2e-3) -> float:
    """Angle [rad] within ``reach`` [rad] of ``start`` where ``h' = 0``, by Newton's
    method from ``start``; ``start`` itself where the iteration leaves that reach (a
    dwell, where ``h'' = 0``, or a corner of the sampled grid)."""
    theta = start
    for _ in range(30):
        _, s1, s2, _ = (float(v[0]) for v in profile.lift(theta))
        if s2 == 0.0:
            break
        step = s1 / s2
        theta -= step
        if not abs(theta - start) < reach:
            return start
        if abs(step) < 1e-15:
            break
    return theta


def reference_angle(profile, lift: bool) -> float:
    """Profile angle ``theta*`` [rad] of the 0-state (:func:`camdyn.model.geometry.zero_state`):
    the maximum lift when ``lift`` (the analogue of the circle's maximum lift, eqs
    3.3-3.4), else ``-pi/2``, where the eccentric circle's runout lies along the follower
    (eqs 4.3-4.4). The cam angle of the 0-state is then ``Theta0 = theta* + pi/2 - a0``,
    from (R1) with ``phi = a0 + Theta0``."""
    if not lift:
        return -HALF_PI
    grid = np.linspace(0.0, 2.0 * math.pi, 3600, endpoint=False)
    theta = _stationary(profile, float(grid[int(np.argmax(profile.lift(grid)[0]))]))
    if not math.isfinite(theta):
        raise GeometryError("the cam profile's maximum lift could not be located")
    return theta
