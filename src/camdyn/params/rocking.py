"""Configuration files of a rocking roller or knife-edge follower on a cam profile: TOML
with units, ``[follower] kind = "rocking"``::

    [follower]
    kind = "rocking"
    face = "roller"
    roller_radius = "8 mm"
    pivot_x = "-70 mm"
    pivot_y = "40 mm"
    arm_length = "70 mm"
    lift_direction = "counter-clockwise"
    inertia = "2e-4 kg*m^2"

    [spring]
    stiffness = "0.5 N*m/rad"
    preload = "0.05 N*m"

    [profile]
    kind = "rise-return"
    face = "flat"
    base_radius = "30 mm"
    segments = [...]

    [motion]
    speed = "500 rpm"

The arm's keys are declared in :data:`SCHEMA`; the ``[profile]`` table takes the keys of
a translating follower's profile (:data:`camdyn.params.profiles.SCHEMA`) and, besides,
``profile.face`` (the follower the profile was made for, ``"flat"`` by default) and
``profile.offset`` (that follower's offset). The profile and the motion are read by the
translating follower's reader, so that they are checked key by key as there;
:func:`read_rocking` returns a :class:`RockingSpec` of SI values, and
:func:`camdyn.simulation.rocking_roller.rocking_from_spec` builds the follower.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, field
from pathlib import Path

from camdyn.errors import ParameterError, UnitError, UnknownKeyError
from camdyn.params.catalog import resolve
from camdyn.params.config import read_toml_file
from camdyn.params.follower_friction import FRICTION_SCHEMA, check_friction
from camdyn.params.profile_table import profile_spec
from camdyn.params.profiles import HERTZ_DAMPING_LAWS, HERTZ_KEYS, TranslatingSpec
from camdyn.params.units import parse_quantity

__all__ = ["ROCKING", "SCHEMA", "LIFT_DIRECTIONS", "RockingSpec", "read_rocking", "rocking_spec_from_table"]

#: The follower kind that selects this schema in ``[follower] kind``.
ROCKING = "rocking"
LIFT_DIRECTIONS = {"counter-clockwise": 1, "clockwise": -1}
_REQUIRED = object()
#: Dotted key -> (unit of the stored SI value, or "str"; default; meaning).
SCHEMA: dict[str, tuple[str, object, str]] = {
    "follower.kind": ("str", _REQUIRED, "'rocking' for this schema"),
    "follower.face": ("str", _REQUIRED, "'roller' or 'knife' (knife edge)"),
    "follower.roller_radius": ("m", 0.0, "roller radius r_r (roller face only)"),
    "follower.pivot_x": ("m", _REQUIRED, "the arm's pivot, x from the cam's axis"),
    "follower.pivot_y": ("m", _REQUIRED, "the arm's pivot, y from the cam's axis"),
    "follower.arm_length": ("m", _REQUIRED, "pivot to roller centre (or knife tip) L"),
    "follower.lift_direction": ("str", "counter-clockwise", "the sense in which the cam lifts the arm: "
                                                            "'counter-clockwise' or 'clockwise'"),
    "follower.inertia": ("kg*m**2", _REQUIRED, "moment of inertia I of the arm about its pivot"),
    "follower.damping": ("N*m*s", 0.0, "viscous damping c_t on the arm [N m s/rad]"),
    "spring.stiffness": ("N*m", _REQUIRED, "torsional spring stiffness k_t [N m/rad]"),
    "spring.preload": ("N*m", _REQUIRED, "spring moment M0 with the arm on the cam's lowest point"),
    "contact.restitution": ("", 0.8, "Newton's coefficient of restitution e of the normal velocity"),
    "contact.capture_velocity": ("1/s", 1e-6, "impacts slower than this [rad/s] end in sustained contact"),
    "contact.law": ("str", "rigid", "'rigid' (Newton restitution), 'compliant' (torsional spring-dashpot) or "
                                    "'hertz' (Hertz line or point contact, the exact lever at every angle)"),
    "contact.stiffness": ("N*m", 0.0, "torsional contact stiffness k_c [N m/rad] (compliant)"),
    "contact.damping": ("N*m*s", 0.0, "torsional contact damping c_c [N m s/rad] (compliant); under the hertz "
                                      "law the viscous law's c [N s/m]"),
    "contact.cam_modulus": ("Pa", 210e9, "Young's modulus of the cam Y_c (hertz)"),
    "contact.cam_poisson": ("", 0.3, "Poisson's ratio of the cam nu_c (hertz)"),
    "contact.follower_modulus": ("Pa", 210e9, "Young's modulus of the roller Y_f (hertz)"),
    "contact.follower_poisson": ("", 0.3, "Poisson's ratio of the roller nu_f (hertz)"),
    "contact.geometry": ("str", "", "'line' (a cylindrical roller) or 'point' (a crowned roller, a knife edge's "
                                    "rounded tip) (hertz); default point for a knife edge, line for a roller"),
    "contact.width": ("m", 0.0, "contact length l of line contact: the cam's or roller's width (hertz)"),
    "contact.tip_radius": ("m", 0.0, "tip radius of a knife edge, point contact (hertz)"),
    "contact.damping_law": ("str", "none", "damping law (hertz): " + ", ".join(HERTZ_DAMPING_LAWS)),
    "contact.reference_velocity": ("m/s", 1e-3, "smallest approach velocity of the restitution laws (hertz)"),
    **FRICTION_SCHEMA,
}
#: Contact laws of the arm.
CONTACT_LAWS = ("rigid", "compliant", "hertz")
#: The Hertz keys of this schema (the translating schema's).
_HERTZ = tuple(key for key in HERTZ_KEYS if key in SCHEMA)
#: Keys passed to the translating follower's reader as they are.
_PASSED = ("profile.", "motion.")
_META_KEYS = ("preset.name", "preset.citation", "preset.description", "preset.provenance")


@dataclass(frozen=True)
class RockingSpec:
    """A rocking follower's configuration in SI units, checked key by key.

    Attributes
    ----------
    name, citation : str
        The configuration's name and the source of its values.
    face : str
        ``"roller"`` or ``"knife"``.
    roller_radius, pivot_x, pivot_y, arm_length : float
        r_r, the pivot's position and L [m].
    lift_direction : int
        +1 counter-clockwise, -1 clockwise.
    inertia, damping, stiffness, preload : float
        I [kg m^2], c_t [N m s/rad], k_t [N m/rad], M0 [N m].
    restitution, capture_velocity : float
        e [-] and [rad/s].
    contact : str
        ``"rigid"``, ``"compliant"`` or ``"hertz"``.
    contact_stiffness, contact_damping : float
        k_c [N m/rad] and c_c [N m s/rad] (compliant); ``contact_damping`` is the viscous
        law's c [N s/m] under the Hertz law.
    static_friction, kinetic_friction, roller_inertia : float
        mu_s [-], mu_k [-] (None: mu_s) and J_r [kg m^2] of the ``[friction]`` table
        (:mod:`camdyn.params.follower_friction`; rigid contact law only).
    hertz : dict
        The Hertz law's keyword arguments of
        :class:`camdyn.simulation.translating_contact.HertzContact` in SI units (empty
        unless ``contact`` is ``"hertz"``).
    profile : TranslatingSpec
        The profile and the motion, as the translating follower's reader gives them
        (its follower's mass, spring and contact are placeholders).
    """

    name: str
    citation: str
    face: str
    roller_radius: float
    pivot_x: float
    pivot_y: float
    arm_length: float
    lift_direction: int
    inertia: float
    damping: float
    stiffness: float
    preload: float
    restitution: float
    capture_velocity: float
    profile: TranslatingSpec
    contact: str = "rigid"
    contact_stiffness: float = 0.0
    contact_damping: float = 0.0
    hertz: dict = field(default_factory=dict)
    static_friction: float = 0.0
    kinetic_friction: float | None = None
    roller_inertia: float = 0.0


def _value(key: str, raw, unit: str):
    if unit == "str":
        if not isinstance(raw, str) or not raw.strip():
            raise ParameterError(f"{key}: expected text, got {raw!r}")
        return raw.strip()
    if isinstance(raw, bool):
        raise ParameterError(f"{key}: expected a number, got {raw!r}")
    if isinstance(raw, (int, float)):
        if unit and float(raw) != 0.0:
            raise UnitError(f"{key}: {raw!r} has no unit; write it as text with one, e.g. \"{raw} {unit}\"")
        value = float(raw)
    elif isinstance(raw, str):
        value = parse_quantity(raw, unit, key)
    else:
        raise ParameterError(f"{key}: cannot read {raw!r}")
    if not math.isfinite(value):
        raise ParameterError(f"{key} must be finite, got {raw!r}")
    return value


def rocking_spec_from_table(flat: dict, name: str = "custom", citation: str = "", folder: Path | None = None
                            ) -> RockingSpec:
    """A :class:`RockingSpec` from flattened TOML (dotted keys -> raw values); ``folder``
    is where a tabulated profile's relative file is read from."""
    flat = {k: v for k, v in flat.items() if k not in _META_KEYS}
    for key in flat:
        if key not in SCHEMA and not key.startswith(_PASSED):
            close = difflib.get_close_matches(key, list(SCHEMA), n=3)
            hint = f"; did you mean {', '.join(close)}?" if close else f"; known keys: {', '.join(SCHEMA)}"
            raise UnknownKeyError(f"unknown key {key!r} in a rocking-follower configuration{hint}")
    if flat.get("follower.kind") != ROCKING:
        raise ParameterError(f"follower.kind is {flat.get('follower.kind')!r}; this reader takes 'rocking'")
    v = {}
    for key, (unit, default, meaning) in SCHEMA.items():
        if key in flat:
            if key == "contact.damping" and flat.get("contact.law") == "hertz":
                unit = "N*s/m"    # the viscous Hertz law's c, on the roller
            v[key] = _value(key, flat[key], unit)
        elif default is _REQUIRED:
            raise ParameterError(f"missing key {key!r} ({meaning})")
        else:
            v[key] = default
    face = v["follower.face"]
    if face not in ("roller", "knife"):
        raise ParameterError(f"follower.face must be 'roller' or 'knife' for a rocking arm, got {face!r}")
    if (face == "roller") != (v["follower.roller_radius"] > 0.0):
        raise ParameterError(f"follower.roller_radius: a roller needs a positive radius and a knife edge none, "
                             f"got {v['follower.roller_radius']!r} m for a {face}")
    if v["follower.lift_direction"] not in LIFT_DIRECTIONS:
        raise ParameterError(f"follower.lift_direction must be one of {', '.join(LIFT_DIRECTIONS)}, "
                             f"got {v['follower.lift_direction']!r}")
    _check_contact(flat, v)
    check_friction(v)
    passed = {key: value for key, value in flat.items() if key.startswith(_PASSED)}
    profile = profile_spec(passed, face, v["follower.roller_radius"], name, folder)
    law = v["contact.law"]
    hertz = {key.split(".")[1]: v[key] for key in _HERTZ} if law == "hertz" else {}
    if hertz:
        hertz.update(damping=v["contact.damping"])
    return RockingSpec(
        name=name, citation=citation, face=face, roller_radius=v["follower.roller_radius"],
        pivot_x=v["follower.pivot_x"], pivot_y=v["follower.pivot_y"], arm_length=v["follower.arm_length"],
        lift_direction=LIFT_DIRECTIONS[v["follower.lift_direction"]], inertia=v["follower.inertia"],
        damping=v["follower.damping"], stiffness=v["spring.stiffness"], preload=v["spring.preload"],
        restitution=v["contact.restitution"], capture_velocity=v["contact.capture_velocity"], profile=profile,
        contact=law, contact_stiffness=v["contact.stiffness"] if law == "compliant" else 0.0,
        contact_damping=v["contact.damping"] if law == "compliant" else 0.0, hertz=hertz,
        static_friction=v["friction.static"], kinetic_friction=v["friction.kinetic"],
        roller_inertia=v["friction.roller_inertia"])


def _check_contact(flat: dict, v: dict) -> None:
    """The contact law's keys: only under their law, a positive stiffness for the
    compliant law, ratios in range (the rest is checked by the follower when built)."""
    law = v["contact.law"]
    if law not in CONTACT_LAWS:
        raise ParameterError(f"contact.law must be one of {', '.join(CONTACT_LAWS)}, got {law!r}")
    own = {"rigid": ("contact.capture_velocity",), "compliant": ("contact.stiffness", "contact.damping"),
           "hertz": _HERTZ + ("contact.damping",)}
    foreign = [key for key in flat if key.startswith("contact.") and key not in own[law]
               and key not in ("contact.law", "contact.restitution") and key in SCHEMA]
    if foreign:
        raise UnknownKeyError(f"{foreign[0]} is not a key of the {law!r} contact law (it takes "
                              f"{', '.join(own[law])})")
    if law == "compliant" and v["contact.stiffness"] <= 0.0:
        raise ParameterError("contact.stiffness: a compliant contact needs a positive stiffness [N m/rad]")
    for key in ("contact.stiffness", "contact.damping", "contact.width", "contact.tip_radius"):
        if v[key] < 0.0:
            raise ParameterError(f"{key} must not be negative, got {v[key]!r}")
    if not 0.0 <= v["contact.restitution"] <= 1.0:
        raise ParameterError(f"contact.restitution must be between 0 and 1, got {v['contact.restitution']!r}")


def read_rocking(source: str | Path, overrides: dict | None = None) -> RockingSpec:
    """Read a rocking-follower TOML file, with dotted-key overrides.

    Parameters
    ----------
    source : str or Path
        The TOML file.
    overrides : dict, optional
        Dotted key -> value as text with its unit (``{"spring.preload": "0.06 N*m"}``).

    Returns
    -------
    RockingSpec
    """
    source = resolve(source)
    path = Path(str(source))
    flat = read_toml_file(source)
    flat.update(overrides or {})
    return rocking_spec_from_table(flat, name=str(flat.get("preset.name", path.stem)),
                                   citation=str(flat.get("preset.citation", "")), folder=path.resolve().parent)
