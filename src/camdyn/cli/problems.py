"""The periodic problem of a configuration of any family, given by its preset's name or
file, at a cam speed: what the commands whose analysis needs only a
:class:`~camdyn.continuation.problem.Problem` (``camdyn lyapunov`` through
:mod:`camdyn.continuation.lyapunov`) take, whatever the family
(:func:`camdyn.systems.families.family_of` tells the families apart). It reads files
(:mod:`camdyn.io`), which the physics packages do not, so it lives with the command line.
"""

from __future__ import annotations

import math

from camdyn.continuation.problem import Problem
from camdyn.errors import ParameterError
from camdyn.params.units import angular_speed
from camdyn.systems.families import family_of

__all__ = ["source_problem"]


def _cam_follower(source, overrides, speed) -> Problem:
    from camdyn.continuation.problem import system_problem
    from camdyn.io.system_config import load_system

    system = load_system(source, overrides)
    if speed is not None:
        system = system.with_values(**{"motion.speed": speed})
    return system_problem(system, "motion.speed")


def _model(source, overrides, speed) -> Problem:
    from camdyn.continuation.problem import bound_problem
    from camdyn.systems.model_files import load_model

    bound = load_model(str(source)).bind(overrides)
    if bound.model.speed is None:
        raise ParameterError(f"model {bound.model.name!r} names no speed parameter: it has no forcing period")
    if speed is not None:
        bound = bound.replace({bound.model.speed: speed})
    return bound_problem(bound)


def _mechanism(source, overrides, speed) -> Problem:
    from camdyn.continuation.mechanisms import mechanism_problem
    from camdyn.io.mechanism_config import load_mechanism, mechanism_rig

    changes = dict(overrides or {})
    if speed is not None:
        changes["system.motion.speed"] = f"{speed!r} Hz"
    return mechanism_problem(mechanism_rig(load_mechanism(source, changes)))


def _translating(source, overrides, speed) -> Problem:
    from camdyn.continuation.translating import translating_problem
    from camdyn.io.lift_table import load_translating

    follower, spec = load_translating(source, overrides)
    if speed is None and spec.speed is None:
        raise ParameterError(f"{spec.name} gives no cam speed: add motion.speed to the file or pass a speed")
    omega = 2.0 * math.pi * speed if speed is not None else float(spec.speed)   # [rad/s]
    return translating_problem(follower, f"{omega!r} rad/s", spec.phase)


def _rocking(source, overrides, speed) -> Problem:
    raise ParameterError(f"{source}: the rocking roller or knife-edge arm has no periodic problem (shooting, "
                         "state-transition matrix) in camdyn yet; 'camdyn simulate' and 'camdyn spectrum' take it")


#: The problem of each family's configuration.
BUILDERS = {"cam-follower": _cam_follower, "model": _model, "mechanism": _mechanism, "translating": _translating,
            "rocking": _rocking}


def source_problem(source, overrides: dict | None = None, speed=None) -> Problem:
    """The periodic problem of the configuration ``source`` of any family.

    Parameters
    ----------
    source : str or Path
        A preset's name (``camdyn presets``), a TOML file or ``FILE.py:NAME``.
    overrides : dict, optional
        Dotted key -> value as text with its unit, as ``--set`` gives them.
    speed : float or str, optional
        Cam speed [Hz] or text with units; default the configuration's.

    Returns
    -------
    Problem
        At the given speed; a cam under its drive has its speed as it runs
        (:attr:`Problem.clock`).

    Raises
    ------
    ParameterError
        For a family with no periodic problem (the rocking arm on a profile), or a bad
        configuration or speed.
    """
    hz = None if speed is None else angular_speed(speed) / (2.0 * math.pi)
    return BUILDERS[family_of(source)](source, overrides, hz)
