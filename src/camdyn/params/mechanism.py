"""Configuration files of the mechanisms with more degrees of freedom: TOML with units,
a ``[mechanism]`` table naming the kind and the cam-follower it is built on::

    [mechanism]
    kind = "two-followers"            # or "driven-cam", "flexible-pivot"
    system = "sundar2014-friction"    # a preset, or a system TOML file beside this one

    [system.environment]              # changes to that system, in its own keys
    gravity = "0 m/s^2"

    [drive]                           # the cam shaft (driven-cam, two-followers)
    shaft_inertia = "2e-4 kg*m^2"
    kind = "constant"
    torque = "0.1 N*m"
    bearing_viscous = "2e-4 N*m*s/rad"

    [second]                          # the second follower (two-followers)
    placement = "180 deg"

    [second.system.spring]            # follower 2's changes to follower 1's system
    stiffness = "3200 N/m"

    [pivot]                           # the bearing of the follower's pivot (flexible-pivot)
    stiffness = "2e7 N/m"
    damping_ratio = 0.05

Every key is declared once in :data:`SCHEMA`, with its unit, default, meaning, range and
the kinds (and drive kinds) it belongs to; :func:`read_mechanism` refuses, by name, a key
that is unknown, out of range or meaningless for the kind, before any work, and returns a
:class:`MechanismSpec` of SI values. The system's own keys under ``[system]`` are checked
by the system's reader (:func:`camdyn.params.config.build_system`); the drive's and the
bearing's physical checks are those of the simulation's dataclasses and functions, which
:func:`camdyn.io.mechanism_config.load_mechanism` calls when it builds the mechanism.
"""

from __future__ import annotations

import difflib
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from camdyn.errors import ParameterError, UnitError, UnknownKeyError
from camdyn.params.catalog import resolve
from camdyn.params.config import loads_toml, read_toml_file
from camdyn.params.toml_text import read_toml_text
from camdyn.params.units import parse_quantity, parse_speed

__all__ = ["KINDS", "DRIVE_KINDS", "SCHEMA", "MechanismSpec", "read_mechanism", "mechanism_spec_from_table",
           "is_mechanism", "ANGULAR_SPEED"]

#: Mechanism kinds and the tables each takes besides ``[mechanism]`` and ``[system]``.
KINDS: dict[str, tuple[str, ...]] = {
    "driven-cam": ("drive",),
    "flexible-pivot": ("pivot",),
    "two-followers": ("drive", "second"),
}
#: Drive kinds and the drive keys each uses besides the shaft's and the bearing's.
DRIVE_KINDS: dict[str, tuple[str, ...]] = {
    "constant": ("drive.torque",),
    "motor": ("drive.stall_torque", "drive.free_speed"),
    "controller": ("drive.torque", "drive.proportional", "drive.integral", "drive.target_speed"),
    "prescribed": (),
}
#: The unit of an angular speed key: Hz and rpm are revolutions, rad/s radians (pint
#: takes the radian as dimensionless, so these keys are read by :func:`angular_speed`).
ANGULAR_SPEED = "rad/s (angular speed)"
REQUIRED = object()


@dataclass(frozen=True)
class Key:
    """One key of a mechanism file: ``unit`` of its SI value (``"str"`` for text,
    :data:`ANGULAR_SPEED`, ``"list"`` for one or two dimensionless numbers), ``default``
    (:data:`REQUIRED`, or None for unset), ``meaning``, ``bound``: ``"positive"``,
    ``"non-negative"`` or ``""`` (any finite value)."""

    unit: str
    default: object
    meaning: str
    bound: str = ""


#: Dotted key -> :class:`Key`. The ``[system]`` table's keys are the system's own.
SCHEMA: dict[str, Key] = {
    "mechanism.kind": Key("str", REQUIRED, "'driven-cam', 'flexible-pivot' or 'two-followers'"),
    "mechanism.system": Key("str", None, "the cam-follower: a preset name or a system TOML file (relative to "
                                         "this file); without it the [system] tables give the whole system"),
    "drive.shaft_inertia": Key("kg*m**2", REQUIRED, "inertia J of the cam and its shaft about the cam pivot",
                               "positive"),
    "drive.kind": Key("str", "constant", "'constant' (a torque), 'motor' (a DC motor's torque-speed line), "
                                         "'controller' (a PI speed controller) or 'prescribed' (the cam held at "
                                         "its starting speed whatever the load; the shaft inertia does not "
                                         "enter)"),
    "drive.torque": Key("N*m", 0.0, "constant drive torque T0, or the controller's feed-forward"),
    "drive.stall_torque": Key("N*m", 0.0, "motor torque at rest T_stall"),
    "drive.free_speed": Key(ANGULAR_SPEED, REQUIRED, "motor's no-load speed omega_free"),
    "drive.proportional": Key("N*m*s", 0.0, "controller's proportional gain Kp [N m s/rad]"),
    "drive.integral": Key("N*m", 0.0, "controller's integral gain Ki [N m/rad]"),
    "drive.target_speed": Key(ANGULAR_SPEED, REQUIRED, "controller's speed set point omega_ref"),
    "drive.bearing_viscous": Key("N*m*s", 0.0, "bearing's viscous coefficient c_b [N m s/rad]", "non-negative"),
    "drive.bearing_coulomb": Key("N*m", 0.0, "bearing's Coulomb torque T_c", "non-negative"),
    "drive.bearing_speed": Key(ANGULAR_SPEED, 1.0, "speed omega_b over which the Coulomb torque is smoothed",
                               "positive"),
    "drive.initial_speed": Key(ANGULAR_SPEED, None, "starting cam speed; default the system's motion.speed"),
    "pivot.stiffness": Key("N/m", REQUIRED, "bearing stiffness kp, the same in x and y", "positive"),
    "pivot.damping": Key("N*s/m", None, "bearing damping cp, the same in x and y", "non-negative"),
    "pivot.damping_ratio": Key("", None, "bearing damping as a ratio zeta of the follower mass on the "
                                         "bearing: cp = 2 zeta sqrt(kp m)", "non-negative"),
    "second.placement": Key("rad", math.pi, "angle of follower 2's pivot turned counter-clockwise about the "
                                            "cam pivot from follower 1's"),
    "second.static_friction": Key("list", None, "static friction coefficients mu_s of the followers (one for "
                                                "both, or a list of two); given, the contacts stick",
                                  "non-negative"),
}
_META_KEYS = ("preset.name", "preset.citation", "preset.description", "preset.provenance")
#: Keys under their own table only (the drive's by drive kind, the rest by mechanism kind).
_SHAFT_KEYS = ("drive.shaft_inertia", "drive.kind", "drive.bearing_viscous", "drive.bearing_coulomb",
               "drive.bearing_speed", "drive.initial_speed")


@dataclass(frozen=True)
class MechanismSpec:
    """A mechanism's configuration in SI units, checked key by key.

    Attributes
    ----------
    name, citation, description : str
        The configuration's name, the source of its values and a one-line description.
    kind : str
        A key of :data:`KINDS`.
    system : str or None
        The cam-follower's preset name or TOML file (resolved against the file's folder);
        None when ``system_keys`` give the whole system.
    system_keys : dict
        The ``[system]`` table's dotted keys (``"cam.runout"``) and raw values, applied to
        ``system`` (or building it).
    second_keys : dict
        The ``[second.system]`` table's dotted keys and raw values: follower 2 is
        follower 1's system with these changes too (two followers).
    drive : dict or None
        Keyword arguments of :class:`camdyn.simulation.mechanisms.CamDrive` [SI units];
        None for the flexible pivot.
    initial_speed : float or None
        Starting cam speed [rad/s] of a driven shaft; None for the system's motion.
    pivot_stiffness : float or None
        Bearing stiffness [N/m] (flexible pivot).
    pivot_damping : float or None
        Bearing damping [N s/m]; None when given as ``pivot_damping_ratio``.
    pivot_damping_ratio : float or None
        Bearing damping ratio [-].
    placement : float
        Follower 2's placement [rad] (two followers).
    static_friction : float, (float, float) or None
        The static friction coefficient of both followers, or one each [-] (two
        followers).
    """

    name: str
    kind: str
    system: str | None
    system_keys: dict = field(default_factory=dict)
    second_keys: dict = field(default_factory=dict)
    citation: str = ""
    description: str = ""
    drive: dict | None = None
    initial_speed: float | None = None
    pivot_stiffness: float | None = None
    pivot_damping: float | None = None
    pivot_damping_ratio: float | None = None
    placement: float = math.pi
    static_friction: float | tuple | None = None


def angular_speed(raw, key: str) -> float:
    """An angular speed [rad/s] from text with its unit: ``"72.6 rad/s"`` as written,
    ``"11.55 Hz"`` and ``"693 rpm"`` as revolutions (``2 pi`` rad each)."""
    try:
        float(raw)
        bare = True
    except (TypeError, ValueError):
        bare = not isinstance(raw, str)
    if bare:
        raise UnitError(f"{key}: {raw!r} has no unit; write it as text with one, e.g. \"{raw} rad/s\" or "
                        f"\"{raw} Hz\"")
    if "rad" in raw:
        return parse_quantity(raw, "rad/s", key)
    return 2.0 * math.pi * parse_speed(raw, key)


def _number(key: str, raw, unit: str) -> float:
    if isinstance(raw, bool) or not isinstance(raw, (int, float, str)):
        raise ParameterError(f"{key}: expected a number with its unit, got {raw!r}")
    if unit == ANGULAR_SPEED:
        return angular_speed(raw, key)
    if isinstance(raw, (int, float)) and unit and float(raw) != 0.0:
        raise UnitError(f"{key}: {raw!r} has no unit; write it as text with one, e.g. \"{raw} {unit}\"")
    return parse_quantity(raw, unit, key) if isinstance(raw, str) else float(raw)


def _value(key: str, raw):
    """The SI value of ``key`` from its raw TOML value, in range, or a refusal naming it."""
    spec = SCHEMA[key]
    if spec.unit == "str":
        if not isinstance(raw, str) or not raw.strip():
            raise ParameterError(f"{key}: expected text, got {raw!r}")
        return raw.strip()
    values = raw if spec.unit == "list" and isinstance(raw, list) else [raw]
    if spec.unit == "list" and not 1 <= len(values) <= 2:
        raise ParameterError(f"{key}: expected one number or a list of two, got {raw!r}")
    numbers = [_number(key, item, "" if spec.unit == "list" else spec.unit) for item in values]
    for value in numbers:
        if not math.isfinite(value):
            raise ParameterError(f"{key} must be finite, got {raw!r}")
        if (spec.bound == "positive" and not value > 0.0) or (spec.bound == "non-negative" and value < 0.0):
            raise ParameterError(f"{key} must be {spec.bound}, got {raw!r}")
    return tuple(numbers) if len(numbers) == 2 else numbers[0]


def _check_keys(flat: dict) -> str:
    """Refuse unknown keys and keys of another kind; return the mechanism kind."""
    for key in flat:
        if key not in SCHEMA and not key.startswith(("system.", "second.system.")):
            close = difflib.get_close_matches(key, list(SCHEMA), n=3)
            hint = f"; did you mean {', '.join(close)}?" if close else f"; known keys: {', '.join(SCHEMA)}"
            raise UnknownKeyError(f"unknown key {key!r} in a mechanism configuration{hint}")
    kind = flat.get("mechanism.kind")
    if not isinstance(kind, str) or kind not in KINDS:
        raise ParameterError(f"mechanism.kind must be one of {', '.join(KINDS)}, got {kind!r}")
    tables = KINDS[kind]
    for key in flat:
        table = key.partition(".")[0]
        if table in ("drive", "pivot", "second") and table not in tables:
            raise UnknownKeyError(f"{key} is not a key of a {kind} mechanism: it takes the tables "
                                  f"{', '.join(f'[{t}]' for t in tables)} besides [mechanism] and [system]")
    if "drive" in tables:
        drive_kind = flat.get("drive.kind", SCHEMA["drive.kind"].default)
        if not isinstance(drive_kind, str) or drive_kind not in DRIVE_KINDS:
            raise ParameterError(f"drive.kind must be one of {', '.join(DRIVE_KINDS)}, got {drive_kind!r}")
        own = _SHAFT_KEYS + DRIVE_KINDS[drive_kind]
        for key in flat:
            if key.startswith("drive.") and key not in own:
                raise UnknownKeyError(f"{key} is not a key of the {drive_kind!r} drive (it takes "
                                      f"{', '.join(DRIVE_KINDS[drive_kind])} besides the shaft's and bearing's)")
    if "pivot.damping" in flat and "pivot.damping_ratio" in flat:
        raise ParameterError("give either pivot.damping or pivot.damping_ratio, not both")
    return kind


def _read(flat: dict, key: str):
    """The SI value of a key of the file, or its default; a missing required key is refused."""
    if key in flat:
        return _value(key, flat[key])
    default = SCHEMA[key].default
    if default is REQUIRED:
        raise ParameterError(f"missing key {key!r} ({SCHEMA[key].meaning})")
    return default


def mechanism_spec_from_table(flat: dict, name: str = "custom", folder: Path | None = None) -> MechanismSpec:
    """A :class:`MechanismSpec` from flattened TOML (dotted keys -> raw values); a
    relative ``mechanism.system`` file is taken from ``folder``."""
    meta = {key: str(flat[key]) for key in _META_KEYS if key in flat}
    flat = {key: value for key, value in flat.items() if key not in _META_KEYS}
    kind = _check_keys(flat)
    system = _read(flat, "mechanism.system")
    system_keys = {key[len("system."):]: value for key, value in flat.items() if key.startswith("system.")}
    if system is not None and folder is not None and Path(system).suffix == ".toml" \
            and not Path(system).is_absolute():
        system = str(folder / system)
    if system is None and not system_keys:
        raise ParameterError("mechanism.system: name the cam-follower (a preset or a system TOML file), or give "
                             "the whole system in [system] tables")
    out = dict(name=meta.get("preset.name", name), citation=meta.get("preset.citation", ""),
               description=meta.get("preset.description", ""), kind=kind, system=system, system_keys=system_keys)
    tables = KINDS[kind]
    if "drive" in tables:
        drive_kind = _read(flat, "drive.kind")
        keys = [key for key in _SHAFT_KEYS if key != "drive.initial_speed"] + list(DRIVE_KINDS[drive_kind])
        out["drive"] = {key.partition(".")[2]: _read(flat, key) for key in keys}
        out["initial_speed"] = _read(flat, "drive.initial_speed")
    if "pivot" in tables:
        out.update(pivot_stiffness=_read(flat, "pivot.stiffness"), pivot_damping=_read(flat, "pivot.damping"),
                   pivot_damping_ratio=_read(flat, "pivot.damping_ratio"))
        if out["pivot_damping"] is None and out["pivot_damping_ratio"] is None:
            raise ParameterError("missing key 'pivot.damping' (or 'pivot.damping_ratio'): the bearing's damping")
    if "second" in tables:
        out.update(placement=_read(flat, "second.placement"), static_friction=_read(flat, "second.static_friction"),
                   second_keys={key[len("second.system."):]: value for key, value in flat.items()
                                if key.startswith("second.system.")})
    return MechanismSpec(**out)


def _table(source: str | Path) -> dict:
    """The flattened TOML of a mechanism file, or a :class:`PresetError`."""
    return read_toml_file(source)


def read_mechanism(source: str | Path, overrides: dict | None = None) -> MechanismSpec:
    """Read a mechanism's TOML file, with dotted-key overrides.

    Parameters
    ----------
    source : str or Path
        The TOML file (with a ``[mechanism]`` table).
    overrides : dict, optional
        Dotted key -> value as text with its unit (``{"drive.torque": "0.2 N*m"}``,
        ``{"system.cam.runout": "2 mm"}``).

    Returns
    -------
    MechanismSpec
    """
    path = Path(str(resolve(source)))
    flat = _table(path)
    flat.update(overrides or {})
    try:
        return mechanism_spec_from_table(flat, name=path.stem, folder=path.resolve().parent)
    except (ParameterError, UnitError) as exc:
        raise type(exc)(f"{path.name}: {exc}") from None


def is_mechanism(source: str | Path) -> bool:
    """Whether ``source`` is a readable TOML file (or a preset) with a ``[mechanism]`` table."""
    path = Path(str(resolve(source)))
    try:
        return path.is_file() and isinstance(loads_toml(read_toml_text(path, source), source).get("mechanism"),
                                             dict)
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return False
