"""The cam-follower's frequency response by harmonic balance from a system and a range,
and its records: the same records, bifurcations and Dataset as shooting's branches
(:mod:`camdyn.continuation.results`), with every point's cam harmonics from its
harmonic-balance orbit."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from camdyn.continuation.orbits import Orbit
from camdyn.continuation.problem import Problem, system_problem
from camdyn.continuation.results import check_trace_settings, orbit_record, parameter_value
from camdyn.continuation.spectra import HARMONIC_CHANNELS, channel_harmonics
from camdyn.errors import ParameterError
from camdyn.model.equilibrium import as_system
from camdyn.model.outputs import CHANNELS, derived
from camdyn.params.system import System
from camdyn.simulation import limits
from camdyn.steady.harmonic_balance import GridModel, HarmonicOrbit
from camdyn.steady.response import HarmonicBranch, continue_harmonic

__all__ = ["METHOD", "trace_harmonic", "harmonic_record", "harmonic_records"]

#: The method as a Dataset's ``method`` attribute names it.
METHOD = "harmonic balance (AFT), pseudo-arclength continuation"
_FN = [name for name, _, _ in CHANNELS].index("Fn")
_DELTA = [name for name, _, _ in CHANNELS].index("penetration")


def trace_harmonic(system: System, key: str, start, stop, harmonics: int | str = "auto", step: float = 0.02,
                   max_points: int = 200, max_step: float = 0.1, rtol: float = 1e-10,
                   progress: Callable[[Orbit], None] | None = None) -> tuple[Problem, HarmonicBranch]:
    """The frequency response of ``system`` (or the preset it names) in the parameter
    ``key`` [SI unit, or text with a unit such as ``"5 Hz"``] from ``start`` towards
    ``stop`` by harmonic balance (:func:`~camdyn.steady.response.continue_harmonic`,
    ``harmonics`` H or ``"auto"``, steps in scaled units). ``rtol`` sets the problem's
    tolerances only (as :func:`~camdyn.continuation.results.trace_branch`'s problem).

    Raises
    ------
    ParameterError
        For a bad key, range or setting, before any work.
    SimulationError
        If no orbit in sustained contact is found at ``start``.
    """
    system = as_system(system)
    if not isinstance(key, str):
        raise ParameterError(f"key must be a parameter's dotted name such as 'motion.speed', got {key!r:.60}")
    if harmonics != "auto" and (isinstance(harmonics, bool) or not isinstance(harmonics, int) or harmonics < 1):
        raise ParameterError(f"harmonics must be a positive integer or 'auto', got {harmonics!r:.60}")
    rtol = limits.check_number("rtol", rtol)
    start, stop = (parameter_value(key, value, name) for value, name in ((start, "start"), (stop, "stop")))
    check_trace_settings(start, stop, 1, 1, 1, max_points, step, "forcing periods")
    problem = system_problem(system.with_values(**{key: start}), key, rtol=rtol, atol=rtol * 1e-2)
    branch = continue_harmonic(problem, start, stop, harmonics, step=step, max_step=max(step, max_step),
                               max_points=max_points, progress=progress)
    return problem, branch


def harmonic_record(problem: Problem, orbit: Orbit, harmonic: HarmonicOrbit, channels=HARMONIC_CHANNELS) -> dict:
    """One point of a frequency response as :func:`~camdyn.continuation.results.orbit_record`
    writes a shooting orbit (the same keys), with ``max_normal_force`` [N] and
    ``max_penetration`` [m] over the orbit's grid samples and ``harmonics``:
    ``{channel: [amplitude of cam harmonic 1..H]}`` (each in its channel's unit) from the
    channels computed at those samples (N >= 8H + 2 of them; None for a model other than
    the cam-follower)."""
    record = orbit_record(replace(problem, system=None), orbit)      # no simulation: the samples give the peaks
    value = orbit.parameter
    model = GridModel(problem, value)
    states, modes = model.balanced_modes(harmonic.times, harmonic.samples)
    spectra = channel_harmonics(problem.system_id, model.p, harmonic.times, states, modes, harmonic.harmonics,
                                names=channels)
    if spectra is not None:
        values = derived(harmonic.times, states[:, :3], modes, model.p)
        record["max_normal_force"] = float(np.max(values[:, _FN]))
        record["max_penetration"] = float(np.max(values[:, _DELTA]))
    record["harmonics"] = spectra
    record["harmonic_count"] = harmonic.harmonics
    return record


def harmonic_records(problem: Problem, branch: HarmonicBranch, channels=HARMONIC_CHANNELS) -> list[dict]:
    """:func:`harmonic_record` of every point of ``branch``."""
    return [harmonic_record(problem, o, h, channels) for o, h in zip(branch.branch.orbits, branch.harmonic_orbits)]

