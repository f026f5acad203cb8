"""Configuration files and presets: TOML with units written as text.

A configuration is a TOML file whose tables are parameter groups and whose values
are quantities with units, for example::

    [cam]
    radius = "17.5 mm"
    runout = "3.5 mm"

Every parameter has a dotted key (``cam.runout``) listed in :data:`SCHEMA`, with the
unit it is stored in (SI). The keys, units and meanings are declared once, on the fields
of the dataclasses of :mod:`camdyn.params.system` (see :mod:`camdyn.params.schema`);
:data:`SCHEMA`, :func:`build_system` and :func:`system_to_toml` are derived from them.
Presets are such files shipped in ``camdyn/params/presets``.

A ``[profile]`` table (:data:`PROFILE_KEYS`, a translating follower's profile keys)
replaces the ellipse by a cam profile: :func:`read_system` returns its keys in SI units
beside the system, and :func:`camdyn.io.system_config.load_system` builds the profile
(this layer knows no cam model); :func:`load_system`, :func:`system_from_toml` and
:func:`system_to_toml` handle the ellipse only and refuse a profile.
"""

from __future__ import annotations

import difflib
import json
import math
import tomllib
from importlib import resources
from pathlib import Path

from camdyn.errors import ParameterError, PresetError, UnitError, UnknownKeyError
from camdyn.params.catalog import preset_kind, preset_names, presets_of_kind, resolve, unknown_preset
from camdyn.params.laws import lookup
from camdyn.params.profile_table import profile_spec
from camdyn.params.profiles import SCHEMA as PROFILE_SCHEMA
from camdyn.params.profiles import TranslatingSpec, list_translating_presets
from camdyn.params.schema import Parameter, groups, parameter_index, parameters
from camdyn.params.system import System
from camdyn.params.toml_text import MAX_TOML_CHARS, MAX_TOML_DEPTH, flatten, loads_toml, read_toml_text
from camdyn.params.units import parse_quantity, parse_speed

__all__ = [
    "SCHEMA", "PARAMETERS", "RADIUS_KEY", "list_presets", "preset_text", "load_system", "build_system", "flatten",
    "beta_unit", "convert_value", "unknown_key_error", "read_table", "system_from_toml", "system_to_toml",
    "parse_assignments", "PROFILE_KEYS", "read_system", "loads_toml", "MAX_TOML_DEPTH", "MAX_TOML_CHARS",
]

#: Every parameter of a :class:`~camdyn.params.system.System`, in the dataclasses' order.
PARAMETERS: tuple[Parameter, ...] = parameters(System)
_BY_KEY = parameter_index(System)
#: Shorthand key of a circular cam: sets both ``cam.semi_major`` and ``cam.semi_minor``.
RADIUS_KEY = "cam.radius"
#: Dotted key -> (unit of the stored SI value, or a kind of :data:`camdyn.params.schema.KINDS`,
#: description).
SCHEMA: dict[str, tuple[str, str]] = {
    RADIUS_KEY: ("m", "radius rc of a circular cam (sets both semi-axes)"),
    **{p.key: (p.unit, p.meaning) for p in PARAMETERS},
}
_META_KEYS = {"preset.name", "preset.citation", "preset.description", "preset.provenance"}
#: Keys of the ``[profile]`` table: a cam profile made for a flat face in place of the
#: ellipse (:attr:`camdyn.params.system.System.profile`), as a translating follower's.
PROFILE_KEYS = tuple(key for key in PROFILE_SCHEMA if key.startswith("profile.")) + ("profile.face",)
_PROFILE_REFUSED = ("the [profile] table (a cam profile in place of the ellipse) is read by camdyn.load_system "
                    "and 'camdyn simulate', which build the profile; this reader builds the ellipse only")


def beta_unit(law: str, exponent: float) -> str:
    """Unit of ``contact.beta`` [pint text] for a damping law (name or alias) and the
    power-law exponent ``n`` = ``exponent`` [-] (docs/model.md §3.4; the law's row of
    :data:`camdyn.params.laws.TABLE`)."""
    return lookup(law).unit_of_beta(exponent)


def read_toml_file(source: str | Path) -> dict:
    """The flattened tables (:func:`flatten`) of the TOML file ``source``, or a
    :class:`PresetError` that says why it cannot be read."""
    path = Path(str(source))
    try:
        return flatten(loads_toml(read_toml_text(path, source), source))
    except FileNotFoundError:
        raise PresetError(f"configuration file {str(source)!r} does not exist") from None
    except OSError as exc:
        raise PresetError(f"{source}: cannot be read ({exc.strerror or exc})") from None
    except UnicodeDecodeError:
        raise PresetError(f"{source}: not UTF-8 text; a configuration file is TOML, saved as UTF-8") from None
    except tomllib.TOMLDecodeError as exc:
        raise PresetError(f"{source}: not valid TOML ({exc})") from None


def unknown_key_error(key: str) -> UnknownKeyError:
    """The error for a dotted ``key`` that is not in :data:`SCHEMA`, suggesting close keys."""
    close = difflib.get_close_matches(key, list(SCHEMA), n=3)
    hint = f"; did you mean {', '.join(close)}?" if close else "; run 'camdyn presets keys' for the list"
    return UnknownKeyError(f"unknown parameter {key!r}{hint}")


def convert_value(key: str, raw, values: dict) -> object:
    """Convert the raw configuration value of ``key`` to its stored form (SI for quantities).

    Parameters
    ----------
    key : str
        Dotted key of :data:`SCHEMA`.
    raw : str, float, int or bool
        Text with a unit (``"17.5 mm"``), a dimensionless number, or a value of a kind
        (text, true/false, integer).
    values : dict
        All raw values being read: the unit of ``contact.beta`` depends on
        ``contact.damping`` and ``contact.exponent`` there.
    """
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
        if isinstance(raw, bool) or (isinstance(raw, float) and not raw.is_integer()):
            raise ParameterError(f"{key}: expected a whole number, got {raw!r}")
        try:
            return int(raw)
        except (TypeError, ValueError, OverflowError):
            raise ParameterError(f"{key}: expected a whole number, got {raw!r}") from None
    if unit == "speed":
        return parse_speed(raw, key)
    if unit == "law":
        law = lookup(str(values.get("contact.damping", _BY_KEY["contact.damping"].default)).strip())
        exponent = values.get("contact.exponent", _BY_KEY["contact.exponent"].default)
        if isinstance(exponent, str):
            exponent = parse_quantity(exponent, "", "contact.exponent")
        if not (isinstance(exponent, (int, float)) and math.isfinite(exponent)):
            raise ParameterError(f"contact.exponent must be a finite number, got {exponent!r}")
        return parse_quantity(raw, law.unit_of_beta(float(exponent)), key)
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
    name, citation : str
        The system's name and the source of its values.
    """
    values = {k: v for k, v in values.items() if k not in _META_KEYS}
    for key in values:
        if key not in SCHEMA:
            raise unknown_key_error(key)
    v = {key: convert_value(key, raw, values) for key, raw in values.items()}
    if RADIUS_KEY in v:
        if "cam.semi_major" in v or "cam.semi_minor" in v:
            raise ParameterError("give either cam.radius or cam.semi_major/cam.semi_minor, not both")
        v["cam.semi_major"] = v["cam.semi_minor"] = v.pop(RADIUS_KEY)
    built = {table: cls(**_arguments(table, v)) for table, cls in groups(System).items()}
    return System(**built, **_arguments("", v), name=name, citation=citation)


def _arguments(table: str, values: dict) -> dict:
    """Keyword arguments of the dataclass of the group ``table`` (``""``: the system's own
    parameters) from converted ``values``; refuses a missing required parameter."""
    kwargs = {}
    for param in PARAMETERS:
        if (param.path[0] if len(param.path) == 2 else "") != table:
            continue
        if param.key in values:
            kwargs[param.name] = values[param.key]
        elif param.required:
            raise ParameterError(f"missing parameter {param.key!r} ({param.meaning})")
    return kwargs


def list_presets() -> list[str]:
    """Names of the bundled presets of the thesis's rocking flat-faced follower on its
    ellipse (every preset, of every kind: :func:`camdyn.params.catalog.preset_names`)."""
    return presets_of_kind("cam-follower")


def preset_text(name: str) -> str:
    """The TOML text of a bundled preset."""
    if name not in list_presets():
        close = difflib.get_close_matches(name, list_presets(), n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise PresetError(f"no preset named {name!r}{hint} (available: {', '.join(list_presets())})")
    return resources.files("camdyn.params.presets").joinpath(f"{name}.toml").read_text()


def _exists(path: Path) -> bool:
    """Whether ``path`` names something; False for a name the system cannot look up
    (too long, a NUL byte)."""
    try:
        return path.exists()
    except (OSError, ValueError):
        return False


def read_table(source: str | Path) -> tuple[dict, str, str]:
    """Read a preset name or TOML file path; return (dotted values, name, citation)."""
    if str(source) in list_translating_presets():
        raise PresetError(f"{str(source)!r} is a preset of the translating follower, not of the rocking one; "
                          "run it with 'camdyn simulate' or load it with camdyn.io.lift_table.load_translating")
    if str(source) in preset_names() and preset_kind(str(source)) not in ("cam-follower", "cam-follower, profile"):
        raise PresetError(f"{str(source)!r} is a preset of the kind {preset_kind(str(source))!r}, not of the "
                          "rocking flat-faced follower of the thesis that this entry takes; 'camdyn simulate' "
                          "takes every kind")
    source = resolve(source)
    path = Path(str(source))
    if str(source) in list_presets():
        text, name = preset_text(str(source)), str(source)
    elif path.suffix == ".toml" or _exists(path):
        if not path.is_file():
            raise PresetError(f"configuration file {str(source)!r} does not exist")
        try:
            text, name = read_toml_text(path, source), path.stem
        except UnicodeDecodeError as exc:
            raise PresetError(f"{source}: not UTF-8 text (byte {exc.object[exc.start]:#04x} at offset "
                              f"{exc.start}); a configuration file is TOML, saved as UTF-8") from None
        except OSError as exc:
            raise PresetError(f"{source}: cannot be read ({exc.strerror or exc})") from None
    else:
        raise unknown_preset(str(source))
    try:
        table = loads_toml(text, source)
    except tomllib.TOMLDecodeError as exc:
        raise PresetError(f"{source}: not valid TOML ({exc})") from None
    other = _other_family(table)
    if other:
        raise ParameterError(f"{source} is {other}, not the rocking flat-faced follower of the thesis that this "
                             "entry takes; camdyn simulate takes every family, and docs/capabilities.md lists which "
                             "commands take which")
    flat = flatten(table)
    meta_name = flat.get("preset.name", name)
    citation = flat.get("preset.citation", "")
    return flat, str(meta_name), str(citation)


def _other_family(table: dict) -> str:
    """What a configuration's tables say it is when it is not the rocking flat-faced
    follower (a mechanism, a follower of another kind), or empty."""
    if isinstance(table.get("mechanism"), dict):
        return "a mechanism's configuration (a [mechanism] table)"
    follower = table.get("follower")
    kind = follower.get("kind") if isinstance(follower, dict) else None
    return f"a configuration of the {kind} follower ([follower] kind = {kind!r})" if isinstance(kind, str) else ""


def system_from_toml(text: str) -> System:
    """Build a system from TOML text (as written by :func:`system_to_toml`); a
    ``[profile]`` table is refused (:func:`read_system` reads it)."""
    try:
        flat = flatten(loads_toml(text, "system TOML"))
    except tomllib.TOMLDecodeError as exc:
        raise PresetError(f"system TOML is not valid ({exc})") from None
    if any(key.startswith("profile.") for key in flat):
        raise ParameterError(_PROFILE_REFUSED)
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

    A file with a ``[profile]`` table is refused here: :func:`camdyn.load_system`
    (:func:`camdyn.io.system_config.load_system`) builds its profile.

    Parameters
    ----------
    source : str or Path
        Preset name (see :func:`list_presets`) or path to a TOML file.
    overrides : dict, optional
        Dotted key -> value with unit as text, e.g. ``{"cam.runout": "3.5 mm"}``.
    """
    system, profile = read_system(source, overrides)
    if profile is not None:
        raise ParameterError(f"{source}: {_PROFILE_REFUSED}")
    return system


def read_system(source: str | Path, overrides: dict | None = None) -> tuple[System, TranslatingSpec | None]:
    """Read a preset or TOML file with dotted-key overrides: the system with its ellipse,
    and the ``[profile]`` table's keys in SI units, when it has one.

    Parameters
    ----------
    source : str or Path
        Preset name (see :func:`list_presets`) or path to a TOML file.
    overrides : dict, optional
        Dotted key -> value with unit as text, e.g. ``{"profile.base_radius": "16 mm"}``.

    Returns
    -------
    system : System
        Built from every key but the profile's (``profile`` is None).
    profile : TranslatingSpec or None
        The profile's keys, checked key by key as a translating follower's
        (:func:`camdyn.params.profile_table.profile_spec`); a relative ``profile.file`` is
        taken from the TOML file's folder. None without a ``[profile]`` table.
    """
    flat, name, citation = read_table(source)
    source = resolve(source)
    if overrides is not None and not isinstance(overrides, dict):
        raise ParameterError(f"overrides must be a dict of dotted key -> value with its unit "
                             f"({{\"cam.runout\": \"3.5 mm\"}}), got {type(overrides).__name__} {overrides!r:.60}")
    overrides = dict(overrides or {})
    for key in overrides:
        if not isinstance(key, str):
            raise unknown_key_error(str(key))
        if key not in SCHEMA and not key.startswith("profile."):
            raise unknown_key_error(key)
    if ("cam.semi_major" in overrides or "cam.semi_minor" in overrides) and RADIUS_KEY in flat:
        radius = flat.pop(RADIUS_KEY)  # a circle preset turned elliptic: start from a = b = rc
        flat.setdefault("cam.semi_major", radius)
        flat.setdefault("cam.semi_minor", radius)
    if RADIUS_KEY in overrides:
        flat.pop("cam.semi_major", None)
        flat.pop("cam.semi_minor", None)
    flat.update(overrides)
    table = {key: value for key, value in flat.items() if key.startswith("profile.")}
    system = build_system({key: value for key, value in flat.items() if key not in table}, name=name,
                          citation=citation)
    if not table:
        return system, None
    return system, _profile(table, name, source)


def _profile(table: dict, name: str, source: str | Path) -> TranslatingSpec:
    """The ``[profile]`` keys of a rocking flat-faced follower's file, in SI units."""
    for key in table:
        if key not in PROFILE_KEYS:
            close = difflib.get_close_matches(key, list(PROFILE_KEYS), n=3)
            hint = f"; did you mean {', '.join(close)}?" if close else f"; known keys: {', '.join(PROFILE_KEYS)}"
            raise UnknownKeyError(f"unknown key {key!r} in the [profile] table of the rocking flat-faced "
                                  f"follower{hint}")
    face = table.get("profile.face", "flat")
    if face != "flat":
        raise ParameterError(f"profile.face {face!r}: the rocking follower of this configuration has a flat face "
                             "and rides a profile made for a flat face only (profile.face = \"flat\"); a roller or "
                             "knife edge on a rocking arm is configured with [follower] kind = \"rocking\"")
    path = Path(str(source))
    folder = path.resolve().parent if str(source) not in list_presets() and path.is_file() else None
    return profile_spec(table, "flat", 0.0, name, folder)


def system_to_toml(system: System, ignore_profile: bool = False) -> str:
    """Write a system as TOML text with units, readable by :func:`load_system`.

    Every parameter of :data:`PARAMETERS` is written in its group's table, in the unit
    its field declares; a cam with equal semi-axes is written with ``radius``, an unset
    optional parameter is left out.

    Parameters
    ----------
    system : System
        The system to write.
    ignore_profile : bool
        Write the ellipse's keys of a system whose cam is a profile (as a result's
        parameters do, beside its ``cam_profile`` attribute). Without it such a system is
        refused: a profile keeps its packed table, not the ``[profile]`` keys it was read
        from, so it cannot be written back.
    """
    if system.profile is not None and not ignore_profile:
        raise ParameterError(f"system {system.name!r}: its cam is a profile, which cannot be written back as TOML "
                             "(a profile keeps its packed table, not the [profile] keys it was read from); write "
                             "the [profile] table by hand, or keep the TOML file it was read from")
    lines = ["[preset]", f"name = {_text(system.name)}", f"citation = {_text(system.citation)}"]
    table = ""
    for param in PARAMETERS:
        group = param.key.partition(".")[0]
        if group != table:
            lines += ["", f"[{group}]"]
            table = group
        lines += _written(param, system)
    lines.append("")
    return "\n".join(lines)


def _written(param: Parameter, system: System) -> list[str]:
    """The TOML lines of one parameter (none, one, or ``radius`` for both semi-axes)."""
    value = param.getter(system)
    # radius only for exactly equal semi-axes (``Cam.is_circle`` allows rounding): it reads back as both
    if param.key in ("cam.semi_major", "cam.semi_minor") and system.cam.semi_major == system.cam.semi_minor:
        return [f"radius = {_quantity(value, 'm')}"] if param.key == "cam.semi_major" else []
    if value is None and param.optional:
        return []
    if param.unit == "str":
        text = _text(value)
    elif param.unit == "bool":
        text = "true" if value else "false"
    elif param.unit == "int":
        text = f"{value}"
    elif param.unit == "law":
        text = _quantity(value, system.contact.law.unit_of_beta(system.contact.exponent))
    elif param.unit == "":
        text = repr(value)
    else:
        text = _quantity(value, param.written)
    return [f"{param.name} = {text}"]


def _text(value: str) -> str:
    """``value`` as a TOML basic string: JSON's escapes, except that a character beyond the
    Basic Multilingual Plane is written ``\\UXXXXXXXX`` (TOML has no surrogate pairs)."""
    return '"' + "".join(json.dumps(c)[1:-1] if ord(c) <= 0xFFFF else f"\\U{ord(c):08X}" for c in value) + '"'


def _quantity(value: float, unit: str) -> str:
    """A value [unit] as quoted TOML text that reads back exactly."""
    return f'"{value!r} {unit}"'
