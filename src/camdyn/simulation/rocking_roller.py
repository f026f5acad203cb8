"""Simulation of a rocking arm with a roller or a knife edge on a cam of any profile: the
arm's dynamics in its angle, run through the translating follower's compiled model
(system 4) with the arm's contact angle as its lift.

**The model.** The arm (moment of inertia ``I`` [kg m^2] about its pivot) turns by the
lift angle ``x = sigma (psi - psi_0)`` [rad], measured in its lift sense ``sigma`` from
the arm angle ``psi_0`` at which it rests on the cam's lowest point; a torsional spring
(stiffness ``k_t`` [N m/rad], preload moment ``M_0`` [N m] at ``x = 0``) and a viscous
damper ``c_t`` [N m s/rad] hold it against the cam. In flight

    I x'' = -M_0 - k_t x - c_t x'                                                  (A1)

and the cam (turning at ``omega``, ``theta = theta_0 + omega t``) keeps ``x >= s(theta)
= sigma (psi_c(theta) - psi_0)`` with ``psi_c`` of :mod:`camdyn.model.rocking_roller`.
This is eq. (1) of :mod:`camdyn.model.translating_follower` with ``m -> I``, ``k -> k_t``,
``F0 -> M_0``, ``c -> c_t``, lengths -> angles.

**Impacts.** The normal gap rate at the roller is ``v_n = L cos(phi) (x' - omega s')``
[m/s] (the roller centre moves at ``L psi'`` along ``e'(psi)``, and ``omega s'`` is the
rate at which the contact angle moves), so Newton's law ``v_n+ = -e v_n-`` at an instant
where ``L cos(phi)`` is fixed is

    x'+ - omega s' = -e (x'- - omega s')                                           (A2)

the translating follower's law in angles, exact for this one-degree-of-freedom arm
(the roller is frictionless and massless: the impulse acts along the normal). In
sustained contact the cam holds the arm with the moment ``M = I omega^2 s'' + c_t omega
s' + M_0 + k_t s`` [N m] (eq. 3 there) and the contact force ``F = M / (L cos(phi))``
[N] along the normal; the arm lifts off where ``M`` falls to zero.

**The lift table.** ``s(theta)`` is sampled exactly at ``n`` equally spaced cam angles
and interpolated by a periodic cubic spline (SciPy's ``CubicSpline``) in the compiled
model's table format; its errors are measured by the tests against the exact
derivatives (see the documentation's section on the rocking roller).

**Compliant contact.** Instead of Newton's law the cam may push the arm through a
penalty: the compliant law, a torsional spring-dashpot on the angular penetration
``delta = s - x`` [rad] (the moment ``M = k_c delta + c_c delta'`` [N m], eq. (1) of the
translating model's compliant law in angles), or Hertz contact (K. L. Johnson, *Contact
Mechanics*, 1985, sections 4.2-4.3) at its exact lever at every cam angle. To first order
in ``delta`` the penetration along the contact normal is

    delta_n = L_n(theta) delta,    L_n = L cos(phi)                                 (A3)

[m], with the normal's lever ``L_n`` [m] about the pivot (the rate at which the roller
centre moves along the normal per radian of the arm, and the lever the contact force's
moment has), its rate ``delta_n' = L_n delta' + omega L_n' delta`` [m/s] and the approach
velocity ``v_n = L_n (s_dot - x')`` [m/s] at the onset. The normal force ``N(delta_n,
delta_n')`` [N] is the translating follower's Hertz law: line contact of a cylindrical
roller of width ``l``, ``(pi/4) E* l delta_n``, or point contact of a crowned roller (its
radius ``r_r``) or a knife edge's rounded tip (radius ``r_f``), ``(4/3) E* sqrt(rho_e)
delta_n^1.5`` with ``1/rho_e = kappa_cam + 1/r_f`` and ``kappa_cam`` [1/m] the curvature
of the cam's surface at the contact (eq. K5 of :mod:`camdyn.model.rocking_roller`); its
damping law acts on ``delta_n'`` and ``v_n``, so a viscous ``c`` is in N s/m and the
reference velocity in m/s, on the roller. The arm feels the moment

    M = L_n(theta) N                                                                (A4)

[N m]. ``L_n`` and ``kappa_cam`` are sampled with ``psi_c`` and read by the compiled law
from their own tables (eqs. 8-9 of :mod:`camdyn.model.translating_follower`). The first
order neglects terms of relative size ``delta_n / rho`` (the normal penetration against
the radii of curvature of the pitch curve and the roller centre's circle, and the lever's
change while the bodies overlap): 2e-6 at 2 um of steel contact on the tests' rig. A knife edge's kinematics stay those
of a sharp edge (its tip radius enters the stiffness only), as for a translating knife edge.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
import xarray as xr
from scipy.interpolate import CubicSpline

from camdyn.errors import ParameterError
from camdyn.model import lift_laws
from camdyn.model.profiles import ROW, TWO_PI, Profile
from camdyn.model.rocking_roller import RockingGeometry, contact_configuration, surface_curvature
from camdyn.params.rocking import RockingSpec
from camdyn.params.units import angular_speed
from camdyn.simulation import limits
from camdyn.simulation.translating import TranslatingFollower, follower_from_spec, simulate_translating
from camdyn.simulation.translating_contact import HertzContact

__all__ = ["RockingFollower", "RockingTable", "rocking_table", "simulate_rocking", "rocking_liftoff_speed",
           "rocking_from_spec", "CONTACT_LAWS"]

#: Samples of the contact angle over one revolution in the lift table.
SAMPLES = 8192
#: Contact laws of the arm: Newton's restitution, a torsional spring-dashpot, Hertz line or point contact.
CONTACT_LAWS = ("rigid", "compliant", "hertz")


@dataclass(frozen=True)
class RockingFollower:
    """A spring-loaded rocking arm with a roller or a knife edge, validated when built.

    Attributes
    ----------
    geometry : RockingGeometry
        Cam profile, pivot, arm length, roller radius and lift sense.
    inertia : float
        Moment of inertia I of the arm about its pivot [kg m^2].
    stiffness : float
        Torsional spring stiffness k_t [N m/rad].
    preload : float
        Spring moment M_0 [N m] with the arm on the cam's lowest point.
    damping : float
        Viscous damping c_t [N m s/rad].
    restitution : float
        Newton's coefficient of restitution e [-] of the normal velocity.
    capture_velocity : float
        Impacts slower than this [rad/s] (relative angular velocity) end in sustained
        contact.
    contact : str
        ``"rigid"`` (Newton's restitution), ``"compliant"`` (torsional spring-dashpot
        ``contact_stiffness``, ``contact_damping``) or ``"hertz"`` (``hertz``: line contact
        of a cylindrical roller, point contact of a crowned roller or a knife edge's
        rounded tip).
    contact_stiffness : float
        k_c [N m/rad] of the compliant law.
    contact_damping : float
        c_c [N m s/rad] of the compliant law.
    hertz : HertzContact or None
        Materials, geometry (``"line"`` with its ``width``, or ``"point"``: the roller's
        radius, or a knife edge's ``tip_radius``) and damping law of Hertz contact.
    samples : int
        Cam angles of the lift table (at least 256).
    citation : str
        Where the numbers come from.
    """

    geometry: RockingGeometry
    inertia: float
    stiffness: float
    preload: float
    damping: float = 0.0
    restitution: float = 0.8
    capture_velocity: float = 1e-6
    contact: str = "rigid"
    contact_stiffness: float = 0.0
    contact_damping: float = 0.0
    hertz: HertzContact | None = None
    samples: int = SAMPLES
    citation: str = field(default="", compare=False)

    def __post_init__(self):
        if not isinstance(self.geometry, RockingGeometry):
            raise ParameterError(f"geometry must be a RockingGeometry, got {type(self.geometry).__name__}")
        for name in ("inertia", "stiffness", "preload", "damping", "restitution", "capture_velocity",
                     "contact_stiffness", "contact_damping"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ParameterError(f"{name} must be a finite number, got {value!r}")
            if value < 0.0:
                raise ParameterError(f"{name} must not be negative, got {value!r}")
        if self.inertia <= 0.0:
            raise ParameterError(f"inertia must be positive, got {self.inertia!r} kg m^2")
        if self.restitution > 1.0:
            raise ParameterError(f"restitution must be between 0 and 1, got {self.restitution!r}")
        if isinstance(self.samples, bool) or not isinstance(self.samples, (int, np.integer)) or self.samples < 256:
            raise ParameterError(f"samples must be a whole number of at least 256, got {self.samples!r}")
        self._check_contact()

    def _check_contact(self):
        """Refuse a contact law the arm cannot take, before any work."""
        if self.contact not in CONTACT_LAWS:
            raise ParameterError(f"contact must be one of {', '.join(CONTACT_LAWS)}, got {self.contact!r}")
        if self.contact == "compliant" and self.contact_stiffness <= 0.0:
            raise ParameterError("the compliant contact needs a positive contact_stiffness [N m/rad]")
        if self.contact != "compliant" and (self.contact_stiffness != 0.0 or self.contact_damping != 0.0):
            raise ParameterError(f"contact_stiffness and contact_damping belong to the compliant law, not the "
                                 f"{self.contact} one")
        if self.contact != "hertz":
            if self.hertz is not None:
                raise ParameterError(f"hertz is the Hertz law's, not the {self.contact} one's (contact='hertz')")
            return
        if not isinstance(self.hertz, HertzContact):
            raise ParameterError("the Hertz contact needs its materials and width (hertz=HertzContact(...))")
        face = "roller" if self.geometry.roller_radius > 0.0 else "knife"
        geometry = self.hertz.geometry_of(face)
        if face == "knife" and geometry == "line":
            raise ParameterError("contact.geometry: a knife edge with a rounded tip makes point contact; use "
                                 "'point' with contact.tip_radius")
        if face == "knife" and self.hertz.tip_radius <= 0.0:
            raise ParameterError("contact.tip_radius: a sharp knife edge has no Hertz stiffness; give the edge's "
                                 "tip radius [m] (point contact)")
        if face == "roller" and self.hertz.tip_radius != 0.0:
            raise ParameterError("contact.tip_radius is for a knife edge only, not a roller")
        if geometry == "line" and self.hertz.width <= 0.0:
            raise ParameterError("contact.width: line contact needs the positive width l [m] of the contact")


def rocking_from_spec(spec, lift=None):
    """The :class:`RockingFollower` of a configuration.

    Parameters
    ----------
    spec : RockingSpec
        The configuration in SI units (:func:`camdyn.params.rocking.read_rocking`).
    lift : array_like, optional
        The lift samples [m] of a tabulated profile (read from its CSV file).

    Returns
    -------
    RockingFollower
        Its geometry checked (a ``GeometryError`` for a cam the arm cannot follow).
    """
    if not isinstance(spec, RockingSpec):
        raise ParameterError(f"expected a RockingSpec, got {type(spec).__name__}")
    profile = follower_from_spec(spec.profile, lift).profile
    geometry = RockingGeometry(profile, spec.pivot_x, spec.pivot_y, spec.arm_length, spec.roller_radius,
                               spec.lift_direction)
    hertz = HertzContact(restitution=spec.restitution, **spec.hertz) if spec.contact == "hertz" else None
    return RockingFollower(geometry, spec.inertia, spec.stiffness, spec.preload, damping=spec.damping,
                           restitution=spec.restitution, capture_velocity=spec.capture_velocity,
                           contact=spec.contact, contact_stiffness=spec.contact_stiffness,
                           contact_damping=spec.contact_damping, hertz=hertz, citation=spec.citation)


@dataclass(frozen=True)
class RockingTable:
    """The arm's contact angle sampled over one revolution, and its spline table.

    Attributes
    ----------
    profile : Profile
        The lift ``s = sigma (psi_c - psi_0)`` [rad] as a cubic-spline table (its
        ``base_radius`` is the cam's, for the record only; its ``follower`` and
        ``roller_radius`` the arm's: ``"roller"`` or ``"knife"``).
    rest_angle : float
        psi_0 [rad]: the arm angle on the cam's lowest point (least ``sigma psi_c``).
    theta : ndarray
        The sample angles [rad].
    lift : ndarray (4, n)
        The exact ``s`` [rad] and its derivatives in theta at the samples.
    pressure_angle : ndarray
        The exact pressure angle [rad] at the samples.
    lever : Profile
        The normal's lever ``L_n = L cos(phi)`` [m] about the pivot (eq. A3), a periodic
        cubic spline through its exact samples.
    curvature : Profile
        The cam surface's curvature ``kappa_cam`` [1/m] at the contact (eq. K5), linear
        between its exact samples (no overshoot where it jumps at a joint of the profile).
    """

    profile: Profile
    rest_angle: float
    theta: np.ndarray
    lift: np.ndarray
    pressure_angle: np.ndarray
    lever: Profile
    curvature: Profile


def _rest_angle(geometry, theta, psi):
    """psi_0 [rad]: the least ``sigma psi_c`` over the cam angles, refined from the best
    sample by Newton's method on ``psi_c' = 0`` (the sample itself on a dwell)."""
    sigma = geometry.lift_direction
    best = int(np.argmin(sigma * psi[0]))
    angle, spacing = theta[best], theta[1] - theta[0]
    for _ in range(30):
        config = contact_configuration(geometry, [angle], reference=psi[0, best])
        slope, curvature = config.psi[1, 0], config.psi[2, 0]
        if curvature == 0.0 or abs(slope) < 1e-15:
            break
        angle -= slope / curvature
        if abs(angle - theta[best]) > spacing:
            return float(psi[0, best])
    value = float(contact_configuration(geometry, [angle], reference=psi[0, best]).psi[0, 0])
    return value if sigma * value <= sigma * psi[0, best] else float(psi[0, best])


def spline_table(theta, values, cubic=True):
    """A profile table [the values' unit] through ``values`` at the equally spaced cam
    angles ``theta`` [rad] over one revolution: a periodic cubic spline (SciPy's
    ``CubicSpline``), or straight lines between the samples (``cubic=False``)."""
    samples = theta.size
    angles = np.r_[theta, TWO_PI]
    table = np.zeros(1 + ROW * samples)
    table[0] = samples
    rows = table[1:].reshape(samples, ROW)
    rows[:, 0] = lift_laws.CUBIC
    rows[:, 1] = theta
    rows[:, 2] = angles[1] - angles[0]
    if cubic:
        spline = CubicSpline(angles, np.r_[values, values[0]], bc_type="periodic")
        rows[:, 3:7] = spline.c[::-1].T       # c0 + c1 t + c2 t^2 + c3 t^3
    else:
        rows[:, 3] = values
        rows[:, 4] = np.diff(np.r_[values, values[0]]) / rows[:, 2]
    return table


@lru_cache(maxsize=8)
def rocking_table(geometry, samples=SAMPLES):
    """The :class:`RockingTable` of a geometry with ``samples`` cam angles (cached)."""
    theta = np.linspace(0.0, TWO_PI, samples, endpoint=False)
    config = contact_configuration(geometry, theta)
    rest = _rest_angle(geometry, theta, config.psi)
    sigma = geometry.lift_direction
    lift = sigma * config.psi.copy()
    lift[0] -= sigma * rest
    cam = geometry.profile
    face = "roller" if geometry.roller_radius > 0.0 else "knife"

    def profile(table):
        return Profile(table, cam.base_radius, face, geometry.roller_radius, 0.0)

    lever = geometry.arm_length * np.cos(config.pressure_angle)                     # (A3)
    curvature = surface_curvature(geometry, config.parameter)                       # (K5)
    return RockingTable(profile(spline_table(theta, lift[0])), rest, theta, lift, config.pressure_angle,
                        profile(spline_table(theta, lever)), profile(spline_table(theta, curvature, cubic=False)))


def _angular_law(follower, table):
    """Keyword arguments of the translating follower's contact law in the arm's angles:
    the Hertz law with the arm's lever and curvature tables (eqs. A3-A4)."""
    if follower.contact == "rigid":
        return {}
    if follower.contact == "compliant":
        return {"contact": "compliant", "contact_stiffness": follower.contact_stiffness,
                "contact_damping": follower.contact_damping}
    return {"contact": "hertz", "hertz": follower.hertz, "lever": table.lever, "curvature": table.curvature}


def rocking_liftoff_speed(follower):
    """The lowest cam speed [rad/s] at which the arm held on the cam would need a pull:
    the smallest positive root over the table's sample angles of ``I s'' omega^2 + c_t
    s' omega + M_0 + k_t s = 0`` (the holding moment of the module's docstring), with the
    exact ``s', s''``; infinite for a cam that never needs a pull."""
    table = rocking_table(follower.geometry, follower.samples)
    s, s1, s2 = table.lift[0], table.lift[1], table.lift[2]
    a = follower.inertia * s2
    b = follower.damping * s1
    c = follower.preload + follower.stiffness * s
    if np.any(c <= 0.0):
        return 0.0
    with np.errstate(invalid="ignore", divide="ignore"):
        disc = b * b - 4.0 * a * c
        roots = np.where(a < 0.0, (-b - np.sqrt(disc)) / (2.0 * a), np.inf)
        both = (a > 0.0) & (b < 0.0) & (disc >= 0.0)
        roots = np.where(both, (-b - np.sqrt(disc)) / (2.0 * a), roots)
        roots = np.where((a == 0.0) & (b < 0.0), -c / b, roots)
    return float(np.min(roots))


def simulate_rocking(follower, speed, duration, sample_rate=10e3, phase=0.0, initial_state=None, rtol=1e-10,
                     atol=1e-12, max_step=None, max_events=None, max_steps=50_000_000) -> xr.Dataset:
    """Simulate a rocking roller or knife-edge follower.

    Parameters
    ----------
    follower : RockingFollower
        The arm and its cam.
    speed : float or str
        Cam speed [Hz] (revolutions per second), or text with units such as ``"358 rpm"``,
        ``"37.5 rad/s"`` or ``"6 Hz"`` (:func:`camdyn.params.units.parse_speed`); positive
        (counter-clockwise). Compiled code runs on omega [rad/s].
    duration : float
        Length of the run [s].
    sample_rate : float
        Output sampling rate [Hz].
    phase : float
        Cam angle theta0 [rad] at t = 0.
    initial_state : (float, float), optional
        ``(psi [rad], psi_dot [rad/s])``, the arm angle and its rate; default on the cam,
        moving with it.
    rtol, atol : float
        Local error tolerances, relative [-] and absolute [rad, rad/s].
    max_step, max_events, max_steps
        As :func:`camdyn.simulation.translating.simulate_translating`.

    Returns
    -------
    xarray.Dataset
        Over ``time``: ``psi`` and ``psi_dot`` (the arm), ``lift_angle`` ``x`` and
        ``contact_angle`` ``s`` [rad] (from the rest angle, in the lift sense), ``gap``
        [rad], ``pressure_angle`` [rad], ``contact_moment`` [N m], ``contact_force`` [N],
        ``in_contact``; over ``event``: ``event_time``, ``event_kind`` (as the
        translating follower's: under a compliant or Hertz law ``contact onset`` and
        ``contact end``), ``event_velocity`` [rad/s] and ``event_normal_velocity``
        [m/s] (relative, before the event). Attributes hold the parameters, the rest
        angle, the contact law (and, Hertz, its materials, geometry and damping) and the
        solver counters.
    """
    if not isinstance(follower, RockingFollower):
        raise ParameterError(f"expected a RockingFollower, got {type(follower).__name__}")
    speed = angular_speed(speed)   # omega [rad/s] from Hz or text with units
    for name, value, unit in (("speed", speed, "rad/s"), ("duration", duration, "s"),
                              ("sample_rate", sample_rate, "Hz")):   # before the table is built
        if not (math.isfinite(limits.check_number(name, value, unit)) and value > 0.0):
            raise ParameterError(f"{name} must be positive and finite, got {value!r} {unit}")
    if initial_state is not None and np.shape(initial_state) != (2,):
        raise ParameterError(f"initial_state must be two finite numbers (psi [rad], psi_dot [rad/s]), "
                             f"got {initial_state!r}")
    geometry = follower.geometry
    table = rocking_table(geometry, follower.samples)
    sigma = geometry.lift_direction
    translating = TranslatingFollower(table.profile, mass=follower.inertia, stiffness=follower.stiffness,
                                      preload=follower.preload, damping=follower.damping,
                                      restitution=follower.restitution,
                                      capture_velocity=follower.capture_velocity, citation=follower.citation,
                                      **_angular_law(follower, table))
    state = None
    if initial_state is not None:
        y0 = np.asarray(initial_state, dtype=float).reshape(-1)
        if y0.shape != (2,) or not np.all(np.isfinite(y0)):
            raise ParameterError(f"initial_state must be two finite numbers (psi [rad], psi_dot [rad/s]), "
                                 f"got {initial_state!r}")
        state = (sigma * (y0[0] - table.rest_angle), sigma * y0[1])
    ds = simulate_translating(translating, f"{float(speed)!r} rad/s", duration, sample_rate=sample_rate, phase=phase,
                              initial_state=state, rtol=rtol, atol=atol, max_step=max_step, max_events=max_events,
                              max_steps=max_steps)
    return _dataset(follower, table, ds, speed, phase)


def _dataset(follower, table, ds, speed, phase):
    """The translating run's Dataset in the arm's terms."""
    geometry = follower.geometry
    sigma = geometry.lift_direction
    angles = np.r_[table.theta, TWO_PI]
    pressure = CubicSpline(angles, np.r_[table.pressure_angle, table.pressure_angle[0]], bc_type="periodic")
    phi = pressure((phase + speed * ds.time.values) % TWO_PI)
    arm = geometry.arm_length * np.cos(phi)    # moment arm of the contact force [m]
    event_arm = geometry.arm_length * np.cos(pressure((phase + speed * ds.event_time.values) % TWO_PI))
    x, x_dot = ds.x.values, ds.x_dot.values
    data = {
        "psi": (("time",), table.rest_angle + sigma * x, {"units": "rad", "long_name": "arm angle"}),
        "psi_dot": (("time",), sigma * x_dot, {"units": "rad/s", "long_name": "arm angular velocity"}),
        "lift_angle": (("time",), x, {"units": "rad", "long_name": "arm angle from rest, in the lift sense"}),
        "lift_rate": (("time",), x_dot, {"units": "rad/s", "long_name": "lift angle rate"}),
        "contact_angle": (("time",), ds.lift.values, {"units": "rad",
                                                       "long_name": "lift angle of contact with the cam"}),
        "gap": (("time",), ds.gap.values, {"units": "rad", "long_name": "angular gap to the cam"}),
        "pressure_angle": (("time",), phi, {"units": "rad", "long_name": "pressure angle of the contact"}),
        "contact_moment": (("time",), ds.contact_force.values,
                           {"units": "N*m", "long_name": "moment of the cam on the arm about the pivot"}),
        "contact_force": (("time",), ds.contact_force.values / arm,
                          {"units": "N", "long_name": "normal force of the cam on the roller"}),
        "in_contact": ds.in_contact,
        "event_time": ds.event_time,
        "event_kind": ds.event_kind,
        "event_velocity": (("event",), ds.event_velocity.values,
                           {"units": "rad/s", "long_name": "relative angular velocity x_dot - s_dot before the event"}),
        "event_normal_velocity": (("event",), ds.event_velocity.values * event_arm,
                                  {"units": "m/s", "long_name": "normal velocity of roller and cam before the event"}),
    }
    out = xr.Dataset(data, coords={"time": ds.time})
    keep = {k: v for k, v in ds.attrs.items() if k.startswith("solver_") or k in (
        "rtol", "atol", "elapsed_s", "status", "speed_rad_s", "phase_rad", "restitution", "citation")}
    out.attrs.update(keep)
    out.attrs.update({
        "title": "camdyn rocking roller follower" if geometry.roller_radius > 0 else "camdyn rocking knife-edge "
                                                                                      "follower",
        "inertia_kg_m2": follower.inertia, "stiffness_N_m_per_rad": follower.stiffness,
        "preload_N_m": follower.preload, "damping_N_m_s_per_rad": follower.damping,
        "capture_velocity_rad_per_s": follower.capture_velocity, "pivot_x_m": geometry.pivot_x,
        "pivot_y_m": geometry.pivot_y, "arm_length_m": geometry.arm_length,
        "roller_radius_m": geometry.roller_radius, "lift_direction": geometry.lift_direction,
        "rest_angle_rad": table.rest_angle, "table_samples": follower.samples,
        "cam_follower_of_profile": geometry.profile.follower, "base_radius_m": geometry.profile.base_radius,
        "contact_law": follower.contact,
    })
    if follower.contact == "compliant":
        out.attrs.update({"contact_stiffness_N_m_per_rad": follower.contact_stiffness,
                          "contact_damping_N_m_s_per_rad": follower.contact_damping})
    elif follower.contact == "hertz":
        law = follower.hertz
        shape = law.geometry_of(table.profile.follower)
        out.attrs.update({"effective_modulus_Pa": law.modulus, "contact_geometry": shape,
                          "contact_width_m": law.width if shape == "line" else 0.0,
                          "contact_follower_radius_m": law.follower_radius(table.profile) if shape == "point" else 0.0,
                          "damping_law": law.damping_law, "contact_damping_N_s_per_m": law.damping,
                          "contact_restitution": law.restitution,
                          "contact_reference_velocity_m_per_s": law.reference_velocity})
    return out
