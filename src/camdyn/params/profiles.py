"""Configuration files of a translating follower on a cam profile: TOML with units.

A translating-follower configuration is a TOML file (or a bundled preset) whose
``[follower]`` table says ``kind = "translating"``; every other key is a quantity written
as text with its unit, as in the rocking follower's files (:mod:`camdyn.params.config`)::

    [follower]
    kind = "translating"
    face = "knife"
    mass = "1.221 kg"

    [spring]
    stiffness = "1430.8 N/m"   # and preload = "143.08 N"

    [profile]
    kind = "rise-return"
    base_radius = "40 mm"
    segments = [{law = "cycloidal", span = "120 deg", lift = "10 mm"}, {law = "dwell", span = "60 deg"},
                {law = "cycloidal", span = "120 deg", lift = "-10 mm"}, {law = "dwell", span = "60 deg"}]

    [motion]
    speed = "358 rpm"

Every key is declared once, in :data:`SCHEMA`, with its unit, default and meaning. A
profile's entries (``segments``, ``arcs``) are tables whose keys are declared in
:data:`SEGMENT_KEYS` and :data:`ARC_KEYS`. Unknown keys, missing keys, keys that do not
belong to the profile's kind, wrong units and values out of range are refused with the
key's name, before any work. :func:`read_translating` returns a
:class:`TranslatingSpec` of SI values; the profile itself is built from it by
:func:`camdyn.simulation.translating.follower_from_spec` (this layer knows no cam
model), and a tabulated profile's CSV file is read by :mod:`camdyn.io.lift_table`.
"""

from __future__ import annotations

import difflib
import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

from camdyn.errors import ParameterError, PresetError, UnitError, UnknownKeyError
from camdyn.params.catalog import preset_file, presets_of_kind, resolve
from camdyn.params.follower_friction import FRICTION_SCHEMA, check_friction
from camdyn.params.toml_text import flatten, loads_toml, read_toml_text
from camdyn.params.units import parse_quantity, parse_speed, registry

__all__ = ["SCHEMA", "SEGMENT_KEYS", "ARC_KEYS", "PROFILE_KINDS", "FACES", "CONTACT_LAWS", "HERTZ_DAMPING_LAWS",
           "HERTZ_KEYS", "TranslatingSpec", "read_translating", "spec_from_table", "is_translating", "declared_kind",
           "list_translating_presets", "translating_preset_text"]

#: The follower kind that selects this schema in ``[follower] kind``.
TRANSLATING = "translating"
FACES = ("flat", "knife", "roller")
CONTACT_LAWS = ("rigid", "compliant", "hertz")
#: The damping laws of :mod:`camdyn.params.laws` offered for the Hertz law of a
#: translating follower (those whose coefficients need no law-dependent unit).
HERTZ_DAMPING_LAWS = ("none", "viscous", "hunt-crossley", "lankarani-nikravesh", "flores", "gonthier", "hu-guo")
#: Keys of the Hertz law only (``contact.law = "hertz"``).
HERTZ_KEYS = ("contact.cam_modulus", "contact.cam_poisson", "contact.follower_modulus", "contact.follower_poisson",
              "contact.geometry", "contact.width", "contact.tip_radius", "contact.damping_law",
              "contact.reference_velocity")
#: Profile kind -> the ``profile.*`` keys it uses (besides ``profile.kind``).
PROFILE_KINDS = {
    "rise-return": ("profile.base_radius", "profile.segments"),
    "circular-arc": ("profile.base_radius", "profile.arcs"),
    "eccentric-circle": ("profile.radius", "profile.eccentricity"),
    "tabulated": ("profile.base_radius", "profile.file"),
}
_REQUIRED = object()

#: Dotted key -> (unit of the stored SI value, or "str", "speed", "angle", "list"; default
#: (``_REQUIRED`` when the key must be given); meaning). Angles are stored in radians,
#: speeds in rad/s.
SCHEMA: dict[str, tuple[str, object, str]] = {
    "follower.kind": ("str", _REQUIRED, "'translating' for this schema"),
    "follower.face": ("str", _REQUIRED, "follower face: 'flat', 'knife' (knife edge) or 'roller'"),
    "follower.mass": ("kg", _REQUIRED, "follower mass m"),
    "follower.damping": ("N*s/m", 0.0, "viscous damping c on the follower"),
    "follower.roller_radius": ("m", 0.0, "roller radius r_r (roller face only)"),
    "follower.offset": ("m", 0.0, "offset epsilon of the follower's line from the cam's axis"),
    "spring.stiffness": ("N/m", _REQUIRED, "spring stiffness k"),
    "spring.preload": ("N", _REQUIRED, "spring force F0 when the follower rests on the base circle"),
    "contact.law": ("str", "rigid", "'rigid' (Newton restitution), 'compliant' (spring-dashpot penalty) or "
                                    "'hertz' (Hertz stiffness of the materials and geometry)"),
    "contact.restitution": ("", 0.8, "coefficient of restitution e: Newton's (rigid), the restitution "
                                      "damping laws' (hertz)"),
    "contact.capture_velocity": ("m/s", 1e-6, "impacts slower than this end in sustained contact (rigid)"),
    "contact.stiffness": ("N/m", 0.0, "penalty stiffness kc (compliant)"),
    "contact.damping": ("N*s/m", 0.0, "penalty damping cc (compliant); c of the viscous damping law (hertz)"),
    "contact.cam_modulus": ("Pa", 210e9, "Young's modulus of the cam Y_c (hertz)"),
    "contact.cam_poisson": ("", 0.3, "Poisson's ratio of the cam nu_c (hertz)"),
    "contact.follower_modulus": ("Pa", 210e9, "Young's modulus of the follower Y_f (hertz)"),
    "contact.follower_poisson": ("", 0.3, "Poisson's ratio of the follower nu_f (hertz)"),
    "contact.geometry": ("str", "", "'line' or 'point' (hertz); default point for a knife edge, line otherwise"),
    "contact.width": ("m", 0.0, "contact length l of line contact: the cam's or roller's width (hertz)"),
    "contact.tip_radius": ("m", 0.0, "tip radius of a knife edge, point contact (hertz)"),
    "contact.damping_law": ("str", "none", "damping law (hertz): " + ", ".join(HERTZ_DAMPING_LAWS)),
    "contact.reference_velocity": ("m/s", 1e-3, "smallest approach velocity of the restitution laws (hertz)"),
    "environment.gravity": ("m/s**2", 0.0, "gravity g along the follower's line, towards the cam"),
    "profile.kind": ("str", _REQUIRED, "'rise-return', 'circular-arc', 'eccentric-circle' or 'tabulated'"),
    "profile.base_radius": ("m", _REQUIRED, "base circle radius r_base (not for an eccentric circle)"),
    "profile.segments": ("list", _REQUIRED, "rise-return: the segments from theta = 0, tables of SEGMENT_KEYS"),
    "profile.arcs": ("list", _REQUIRED, "circular-arc: the arcs from theta = 0, tables of ARC_KEYS"),
    "profile.radius": ("m", _REQUIRED, "eccentric-circle: the circle's radius R"),
    "profile.eccentricity": ("m", _REQUIRED, "eccentric-circle: distance e from the axis to the circle's centre"),
    "profile.file": ("str", _REQUIRED, "tabulated: CSV file of the lift, relative to the TOML file"),
    "motion.speed": ("speed", None, "cam speed omega (rpm, Hz = rev/s or rad/s)"),
    "motion.phase": ("angle", 0.0, "cam angle theta0 at t = 0"),
    **FRICTION_SCHEMA,
}
#: Keys of one rise-return segment: law name, angular span, change of lift.
SEGMENT_KEYS = {"law": ("str", _REQUIRED, "'dwell', 'cycloidal', 'harmonic', 'polynomial-345' or "
                                          "'polynomial-4567'"),
                "span": ("angle", _REQUIRED, "angular span of the segment"),
                "lift": ("m", 0.0, "change of lift over the segment (negative for a return; 0 for a dwell)")}
#: Keys of one circular arc of the cam.
ARC_KEYS = {"span": ("angle", _REQUIRED, "angular span of the arc"),
            "centre_distance": ("m", _REQUIRED, "distance d of the arc's centre from the cam's axis"),
            "centre_angle": ("angle", 0.0, "direction phi_c of the arc's centre in the cam's frame"),
            "radius": ("m", _REQUIRED, "the arc's radius rho")}
_META_KEYS = ("preset.name", "preset.citation", "preset.description", "preset.provenance")
#: Keys that must not be negative, and those that must be positive.
_NOT_NEGATIVE = ("follower.damping", "follower.roller_radius", "spring.stiffness", "spring.preload",
                 "contact.capture_velocity", "contact.stiffness", "contact.damping", "environment.gravity",
                 "profile.eccentricity", "contact.width", "contact.tip_radius")
_POSITIVE = ("follower.mass", "profile.base_radius", "profile.radius", "contact.cam_modulus",
             "contact.follower_modulus", "contact.reference_velocity")


@dataclass(frozen=True)
class TranslatingSpec:
    """A translating follower's configuration in SI units, checked key by key.

    Attributes
    ----------
    name, citation : str
        The configuration's name and the source of its values.
    face : str
        ``"flat"``, ``"knife"`` or ``"roller"``.
    mass, damping, stiffness, preload, gravity : float
        m [kg], c [N s/m], k [N/m], F0 [N], g [m/s^2].
    roller_radius, offset : float
        r_r and epsilon [m].
    contact : str
        ``"rigid"``, ``"compliant"`` or ``"hertz"``.
    restitution, capture_velocity, contact_stiffness, contact_damping : float
        e [-], [m/s], kc [N/m], cc [N s/m] (cc: the viscous c of the Hertz law).
    cam_modulus, cam_poisson, follower_modulus, follower_poisson, width, tip_radius : float
        Y_c [Pa], nu_c [-], Y_f [Pa], nu_f [-], l [m], r_f [m] of the Hertz law.
    geometry, damping_law : str
        ``"line"``, ``"point"`` or ``""`` (the face's own); a :data:`HERTZ_DAMPING_LAWS` name.
    reference_velocity : float
        Smallest approach velocity of its restitution laws [m/s].
    static_friction, kinetic_friction, roller_inertia : float
        mu_s [-], mu_k [-] (None: mu_s) and J_r [kg m^2] of :mod:`camdyn.params.follower_friction`.
    profile_kind : str
        A key of :data:`PROFILE_KINDS`.
    base_radius : float
        r_base [m] (``radius - eccentricity`` for an eccentric circle).
    segments : tuple of (str, float, float)
        ``(law, span [rad], lift [m])`` of a rise-return profile.
    arcs : tuple of (float, float, float, float)
        ``(span [rad], centre distance [m], centre angle [rad], radius [m])``.
    radius, eccentricity : float
        R and e [m] of an eccentric circle.
    file : Path or None
        The CSV file of a tabulated profile (absolute, or relative to the working folder).
    speed : float or None
        Cam speed omega [rad/s]; None when the file gives none.
    phase : float
        Cam angle theta0 [rad] at t = 0.
    """

    name: str
    citation: str
    face: str
    mass: float
    damping: float
    stiffness: float
    preload: float
    gravity: float
    roller_radius: float
    offset: float
    contact: str
    restitution: float
    capture_velocity: float
    contact_stiffness: float
    contact_damping: float
    profile_kind: str
    base_radius: float = 0.0
    segments: tuple = ()
    arcs: tuple = ()
    radius: float = 0.0
    eccentricity: float = 0.0
    file: Path | None = None
    speed: float | None = None
    phase: float = 0.0
    cam_modulus: float = 210e9
    cam_poisson: float = 0.3
    follower_modulus: float = 210e9
    follower_poisson: float = 0.3
    geometry: str = ""
    width: float = 0.0
    tip_radius: float = 0.0
    damping_law: str = "none"
    reference_velocity: float = 1e-3
    static_friction: float = 0.0
    kinetic_friction: float | None = None
    roller_inertia: float = 0.0


def _unknown(key: str, known) -> UnknownKeyError:
    close = difflib.get_close_matches(key, list(known), n=3)
    hint = f"; did you mean {', '.join(close)}?" if close else f"; known keys: {', '.join(known)}"
    return UnknownKeyError(f"unknown key {key!r} in a translating-follower configuration{hint}")


def _angle(raw, key: str) -> float:
    """An angle [rad] from text with its unit ("90 deg", "1.5708 rad"): a bare number is
    refused, since degrees and radians are both dimensionless to pint."""
    if not isinstance(raw, str):
        raise UnitError(f"{key}: write the angle as text with its unit, e.g. \"{raw} deg\"")
    try:
        unitless = registry().Quantity(raw.strip().replace("^", "**")).unitless
    except Exception:  # noqa: BLE001 - parse_quantity below gives the message
        unitless = False
    if unitless:
        raise UnitError(f"{key}: {raw!r} has no unit; write it as '{raw.strip()} deg' or '{raw.strip()} rad'")
    return parse_quantity(raw, "rad", key)


def _value(key: str, raw, unit: str):
    """The stored value of one key: text, an angle [rad], a speed [rad/s] or a quantity
    [unit] (a bare number only where the unit is dimensionless, or 0)."""
    if unit == "str":
        if not isinstance(raw, str) or not raw.strip():
            raise ParameterError(f"{key}: expected text, got {raw!r}")
        return raw.strip()
    if unit == "list":
        if not isinstance(raw, list) or not all(isinstance(item, dict) for item in raw) or not raw:
            raise ParameterError(f"{key}: expected a list of tables such as [{{span = \"90 deg\", ...}}], "
                                 f"got {raw!r}")
        return raw
    if unit == "angle":
        return _angle(raw, key)
    if unit == "speed":
        if not isinstance(raw, str):
            raise UnitError(f"{key}: write the speed as text with its unit, e.g. \"{raw} rpm\"")
        return 2.0 * math.pi * parse_speed(raw, key)
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


def _entries(key: str, items: list, keys: dict) -> list[dict]:
    """The converted tables of a profile's list (``profile.segments``, ``profile.arcs``)."""
    out = []
    for i, item in enumerate(items):
        where = f"{key}[{i}]"
        for name in item:
            if name not in keys:
                close = difflib.get_close_matches(name, list(keys), n=1)
                hint = f"; did you mean {close[0]}?" if close else f"; known: {', '.join(keys)}"
                raise UnknownKeyError(f"unknown key {where}.{name}{hint}")
        entry = {}
        for name, (unit, default, meaning) in keys.items():
            if name in item:
                entry[name] = _value(f"{where}.{name}", item[name], unit)
            elif default is _REQUIRED:
                raise ParameterError(f"missing key {where}.{name} ({meaning})")
            else:
                entry[name] = default
        out.append(entry)
    return out


def _check_ranges(values: dict) -> None:
    for key in _NOT_NEGATIVE:
        if key in values and values[key] < 0.0:
            raise ParameterError(f"{key} must not be negative, got {values[key]!r} {SCHEMA[key][0]}")
    for key in _POSITIVE:
        if key in values and values[key] <= 0.0:
            raise ParameterError(f"{key} must be positive, got {values[key]!r} {SCHEMA[key][0]}")
    if not 0.0 <= values["contact.restitution"] <= 1.0:
        raise ParameterError(f"contact.restitution must be between 0 and 1, got {values['contact.restitution']!r}")
    for key, allowed in (("follower.face", FACES), ("contact.law", CONTACT_LAWS)):
        if values[key] not in allowed:
            raise ParameterError(f"{key} must be one of {', '.join(allowed)}, got {values[key]!r}")
    if values["contact.law"] == "compliant" and values["contact.stiffness"] <= 0.0:
        raise ParameterError("contact.stiffness: a compliant contact needs a positive penalty stiffness [N/m]")
    if values["follower.face"] == "roller" and values["follower.roller_radius"] <= 0.0:
        raise ParameterError("follower.roller_radius: a roller face needs a positive roller radius [m]")
    if values["follower.face"] != "roller" and values["follower.roller_radius"] != 0.0:
        raise ParameterError(f"follower.roller_radius is for a roller face only, not a {values['follower.face']} one")
    if values["speed"] is not None and values["speed"] <= 0.0:
        raise ParameterError(f"motion.speed must be positive, got {values['speed']!r} rad/s")


def _check_hertz(flat: dict, values: dict) -> None:
    """The Hertz law's keys: only under it (and no penalty stiffness there), ratios in range,
    a known damping law (the geometry is checked with the profile, by
    :class:`camdyn.simulation.translating_contact.HertzContact`)."""
    law = values["contact.law"]
    foreign = [key for key in (HERTZ_KEYS if law != "hertz" else ("contact.stiffness",)) if key in flat]
    if foreign:
        raise UnknownKeyError(f"{foreign[0]} is not a key of the {law!r} contact law (the Hertz law takes "
                              f"{', '.join(HERTZ_KEYS)}, and no contact.stiffness)")
    for key in ("contact.cam_poisson", "contact.follower_poisson"):
        if not -1.0 < values[key] < 0.5:
            raise ParameterError(f"{key} must lie in (-1, 0.5), got {values[key]!r}")
    if values["contact.damping_law"] not in HERTZ_DAMPING_LAWS:
        raise ParameterError(f"contact.damping_law must be one of {', '.join(HERTZ_DAMPING_LAWS)}, got "
                             f"{values['contact.damping_law']!r}")
    if values["contact.geometry"] not in ("", "line", "point"):
        raise ParameterError(f"contact.geometry must be 'line' or 'point', got {values['contact.geometry']!r}")


def _converted(flat: dict) -> dict:
    """Dotted key -> stored value, defaults filled in, for the keys of the profile's kind."""
    kind = flat.get("profile.kind")
    if kind is not None and kind not in PROFILE_KINDS:
        raise ParameterError(f"profile.kind must be one of {', '.join(PROFILE_KINDS)}, got {kind!r}")
    profile_keys = PROFILE_KINDS.get(kind, ())
    for key in flat:
        if key.startswith("profile.") and key != "profile.kind" and key in SCHEMA and key not in profile_keys:
            raise UnknownKeyError(f"{key} is not a key of a {kind or 'profile without a kind'} profile "
                                  f"(it takes {', '.join(profile_keys) or 'profile.kind first'})")
    values = {}
    for key, (unit, default, meaning) in SCHEMA.items():
        if key.startswith("profile.") and key != "profile.kind" and key not in profile_keys:
            continue
        if key in flat:
            values[key] = _value(key, flat[key], unit)
        elif default is _REQUIRED:
            raise ParameterError(f"missing key {key!r} ({meaning})")
        else:
            values[key] = default
    values["speed"] = values.pop("motion.speed")
    return values


def spec_from_table(flat: dict, name: str = "custom", citation: str = "", folder: Path | None = None
                    ) -> TranslatingSpec:
    """A :class:`TranslatingSpec` from flattened TOML (dotted keys -> raw values).

    Parameters
    ----------
    flat : dict
        Dotted key -> raw value as written in the file (``"1.221 kg"``).
    name, citation : str
        The configuration's name and source.
    folder : Path, optional
        The folder a relative ``profile.file`` is read from (the TOML file's folder).
    """
    flat = {k: v for k, v in flat.items() if k not in _META_KEYS}
    for key in flat:
        if key not in SCHEMA:
            raise _unknown(key, SCHEMA)
    if flat.get("follower.kind", TRANSLATING) != TRANSLATING:
        raise ParameterError(f"follower.kind is {flat['follower.kind']!r}; this reader takes 'translating'")
    v = _converted(flat)
    _check_ranges(v)
    _check_hertz(flat, v)
    check_friction(v)
    kind = v["profile.kind"]
    extra = {}
    if kind == "rise-return":
        extra["segments"] = tuple((e["law"], e["span"], e["lift"])
                                  for e in _entries("profile.segments", v["profile.segments"], SEGMENT_KEYS))
    elif kind == "circular-arc":
        extra["arcs"] = tuple((e["span"], e["centre_distance"], e["centre_angle"], e["radius"])
                              for e in _entries("profile.arcs", v["profile.arcs"], ARC_KEYS))
    elif kind == "eccentric-circle":
        extra.update(radius=v["profile.radius"], eccentricity=v["profile.eccentricity"])
    else:
        path = Path(v["profile.file"])
        extra["file"] = path if path.is_absolute() or folder is None else folder / path
    base = v.get("profile.base_radius", v.get("profile.radius", 0.0) - v.get("profile.eccentricity", 0.0))
    return TranslatingSpec(
        name=name, citation=citation, face=v["follower.face"], mass=v["follower.mass"],
        damping=v["follower.damping"], stiffness=v["spring.stiffness"], preload=v["spring.preload"],
        gravity=v["environment.gravity"], roller_radius=v["follower.roller_radius"], offset=v["follower.offset"],
        contact=v["contact.law"], restitution=v["contact.restitution"],
        capture_velocity=v["contact.capture_velocity"], contact_stiffness=v["contact.stiffness"],
        contact_damping=v["contact.damping"], profile_kind=kind, base_radius=base, speed=v["speed"],
        phase=v["motion.phase"], static_friction=v["friction.static"], kinetic_friction=v["friction.kinetic"],
        roller_inertia=v["friction.roller_inertia"], **{key.split(".")[1]: v[key] for key in HERTZ_KEYS}, **extra)


def list_translating_presets() -> list[str]:
    """Names of the bundled presets whose ``[follower]`` is translating."""
    return presets_of_kind(TRANSLATING)


def translating_preset_text(name: str) -> str:
    """The TOML text of a bundled translating-follower preset."""
    if name not in list_translating_presets():
        raise PresetError(f"no translating-follower preset named {name!r} "
                          f"(available: {', '.join(list_translating_presets())})")
    return preset_file(name).read_text(encoding="utf-8")


def _kind_in(text: str, source="TOML") -> str | None:
    """The ``[follower] kind`` TOML text declares (None without one, or where not TOML)."""
    try:
        follower = loads_toml(text, source).get("follower", {})
    except tomllib.TOMLDecodeError:
        return None
    kind = follower.get("kind") if isinstance(follower, dict) else None
    return None if kind is None else str(kind)


def _source_text(source: str | Path) -> tuple[str, str, Path | None]:   # (text, name, folder of relative paths)
    path = Path(str(resolve(source)))
    if not path.is_file():
        raise PresetError(f"{str(source)!r} is neither a translating-follower preset "
                          f"({', '.join(list_translating_presets())}) nor a TOML file")
    try:
        return read_toml_text(path, source), path.stem, path.resolve().parent
    except UnicodeDecodeError:
        raise PresetError(f"{source}: not UTF-8 text; a configuration file is TOML, saved as UTF-8") from None
    except OSError as exc:
        raise PresetError(f"{source}: cannot be read ({exc.strerror or exc})") from None


def declared_kind(source: str | Path) -> str | None:
    """The ``[follower] kind`` a TOML file or preset declares (None without one, or where
    unreadable)."""
    path = Path(str(resolve(source)))
    try:
        return _kind_in(read_toml_text(path, source), source) if path.is_file() else None
    except (OSError, UnicodeDecodeError):
        return None


def is_translating(source: str | Path) -> bool:
    """Whether a preset name or TOML file describes a translating follower (its
    ``[follower] kind`` is ``"translating"``); False for anything unreadable."""
    path = Path(str(resolve(source)))
    try:
        return path.is_file() and _kind_in(read_toml_text(path, source)) == TRANSLATING
    except (OSError, UnicodeDecodeError):
        return False


def read_translating(source: str | Path, overrides: dict | None = None) -> TranslatingSpec:
    """Read a translating-follower preset or TOML file, with dotted-key overrides.

    Parameters
    ----------
    source : str or Path
        Preset name (:func:`list_translating_presets`) or TOML file.
    overrides : dict, optional
        Dotted key -> value as text with its unit (``{"spring.preload": "150 N"}``).

    Returns
    -------
    TranslatingSpec
    """
    text, name, folder = _source_text(source)
    try:
        table = loads_toml(text, source)
    except tomllib.TOMLDecodeError as exc:
        raise PresetError(f"{source}: not valid TOML ({exc})") from None
    flat = flatten(table)
    for key, value in (overrides or {}).items():
        if key not in SCHEMA:
            raise _unknown(key, SCHEMA)
        flat[key] = value
    return spec_from_table(flat, name=str(flat.get("preset.name", name)),
                           citation=str(flat.get("preset.citation", "")), folder=folder)
