"""Configuration files and presets: TOML with units written as text.

A configuration is a TOML file whose tables are parameter groups and whose values
are quantities with units, for example::

    [cam]
    radius = "17.5 mm"
    runout = "3.5 mm"

Every parameter has a dotted key (``cam.runout``) listed in :data:`SCHEMA`, with the
unit it is stored in (SI). Presets are such files shipped in ``camdyn/presets``.
"""

from __future__ import annotations

import difflib
import json
import math
import tomllib
from importlib import resources
from pathlib import Path

from camdyn.errors import ParameterError, PresetError, UnitError, UnknownKeyError
from camdyn.params.system import (
    DAMPING_ALIASES,
    DAMPING_LAWS,
    Cam,
    Contact,
    Follower,
    Friction,
    Motion,
    Spring,
    System,
)
from camdyn.params.units import parse_quantity, parse_speed

__all__ = ["SCHEMA", "list_presets", "preset_text", "load_system", "build_system", "flatten"]

#: Dotted key -> (unit of the stored SI value, or a type name, description).
SCHEMA: dict[str, tuple[str, str]] = {
    "cam.radius": ("m", "radius rc of a circular cam (sets both semi-axes)"),
    "cam.semi_major": ("m", "semi-axis a of an elliptic cam, along the line through the pivot"),
    "cam.semi_minor": ("m", "semi-axis b of an elliptic cam"),
    "cam.runout": ("m", "runout e: distance from the cam pivot to its centroid"),
    "cam.pivot_x": ("m", "horizontal position of the cam pivot E relative to the follower pivot P"),
    "cam.pivot_y": ("m", "vertical position of the cam pivot E relative to P"),
    "cam.youngs_modulus": ("Pa", "Young's modulus of the cam"),
    "cam.poisson_ratio": ("", "Poisson's ratio of the cam"),
    "follower.mass": ("kg", "follower mass m"),
    "follower.inertia": ("kg*m**2", "moment of inertia about the pivot I_P"),
    "follower.cg_distance": ("m", "distance from the pivot to the centre of gravity"),
    "follower.length": ("m", "bar length"),
    "follower.width": ("m", "bar width wb"),
    "follower.pin_radius": ("m", "dowel-pin radius rd (0: contact on the bar face; a point contact then uses "
                                     "the cam curvature alone, eq 2.34)"),
    "follower.youngs_modulus": ("Pa", "Young's modulus of the follower"),
    "follower.poisson_ratio": ("", "Poisson's ratio of the follower"),
    "follower.accelerometer_distance": ("m", "distance l_a of the tangential accelerometer from the pivot"),
    "spring.stiffness": ("N/m", "spring stiffness ks"),
    "spring.free_length": ("m", "spring free length Ls"),
    "spring.attachment_x": ("m", "horizontal distance dx from the pivot to the spring"),
    "spring.ground_depth": ("m", "depth dy of the spring's grounded end below the pivot"),
    "spring.tilt": ("rad", "spring tilt sigma from the vertical, clockwise (eq 4.44)"),
    "contact.kind": ("str", "'point' (dowel pin, Hertz point contact) or 'line' (bar face)"),
    "contact.length": ("m", "line-contact length l"),
    "contact.damping": ("str", "damping law: " + ", ".join(DAMPING_LAWS) + " (or A-E)"),
    "contact.damping_ratio": ("", "zeta of the viscous law A (and the restoring phase of D, E)"),
    "contact.beta": ("law", "damping coefficient beta; unit depends on the law"),
    "contact.exponent": ("", "exponent n of the power law beta*delta^n*delta_dot"),
    "contact.restitution": ("", "coefficient of restitution e of the restitution laws"),
    "contact.reference_velocity": ("m/s", "approach velocity of restitution laws when starting in contact"),
    "contact.clip_adhesion": ("bool", "set negative (adhesive) normal force to zero"),
    "friction.law": ("str", "'coulomb', 'tanh' or 'none'"),
    "friction.coefficient": ("", "friction coefficient mu_m"),
    "friction.smoothing": ("s/m", "sigma of the tanh friction law"),
    "motion.kind": ("str", "'constant' or 'oscillating'"),
    "motion.speed": ("speed", "cam speed (Hz = rev/s, rpm or rad/s)"),
    "motion.amplitude": ("rad", "peak-to-peak swing Theta_p of oscillating motion"),
    "motion.frequency": ("Hz", "frequency of oscillating motion"),
    "motion.initial_angle": ("rad", "initial cam angle Theta0 (default: the 0-state)"),
    "motion.direction": ("int", "+1 counter-clockwise (default), -1 clockwise"),
    "motion.zero_state": ("str", "0-state fixing Theta0: 'maximum-lift' (thesis ch 3), 'runout-parallel' (ch 4) "
                                 "or 'auto'"),
    "environment.gravity": ("m/s**2", "gravitational acceleration g"),
}
_META_KEYS = {"preset.name", "preset.citation", "preset.description"}


def beta_unit(law: str, exponent: float) -> str:
    """Unit of ``contact.beta`` for a damping law (docs/model.md §3)."""
    law = DAMPING_ALIASES.get(law, law)
    if law in ("stiffness-proportional", "stiffness-proportional-viscous"):
        return "s/m"
    if law in ("zhang-whiten", "zhang-whiten-viscous"):
        return "N*s/m**1.25"
    if law == "power":
        return f"N*s/m**{1.0 + exponent!r}"
    return "N*s/m"


def flatten(table: dict, prefix: str = "") -> dict:
    """Flatten nested TOML tables into dotted keys."""
    out = {}
    for key, value in table.items():
        dotted = f"{prefix}{key}"
        if isinstance(value, dict):
            out.update(flatten(value, dotted + "."))
        else:
            out[dotted] = value
    return out


def _unknown(key: str) -> UnknownKeyError:
    close = difflib.get_close_matches(key, list(SCHEMA), n=3)
    hint = f"; did you mean {', '.join(close)}?" if close else "; run 'camdyn presets keys' for the list"
    return UnknownKeyError(f"unknown parameter {key!r}{hint}")


def _convert(key: str, raw, values: dict) -> object:
    unit, _ = SCHEMA[key]
    if unit == "str":
        if not isinstance(raw, str):
            raise ParameterError(f"{key}: expected text, got {raw!r}")
        return raw.strip()
    if unit == "bool":
        if isinstance(raw, bool):
            return raw
        if isinstance(raw, str) and raw.strip().lower() in ("true", "false", "yes", "no", "1", "0"):
            return raw.strip().lower() in ("true", "yes", "1")
        raise ParameterError(f"{key}: expected true or false, got {raw!r}")
    if unit == "int":
        try:
            return int(raw)
        except (TypeError, ValueError):
            raise ParameterError(f"{key}: expected an integer, got {raw!r}") from None
    if unit == "speed":
        return parse_speed(raw, key)
    if unit == "law":
        law = str(values.get("contact.damping", "none")).strip()
        if DAMPING_ALIASES.get(law, law) not in DAMPING_LAWS:
            raise ParameterError(f"contact.damping must be one of {sorted(DAMPING_LAWS)} (or A-E), got {law!r}")
        exponent = values.get("contact.exponent", 1.5)
        if isinstance(exponent, str):
            exponent = parse_quantity(exponent, "", "contact.exponent")
        return parse_quantity(raw, beta_unit(str(law).strip(), float(exponent)), key)
    if isinstance(raw, str):
        return parse_quantity(raw, unit, key)
    if isinstance(raw, (int, float)) and not isinstance(raw, bool):
        if unit and float(raw) != 0.0:
            raise UnitError(f"{key}: {raw!r} has no unit; write it as text with one, e.g. \"{raw} {unit}\"")
        return float(raw)
    raise ParameterError(f"{key}: cannot read {raw!r}")


def build_system(values: dict, name: str = "custom", citation: str = "") -> System:
    """Build a :class:`~camdyn.params.system.System` from dotted keys and raw values.

    Parameters
    ----------
    values : dict
        Dotted key -> text with unit (``"17.5 mm"``), number (dimensionless) or SI
        float for keys whose unit is given in :data:`SCHEMA`.
    """
    values = {k: v for k, v in values.items() if k not in _META_KEYS}
    for key in values:
        if key not in SCHEMA:
            raise _unknown(key)
    v = {key: _convert(key, raw, values) for key, raw in values.items()}

    def need(key):
        if key not in v:
            raise ParameterError(f"missing parameter {key!r} ({SCHEMA[key][1]})")
        return v[key]

    if "cam.radius" in v:
        if "cam.semi_major" in v or "cam.semi_minor" in v:
            raise ParameterError("give either cam.radius or cam.semi_major/cam.semi_minor, not both")
        a = b = v["cam.radius"]
    else:
        a, b = need("cam.semi_major"), need("cam.semi_minor")

    def pick(prefix, cls, skip=()):
        kwargs = {}
        for key, val in v.items():
            group, _, attr = key.partition(".")
            if group == prefix and attr not in skip:
                kwargs[attr] = val
        return cls, kwargs

    cls, kw = pick("cam", Cam, skip=("radius", "semi_major", "semi_minor"))
    for req in ("runout", "pivot_x", "pivot_y"):
        need(f"cam.{req}")
    cam = Cam(semi_major=a, semi_minor=b, **kw)
    for req in ("mass", "inertia", "cg_distance", "length", "width"):
        need(f"follower.{req}")
    follower = Follower(**pick("follower", Follower)[1])
    for req in ("stiffness", "free_length", "attachment_x", "ground_depth"):
        need(f"spring.{req}")
    spring = Spring(**pick("spring", Spring)[1])
    contact = Contact(**pick("contact", Contact)[1])
    friction = Friction(**pick("friction", Friction)[1])
    motion = Motion(**pick("motion", Motion)[1])
    gravity = v.get("environment.gravity", 9.81)
    return System(cam=cam, follower=follower, spring=spring, contact=contact, friction=friction,
                  motion=motion, gravity=gravity, name=name, citation=citation)


def list_presets() -> list[str]:
    """Names of the bundled presets."""
    folder = resources.files("camdyn.params.presets")
    return sorted(p.name[:-5] for p in folder.iterdir() if p.name.endswith(".toml"))


def preset_text(name: str) -> str:
    """The TOML text of a bundled preset."""
    if name not in list_presets():
        close = difflib.get_close_matches(name, list_presets(), n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise PresetError(f"no preset named {name!r}{hint} (available: {', '.join(list_presets())})")
    return resources.files("camdyn.params.presets").joinpath(f"{name}.toml").read_text()


def read_table(source: str | Path) -> tuple[dict, str, str]:
    """Read a preset name or TOML file path; return (dotted values, name, citation)."""
    path = Path(str(source))
    if str(source) in list_presets():
        text, name = preset_text(str(source)), str(source)
    elif path.suffix == ".toml" or path.exists():
        if not path.is_file():
            raise PresetError(f"configuration file {str(source)!r} does not exist")
        text, name = path.read_text(), path.stem
    else:
        preset_text(str(source))  # raises a PresetError with suggestions
        raise AssertionError("unreachable")
    try:
        table = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise PresetError(f"{source}: not valid TOML ({exc})") from None
    flat = flatten(table)
    meta_name = flat.get("preset.name", name)
    citation = flat.get("preset.citation", "")
    return flat, str(meta_name), str(citation)


def system_from_toml(text: str) -> System:
    """Build a system from TOML text (as written by :func:`system_to_toml`)."""
    try:
        flat = flatten(tomllib.loads(text))
    except tomllib.TOMLDecodeError as exc:
        raise PresetError(f"system TOML is not valid ({exc})") from None
    return build_system(flat, name=str(flat.get("preset.name", "custom")),
                        citation=str(flat.get("preset.citation", "")))


def parse_assignments(assignments: list[str] | None) -> dict:
    """Parse ``KEY=VALUE`` strings from the command line."""
    out = {}
    for item in assignments or []:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise ParameterError(f"--set expects KEY=VALUE, got {item!r}")
        out[key.strip()] = value.strip()
    return out


def load_system(source: str | Path, overrides: dict | None = None) -> System:
    """Load a preset or TOML file, apply dotted-key overrides, and validate.

    Parameters
    ----------
    source : str or Path
        Preset name (see :func:`list_presets`) or path to a TOML file.
    overrides : dict, optional
        Dotted key -> value with unit as text, e.g. ``{"cam.runout": "3.5 mm"}``.
    """
    flat, name, citation = read_table(source)
    overrides = dict(overrides or {})
    for key in overrides:
        if key not in SCHEMA:
            raise _unknown(key)
    if ("cam.semi_major" in overrides or "cam.semi_minor" in overrides) and "cam.radius" in flat:
        radius = flat.pop("cam.radius")  # a circle preset turned elliptic: start from a = b = rc
        flat.setdefault("cam.semi_major", radius)
        flat.setdefault("cam.semi_minor", radius)
    if "cam.radius" in overrides:
        flat.pop("cam.semi_major", None)
        flat.pop("cam.semi_minor", None)
    flat.update(overrides)
    return build_system(flat, name=name, citation=citation)


def system_to_toml(system: System) -> str:
    """Write a system as TOML text with units, readable by :func:`load_system`."""
    s = system
    lines = ["[preset]", f"name = {json.dumps(s.name)}", f"citation = {json.dumps(s.citation)}", ""]

    def q(value, unit):
        return f'"{value!r} {unit}"'

    lines += ["[cam]"]
    if s.cam.is_circle:
        lines.append(f"radius = {q(s.cam.semi_major, 'm')}")
    else:
        lines += [f"semi_major = {q(s.cam.semi_major, 'm')}", f"semi_minor = {q(s.cam.semi_minor, 'm')}"]
    lines += [f"runout = {q(s.cam.runout, 'm')}", f"pivot_x = {q(s.cam.pivot_x, 'm')}",
              f"pivot_y = {q(s.cam.pivot_y, 'm')}", f"youngs_modulus = {q(s.cam.youngs_modulus, 'Pa')}",
              f"poisson_ratio = {s.cam.poisson_ratio!r}", "", "[follower]"]
    f = s.follower
    lines += [f"mass = {q(f.mass, 'kg')}", f"inertia = {q(f.inertia, 'kg*m^2')}",
              f"cg_distance = {q(f.cg_distance, 'm')}", f"length = {q(f.length, 'm')}",
              f"width = {q(f.width, 'm')}", f"pin_radius = {q(f.pin_radius, 'm')}",
              f"youngs_modulus = {q(f.youngs_modulus, 'Pa')}", f"poisson_ratio = {f.poisson_ratio!r}",
              f"accelerometer_distance = {q(f.accelerometer_distance, 'm')}",
              "", "[spring]"]
    sp = s.spring
    lines += [f"stiffness = {q(sp.stiffness, 'N/m')}", f"free_length = {q(sp.free_length, 'm')}",
              f"attachment_x = {q(sp.attachment_x, 'm')}", f"ground_depth = {q(sp.ground_depth, 'm')}",
              f"tilt = {q(sp.tilt, 'rad')}", "", "[contact]"]
    c = s.contact
    lines += [f'kind = "{c.kind}"', f"length = {q(c.length, 'm')}", f'damping = "{c.damping}"',
              f"damping_ratio = {c.damping_ratio!r}", f"exponent = {c.exponent!r}",
              f"beta = {q(c.beta, beta_unit(c.damping, c.exponent))}",
              f"restitution = {c.restitution!r}", f"reference_velocity = {q(c.reference_velocity, 'm/s')}",
              f"clip_adhesion = {'true' if c.clip_adhesion else 'false'}", "", "[friction]"]
    fr = s.friction
    lines += [f'law = "{fr.law}"', f"coefficient = {fr.coefficient!r}",
              f"smoothing = {q(fr.smoothing, 's/m')}", "", "[motion]"]
    m = s.motion
    lines += [f'kind = "{m.kind}"', f"speed = {q(m.speed, 'Hz')}", f"amplitude = {q(m.amplitude, 'rad')}",
              f"frequency = {q(m.frequency, 'Hz')}", f"direction = {m.direction}",
              f'zero_state = "{m.zero_state}"']
    if m.initial_angle is not None:
        lines.append(f"initial_angle = {q(m.initial_angle, 'rad')}")
    lines += ["", "[environment]", f"gravity = {q(s.gravity, 'm/s^2')}", ""]
    if not all(math.isfinite(x) for x in (s.gravity,)):
        raise ParameterError("cannot write a non-finite parameter")
    return "\n".join(lines)
