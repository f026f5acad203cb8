"""``camdyn.simulate``: the one entry that runs a model of any family, given as an object or
by its preset name or file (:func:`camdyn.systems.families.family_of` tells the families
of a source apart).

- ``FILE.py:NAME``: a model of the model protocol (:mod:`camdyn.simulation.models`);
- a ``[mechanism]`` table: the driven cam, the flexible pivot, two followers
  (:func:`camdyn.io.mechanism_config.simulate_mechanism`);
- ``[follower] kind = "translating"``: a translating follower on a cam profile, with
  friction at its contact where the file gives one (:mod:`camdyn.simulation.translating`,
  :mod:`camdyn.simulation.sliding`);
- ``[follower] kind = "rocking"``: a rocking roller or knife edge on a profile
  (:mod:`camdyn.simulation.rocking_roller`, :mod:`camdyn.simulation.rocking_friction`);
- anything else: the thesis's rocking flat-faced follower, which
  :func:`camdyn.simulation.runner.simulate` runs (:func:`simulate_source` returns None).

The speed is a number of Hz or text with units, as everywhere in camdyn.
"""

from __future__ import annotations

import math
import os

import xarray as xr

from camdyn.errors import ParameterError
from camdyn.params.units import angular_speed
from camdyn.systems.families import family_of

__all__ = ["simulate", "simulate_source"]


def simulate_source(source, overrides: dict | None = None, speed=None, revolutions: float = 30.0,
                    sample_rate: float = 20e3, rtol: float | None = None) -> xr.Dataset | None:
    """Simulate the configuration ``source`` (preset name or file) of any family but the
    thesis's rocking follower; None for that one.

    Parameters
    ----------
    source : str or Path
        A preset's name (``camdyn presets``), a TOML file or ``FILE.py:NAME``.
    overrides : dict, optional
        Dotted key -> value as text with its unit, as ``--set`` gives them.
    speed : float or str, optional
        Cam speed [Hz] or text with units; default the configuration's.
    revolutions : float
        Length of the run in cam revolutions [-].
    sample_rate : float
        Output sampling rate [Hz].
    rtol : float, optional
        Relative tolerance [-]; default the family's entry's own.

    Returns
    -------
    xarray.Dataset or None
        The family's Dataset, its cam speed in the attribute ``speed_hz`` [Hz] (a
        driven shaft's mean speed); None for the thesis's follower.
    """
    family = family_of(source)
    if family == "cam-follower":
        return None
    if not (isinstance(revolutions, (int, float)) and math.isfinite(revolutions) and revolutions > 0):
        raise ParameterError(f"revolutions must be positive and finite, got {revolutions!r}")
    tolerance = {} if rtol is None else {"rtol": rtol}
    if family == "model":
        from camdyn.simulation.models import simulate_model
        from camdyn.systems.model_files import load_model

        return simulate_model(load_model(str(source)).bind(overrides), speed=speed, revolutions=revolutions,
                              sample_rate=sample_rate, **tolerance)
    if family == "mechanism":
        from camdyn.io.mechanism_config import load_mechanism, simulate_mechanism

        changes = dict(overrides or {})
        if speed is not None:
            changes["system.motion.speed"] = f"{angular_speed(speed) / (2.0 * math.pi)!r} Hz"
        ds = simulate_mechanism(load_mechanism(source, changes), revolutions=revolutions, sample_rate=sample_rate,
                                **tolerance)
        if "speed_hz" not in ds.attrs and "mean_cam_speed" in ds.attrs:   # a driven shaft: its mean speed
            ds.attrs["speed_hz"] = abs(float(ds.attrs["mean_cam_speed"])) / (2.0 * math.pi)
        return ds
    return _profile_run(source, overrides, speed, revolutions, sample_rate, tolerance, rocking=family == "rocking")


def _profile_run(source, overrides, speed, revolutions, sample_rate, tolerance, rocking: bool) -> xr.Dataset:
    """A follower on a cam profile (translating, or a rocking arm), with friction at its
    contact where the configuration gives one."""
    from camdyn.simulation.sliding import friction_from_spec

    if rocking:
        from camdyn.io.rocking_config import load_rocking
        from camdyn.simulation.rocking_friction import simulate_rocking_friction as with_friction
        from camdyn.simulation.rocking_roller import simulate_rocking as plain

        follower, spec = load_rocking(source, overrides)
        own_speed, phase = spec.profile.speed, spec.profile.phase
    else:
        from camdyn.io.lift_table import load_translating
        from camdyn.simulation.sliding import simulate_sliding as with_friction
        from camdyn.simulation.translating import simulate_translating as plain

        follower, spec = load_translating(source, overrides)
        own_speed, phase = spec.speed, spec.phase
    if speed is None and own_speed is None:
        raise ParameterError(f"{spec.name} gives no cam speed: add motion.speed to the file or pass speed")
    omega = angular_speed(speed) if speed is not None else float(own_speed)   # [rad/s]
    cam = f"{omega!r} rad/s"
    duration = revolutions * 2.0 * math.pi / omega
    friction = friction_from_spec(spec)
    if friction is None:
        ds = plain(follower, cam, duration, sample_rate=sample_rate, phase=phase, **tolerance)
    else:
        ds = with_friction(follower, friction, cam, duration, sample_rate=sample_rate, phase=phase, **tolerance)
    ds.attrs["name"] = spec.name
    ds.attrs["speed_hz"] = omega / (2.0 * math.pi)
    return ds


def simulate(system, speed=None, revolutions: float = 30.0, *args, **options) -> xr.Dataset:
    """Simulate a model of any family: :func:`camdyn.simulation.runner.simulate` for the
    thesis's follower (a ``System`` or its preset's name) and for a model of your own
    (``Model.bind()``), with every option that function documents; a configuration of
    another family by its preset's name or file (``"drum-brake"``, ``"alzate"``,
    ``"valve_train.py:VALVE_TRAIN"``) with ``speed``, ``revolutions``, ``sample_rate``
    and ``rtol`` (:func:`simulate_source`).

    Parameters
    ----------
    system : System, Model, BoundModel, str or Path
        The model, or the name or file of a configuration.
    speed : float or str, optional
        Cam speed [Hz] or text with units (``"693 rpm"``); default the configuration's.
    revolutions : float
        Length of the run in cam periods [-].
    *args, **options
        The other options of :func:`camdyn.simulation.runner.simulate` (``sample_rate``
        [Hz], ``rtol``, ``atol``, ``duration`` [s], ``method``, ...).

    Returns
    -------
    xarray.Dataset
        The run over ``time`` with units on every variable, its cam speed in the
        attribute ``speed_hz`` [Hz].
    """
    from camdyn.interrupts import deferred

    with deferred():   # the first call imports numba and the integrator: not to be cut in half
        from camdyn.simulation.runner import simulate as run

    if isinstance(system, (str, os.PathLike)):
        if family_of(system) == "cam-follower":
            from camdyn.io.system_config import load_system

            system = load_system(system)
        else:
            other = sorted(set(options) - {"sample_rate", "rtol"}) + (["arguments after revolutions"] if args else [])
            if other:
                raise ParameterError(f"{system}: {', '.join(other)} are offered for the thesis's follower and "
                                     "models of your own given as objects; a configuration of another family by "
                                     "name or file runs with speed, revolutions, sample_rate and rtol")
            return simulate_source(system, speed=speed, revolutions=revolutions, **options)
    return run(system, speed, revolutions, *args, **options)
