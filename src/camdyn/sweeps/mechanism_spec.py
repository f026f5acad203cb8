"""Sweeps over a mechanism (:mod:`camdyn.params.mechanism`): the keys a ``[[vary]]`` table
may name, their SI values, the checks of every value before any work, and each point's
:class:`~camdyn.io.mechanism_config.Mechanism`.

A sweep is over a mechanism when its ``[system] source`` is a TOML file with a
``[mechanism]`` table. Its varied keys are the keys a mechanism file's overrides take
(:func:`camdyn.io.mechanism_config.load_mechanism`):

- a key of the mechanism's own tables: ``drive.torque`` [N m], ``drive.free_speed``
  [rad/s], ``pivot.stiffness`` [N/m], ``pivot.damping_ratio`` [-], ``second.placement``
  [rad], ...;
- a key of its cam-follower, prefixed ``system.`` (``system.cam.runout`` [m],
  ``system.motion.speed`` [Hz], the starting speed of a driven cam), or of follower 2's
  changes, prefixed ``second.system.`` (two followers).

Each point's mechanism is the file with the ``[system] set`` changes and the point's
values, every value written back as text in its SI unit (``"20000000.0 N/m"``), so that
:func:`point_mechanism` builds the same mechanism a direct
``load_mechanism(file, {key: text})`` builds.
"""

from __future__ import annotations

import difflib
import math

from camdyn.errors import CamdynError, ParameterError, UnknownKeyError
from camdyn.params import mechanism as schema
from camdyn.params.config import SCHEMA as SYSTEM_SCHEMA
from camdyn.params.config import convert_value

__all__ = ["MECHANISM_METRICS", "KIND_METRICS", "key_unit", "override_text", "point_mechanism", "check_mechanism",
           "base_mechanism", "check_values", "drive_sets_speed"]

#: metric name -> what it adds to the result of a sweep over a mechanism
MECHANISM_METRICS = {
    "impacts": "impacts (rises of the sampled contact flag, and contacts between two samples found by the cam's "
               "work on the follower) per cam revolution, per follower [1/rev]",
    "max_force": "largest sampled normal contact force, per follower [N]",
    "poincare": "follower angle [rad] and angular velocity [rad/s] once per cam revolution (by cam angle), "
                "per follower",
    "regime": "contact kept / sliding reversal / periodic impacts / irregular impacts, and the Poincare period",
    "speed_fluctuation": "the cam speed's coefficient of fluctuation (max - min) / mean [-] and its mean [rad/s]",
    "bearing_force": "largest sampled force of the flexible pivot's bearing on the follower [N]",
    "residual": "rms and peak-to-peak of alpha - alpha_rigid (rigid contact on a rigid pivot at the sample's cam "
                "angle), per follower [rad]",
    "spectrum": "cam-harmonic amplitudes of alpha_ddot [rad/s^2] and the largest spectral peak, per follower, as "
                "camdyn spectrum finds them",
    "stick_slip": "sticks, slips (break-aways) and sprags of the event log per cam revolution, per follower [1/rev]",
}
#: the metrics of each mechanism kind (its default list)
KIND_METRICS = {
    "driven-cam": ("impacts", "max_force", "poincare", "regime", "speed_fluctuation", "residual", "spectrum"),
    "flexible-pivot": ("impacts", "max_force", "poincare", "regime", "bearing_force", "residual", "spectrum"),
    "two-followers": ("impacts", "max_force", "poincare", "regime", "speed_fluctuation", "residual", "spectrum",
                      "stick_slip"),
}
_PREFIXES = ("second.system.", "system.")


def key_unit(key: str) -> tuple[str, callable]:
    """The SI unit of a mechanism sweep's varied ``key`` and the function that converts a
    raw spec value (text with its unit, or a bare number) to it; a key that is unknown or
    not a quantity is refused by name."""
    for prefix in _PREFIXES:
        if key.startswith(prefix):
            inner = key[len(prefix):]
            if inner not in SYSTEM_SCHEMA:
                close = difflib.get_close_matches(inner, list(SYSTEM_SCHEMA), n=3)
                hint = f"; did you mean {', '.join(prefix + c for c in close)}?" if close else ""
                raise UnknownKeyError(f"sweep spec: unknown parameter {key!r} of the mechanism's cam-follower{hint}")
            unit, _ = SYSTEM_SCHEMA[inner]
            if unit in ("str", "bool", "int", "law"):
                raise ParameterError(f"sweep spec: {key} cannot be swept (only quantities with units can)")
            return ("Hz" if unit == "speed" else unit), _named(key, lambda raw: float(convert_value(inner, raw, {})))
    if key not in schema.SCHEMA:
        if key in SYSTEM_SCHEMA:
            raise UnknownKeyError(f"sweep spec: {key!r} is a key of the cam-follower: over a mechanism write it "
                                  f"system.{key}")
        close = difflib.get_close_matches(key, list(schema.SCHEMA), n=3)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise UnknownKeyError(f"sweep spec: unknown mechanism key {key!r}{hint}")
    unit = schema.SCHEMA[key].unit
    if unit in ("str", "list"):
        raise ParameterError(f"sweep spec: {key} cannot be swept (only quantities with units can)")
    unit = "rad/s" if unit == schema.ANGULAR_SPEED else unit
    return unit, _named(key, lambda raw: float(schema._value(key, raw)))


def _named(key: str, convert):
    """``convert`` with its refusals naming the ``[[vary]]`` key."""
    def named(raw):
        try:
            return convert(raw)
        except CamdynError as exc:
            raise type(exc)(f"sweep spec: [[vary]] {key}: {exc}") from None
    return named


def override_text(key: str, value: float):
    """The override of ``key`` at the SI ``value``: text with its SI unit (a bare number
    for a dimensionless key), as :func:`camdyn.io.mechanism_config.load_mechanism` takes it."""
    unit, _ = key_unit(key)
    return float(value) if unit in ("", "1") else f"{float(value)!r} {unit}"


def point_mechanism(source: str, overrides: dict, values: dict):
    """The mechanism of one point: the file ``source`` with the spec's ``[system] set``
    changes ``overrides`` and the point's SI ``values`` (dotted key -> value)."""
    from camdyn.io.mechanism_config import load_mechanism

    changes = dict(overrides)
    changes.update({key: override_text(key, value) for key, value in values.items()})
    return load_mechanism(source, changes)


def check_mechanism(mechanism) -> None:
    """The checks a run makes before it starts, without running it: the cam-follower's
    static equilibrium, a constant motion and follower 2's system."""
    from camdyn.simulation.runner import prepare

    prepare(mechanism.system)
    if mechanism.second is not None:
        prepare(mechanism.second)
    if mechanism.system.motion.kind != "constant":
        raise ParameterError("a mechanism runs from a constant cam motion (system.motion.kind = 'constant')")
    if not math.isfinite(mechanism.system.motion.period):
        raise ParameterError("the cam does not move (speed 0)")


def base_mechanism(source: str, overrides: dict) -> tuple[str, str]:
    """The mechanism kind and the whole base mechanism as TOML (for the digest and the
    result's attributes), checked; a bad file or ``[system] set`` is refused."""
    from camdyn.io.mechanism_config import mechanism_to_toml

    for key in overrides:
        key_unit(key)
    mechanism = point_mechanism(source, overrides, {})
    try:
        check_mechanism(mechanism)
    except CamdynError as exc:
        raise ParameterError(f"sweep spec: the base mechanism {source}: {exc}") from None
    return mechanism.spec.kind, mechanism_to_toml(mechanism)


def drive_sets_speed(text: str) -> bool:
    """Whether the mechanism written as TOML ``text`` (:func:`base_mechanism`) has its cam
    turned by a drive (a torque, a motor, a controller), so that the cam's speed is the
    run's, not a key to vary; a mechanism with no ``[drive]`` or a prescribed one holds
    its system's ``motion.speed``."""
    import tomllib

    drive = tomllib.loads(text).get("drive")
    return drive is not None and drive.get("kind", "constant") != "prescribed"


def check_values(source: str, overrides: dict, vary) -> None:
    """Apply every value of every varied key on its own to the base mechanism and check
    it (:func:`camdyn.sweeps.spec.checked_values`: at most
    :data:`~camdyn.sweeps.spec.CHECKED_VALUES` of each key, its ends among them); the
    first bad one is refused naming ``[[vary]]`` key and value."""
    from camdyn.sweeps.spec import checked_values

    for v in vary:
        for value in checked_values(v.values):
            try:
                check_mechanism(point_mechanism(source, overrides, {v.key: value}))
            except CamdynError as exc:
                raise ParameterError(f"sweep spec: [[vary]] {v.key} = {value:g} {v.unit}: {exc}") from None
