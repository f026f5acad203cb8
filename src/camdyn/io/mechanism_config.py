"""The loader of a mechanism's configuration (:mod:`camdyn.params.mechanism`): the
cam-follower it is built on (a preset or system file, with the ``[system]`` table's
changes), the drive (:class:`camdyn.simulation.mechanisms.CamDrive`, whose checks refuse
a bad drive), the bearing or the second follower; :func:`simulate_mechanism` runs it with
the Python entry of its kind, and :func:`mechanism_to_toml` writes it back whole."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import xarray as xr

from camdyn.errors import ParameterError
from camdyn.io.system_config import load_system
from camdyn.params.config import build_system, system_to_toml
from camdyn.params.mechanism import MechanismSpec, read_mechanism
from camdyn.params.system import System
from camdyn.simulation.mechanisms import CamDrive

__all__ = ["Mechanism", "load_mechanism", "simulate_mechanism", "mechanism_to_toml", "mechanism_rig"]


@dataclasses.dataclass(frozen=True)
class Mechanism:
    """A mechanism built from its configuration.

    Attributes
    ----------
    spec : MechanismSpec
        The configuration, in SI units.
    system : System
        The cam-follower (follower 1 of two).
    second : System or None
        Follower 2 (two followers): follower 1's system with the ``[second.system]``
        changes.
    drive : CamDrive or None
        The cam shaft (driven cam, two followers).
    pivot_damping : float or None
        The bearing's damping [N s/m] (flexible pivot), from ``pivot.damping`` or from
        ``pivot.damping_ratio`` as ``2 zeta sqrt(kp m)``.
    """

    spec: MechanismSpec
    system: System
    drive: CamDrive | None = None
    second: System | None = None
    pivot_damping: float | None = None


def _system(spec: MechanismSpec, changes: dict) -> System:
    """The cam-follower: ``spec.system`` with the ``[system]`` changes and ``changes``,
    or built from them."""
    if spec.system is None:
        keys = {**spec.system_keys, **changes}
        name = str(keys.pop("preset.name", spec.name))
        citation = str(keys.pop("preset.citation", ""))
        keys.pop("preset.description", None)
        return build_system(keys, name=name, citation=citation)
    return load_system(spec.system, {key: value for key, value in {**spec.system_keys, **changes}.items()
                                     if not key.startswith("preset.")})


def load_mechanism(source: str | Path, overrides: dict | None = None) -> Mechanism:
    """A mechanism from its TOML file, checked before any work.

    Parameters
    ----------
    source : str or Path
        The TOML file (with a ``[mechanism]`` table).
    overrides : dict, optional
        Dotted key -> value as text with its unit (``{"drive.torque": "0.2 N*m"}``,
        ``{"system.motion.speed": "12 Hz"}``).

    Returns
    -------
    Mechanism
    """
    spec = read_mechanism(source, overrides)
    try:
        system = _system(spec, {})
        second = _system(spec, spec.second_keys) if spec.kind == "two-followers" else None
        if second is not None and not spec.second_keys:
            second = system
        drive = None if spec.drive is None else CamDrive(**spec.drive)
    except ParameterError as exc:
        raise type(exc)(f"{Path(str(source)).name}: {exc}") from None
    damping = spec.pivot_damping
    if spec.kind == "flexible-pivot" and damping is None:
        # the damping of a ratio zeta of the follower's mass on the bearing (a critically damped
        # oscillator of mass m and stiffness kp has c = 2 sqrt(kp m))
        damping = 2.0 * spec.pivot_damping_ratio * math.sqrt(spec.pivot_stiffness * system.follower.mass)
    return Mechanism(spec, system, drive, second, damping)


def simulate_mechanism(mechanism: Mechanism, revolutions: float = 5.0, sample_rate: float = 20e3,
                       rtol: float = 1e-9, method: str = "auto") -> xr.Dataset:
    """Run a mechanism with the Python entry of its kind.

    Parameters
    ----------
    mechanism : Mechanism
        From :func:`load_mechanism`.
    revolutions : float
        Length of the run in periods of the starting cam speed [-].
    sample_rate : float
        Output sampling rate [Hz].
    rtol : float
        Relative tolerance [-] (the absolute one is each entry's default).
    method : {"auto", "dop853", "explicit", "rosenbrock"}
        Stepper choice.

    Returns
    -------
    xarray.Dataset
        As :func:`camdyn.simulation.mechanisms.simulate_driven_cam`,
        :func:`camdyn.simulation.flexible_pivot.simulate_flexible_pivot` or
        :func:`camdyn.simulation.two_followers.simulate_two_followers` return it, with the
        attributes ``mechanism`` (the kind) and ``name``.
    """
    spec = mechanism.spec
    run = dict(revolutions=revolutions, sample_rate=sample_rate, rtol=rtol, method=method)
    if spec.kind == "driven-cam":
        from camdyn.simulation.mechanisms import simulate_driven_cam
        ds = simulate_driven_cam(mechanism.system, mechanism.drive, initial_speed=spec.initial_speed, **run)
    elif spec.kind == "flexible-pivot":
        from camdyn.simulation.flexible_pivot import simulate_flexible_pivot
        ds = simulate_flexible_pivot(mechanism.system, spec.pivot_stiffness, mechanism.pivot_damping, **run)
    else:
        from camdyn.simulation.two_followers import simulate_two_followers
        ds = simulate_two_followers(mechanism.system, mechanism.drive, mechanism.second, placement=spec.placement,
                                    initial_speed=spec.initial_speed, static_friction=spec.static_friction, **run)
    ds.attrs.update(mechanism=spec.kind, name=spec.name)
    return ds


def mechanism_rig(mechanism: Mechanism):
    """The mechanism as the rig its Python entry takes: a
    :class:`~camdyn.simulation.mechanisms.DrivenCamRig`, a
    :class:`~camdyn.simulation.flexible_pivot.FlexiblePivotRig` or a
    :class:`~camdyn.simulation.two_followers.TwoFollowerRig` (its ``drive.initial_speed``,
    if given, becomes the systems' ``motion.speed``), for
    :func:`camdyn.continuation.mechanisms.mechanism_problem`."""
    spec = mechanism.spec
    if spec.kind == "flexible-pivot":
        from camdyn.simulation.flexible_pivot import FlexiblePivotRig
        return FlexiblePivotRig(mechanism.system, spec.pivot_stiffness, mechanism.pivot_damping)
    system, second = mechanism.system, mechanism.second
    if spec.initial_speed is not None:
        motion = {"motion.speed": abs(spec.initial_speed) / (2.0 * math.pi),
                  "motion.direction": 1 if spec.initial_speed >= 0.0 else -1}
        system = system.with_values(**motion)
        second = None if second is None else second.with_values(**motion)
    if spec.kind == "driven-cam":
        from camdyn.simulation.mechanisms import DrivenCamRig
        return DrivenCamRig(system, mechanism.drive)
    from camdyn.simulation.two_followers import TwoFollowerRig
    return TwoFollowerRig(system, second, spec.placement, mechanism.drive)


def _quoted(value: float, unit: str) -> str:
    return f'"{value!r} {unit}"'


def mechanism_to_toml(mechanism: Mechanism) -> str:
    """The mechanism as a self-contained TOML file that reads back to the same mechanism:
    its ``[mechanism]`` kind, the whole system under ``[system.*]`` tables
    (:func:`camdyn.params.config.system_to_toml`), and every key of its kind's tables in
    SI units."""
    spec = mechanism.spec
    lines = ["[preset]", f"name = {json.dumps(spec.name)}"]
    if spec.description:
        lines.append(f"description = {json.dumps(spec.description)}")
    lines += ["", "[mechanism]", f'kind = "{spec.kind}"']
    if mechanism.drive is not None:
        d = mechanism.drive
        lines += ["", "[drive]", f"shaft_inertia = {_quoted(d.shaft_inertia, 'kg*m^2')}", f'kind = "{d.kind}"']
        fields = {"torque": "N*m", "stall_torque": "N*m", "free_speed": "rad/s", "proportional": "N*m*s/rad",
                  "integral": "N*m/rad", "target_speed": "rad/s"}
        used = {"constant": ("torque",), "motor": ("stall_torque", "free_speed"),
                "controller": ("torque", "proportional", "integral", "target_speed"), "prescribed": ()}[d.kind]
        lines += [f"{name} = {_quoted(getattr(d, name), fields[name])}" for name in used]
        lines += [f"bearing_viscous = {_quoted(d.bearing_viscous, 'N*m*s/rad')}",
                  f"bearing_coulomb = {_quoted(d.bearing_coulomb, 'N*m')}",
                  f"bearing_speed = {_quoted(d.bearing_speed, 'rad/s')}"]
        if spec.initial_speed is not None:
            lines.append(f"initial_speed = {_quoted(spec.initial_speed, 'rad/s')}")
    if spec.kind == "flexible-pivot":
        lines += ["", "[pivot]", f"stiffness = {_quoted(spec.pivot_stiffness, 'N/m')}",
                  f"damping = {_quoted(mechanism.pivot_damping, 'N*s/m')}"]
    if spec.kind == "two-followers":
        lines += ["", "[second]", f"placement = {_quoted(spec.placement, 'rad')}"]
        if spec.static_friction is not None:
            values = np.atleast_1d(spec.static_friction).tolist()
            lines.append(f"static_friction = [{', '.join(repr(mu) for mu in values)}]")
        if mechanism.second != mechanism.system:
            # follower 2 whole, as changes to follower 1 (every key, so the changes are all of it)
            second = system_to_toml(mechanism.second).split("\n[", 1)[1]
            lines += ["", "[second.system." + second.replace("\n[", "\n[second.system.")]
    system = system_to_toml(mechanism.system).replace("\n[", "\n[system.")
    if system.startswith("["):
        system = "[system." + system[1:]
    return "\n".join(lines) + "\n\n" + system
