"""Parameter sets of the cam-follower model, as frozen dataclasses validated when built.

All values are SI inside camdyn. Configuration files and the command line give them
as text with units (see :mod:`camdyn.params.units`); :func:`camdyn.params.config.build_system`
turns dotted keys such as ``cam.runout`` into these dataclasses.

Symbols (docs/model.md, thesis nomenclature) are mapped in each field's docstring.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace

from camdyn.errors import GeometryError, ParameterError

__all__ = [
    "Cam", "Follower", "Spring", "Contact", "Friction", "Motion", "System",
    "DAMPING_LAWS", "FRICTION_LAWS", "MOTION_KINDS", "ZERO_STATES", "CONTACT_KINDS",
]

#: Contact damping laws (docs/model.md §3; thesis 2.3.4 and 3.2) and their integer codes
#: used by the compiled core. Letters A-E are the thesis's models.
DAMPING_LAWS = {
    "none": 0,
    "viscous": 1,                 # A: c = 2 zeta omega_n I_P / chi*^2       (eq 2.24, 4.20)
    "stiffness-proportional": 2,  # B: c = beta F_k(delta) (eq 2.25)          [beta: s/m]
    "zhang-whiten": 3,            # C: c = beta delta^0.25                    [N s / m^1.25]
    "stiffness-proportional-viscous": 4,  # D: B while compressing, A while restoring
    "zhang-whiten-viscous": 5,    # E: C while compressing, A while restoring
    "power": 6,                   # F_d = beta delta^n delta_dot (eq 3.2, 3.14) [N s / m^(n+1)]
    "hunt-crossley": 7,           # restitution-parameterised laws:
    "lankarani-nikravesh": 8,     #   F_d = D(e, v-) K delta^n_H delta_dot
    "flores": 9,
    "gonthier": 10,
    "hu-guo": 11,
}
#: Aliases using the thesis's letters.
DAMPING_ALIASES = {"A": "viscous", "B": "stiffness-proportional", "C": "zhang-whiten",
                   "D": "stiffness-proportional-viscous", "E": "zhang-whiten-viscous",
                   "generalized": "power"}
RESTITUTION_LAWS = ("hunt-crossley", "lankarani-nikravesh", "flores", "gonthier", "hu-guo")
FRICTION_LAWS = {"none": 0, "coulomb": 1, "tanh": 2}
MOTION_KINDS = {"constant": 0, "oscillating": 1}
#: Conventions for the 0-state that fixes ``Theta0`` when no initial angle is given
#: (docs/model.md §2): the thesis's chapter 3 (eqs 3.3-3.4) and chapter 4 (eqs 4.3-4.4).
ZERO_STATES = ("auto", "maximum-lift", "runout-parallel")
CONTACT_KINDS = {"point": 0, "line": 1}


def _check_finite(owner: str, obj) -> None:
    for f in fields(obj):
        v = getattr(obj, f.name)
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

    semi_major: float
    semi_minor: float
    runout: float
    pivot_x: float
    pivot_y: float
    youngs_modulus: float = 210e9
    poisson_ratio: float = 0.3

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

    mass: float
    inertia: float
    cg_distance: float
    length: float
    width: float
    pin_radius: float = 0.0
    youngs_modulus: float = 210e9
    poisson_ratio: float = 0.3
    accelerometer_distance: float = 0.0

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

    stiffness: float
    free_length: float
    attachment_x: float
    ground_depth: float
    tilt: float = 0.0

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
        A key of :data:`DAMPING_LAWS` (thesis letters A-E are accepted as aliases).
    damping_ratio : float
        ``zeta`` of the viscous law A, and of the restoring phase of D and E [-].
    beta : float
        Damping coefficient of laws B [s/m], C and E [N s/m^1.25], power law
        [N s/m^(n+1)].
    exponent : float
        ``n`` of the power law [-].
    restitution : float
        Coefficient of restitution ``e`` of the restitution-parameterised laws [-].
    reference_velocity : float
        Approach velocity used by restitution laws when a simulation starts in
        contact (no impact to measure it from) and lower bound on it [m/s].
    clip_adhesion : bool
        If True, negative (adhesive) normal force is set to zero. The thesis does not
        clip (its fig 3.8), so the default is False.
    """

    kind: str = "point"
    length: float = 0.0
    damping: str = "none"
    damping_ratio: float = 0.0
    beta: float = 0.0
    exponent: float = 1.5
    restitution: float = 1.0
    reference_velocity: float = 0.01
    clip_adhesion: bool = False

    def __post_init__(self):
        _check_finite("contact", self)
        if self.kind not in CONTACT_KINDS:
            raise ParameterError(f"contact.kind must be one of {sorted(CONTACT_KINDS)}, got {self.kind!r}")
        law = DAMPING_ALIASES.get(self.damping, self.damping)
        if law not in DAMPING_LAWS:
            raise ParameterError(
                f"contact.damping must be one of {sorted(DAMPING_LAWS)} (or A-E), got {self.damping!r}")
        object.__setattr__(self, "damping", law)
        if self.kind == "line":
            _positive("contact", "length", self.length)
        _nonnegative("contact", "damping_ratio", self.damping_ratio)
        _nonnegative("contact", "beta", self.beta)
        _nonnegative("contact", "exponent", self.exponent)
        if law in RESTITUTION_LAWS:
            lo = 0.0 if law in ("hunt-crossley", "lankarani-nikravesh") else 1e-3
            if not lo <= self.restitution <= 1.0:
                raise ParameterError(f"contact.restitution must lie in ({lo:g}, 1], got {self.restitution:g}")
        _positive("contact", "reference_velocity", self.reference_velocity)


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

    law: str = "coulomb"
    coefficient: float = 0.0
    smoothing: float = 10.0

    def __post_init__(self):
        _check_finite("friction", self)
        if self.law not in FRICTION_LAWS:
            raise ParameterError(f"friction.law must be one of {sorted(FRICTION_LAWS)}, got {self.law!r}")
        _nonnegative("friction", "coefficient", self.coefficient)
        _positive("friction", "smoothing", self.smoothing)


@dataclass(frozen=True)
class Motion:
    """Cam motion input (docs/model.md §1).

    Attributes
    ----------
    kind : str
        ``"constant"``: ``Theta = Theta0 + 2 pi f t``; ``"oscillating"``:
        ``Theta = Theta0 + 0.5 Theta_p sin(2 pi f_c t)`` (thesis 2.7.2).
    speed : float
        Cam speed ``f`` [Hz] (revolutions per second), constant motion.
    amplitude : float
        Peak-to-peak swing ``Theta_p`` [rad], oscillating motion.
    frequency : float
        Oscillation frequency ``f_c`` [Hz], oscillating motion.
    initial_angle : float or None
        ``Theta0`` [rad]; None uses the 0-state (docs/model.md §2).
    zero_state : str
        Which 0-state fixes ``Theta0`` when ``initial_angle`` is None:
        ``"maximum-lift"`` (thesis eqs 3.3-3.4: the cam centroid offset along the
        follower normal), ``"runout-parallel"`` (thesis eqs 4.3-4.4: the runout, the
        ellipse's major axis, parallel to the follower), or ``"auto"``: maximum lift for
        a circle, runout parallel for an ellipse.
    direction : int
        +1 for counter-clockwise cam rotation (the default), -1 for clockwise; the
        thesis's self- against de-energizing studies (2.7.1) flip it.
    """

    kind: str = "constant"
    speed: float = 10.0
    amplitude: float = 0.0
    frequency: float = 0.0
    initial_angle: float | None = None
    direction: int = 1
    zero_state: str = "auto"

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

    @property
    def angular_speed(self) -> float:
        """Signed cam angular speed ``Omega`` [rad/s] of constant motion."""
        return self.direction * 2.0 * math.pi * self.speed

    @property
    def period(self) -> float:
        """Period of the cam input [s]: one revolution, or one oscillation."""
        f = self.speed if self.kind == "constant" else self.frequency
        return math.inf if f == 0 else 1.0 / f


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
    """

    cam: Cam
    follower: Follower
    spring: Spring
    contact: Contact = field(default_factory=Contact)
    friction: Friction = field(default_factory=Friction)
    motion: Motion = field(default_factory=Motion)
    gravity: float = 9.81
    name: str = "custom"
    citation: str = ""

    def __post_init__(self):
        if not math.isfinite(self.gravity):
            raise ParameterError("environment.gravity must be finite")
        _nonnegative("environment", "gravity", self.gravity)
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
