"""Kinematics of a rocking (oscillating) arm carrying a roller or a knife edge on a cam of
any profile (:mod:`camdyn.model.profiles`): the arm angle ``psi_c(theta)`` [rad] at which
the roller touches the cam turned by ``theta`` [rad], its derivatives in ``theta`` up to
the third, and the pressure angle.

**Frames.** The cam turns counter-clockwise about its axis O (the origin) by ``theta``,
as the translating follower's cam does (:mod:`camdyn.model.translating_follower`). The
arm is pivoted at ``P = (px, py)`` [m] in the fixed frame, its roller centre (the knife's
tip for radius 0) at ``C(psi) = P + L e(psi)``, ``e(psi) = (cos psi, sin psi)``, with the
arm length ``L`` [m] and the arm angle ``psi`` [rad], counter-clockwise from the x axis.

**The pitch curve.** The roller's centre touches the cam where it lies on the pitch
curve, the cam's outer offset by the roller radius ``r_r`` [m]. In the cam's frame it is
written ``P(u) = R(-u) q(u)`` with ``R`` the rotation matrix and ``q = (a, b)`` [m]:

- a profile made for a flat face (support function ``h = r_base + s``, Rothbart 2004):
  ``a = s'(u)``, ``b = r_base + s(u) + r_r``: the support function ``h + r_r`` of the
  offset curve, whose radius of curvature is ``h + h'' + r_r``                      (K1)
- a profile made for a knife edge or a roller of radius ``r_p`` with offset ``eps`` (the
  translating follower's pitch curve, Norton 2009): ``a = eps``,
  ``b = sqrt((r_base + r_p)^2 - eps^2) + s(u)``; the rocking roller's radius must then be
  ``r_p``                                                                           (K2)

With the cam turned by ``theta`` the pitch point is ``X(u, theta) = R(theta - u) q(u)``
in the fixed frame, and contact is

    R(theta - u) q(u) = P + L e(psi)                                                (K3)

two equations in ``(u, psi)``. Of the two points where the arm's circle crosses the
(convex) pitch curve, the contact is the one from which turning the arm in its lift
sense ``sigma`` (+1 counter-clockwise, -1 clockwise) moves the roller out of the pitch
curve: ``sigma e'(psi) . N > 0`` with ``N`` the pitch curve's outward normal. The
pressure angle ``phi`` is the angle from the roller centre's direction of motion ``m =
sigma e'(psi)`` to ``N``, counter-clockwise positive:

    phi = atan2(m x N, m . N)                                                       (K4)

and a contact force ``F`` [N] along ``N`` turns the arm in its lift sense with the
moment ``F L cos(phi)`` [N m].

**Derivatives.** ``(u, psi)`` of (K3) are found by bracketing on a grid of the pitch curve
and Newton's method; their derivatives in ``theta`` by the implicit function theorem
written as truncated Taylor series: with ``theta = theta0 + eps``, ``u = u0 + U(eps)``,
``psi = psi0 + Psi(eps)``, each order ``k`` of the residual of (K3) is
``A (u_k, psi_k) + (terms of lower orders)`` with the Jacobian
``A = [dX/du, -L e'(psi0)]``, ``dX/du = R(theta - u)(a' + b, b' - a)``, solved order by
order (k = 1, 2, 3). ``psi_c^(k) = k! psi_k``. The third order needs ``q'''``, hence
``s''''`` for a flat-face profile: a five-point central difference of ``s'''`` (one-sided,
second order, next to a joint of the profile).

References: H. A. Rothbart, *Cam Design Handbook*, McGraw-Hill 2004; R. L. Norton, *Cam
Design and Manufacturing Handbook*, 2nd ed., Industrial Press 2009.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from camdyn.errors import GeometryError, ParameterError
from camdyn.model import profiles

__all__ = ["RockingGeometry", "ContactConfiguration", "contact_configuration", "pitch_points", "lift_values",
           "surface_curvature"]

#: Points of the pitch curve on which the contacts are bracketed.
GRID = 2048
#: Largest pressure angle accepted [rad]: beyond it the arm nearly runs along the cam's
#: normal and the cam locks it.
MAX_PRESSURE_ANGLE = math.radians(80.0)
#: Steps [rad] of the difference quotients of ``s'''`` (central, one-sided).
CENTRAL_STEP = 1e-3
SIDED_STEP = 1e-4


@numba.njit(cache=True)
def lift_values(table, angles):
    """``(s, s', s'', s''')`` [m, m/rad, m/rad^2, m/rad^3] of a profile table at each of
    ``angles`` [rad], as an ``(n, 4)`` array (:func:`camdyn.model.profiles.evaluate`)."""
    out = np.empty((angles.size, 4))
    for i in range(angles.size):
        s, s1, s2, s3 = profiles.evaluate(table, 0, angles[i])
        out[i, 0] = s
        out[i, 1] = s1
        out[i, 2] = s2
        out[i, 3] = s3
    return out


@dataclass(frozen=True)
class RockingGeometry:
    """A rocking arm with a roller (or a knife edge, radius 0) on a cam profile,
    validated when built.

    Attributes
    ----------
    profile : Profile
        The cam (:mod:`camdyn.model.profiles`), its follower ``"flat"`` (any roller radius)
        or ``"knife"``/``"roller"`` (the same radius as the profile's roller).
    pivot_x, pivot_y : float
        The arm's pivot relative to the cam's axis [m].
    arm_length : float
        Pivot to roller centre L [m].
    roller_radius : float
        r_r [m]; 0 for a knife edge.
    lift_direction : int
        +1 when the cam lifts the arm counter-clockwise, -1 clockwise.
    """

    profile: profiles.Profile
    pivot_x: float
    pivot_y: float
    arm_length: float
    roller_radius: float = 0.0
    lift_direction: int = 1

    def __post_init__(self):
        if not isinstance(self.profile, profiles.Profile):
            raise ParameterError(f"profile must be a camdyn Profile, got {type(self.profile).__name__}")
        for name in ("pivot_x", "pivot_y", "arm_length", "roller_radius"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ParameterError(f"{name} must be a finite number of metres, got {value!r}")
        if self.arm_length <= 0.0:
            raise ParameterError(f"the arm length must be positive, not {self.arm_length} m")
        if self.roller_radius < 0.0:
            raise ParameterError(f"the roller radius must not be negative, not {self.roller_radius} m")
        if self.lift_direction not in (1, -1):
            raise ParameterError(f"lift_direction must be +1 (counter-clockwise) or -1, not {self.lift_direction!r}")
        if self.profile.follower != "flat" and self.roller_radius != self.profile.roller_radius:
            raise ParameterError(
                f"a profile made for a {self.profile.follower} of radius {self.profile.roller_radius} m gives "
                f"that roller's pitch curve: the rocking roller must have the same radius, not "
                f"{self.roller_radius} m (a profile made for a flat face takes any roller radius)")
        _check_pitch_curve(self)

    @property
    def pivot(self):
        """The pivot ``(px, py)`` [m] as an array."""
        return np.array([self.pivot_x, self.pivot_y], dtype=float)


def _fourth_derivative(profile, u):
    """``s''''`` [m/rad^4] at ``u`` [rad]: the five-point central difference of ``s'''``
    (error ``h^4 s^(7) / 30``), or a one-sided second-order one (error ``h^2 s^(6) / 3``)
    where the central stencil would cross a joint of the profile."""
    h, k = CENTRAL_STEP, SIDED_STEP
    third = [lift_values(profile.table, u + d)[:, 3] for d in (-2 * h, -h, h, 2 * h)]
    central = (third[0] - 8.0 * third[1] + 8.0 * third[2] - third[3]) / (12.0 * h)
    joints = profile.joints
    offset = (joints[None, :] - u[:, None] + math.pi) % profiles.TWO_PI - math.pi   # joint - u, wrapped
    near = np.abs(offset) <= 2.0 * h
    after = np.any(near & (offset <= 0.0), axis=1)    # a joint at or just before u: forward stencil
    before = np.any(near & (offset > 0.0), axis=1) & ~after
    out = central
    if np.any(after | before):
        f = [lift_values(profile.table, u + d)[:, 3] for d in (-2 * k, -k, 0.0, k, 2 * k)]
        forward = (-3.0 * f[2] + 4.0 * f[3] - f[4]) / (2.0 * k)
        backward = (3.0 * f[2] - 4.0 * f[1] + f[0]) / (2.0 * k)
        out = np.where(after, forward, np.where(before, backward, central))
    return out


def pitch_coordinates(geometry, u, order=3):
    """``q = (a, b)`` [m] of (K1)/(K2) and its derivatives in ``u`` up to ``order`` (at most
    3): an array ``(order + 1, 2, n)``, ``[k]`` the k-th derivative [m/rad^k]."""
    profile = geometry.profile
    u = np.atleast_1d(np.asarray(u, dtype=float))
    s = lift_values(profile.table, u).T
    q = np.zeros((order + 1, 2, u.size))
    if profile.follower == "flat":   # (K1)
        q[0, 1] = profile.base_radius + s[0] + geometry.roller_radius
        for k in range(order + 1):
            if k + 1 <= 3:
                q[k, 0] = s[k + 1]
            if k >= 1:
                q[k, 1] = s[k]
        if order >= 3:
            q[3, 0] = _fourth_derivative(profile, u)
    else:                            # (K2)
        eps = profile.offset
        q[0, 0] = eps
        q[0, 1] = math.sqrt(profile.prime_radius ** 2 - eps ** 2) + s[0]
        for k in range(1, order + 1):
            q[k, 1] = s[k]
    return q


def pitch_points(geometry, u):
    """The pitch curve ``P(u) = R(-u) q(u)`` [m] in the cam's frame and its tangent
    ``P'(u) = R(-u)(a' + b, b' - a)`` [m/rad]: two arrays ``(2, n)``."""
    q = pitch_coordinates(geometry, u, order=1)
    c, s = np.cos(u), np.sin(u)
    a, b = q[0]
    da, db = q[1, 0] + b, q[1, 1] - a
    return (np.array([a * c + b * s, -a * s + b * c]), np.array([da * c + db * s, -da * s + db * c]))


def surface_curvature(geometry, u):
    """Curvature ``kappa_cam`` [1/m] of the cam's surface where the pitch curve's parameter
    is ``u`` [rad]: the pitch curve's radius of curvature ``rho_p = |w|^3 / (w x z)`` with
    ``w = (a' + b, b' - a)`` and ``z = w' + (w_y, -w_x) = (a'' + 2 b' - a, b'' - 2 a' - b)``
    (``P' = R(-u) w``, ``P'' = R(-u) z``; the sign of
    :func:`camdyn.model.profiles.curvature_terms`, positive where convex), less the roller's
    radius (the surface is the pitch curve's inner offset by ``r_r``): ``kappa_cam = 1 /
    (rho_p - r_r)``                                                                 (K5)"""
    q = pitch_coordinates(geometry, u, order=2)
    a, b = q[0]
    wx, wy = q[1, 0] + b, q[1, 1] - a
    zx, zy = q[2, 0] + 2.0 * q[1, 1] - a, q[2, 1] - 2.0 * q[1, 0] - b
    rho = (wx * wx + wy * wy) ** 1.5 / (wy * zx - wx * zy)
    return 1.0 / (rho - geometry.roller_radius)


def _check_pitch_curve(geometry):
    """Refuse a pitch curve that is not convex (cusps or a concave flank the roller could
    not follow as this model does) and a pivot inside the circle the pitch curve sweeps."""
    profile = geometry.profile
    angles = np.linspace(0.0, profiles.TWO_PI, 7200, endpoint=False)
    if profile.follower == "flat":
        s = lift_values(profile.table, angles)
        rho = profile.base_radius + s[:, 0] + s[:, 2] + geometry.roller_radius   # (K1)
    else:
        rho = profiles.pitch_curvature_radius(profile, angles)
    if np.min(rho) <= 0.0:
        worst = int(np.argmin(rho))
        raise GeometryError(f"the pitch curve is not convex (radius of curvature {rho[worst]:.4g} m at "
                            f"{math.degrees(angles[worst]):.3f} deg): the rocking roller needs a convex cam")
    reach = float(np.max(np.hypot(*pitch_points(geometry, angles)[0])))
    if math.hypot(geometry.pivot_x, geometry.pivot_y) <= reach:
        raise GeometryError(f"the arm's pivot, {math.hypot(geometry.pivot_x, geometry.pivot_y):.6g} m from the "
                            f"cam's axis, lies within the circle the pitch curve sweeps (radius {reach:.6g} m)")


@dataclass(frozen=True)
class ContactConfiguration:
    """The contact of the arm at cam angles ``theta`` [rad], arrays over them.

    Attributes
    ----------
    theta : ndarray
        Cam angles [rad].
    psi : ndarray (4, n)
        The arm angle psi_c [rad] and its derivatives in theta [rad/rad^k], k = 1, 2, 3.
    parameter : ndarray
        The pitch curve's parameter u [rad] at the contact.
    centre : ndarray (2, n)
        The roller centre in the fixed frame [m].
    normal : ndarray (2, n)
        The pitch curve's outward unit normal there (the line of the contact force) [-].
    pressure_angle : ndarray
        phi of (K4) [rad].
    """

    theta: np.ndarray
    psi: np.ndarray
    parameter: np.ndarray
    centre: np.ndarray
    normal: np.ndarray
    pressure_angle: np.ndarray


def _residual_function(geometry, theta):
    """``f(u) = |P(u) - Pc|^2 - L^2`` [m^2] and ``f'(u)`` [m^2/rad] with ``Pc = R(-theta) P``
    the pivot in the cam's frame."""
    c, s = np.cos(theta), np.sin(theta)
    pcx = c * geometry.pivot_x + s * geometry.pivot_y
    pcy = -s * geometry.pivot_x + c * geometry.pivot_y

    def f(u):
        point, tangent = pitch_points(geometry, u)
        dx, dy = point[0] - pcx, point[1] - pcy
        return dx * dx + dy * dy - geometry.arm_length ** 2, 2.0 * (dx * tangent[0] + dy * tangent[1])

    return f, pcx, pcy


def _brackets(geometry, theta, chunk=1024):
    """For each ``theta``, the two grid intervals of ``u`` where the arm's circle crosses
    the pitch curve: ``(lo, hi)`` [rad], arrays ``(n, 2)``; a ``GeometryError`` where the
    arm cannot reach the cam."""
    grid = np.linspace(0.0, profiles.TWO_PI, GRID + 1)
    points = pitch_points(geometry, grid[:-1])[0]
    lo = np.empty((theta.size, 2))
    for start in range(0, theta.size, chunk):
        part = theta[start:start + chunk]
        c, s = np.cos(part)[:, None], np.sin(part)[:, None]
        pcx = c * geometry.pivot_x + s * geometry.pivot_y
        pcy = -s * geometry.pivot_x + c * geometry.pivot_y
        f = (points[0] - pcx) ** 2 + (points[1] - pcy) ** 2 - geometry.arm_length ** 2
        change = np.signbit(f) != np.signbit(np.roll(f, -1, axis=1))
        count = change.sum(axis=1)
        if np.any(count != 2):
            bad = int(np.argmax(count != 2))
            raise GeometryError(f"at cam angle {math.degrees(part[bad]):.3f} deg the arm's circle (length "
                                f"{geometry.arm_length} m about the pivot) crosses the pitch curve "
                                f"{int(count[bad])} times, not twice: the arm cannot reach the cam there")
        index = np.argsort(~change, axis=1, kind="stable")[:, :2]
        lo[start:start + chunk] = grid[index]
    return lo, lo + grid[1]


def _newton(geometry, theta, lo, hi):
    """The root of ``f(u)`` in each bracket ``[lo, hi]`` [rad]: Newton's method kept in the
    bracket by bisection."""
    f, _, _ = _residual_function(geometry, theta)
    f_lo = f(lo)[0]
    f_hi = f(hi)[0]
    u = lo + (hi - lo) * f_lo / (f_lo - f_hi)
    for _ in range(60):
        value, slope = f(u)
        low_side = np.signbit(value) == np.signbit(f_lo)
        lo, hi = np.where(low_side, u, lo), np.where(low_side, hi, u)
        f_lo = np.where(low_side, value, f_lo)
        step = np.where(slope != 0.0, value / np.where(slope != 0.0, slope, 1.0), np.inf)
        new = u - step
        outside = ~((new > np.minimum(lo, hi)) & (new < np.maximum(lo, hi)))
        new = np.where(outside, 0.5 * (lo + hi), new)
        if np.all(np.abs(new - u) <= 4e-16 * (1.0 + np.abs(u))):
            return new
        u = new
    return u


def _series_mul(x, y):
    """Product of two truncated Taylor series (coefficients along axis 0, order 3)."""
    out = np.zeros(np.broadcast_shapes(x.shape, y.shape))
    for k in range(4):
        for i in range(k + 1):
            out[k] = out[k] + x[i] * y[k - i]
    return out


def _cos_sin(angle0, delta):
    """Series of ``cos`` and ``sin`` of ``angle0 + delta``, ``delta`` a series without a
    constant term."""
    d2 = _series_mul(delta, delta)
    d3 = _series_mul(d2, delta)
    cd = -0.5 * d2
    cd[0] = cd[0] + 1.0
    sd = delta - d3 / 6.0
    c0, s0 = np.cos(angle0), np.sin(angle0)
    return c0 * cd - s0 * sd, s0 * cd + c0 * sd


def _taylor(q, u0, psi0, theta0, geometry):
    """``u_k``, ``psi_k`` (k = 0..3) of (K3) order by order (see the module's docstring)."""
    n = u0.size
    u = np.zeros((4, n))
    psi = np.zeros((4, n))
    u[0], psi[0] = u0, psi0
    cw, sw = np.cos(theta0 - u0), np.sin(theta0 - u0)
    da, db = q[1, 0] + q[0, 1], q[1, 1] - q[0, 0]
    jacobian = np.empty((n, 2, 2))
    jacobian[:, 0, 0] = cw * da - sw * db          # dX/du
    jacobian[:, 1, 0] = sw * da + cw * db
    jacobian[:, 0, 1] = geometry.arm_length * np.sin(psi0)    # -L e'(psi)
    jacobian[:, 1, 1] = -geometry.arm_length * np.cos(psi0)
    for k in range(1, 4):
        du = u.copy()
        du[0] = 0.0
        dpsi = psi.copy()
        dpsi[0] = 0.0
        dw = -du
        dw[1] = dw[1] + 1.0
        cw_s, sw_s = _cos_sin(theta0 - u0, dw)
        powers = [np.zeros((4, n)), du, _series_mul(du, du)]
        powers.append(_series_mul(powers[2], du))
        powers[0][0] = 1.0
        a = sum(q[j, 0] * powers[j] / math.factorial(j) for j in range(4))
        b = sum(q[j, 1] * powers[j] / math.factorial(j) for j in range(4))
        cp, sp = _cos_sin(psi0, dpsi)
        # orders k >= 1 of the residual of (K3): the pivot, a constant, drops out
        gx = _series_mul(cw_s, a) - _series_mul(sw_s, b) - geometry.arm_length * cp
        gy = _series_mul(sw_s, a) + _series_mul(cw_s, b) - geometry.arm_length * sp
        step = np.linalg.solve(jacobian, -np.stack([gx[k], gy[k]], axis=1)[..., None])[..., 0]
        u[k], psi[k] = step[:, 0], step[:, 1]
    return u, psi


def contact_configuration(geometry, theta, reference=None):
    """The arm's contact with the cam at the cam angles ``theta`` [rad], exact to rounding
    (module docstring, eqs K3-K4).

    Parameters
    ----------
    geometry : RockingGeometry
    theta : array_like
        Cam angles [rad].
    reference : float, optional
        An arm angle [rad] near the contact angles: the result is wrapped to within pi of
        it (default: the first contact's angle).

    Returns
    -------
    ContactConfiguration
        A ``GeometryError`` where the arm cannot reach the cam or the pressure angle
        exceeds :data:`MAX_PRESSURE_ANGLE`.
    """
    theta = np.atleast_1d(np.asarray(theta, dtype=float))
    lo, hi = _brackets(geometry, theta)
    roots = np.stack([_newton(geometry, theta, lo[:, i], hi[:, i]) for i in range(2)], axis=1)
    c, s = np.cos(theta), np.sin(theta)
    best, found = None, np.zeros(theta.size, dtype=int)
    for i in range(2):
        u = roots[:, i]
        point, tangent = pitch_points(geometry, u)
        centre = np.array([c * point[0] - s * point[1], s * point[0] + c * point[1]])   # R(theta) P(u)
        outward = np.array([-(s * tangent[0] + c * tangent[1]), c * tangent[0] - s * tangent[1]])  # R(theta) J P'
        outward /= np.hypot(*outward)
        psi = np.arctan2(centre[1] - geometry.pivot_y, centre[0] - geometry.pivot_x)
        motion = geometry.lift_direction * np.array([-np.sin(psi), np.cos(psi)])
        cosine = motion[0] * outward[0] + motion[1] * outward[1]
        chosen = cosine > 0.0
        found += chosen
        if best is None:
            best = [u, centre, outward, psi, motion, cosine]
        else:
            for j, value in enumerate((u, centre, outward, psi, motion, cosine)):
                best[j] = np.where(chosen, value, best[j])
    if np.any(found != 1):   # a convex pitch curve is entered at one crossing and left at the other
        bad = int(np.argmax(found != 1))
        raise GeometryError(f"at cam angle {math.degrees(theta[bad]):.3f} deg the arm meets the pitch curve at "
                            f"{int(found[bad])} points where the cam lifts it, not one")
    u, centre, outward, psi, motion, cosine = best
    phi = np.arctan2(motion[0] * outward[1] - motion[1] * outward[0], cosine)   # (K4)
    if np.any(np.abs(phi) > MAX_PRESSURE_ANGLE):
        worst = int(np.argmax(np.abs(phi)))
        raise GeometryError(f"the pressure angle reaches {math.degrees(phi[worst]):.2f} deg at cam angle "
                            f"{math.degrees(theta[worst]):.3f} deg (limit {math.degrees(MAX_PRESSURE_ANGLE):.0f} "
                            "deg): the cam would lock the arm; move the pivot or change the arm length")
    centre_ref = psi[0] if reference is None else reference
    psi = centre_ref + (psi - centre_ref + math.pi) % profiles.TWO_PI - math.pi
    q = pitch_coordinates(geometry, u, order=3)
    _, series = _taylor(q, u, psi, theta, geometry)
    derivatives = series * np.array([1.0, 1.0, 2.0, 6.0])[:, None]
    return ContactConfiguration(theta, derivatives, u, centre, outward, phi)
