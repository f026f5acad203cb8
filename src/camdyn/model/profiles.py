"""Cam profiles for a translating follower: the lift ``s(theta)`` [m] of the follower over
one revolution of the cam, built from segments (:mod:`camdyn.model.lift_laws`), packed into
a flat float64 table that the compiled model reads, and checked for a cam that can be
made.

The table is ``(n, row_0, ..., row_{n-1})``, each row :data:`ROW` numbers wide
(``kind, theta_start, span`` and five coefficients), the rows in increasing
``theta_start`` from 0 and covering ``[0, 2 pi)`` without gaps. :func:`evaluate` finds a
segment by bisection and evaluates it; the lift is periodic in ``theta``.

Followers (the lift is that of the follower's reference point):

- ``"flat"``: a flat face normal to the follower's line. The cam is recovered from the
  lift through its support function ``h = r_base + s`` and its radius of curvature
  ``rho = h + h''`` (Rothbart 2004), which must be positive: the cam convex.
- ``"knife"``: a knife edge; the contact point is the pitch point.
- ``"roller"``: a roller of radius ``r_r`` whose centre describes the pitch curve; the cam
  is the pitch curve's inner offset by ``r_r``, undercut where the pitch curve's radius of
  curvature is positive but below ``r_r`` (Norton 2009).

References: R. L. Norton, *Cam Design and Manufacturing Handbook*, 2nd ed., Industrial
Press 2009; H. A. Rothbart, *Cam Design Handbook*, McGraw-Hill 2004.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from camdyn.errors import GeometryError, ParameterError
from camdyn.model import lift_laws as laws

__all__ = ["Profile", "evaluate", "rise_return_profile", "circular_arc_profile", "eccentric_circle",
           "tabulated_profile", "pressure_angle", "LAW_NAMES", "FOLLOWERS"]

ROW = 8
TWO_PI = 2.0 * math.pi
#: Names of the rise, return and dwell laws accepted by :func:`rise_return_profile`.
LAW_NAMES = {"dwell": laws.DWELL, "cycloidal": laws.CYCLOIDAL, "harmonic": laws.HARMONIC,
             "polynomial-345": laws.POLYNOMIAL_345, "polynomial-4567": laws.POLYNOMIAL_4567}
FOLLOWERS = ("flat", "knife", "roller")
#: Angles [rad] at which a profile is checked: a uniform grid and both sides of every joint.
CHECK_POINTS = 7200
#: Largest jump of the lift [m, relative to the total lift] and of its slope allowed at a
#: joint: a jump in ``s`` or ``s'`` is an impact of the cam itself.
JOINT_TOLERANCE = 1e-9


@numba.njit(cache=True)
def evaluate(table, start, theta):
    """Lift and derivatives ``(s [m], s' [m/rad], s'' [m/rad^2], s''' [m/rad^3])`` at the
    cam angle ``theta`` [rad] of the profile table stored in ``table[start:]``."""
    angle = theta % TWO_PI
    first = start + 1 + segment_index(table, start, angle) * ROW
    return laws.segment(table[first:first + ROW], angle)


@numba.njit(cache=True)
def segment_index(table, start, angle):
    """Index of the segment of the profile table in ``table[start:]`` under the cam angle
    ``angle`` [rad] in ``[0, 2 pi)``: the last row whose start is at most ``angle``
    (by bisection)."""
    lo = 0
    hi = int(table[start]) - 1
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if table[start + 1 + mid * ROW + 1] <= angle:
            lo = mid
        else:
            hi = mid - 1
    return lo


@dataclass(frozen=True)
class Profile:
    """A packed cam profile with its follower.

    Attributes
    ----------
    table : ndarray
        The packed segment table (see the module's docstring).
    base_radius : float
        Base circle radius of the cam r_base [m].
    follower : str
        ``"flat"``, ``"knife"`` or ``"roller"``.
    roller_radius : float
        Roller radius r_r [m] (0 unless a roller).
    offset : float
        Offset of the follower's line from the cam's axis epsilon [m].
    """

    table: np.ndarray
    base_radius: float
    follower: str
    roller_radius: float = 0.0
    offset: float = 0.0

    def lift(self, theta):
        """``(s, s', s'', s''')`` [m, m/rad, m/rad^2, m/rad^3] at the angles ``theta`` [rad]."""
        angles = np.atleast_1d(np.asarray(theta, dtype=float))
        out = np.array([evaluate(self.table, 0, a) for a in angles]).reshape(angles.shape + (4,))
        return tuple(out[..., i] for i in range(4))

    def __eq__(self, other):
        """Equal profiles: the same table, radii, follower and offset (the table compared
        by value, so that systems holding equal profiles compare equal)."""
        if not isinstance(other, Profile):
            return NotImplemented
        return (self.base_radius, self.follower, self.roller_radius, self.offset) == (
            other.base_radius, other.follower, other.roller_radius, other.offset) and np.array_equal(
            self.table, other.table)

    def __hash__(self):
        return hash((self.table.tobytes(), self.base_radius, self.follower, self.roller_radius, self.offset))

    @property
    def joints(self):
        """Start angles of the segments [rad]."""
        n = int(self.table[0])
        return self.table[2:2 + n * ROW:ROW].copy()

    @property
    def prime_radius(self):
        """Radius of the prime circle [m]: the base circle plus the roller."""
        return self.base_radius + self.roller_radius


def _check_follower(follower, base_radius, roller_radius, offset):
    if follower not in FOLLOWERS:
        raise ParameterError(f"follower {follower!r} is not one of {', '.join(FOLLOWERS)}")
    for name, value in (("base radius", base_radius), ("roller radius", roller_radius), ("offset", offset)):
        if not math.isfinite(value):
            raise ParameterError(f"the {name} must be finite, not {value}")
    if base_radius <= 0.0:
        raise ParameterError(f"the base radius must be positive, not {base_radius} m")
    if follower == "roller" and roller_radius <= 0.0:
        raise ParameterError(f"a roller follower needs a positive roller radius, not {roller_radius} m")
    if follower != "roller" and roller_radius != 0.0:
        raise ParameterError("only a roller follower has a roller radius")
    if abs(offset) >= base_radius + roller_radius:
        raise GeometryError(f"the follower's offset {offset} m does not meet the prime circle "
                            f"(radius {base_radius + roller_radius} m)")


def _pack(rows):
    table = np.zeros(1 + ROW * len(rows))
    table[0] = len(rows)
    for i, row in enumerate(rows):
        table[1 + i * ROW:1 + i * ROW + len(row)] = row
    return table


def rise_return_profile(segments, base_radius, follower="flat", roller_radius=0.0, offset=0.0):
    """A profile of dwells, rises and returns over one revolution.

    Parameters
    ----------
    segments : sequence of (str, float, float)
        ``(law, span [rad], lift [m])`` in order from ``theta = 0``: a law of
        :data:`LAW_NAMES`, its angular span, and the change of lift over it (positive for
        a rise, negative for a return, 0 for a dwell). The spans must add up to ``2 pi``
        and the lifts to 0.
    base_radius, roller_radius, offset : float
        r_base, r_r and epsilon [m] (see :class:`Profile`).
    follower : str
        ``"flat"``, ``"knife"`` or ``"roller"``.

    Returns
    -------
    Profile
        Checked by :func:`check_profile`.
    """
    _check_follower(follower, base_radius, roller_radius, offset)
    if len(segments) == 0:
        raise ParameterError("a profile needs at least one segment")
    rows, theta, level = [], 0.0, 0.0
    for law, span, lift in segments:
        if law not in LAW_NAMES:
            raise ParameterError(f"lift law {law!r} is not one of {', '.join(LAW_NAMES)}")
        if not (math.isfinite(span) and span > 0.0 and math.isfinite(lift)):
            raise ParameterError(f"segment {law!r}: the span must be positive and the lift finite "
                                 f"(span {span} rad, lift {lift} m)")
        if law == "dwell" and lift != 0.0:
            raise ParameterError(f"a dwell has no lift, not {lift} m")
        rows.append((LAW_NAMES[law], theta, span, level, lift))
        theta += span
        level += lift
    if abs(theta - TWO_PI) > 1e-9:
        raise ParameterError(f"the segments span {math.degrees(theta):.6f} deg, not one revolution (360 deg)")
    if abs(level) > 1e-12 + 1e-9 * max(abs(s[2]) for s in segments):
        raise ParameterError(f"the lifts add up to {level} m: the follower must come back to the base circle")
    if min(r[3] + min(0.0, r[4]) for r in rows) < -1e-12:
        raise GeometryError("the lift goes below the base circle")
    return check_profile(Profile(_pack(rows), float(base_radius), follower, float(roller_radius), float(offset)))


def circular_arc_profile(arcs, base_radius, follower="flat", roller_radius=0.0):
    """A cam made of circular arcs (base circle, flanks, nose), with an in-line follower.

    Parameters
    ----------
    arcs : sequence of (float, float, float)
        ``(span [rad], centre distance d [m], centre angle phi_c [rad], radius rho [m])``
        in order from ``theta = 0``: each arc of the cam, its centre at ``d`` from the
        cam's axis in the direction ``phi_c`` of the cam's frame. Spans add up to ``2 pi``;
        neighbouring arcs must meet with a common tangent.
    base_radius : float
        Base circle radius r_base [m]; the lift is measured from it.
    follower : str
        ``"flat"`` (lift from the arcs' support functions), ``"knife"`` or ``"roller"``
        (the follower's line crosses the arc, or the roller centre's offset arc of radius
        ``rho + r_r``).
    roller_radius : float
        r_r [m] of a roller follower.

    Returns
    -------
    Profile
    """
    _check_follower(follower, base_radius, roller_radius, 0.0)
    form = laws.ARC_FLAT if follower == "flat" else laws.ARC_RAY
    rows, theta = [], 0.0
    for span, d, phi_c, rho in arcs:
        values = (span, d, phi_c, rho)
        if not all(math.isfinite(v) for v in values) or span <= 0.0 or d < 0.0 or rho <= 0.0:
            raise ParameterError(f"arc {values}: the span and radius must be positive, the centre distance >= 0")
        radius = rho + roller_radius
        phi = np.linspace(theta, theta + span, 257) - phi_c
        if form == laws.ARC_RAY and np.min(radius ** 2 - (d * np.sin(phi)) ** 2) < 0.0:
            raise GeometryError(f"the follower's line misses the arc of radius {rho} m centred {d} m from the "
                                f"axis between {math.degrees(theta):.3f} and {math.degrees(theta + span):.3f} deg")
        rows.append((laws.ARC, theta, span, d, phi_c, radius, form, base_radius + roller_radius))
        theta += span
    if abs(theta - TWO_PI) > 1e-9:
        raise ParameterError(f"the arcs span {math.degrees(theta):.6f} deg, not one revolution (360 deg)")
    return check_profile(Profile(_pack(rows), float(base_radius), follower, float(roller_radius), 0.0))


def eccentric_circle(radius, eccentricity, follower="flat", roller_radius=0.0):
    """A circular cam of radius ``R`` [m] turning about a point at ``eccentricity`` [m]
    from its centre, with an in-line follower: the base radius is ``R - e``; for a flat
    face the lift is ``s = e (1 + cos theta)`` (the support function of the circle)."""
    if not (math.isfinite(radius) and math.isfinite(eccentricity)) or radius <= 0.0 or eccentricity < 0.0:
        raise ParameterError(f"an eccentric circle needs a positive radius and an eccentricity >= 0 "
                             f"(radius {radius} m, eccentricity {eccentricity} m)")
    if eccentricity >= radius:
        raise GeometryError(f"the eccentricity {eccentricity} m is not inside the cam's radius {radius} m")
    return circular_arc_profile([(TWO_PI, eccentricity, 0.0, radius)], radius - eccentricity, follower,
                                roller_radius)


def tabulated_profile(lift, base_radius, follower="flat", roller_radius=0.0, offset=0.0):
    """A profile through lift samples at equally spaced cam angles ``2 pi i / n``, ``i``
    from 0 to ``n - 1``: a periodic cubic spline (SciPy's ``CubicSpline(bc_type="periodic")``), so
    ``s``, ``s'`` and ``s''`` are continuous and ``s'''`` is constant per interval.

    Parameters
    ----------
    lift : array_like (n,)
        Lift samples [m], at least 8, finite and >= 0.
    base_radius, roller_radius, offset : float
        [m] (see :class:`Profile`).
    follower : str
        ``"flat"``, ``"knife"`` or ``"roller"``.
    """
    from scipy.interpolate import CubicSpline

    _check_follower(follower, base_radius, roller_radius, offset)
    values = np.asarray(lift, dtype=float)
    if values.ndim != 1 or values.size < 8:
        raise ParameterError(f"a tabulated lift needs at least 8 samples in one dimension, not shape {values.shape}")
    if not np.all(np.isfinite(values)) or values.min() < 0.0:
        raise ParameterError("the lift samples must be finite and >= 0 (measured from the base circle)")
    angles = np.linspace(0.0, TWO_PI, values.size + 1)
    spline = CubicSpline(angles, np.r_[values, values[0]], bc_type="periodic")
    c = spline.c   # c[k, i] multiplies (theta - theta_i)^(3 - k)
    rows = [(laws.CUBIC, angles[i], angles[i + 1] - angles[i], c[3, i], c[2, i], c[1, i], c[0, i])
            for i in range(values.size)]
    return check_profile(Profile(_pack(rows), float(base_radius), follower, float(roller_radius), float(offset)))


def _check_points(profile):
    joints = profile.joints
    near = np.concatenate([joints + 1e-9, (joints - 1e-9) % TWO_PI])
    return np.sort(np.concatenate([np.linspace(0.0, TWO_PI, CHECK_POINTS, endpoint=False), near]))


def _check_joints(profile):
    joints = profile.joints
    s_after = profile.lift(joints)
    s_before = profile.lift(joints - 1e-12)
    s_all = profile.lift(np.linspace(0.0, TWO_PI, 721))[0]
    scale = max(float(np.ptp(s_all)), profile.base_radius * 1e-6)
    for name, i in (("lift", 0), ("slope ds/dtheta", 1)):
        jump = np.abs(s_after[i] - s_before[i])
        worst = int(np.argmax(jump))
        if jump[worst] > JOINT_TOLERANCE * scale * 10.0 + 1e-12 * scale:
            raise GeometryError(f"the {name} jumps by {jump[worst]:.3g} at the joint at "
                                f"{math.degrees(joints[worst]):.4f} deg: neighbouring segments must meet "
                                "with a common lift and slope")


def pitch_curvature_radius(profile, theta):
    """Radius of curvature [m] of the pitch curve (the follower's reference point in the
    cam's frame: ``x = eps cos(theta) + Y sin(theta)``, ``y = -eps sin(theta) + Y cos(theta)``
    with ``Y = sqrt(Rp^2 - eps^2) + s``), positive where convex; for a flat face, the cam's
    radius of curvature ``r_base + s + s''``."""
    s, s1, s2, _ = profile.lift(theta)
    theta = np.asarray(theta, dtype=float)
    if profile.follower == "flat":
        return profile.base_radius + s + s2
    speed_cubed, cross = curvature_terms(theta, s, s1, s2, profile.prime_radius, profile.offset)
    return speed_cubed / cross


def curvature_terms(theta, s, s1, s2, prime_radius, offset):
    """The pitch curve's ``|r'|^3`` [m^3] and ``r' x r''`` [m^2] at the cam angles ``theta``
    [rad] (arrays or numbers), from the lift ``s`` [m] and its derivatives ``s'``, ``s''``
    [m/rad, m/rad^2]: its radius of curvature is their ratio, its curvature the inverse
    (the pitch point in the cam's frame as in :func:`pitch_curvature_radius`)."""
    big = math.sqrt(prime_radius ** 2 - offset ** 2) + s
    c, n = np.cos(theta), np.sin(theta)
    dx = -offset * n + s1 * n + big * c
    dy = -offset * c + s1 * c - big * n
    ddx = -offset * c + s2 * n + 2.0 * s1 * c - big * n
    ddy = offset * n + s2 * c - 2.0 * s1 * n - big * c
    return (dx * dx + dy * dy) ** 1.5, dy * ddx - dx * ddy


#: :func:`curvature_terms` compiled for the compiled models (the same lines).
pitch_curvature_terms = numba.njit(cache=True)(curvature_terms)


def check_profile(profile):
    """Refuse, with :class:`~camdyn.errors.GeometryError` naming the angle, a profile whose
    lift or slope jumps at a joint, a flat-faced cam that is not convex, or a roller cam
    that is undercut; return the profile otherwise."""
    _check_joints(profile)
    theta = _check_points(profile)
    s = profile.lift(theta)[0]
    if np.any(~np.isfinite(s)):
        raise GeometryError("the lift is not finite everywhere")
    rho = pitch_curvature_radius(profile, theta)
    if profile.follower == "flat" and rho.min() <= 0.0:
        worst = int(np.argmin(rho))
        raise GeometryError(f"the flat-faced cam is not convex: its radius of curvature r_base + s + s'' is "
                            f"{rho[worst]:.4g} m at {math.degrees(theta[worst]):.3f} deg; raise the base radius")
    if profile.follower == "roller":
        bad = (rho > 0.0) & (rho < profile.roller_radius)
        if np.any(bad):
            worst = int(np.argmin(np.where(bad, rho, np.inf)))
            raise GeometryError(f"the roller cam is undercut: the pitch curve's radius of curvature is "
                                f"{rho[worst]:.4g} m, below the roller's {profile.roller_radius} m, at "
                                f"{math.degrees(theta[worst]):.3f} deg; raise the base radius or use a "
                                "smaller roller")
    return profile


def pressure_angle(profile, theta):
    """Pressure angle [rad] of a knife-edge or roller follower at the cam angles ``theta``
    [rad]: ``tan(phi) = (s' - eps) / (sqrt(Rp^2 - eps^2) + s)`` (Norton 2009),
    with ``Rp`` the prime circle radius and ``eps`` the offset; 0 for a flat face, whose
    contact force stays along its line."""
    s, s1, _, _ = profile.lift(theta)
    if profile.follower == "flat":
        return np.zeros_like(s)
    eps = profile.offset
    return np.arctan((s1 - eps) / (math.sqrt(profile.prime_radius ** 2 - eps ** 2) + s))
