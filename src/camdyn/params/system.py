"""Parameter sets of the cam-follower model, as frozen dataclasses validated when built.

All values are SI inside camdyn. Configuration files and the command line give them
as text with units (see :mod:`camdyn.params.units`); :func:`camdyn.params.config.build_system`
turns dotted keys such as ``cam.runout`` into these dataclasses.

Symbols (docs/model.md, thesis nomenclature) are mapped in each field's docstring. Each
field is declared with :func:`camdyn.params.schema.parameter`: its unit, its meaning and
the unit configuration files write it in are given there once, and the configuration
schema, reader and writer (:mod:`camdyn.params.config`) are derived from them. The
damping laws are the rows of :mod:`camdyn.params.laws`.
"""

from __future__ import annotations

import difflib
import math
import warnings
from dataclasses import dataclass, fields, replace

from camdyn.errors import GeometryError, ParameterError, UnknownKeyError
from camdyn.params.laws import DAMPING_ALIASES, DAMPING_LAWS, RESTITUTION_LAWS, DampingLaw, lookup
from camdyn.params.schema import group, parameter, parameter_index

# DAMPING_LAWS, DAMPING_ALIASES and RESTITUTION_LAWS are views of the damping-law table
# (camdyn.params.laws.TABLE), also offered here beside the other name tables.
__all__ = [
    "Cam", "Follower", "Spring", "Contact", "Friction", "Motion", "System",
    "DAMPING_LAWS", "DAMPING_ALIASES", "RESTITUTION_LAWS", "FRICTION_LAWS", "MOTION_KINDS", "ZERO_STATES",
    "CONTACT_KINDS",
]

FRICTION_LAWS = {"none": 0, "coulomb": 1, "tanh": 2}
MOTION_KINDS = {"constant": 0, "oscillating": 1, "ramp": 2}
#: Conventions for the 0-state that fixes ``Theta0`` when no initial angle is given
#: (docs/model.md §2): the thesis's chapter 3 (eqs 3.3-3.4) and chapter 4 (eqs 4.3-4.4).
ZERO_STATES = ("auto", "maximum-lift", "runout-parallel")
CONTACT_KINDS = {"point": 0, "line": 1}


def _check_finite(owner: str, obj) -> None:
    """Refuse values of the wrong type (text where a number is due) and non-finite numbers."""
    for f in fields(obj):
        v = getattr(obj, f.name)
        unit = f.metadata.get("unit")
        if unit == "str":
            if not isinstance(v, str):
                raise ParameterError(f"{owner}.{f.name} must be text, got {v!r}")
            continue
        if unit == "bool":
            if not isinstance(v, bool):
                raise ParameterError(f"{owner}.{f.name} must be true or false, got {v!r}")
            continue
        if v is None and f.default is None:
            continue
        if unit is not None and (isinstance(v, bool) or not isinstance(v, (int, float))):
            raise ParameterError(f"{owner}.{f.name} must be a number in SI units ({unit}), got {v!r}; text with "
                                 f"units is read by camdyn.load_system(source, {{'{owner}.{f.name}': ...}})")
        if isinstance(v, float) and not math.isfinite(v):
            raise ParameterError(f"{owner}.{f.name} must be a finite number, got {v}")


def _positive(owner: str, name: str, value: float) -> None:
    if not value > 0.0:
        raise ParameterError(f"{owner}.{name} must be positive, got {value:g}")


def _nonnegative(owner: str, name: str, value: float) -> None:
    if not value >= 0.0:
        raise ParameterError(f"{owner}.{name} must be zero or positive, got {value:g}")


def _poisson(owner: str, value: float) -> None:
    if not -1.0 < value < 0.5:
        raise ParameterError(f"{owner}.poisson_ratio must lie in (-1, 0.5), got {value:g}")


@dataclass(frozen=True)
class Cam:
    """Eccentric circular or elliptic cam (docs/model.md §2).

    Attributes
    ----------
    semi_major : float
        Semi-axis ``a`` along the line through the pivot [m]; the radius ``rc`` of a circle.
    semi_minor : float
        Semi-axis ``b`` [m]; equal to ``semi_major`` for a circle.
    runout : float
        Eccentricity ``e``: distance from the cam's rotation axis E to its centroid [m].
    pivot_x, pivot_y : float
        Position ``PE`` of the cam pivot relative to the follower pivot P [m].
    youngs_modulus : float
        Young's modulus ``Y_c`` [Pa].
    poisson_ratio : float
        Poisson's ratio ``nu_c`` [-].
    """

    semi_major: float = parameter("m", "semi-axis a of an elliptic cam, along the line through the pivot")
    semi_minor: float = parameter("m", "semi-axis b of an elliptic cam")
    runout: float = parameter("m", "runout e: distance from the cam pivot to its centroid")
    pivot_x: float = parameter("m", "horizontal position of the cam pivot E relative to the follower pivot P")
    pivot_y: float = parameter("m", "vertical position of the cam pivot E relative to P")
    youngs_modulus: float = parameter("Pa", "Young's modulus of the cam", 210e9)
    poisson_ratio: float = parameter("", "Poisson's ratio of the cam", 0.3)

    def __post_init__(self):
        _check_finite("cam", self)
        _positive("cam", "semi_major", self.semi_major)
        _positive("cam", "semi_minor", self.semi_minor)
        if self.semi_minor > self.semi_major * (1 + 1e-12):
            raise ParameterError(
                f"cam.semi_minor ({self.semi_minor:g} m) must not exceed cam.semi_major "
                f"({self.semi_major:g} m): the pivot lies on the major axis")
        _nonnegative("cam", "runout", self.runout)
        if self.runout >= self.semi_minor:
            raise GeometryError(
                f"cam.runout ({self.runout*1e3:g} mm) must be smaller than the cam's "
                f"semi-minor axis ({self.semi_minor*1e3:g} mm): the pivot must lie inside the cam")
        _positive("cam", "youngs_modulus", self.youngs_modulus)
        _poisson("cam", self.poisson_ratio)

    @property
    def is_circle(self) -> bool:
        """True when the two semi-axes are equal."""
        return abs(self.semi_major - self.semi_minor) <= 1e-12 * self.semi_major


@dataclass(frozen=True)
class Follower:
    """Rocking bar follower pivoted at P (docs/model.md §1, §4).

    Attributes
    ----------
    mass : float
        Follower mass ``m`` [kg].
    inertia : float
        Moment of inertia about the pivot ``I_P`` [kg m^2].
    cg_distance : float
        Distance from P to the centre of gravity along the bar [m]; 0 when the pivot
        is at the centre of gravity (chapter 2 layout).
    length : float
        Bar length [m]; the contact point must stay on the bar.
    width : float
        Bar width ``wb`` [m].
    pin_radius : float
        Radius ``rd`` of the dowel pin lying on the bar [m]; 0 for contact on the bar face.
    youngs_modulus, poisson_ratio : float
        Elastic constants of the contacting follower surface [Pa], [-].
    accelerometer_distance : float
        Distance ``l_a`` from P of the tangential accelerometer [m]; 0 means at the
        free end (``length``). Measured ``alpha_ddot = a_t / l_a`` (docs/model.md §3).
    """

    mass: float = parameter("kg", "follower mass m")
    inertia: float = parameter("kg*m**2", "moment of inertia about the pivot I_P")
    cg_distance: float = parameter("m", "distance from the pivot to the centre of gravity")
    length: float = parameter("m", "bar length")
    width: float = parameter("m", "bar width wb")
    pin_radius: float = parameter("m", "dowel-pin radius rd (0: contact on the bar face; a point contact then "
                                       "uses the cam curvature alone, eq 2.34)", 0.0)
    youngs_modulus: float = parameter("Pa", "Young's modulus of the follower", 210e9)
    poisson_ratio: float = parameter("", "Poisson's ratio of the follower", 0.3)
    accelerometer_distance: float = parameter("m", "distance l_a of the tangential accelerometer from the pivot",
                                              0.0)

    def __post_init__(self):
        _check_finite("follower", self)
        _nonnegative("follower", "accelerometer_distance", self.accelerometer_distance)
        _positive("follower", "mass", self.mass)
        _positive("follower", "inertia", self.inertia)
        _nonnegative("follower", "cg_distance", self.cg_distance)
        _positive("follower", "length", self.length)
        _positive("follower", "width", self.width)
        _nonnegative("follower", "pin_radius", self.pin_radius)
        _positive("follower", "youngs_modulus", self.youngs_modulus)
        _poisson("follower", self.poisson_ratio)
        if self.cg_distance > self.length:
            raise ParameterError("follower.cg_distance must not exceed follower.length")
        if self.inertia < self.mass * self.cg_distance ** 2 * (1 - 1e-9):
            raise ParameterError(
                f"follower.inertia ({self.inertia:g} kg m^2) is smaller than m*l_cg^2 "
                f"({self.mass * self.cg_distance ** 2:g} kg m^2): impossible by the parallel-axis theorem")

    @property
    def sensor_distance(self) -> float:
        """Accelerometer distance ``l_a`` from P [m] (the free end when not given)."""
        return self.accelerometer_distance or self.length

    @property
    def surface_offset(self) -> float:
        """Distance ``h`` from the bar axis to the contact surface [m] (docs/model.md §1)."""
        return 0.5 * self.width + 2.0 * self.pin_radius


@dataclass(frozen=True)
class Spring:
    """Follower spring (eq 3.10 / 4.14, tilted: eq 4.44).

    Attributes
    ----------
    stiffness : float
        ``ks`` [N/m].
    free_length : float
        Free length ``Ls`` [m].
    attachment_x : float
        Horizontal distance ``dx`` from P to the spring's attachment on the bar [m].
    ground_depth : float
        Depth ``dy`` of the spring's grounded end below P [m].
    tilt : float
        Angle ``sigma`` of the spring from the vertical, clockwise [rad].
    """

    stiffness: float = parameter("N/m", "spring stiffness ks")
    free_length: float = parameter("m", "spring free length Ls")
    attachment_x: float = parameter("m", "horizontal distance dx from the pivot to the spring")
    ground_depth: float = parameter("m", "depth dy of the spring's grounded end below the pivot")
    tilt: float = parameter("rad", "spring tilt sigma from the vertical, clockwise (eq 4.44)", 0.0)

    def __post_init__(self):
        _check_finite("spring", self)
        _nonnegative("spring", "stiffness", self.stiffness)
        _nonnegative("spring", "free_length", self.free_length)
        _nonnegative("spring", "attachment_x", self.attachment_x)
        if abs(self.tilt) >= math.pi / 4:
            raise ParameterError(f"spring.tilt must be within ±45 degrees, got {math.degrees(self.tilt):g} deg")


@dataclass(frozen=True)
class Contact:
    """Normal contact law (docs/model.md §3).

    Attributes
    ----------
    kind : str
        ``"point"`` (crossed cylinders, Hertz eq 3.11-3.13) or ``"line"`` (eq 2.13-2.14).
    length : float
        Line-contact length ``l`` [m]; unused for point contact.
    damping : str
        Name of a damping law, a row of :data:`camdyn.params.laws.TABLE` (thesis letters
        A-E are accepted as aliases and replaced by the name).
    damping_ratio : float
        ``zeta`` of the viscous law A, and of the restoring phase of D and E [-].
    exponent : float
        ``n`` of the power law [-].
    beta : float
        Damping coefficient of laws B and D [s/m], C and E [N s/m^1.25], power law
        [N s/m^(n+1)] (the law's row gives its unit).
    restitution : float
        Coefficient of restitution ``e`` of the restitution-parameterised laws [-].
    reference_velocity : float
        Approach velocity used by restitution laws when a simulation starts in
        contact (no impact to measure it from) and lower bound on it [m/s].
    clip_adhesion : bool
        If True, negative (adhesive) normal force is set to zero. The thesis does not
        clip (its fig 3.8), so the default is False.
    """

    kind: str = parameter("str", "'point' (dowel pin, Hertz point contact) or 'line' (bar face)", "point")
    length: float = parameter("m", "line-contact length l", 0.0)
    damping: str = parameter("str", "damping law: " + ", ".join(DAMPING_LAWS) + " (or A-E)", "none")
    damping_ratio: float = parameter("", "zeta of the viscous law A (and the restoring phase of D, E)", 0.0)
    exponent: float = parameter("", "exponent n of the power law beta*delta^n*delta_dot", 1.5)
    beta: float = parameter("law", "damping coefficient beta; unit depends on the law", 0.0)
    restitution: float = parameter("", "coefficient of restitution e of the restitution laws", 1.0)
    reference_velocity: float = parameter("m/s", "approach velocity of restitution laws when starting in contact",
                                          0.01)
    clip_adhesion: bool = parameter("bool", "set negative (adhesive) normal force to zero", False)

    def __post_init__(self):
        _check_finite("contact", self)
        if self.kind not in CONTACT_KINDS:
            raise ParameterError(f"contact.kind must be one of {sorted(CONTACT_KINDS)}, got {self.kind!r}")
        law = lookup(self.damping)
        object.__setattr__(self, "damping", law.name)
        if self.kind == "line":
            _positive("contact", "length", self.length)
        _nonnegative("contact", "damping_ratio", self.damping_ratio)
        _nonnegative("contact", "beta", self.beta)
        _nonnegative("contact", "exponent", self.exponent)
        if law.restitution is not None:
            lo = law.lowest_restitution
            if not lo <= self.restitution <= 1.0:
                raise ParameterError(f"contact.restitution must lie in ({lo:g}, 1], got {self.restitution:g}")
        _positive("contact", "reference_velocity", self.reference_velocity)

    @property
    def law(self) -> DampingLaw:
        """The damping law's row (:data:`camdyn.params.laws.TABLE`)."""
        return lookup(self.damping)


#: Friction coefficient above which a warning says it is outside any physical range [-]
#: (clean metals in vacuum reach about 1-2; lubricated or dry cam contacts 0.01-0.6).
MAX_FRICTION = 2.0


@dataclass(frozen=True)
class Friction:
    """Friction law on the follower, ``Ff = mu(vr) Fn`` (docs/model.md §3).

    Attributes
    ----------
    law : str
        ``"coulomb"`` (model I, ``mu_m sgn(vr)``), ``"tanh"`` (model II,
        ``mu_m tanh(sigma vr)``) or ``"none"``.
    coefficient : float
        ``mu_m`` [-].
    smoothing : float
        ``sigma`` of the tanh law [s/m]; the thesis used 10 s/m.
    """

    law: str = parameter("str", "'coulomb', 'tanh' or 'none'", "coulomb")
    coefficient: float = parameter("", "friction coefficient mu_m", 0.0)
    smoothing: float = parameter("s/m", "sigma of the tanh friction law", 10.0)

    def __post_init__(self):
        _check_finite("friction", self)
        if self.law not in FRICTION_LAWS:
            raise ParameterError(f"friction.law must be one of {sorted(FRICTION_LAWS)}, got {self.law!r}")
        _nonnegative("friction", "coefficient", self.coefficient)
        _positive("friction", "smoothing", self.smoothing)
        if self.coefficient > MAX_FRICTION:
            warnings.warn(f"friction.coefficient = {self.coefficient:g} is outside any physical range (dry metal "
                          f"pairs 0.1-1; above {MAX_FRICTION:g} is not a sliding contact): is it a percentage or a "
                          f"typing slip?", UserWarning, stacklevel=2)


@dataclass(frozen=True)
class Motion:
    """Cam motion input (docs/model.md §1).

    Attributes
    ----------
    kind : str
        ``"constant"``: ``Theta = Theta0 + 2 pi f t``; ``"oscillating"``:
        ``Theta = Theta0 + 0.5 Theta_p sin(2 pi f_c t)`` (thesis 2.7.2); ``"ramp"``:
        constant angular acceleration from ``start_speed`` to ``speed`` over
        ``ramp_time``, then constant speed (a run-up, or a slow-down when
        ``start_speed > speed``).
    speed : float
        Cam speed ``f`` [Hz] (revolutions per second), constant motion; the speed a ramp
        ends at.
    amplitude : float
        Peak-to-peak swing ``Theta_p`` [rad], oscillating motion.
    frequency : float
        Oscillation frequency ``f_c`` [Hz], oscillating motion.
    direction : int
        +1 for counter-clockwise cam rotation (the default), -1 for clockwise; the
        thesis's self- against de-energizing studies (2.7.1) flip it.
    zero_state : str
        Which 0-state fixes ``Theta0`` when ``initial_angle`` is None:
        ``"maximum-lift"`` (thesis eqs 3.3-3.4: the cam centroid offset along the
        follower normal), ``"runout-parallel"`` (thesis eqs 4.3-4.4: the runout, the
        ellipse's major axis, parallel to the follower), or ``"auto"``: maximum lift for
        a circle, runout parallel for an ellipse.
    initial_angle : float or None
        ``Theta0`` [rad]; None uses the 0-state (docs/model.md §2).
    start_speed : float
        Cam speed [Hz] a ramp starts from.
    ramp_time : float
        Duration [s] of a ramp's constant acceleration.
    """

    kind: str = parameter("str", "'constant', 'oscillating' or 'ramp'", "constant")
    speed: float = parameter("speed", "cam speed (Hz = rev/s, rpm or rad/s)", 10.0, written="Hz")
    amplitude: float = parameter("rad", "peak-to-peak swing Theta_p of oscillating motion", 0.0)
    frequency: float = parameter("Hz", "frequency of oscillating motion", 0.0)
    direction: int = parameter("int", "+1 counter-clockwise (default), -1 clockwise", 1)
    zero_state: str = parameter("str", "0-state fixing Theta0: 'maximum-lift' (thesis ch 3), 'runout-parallel' "
                                       "(ch 4) or 'auto'", "auto")
    initial_angle: float | None = parameter("rad", "initial cam angle Theta0 (default: the 0-state)", None)
    start_speed: float = parameter("speed", "cam speed a ramp starts from (Hz = rev/s, rpm or rad/s)", 0.0,
                                   written="Hz")
    ramp_time: float = parameter("s", "duration of a ramp's constant acceleration", 0.0)

    def __post_init__(self):
        _check_finite("motion", self)
        if self.kind not in MOTION_KINDS:
            raise ParameterError(f"motion.kind must be one of {sorted(MOTION_KINDS)}, got {self.kind!r}")
        _nonnegative("motion", "speed", self.speed)
        _nonnegative("motion", "amplitude", self.amplitude)
        _nonnegative("motion", "frequency", self.frequency)
        if self.initial_angle is not None and not math.isfinite(self.initial_angle):
            raise ParameterError("motion.initial_angle must be finite")
        if self.zero_state not in ZERO_STATES:
            raise ParameterError(f"motion.zero_state must be one of {list(ZERO_STATES)}, got {self.zero_state!r}")
        if self.direction not in (1, -1):
            raise ParameterError(f"motion.direction must be +1 or -1, got {self.direction}")
        if self.kind == "oscillating" and (self.amplitude <= 0 or self.frequency <= 0):
            raise ParameterError("oscillating cam motion needs motion.amplitude > 0 and motion.frequency > 0")
        _nonnegative("motion", "start_speed", self.start_speed)
        _nonnegative("motion", "ramp_time", self.ramp_time)
        if self.kind == "ramp" and self.ramp_time <= 0:
            raise ParameterError("a ramp of the cam speed needs motion.ramp_time > 0 [s]")

    @property
    def angular_speed(self) -> float:
        """Signed cam angular speed ``Omega`` [rad/s] of constant motion."""
        return self.direction * 2.0 * math.pi * self.speed

    @property
    def period(self) -> float:
        """Period of the cam input [s]: one revolution, or one oscillation."""
        f = self.frequency if self.kind == "oscillating" else self.speed   # a ramp: the final speed
        return math.inf if f == 0 else 1.0 / f


def _check_profile(profile) -> None:
    """Refuse a cam profile the rocking follower cannot ride: anything but a profile of
    :mod:`camdyn.model.profiles` (read by its attributes: this layer imports no model), or
    one made for a roller or knife-edge follower (the rocking follower has a flat face)."""
    if profile is None:
        return
    follower = getattr(profile, "follower", None)
    table = getattr(profile, "table", None)
    if not isinstance(follower, str) or table is None or not hasattr(profile, "base_radius"):
        raise ParameterError(f"profile must be a cam profile of camdyn.model.profiles (e.g. eccentric_circle(...)), "
                             f"got {type(profile).__name__}")
    if follower != "flat":
        raise ParameterError(f"the rocking follower has a flat face: its cam profile must be made for a flat-faced "
                             f"follower (follower='flat'), not for a {follower} follower")


@dataclass(frozen=True)
class System:
    """A complete cam-follower system: geometry, contact, friction, spring and motion.

    Attributes
    ----------
    name : str
        Preset or file name it came from.
    citation : str
        Source of the parameter values.
    gravity : float
        Gravitational acceleration ``g`` [m/s^2].
    profile : camdyn.model.profiles.Profile or None
        The cam's shape as a profile table made for a flat-faced follower (e.g.
        ``eccentric_circle``, ``rise_return_profile``, ``tabulated_profile``), in place of
        the ellipse of ``cam.semi_major``, ``cam.semi_minor`` and ``cam.runout``, which it
        overrides; the cam's pivot and material still come from ``cam``. None (the
        default): the ellipse. See docs/profiles.md, "The rocking follower on a profile".
    """

    cam: Cam = group(Cam, required=True)
    follower: Follower = group(Follower, required=True)
    spring: Spring = group(Spring, required=True)
    contact: Contact = group(Contact)
    friction: Friction = group(Friction)
    motion: Motion = group(Motion)
    gravity: float = parameter("m/s**2", "gravitational acceleration g", 9.81, table="environment")
    name: str = "custom"
    citation: str = ""
    profile: object = None

    def __post_init__(self):
        if not math.isfinite(self.gravity):
            raise ParameterError("environment.gravity must be finite")
        _nonnegative("environment", "gravity", self.gravity)
        _check_profile(self.profile)
        # The follower's contact line must pass below the cam pivot region: the cam
        # pivot has to be on the cam's side of the follower (docs/model.md §1: cam above).
        h = self.follower.surface_offset
        reach = math.hypot(self.cam.pivot_x, self.cam.pivot_y)
        if reach <= h:
            raise GeometryError(
                f"the cam pivot ({self.cam.pivot_x*1e3:g}, {self.cam.pivot_y*1e3:g}) mm lies inside "
                f"the follower's contact surface offset ({h*1e3:g} mm)")

    def with_values(self, **dotted) -> System:
        """Return a copy with SI values changed by dotted key, e.g. ``with_values(**{"cam.runout": 3.5e-3})``;
        ``cam.radius`` sets both semi-axes."""
        groups: dict[str, dict] = {}
        top: dict = {}
        known = parameter_index(System)
        for key in dotted:
            if key not in known and key != "cam.radius":
                close = difflib.get_close_matches(key, [*known, "cam.radius"], n=3)
                hint = f"; did you mean {', '.join(close)}?" if close else ""
                raise UnknownKeyError(f"unknown parameter {key!r}{hint}")
        for key, value in dotted.items():
            if key == "cam.radius":                   # a circle: both semi-axes
                groups.setdefault("cam", {}).update(semi_major=value, semi_minor=value)
            elif "." in key:
                group, name = key.split(".", 1)
                groups.setdefault(group, {})[name] = value
            else:
                top[key] = value
        new = {}
        for group, values in groups.items():
            if group == "environment":
                top.update(values)
                continue
            if not hasattr(self, group):
                raise ParameterError(f"unknown parameter group {group!r}")
            new[group] = replace(getattr(self, group), **values)
        return replace(self, **new, **top)
