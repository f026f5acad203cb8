"""The cam-follower's branches of periodic orbits from a system and a parameter range,
and their tables: one record per orbit (with the peak contact force and penetration over
the orbit), the located bifurcations, and an xarray Dataset with units."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import xarray as xr

from camdyn.continuation.branches import MIN_STEP, Branch, continue_orbits
from camdyn.continuation.orbits import Orbit, find_orbit, shoot
from camdyn.continuation.problem import Problem, system_problem
from camdyn.continuation.spectra import HARMONIC_CHANNELS, cam_harmonics, channel_units
from camdyn.continuation.switching import switch_branch
from camdyn.errors import CamdynError, ParameterError
from camdyn.model.equilibrium import as_system
from camdyn.params.system import System
from camdyn.simulation import limits

#: The first period-``2k`` orbit's distance from a period doubling (scaled,
#: :func:`~camdyn.continuation.switching.doubled_orbit`) for a cam under its drive
#: (:attr:`Problem.clock` set): on the chapter 3 impact rig on a motor (3e-4 kg m^2,
#: doubling at a mean cam speed of 16.18 Hz) Newton's steps at 1e-3 stalled at 5.6e-10,
#: above its tolerance (the residual's noise in the cam's speed, carried into the
#: parameter's column by its central difference), and converged at 1e-2 [-].
AUTONOMOUS_AMPLITUDE = 1e-2
#: Cam harmonics per channel in a shooting orbit's record [-].
HARMONICS = 8

__all__ = ["check_trace_settings", "parameter_value", "trace_branch", "switch_doublings", "orbit_record",
           "branch_records", "bifurcation_records", "branches_dataset"]


def _real(value) -> bool:
    return not isinstance(value, bool) and isinstance(value, (int, float, np.integer, np.floating))


def _whole(value, low: int) -> bool:
    """Whether ``value`` is a whole number (an int, or a float without a fraction) >= ``low``."""
    return _real(value) and math.isfinite(value) and int(value) == value and value >= low


def check_trace_settings(start: float, stop: float, periods, segments, transient, max_points, step: float,
                         period_name: str) -> None:
    """Refuse, before any work, a branch's range ``start``-``stop`` [the parameter's unit]
    that is not two different finite values, a period (in ``period_name``) or a number of
    shooting segments that is not a positive integer, and a transient, point budget or
    step out of range."""
    if not (math.isfinite(start) and math.isfinite(stop)) or start == stop:
        raise ParameterError(f"the range must be two different finite values, got {start} and {stop}")
    if not _whole(periods, 1):
        raise ParameterError(f"the period must be a positive integer number of {period_name}, got {periods!r:.60}")
    if not _whole(segments, 1):
        raise ParameterError(f"the number of shooting segments must be a positive integer, got {segments!r:.60}")
    if not _whole(transient, 1) or not _whole(max_points, 2) or not _real(step) or not step >= MIN_STEP:
        raise ParameterError(f"transient must be at least 1, max_points at least 2 and step at least {MIN_STEP:g}")


def parameter_value(key: str, value, name: str = "value") -> float:
    """A value of the system parameter ``key`` [SI]: a number as it is, or text with a
    unit as a configuration file or ``--set`` reads it (``"5 Hz"``, ``"693 rpm"``,
    ``"1.2 mm"``); ``name`` names it in the messages."""
    if isinstance(value, str):
        from camdyn.params.config import SCHEMA, convert_value, unknown_key_error

        if key not in SCHEMA:
            raise unknown_key_error(key)
        converted = convert_value(key, value, {})
        if isinstance(converted, bool) or not isinstance(converted, (int, float)):
            raise ParameterError(f"{key} is not a numeric parameter: it cannot be continued")
        return float(converted)
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ParameterError(f"{name} must be a number [SI] or text with a unit, got {value!r}")
    return float(value)


def trace_branch(system: System, key: str, start: float, stop: float, periods: int = 1, step: float = 0.02,
                 max_points: int = 200, transient: int = 50, rtol: float = 1e-10,
                 progress: Callable[[Orbit], None] | None = None, segments: int = 1,
                 stall: int = 0) -> tuple[Problem, Branch]:
    """The branch of period-``periods`` orbits of ``system`` (or the preset it names)
    from the parameter ``key`` [SI unit, or text with a unit such as ``"5 Hz"``] at
    ``start`` towards ``stop``: the orbit at ``start`` from a transient of
    ``transient`` forcing periods and Newton's method, then pseudo-arclength continuation
    (:func:`~camdyn.continuation.branches.continue_orbits`, steps in scaled units, and
    ``stall`` its stall test), by multiple shooting over ``segments`` segments when more
    than 1.

    Raises
    ------
    ParameterError
        For a bad key, range or setting, before any work.
    SimulationError
        If no orbit is found at ``start``.
    """
    system = as_system(system)
    if not isinstance(key, str):
        raise ParameterError(f"key must be a parameter's dotted name such as 'motion.speed', got {key!r:.60}")
    rtol = limits.check_number("rtol", rtol)
    start, stop = (parameter_value(key, value, name) for value, name in ((start, "start"), (stop, "stop")))
    check_trace_settings(start, stop, periods, segments, transient, max_points, step, "forcing periods")
    problem = system_problem(system.with_values(**{key: start}), key, rtol=rtol, atol=rtol * 1e-2)
    problem.build(stop)                                       # refuse an end value the system cannot take
    orbit = find_orbit(problem, periods=int(periods), transient=transient, segments=int(segments))
    branch = continue_orbits(problem, orbit, stop, step=step, max_step=max(step, 0.1), max_points=max_points,
                             progress=progress, stall=stall)
    return problem, branch


def trace_model(bound, key: str | None, start, stop, periods: int = 1, step: float = 0.02, max_points: int = 200,
                transient: int = 50, rtol: float = 1e-10, progress: Callable[[Orbit], None] | None = None,
                segments: int = 1, stall: int = 0) -> tuple[Problem, Branch]:
    """:func:`trace_branch` for a model of the model protocol (``Model.bind()``): the
    branch in its parameter ``key`` (default its speed), ``start`` and ``stop`` numbers in
    the parameter's unit or text with units, through
    :func:`~camdyn.continuation.problem.bound_problem`."""
    from camdyn.continuation.problem import bound_problem
    from camdyn.systems.protocol import BoundModel, read_value

    if not isinstance(bound, BoundModel):
        raise ParameterError(f"expected a model with its parameters (Model.bind()), got {type(bound).__name__}")
    key = bound.model.speed if key is None else key
    quantity = {q.name: q for q in bound.model.parameters}.get(key)
    if quantity is None:
        raise ParameterError(f"model {bound.model.name!r} has no parameter {key!r}; its parameters: "
                             f"{', '.join(bound.model.parameter_names)}")
    start, stop = read_value(start, quantity), read_value(stop, quantity)
    check_trace_settings(start, stop, periods, segments, transient, max_points, step, "forcing periods")
    problem = bound_problem(bound.replace({key: start}), key, rtol=rtol, atol=rtol * 1e-2)
    problem.build(stop)                                       # refuse an end value the model cannot take
    orbit = find_orbit(problem, periods=int(periods), transient=transient, segments=int(segments))
    branch = continue_orbits(problem, orbit, stop, step=step, max_step=max(step, 0.1), max_points=max_points,
                             progress=progress, stall=stall)
    return problem, branch


def switch_doublings(problem: Problem, branch: Branch, stop: float, levels: int = 1, step: float = 0.02,
                     max_points: int = 200, progress: Callable[[Orbit], None] | None = None,
                     stall: int = 0) -> list[Branch]:
    """The period-doubled branches born on ``branch``: at each of its period doublings the
    period-``2k`` branch (:func:`~camdyn.continuation.switching.switch_branch`) continued
    towards ``stop``, and on those their own doublings, down to ``levels`` doublings
    (1: the period-2 branches only). A doubling whose switch fails (the corrector does
    not converge next to it) is skipped. Returns the new branches, parents first. For a
    cam under its drive the first orbit is sought at :data:`AUTONOMOUS_AMPLITUDE`;
    ``stall`` as :func:`~camdyn.continuation.branches.continue_orbits` takes it."""
    if int(levels) != levels or levels < 0:
        raise ParameterError(f"the number of doublings to follow must be a whole number >= 0, got {levels}")
    found, parents = [], [branch]
    for _ in range(int(levels)):
        children = []
        for parent in parents:
            for item in parent.bifurcations:
                if item.kind != "period-doubling":
                    continue
                try:
                    amplitude = 1e-3 if problem.clock is None else AUTONOMOUS_AMPLITUDE
                    children.append(switch_branch(problem, item, stop, amplitude, step=step,
                                                  max_step=max(step, 0.1), max_points=max_points, progress=progress,
                                                  stall=stall))
                except CamdynError:
                    continue
        found.extend(children)
        parents = children
    return found


def _sections(problem: Problem, orbit: Orbit) -> list[float]:
    """The first unknown (the follower angle alpha [rad]) at each forcing period of the
    orbit: its ``k`` points on the stroboscopic Poincare section."""
    x, points = orbit.state, [float(orbit.state[0])]
    for _ in range(orbit.periods - 1):
        x = shoot(problem, x, orbit.parameter, 1)
        points.append(float(x[0]))
    return points


def orbit_record(problem: Problem, orbit: Orbit, harmonics: int = HARMONICS) -> dict:
    """One orbit as a record: ``parameter`` [SI], ``stable``, ``multipliers`` ([re, im]
    pairs), ``period`` [s], ``periods`` (forcing periods per orbit period),
    ``impacts_per_period``, ``max_normal_force`` [N] and ``max_penetration`` [m] over the
    orbit (from a simulation of one orbit period from its state, its samples and its
    impacts' peaks; NaN for a test model),
    ``min_normal_force`` [N] and ``min_sliding_velocity`` [m/s] (the contact-loss and
    sliding-reversal test functions; NaN for a test model), ``state`` (the unknowns at
    the phase ``t_start``) and ``poincare`` (the first unknown at each of the orbit's
    forcing periods: its points on the stroboscopic section), ``harmonics`` (the cam-follower's:
    ``{channel: [amplitude of cam harmonic 1..harmonics]}`` of :data:`~.spectra.HARMONIC_CHANNELS`,
    each in its channel's unit, by a DFT of the simulation's 512 samples per forcing period;
    None for a test model)."""
    force = penetration = math.nan
    spectra = None
    if problem.system is not None:
        from camdyn.simulation.runner import simulate
        system = problem.system.with_values(**{problem.key: orbit.parameter})
        ds = simulate(system, revolutions=orbit.periods, initial_state=orbit.state, rtol=problem.rtol,
                      atol=problem.atol, sample_rate=512.0 / orbit.period * orbit.periods,
                      variables=["penetration", "impact", *HARMONIC_CHANNELS])
        count = 512 * orbit.periods                            # one orbit period, the end point left out
        spectra = {n: cam_harmonics(ds[n].values[:count], harmonics, orbit.periods) for n in HARMONIC_CHANNELS}
        # an impact's peak (tracked by the event log) falls between samples
        force = float(np.nanmax(np.r_[ds["Fn"].values, ds["impact_peak_force"].values]))
        penetration = float(np.nanmax(np.r_[ds["penetration"].values, ds["impact_peak_penetration"].values]))
    return {"parameter": orbit.parameter, "stable": orbit.stable,
            "multipliers": [[float(m.real), float(m.imag)] for m in orbit.multipliers], "period": orbit.period,
            "periods": orbit.periods, "impacts_per_period": orbit.impacts_per_period, "max_normal_force": force,
            "max_penetration": penetration, "min_normal_force": _finite(orbit.force_minimum),
            "min_sliding_velocity": _finite(orbit.sliding_minimum), "state": [float(v) for v in orbit.state],
            "poincare": _sections(problem, orbit), "harmonics": spectra}


def _finite(value: float) -> float | None:
    """``value``, or None (JSON null) where it is NaN."""
    return float(value) if math.isfinite(value) else None


def branch_records(problem: Problem, branch: Branch, harmonics: int = HARMONICS) -> list[dict]:
    """:func:`orbit_record` of every orbit of ``branch``, ``harmonics`` cam harmonics per channel."""
    return [orbit_record(problem, orbit, harmonics) for orbit in branch.orbits]


def bifurcation_records(branches: list[Branch]) -> list[dict]:
    """``{kind, parameter, branch}`` of every located bifurcation (``branch``: index into
    ``branches``)."""
    return [{"kind": b.kind, "parameter": b.parameter, "branch": index}
            for index, branch in enumerate(branches) for b in branch.bifurcations]


def _harmonic_variables(points: list[dict]) -> dict:
    """``harmonic_<channel>`` over ``(point, harmonic)`` [the channel's unit] from the
    records' ``harmonics`` (NaN where a record has fewer or none); none without any."""
    spectra = [r.get("harmonics") or {} for r in points]
    names = list(dict.fromkeys(n for item in spectra for n in item))
    if not names:
        return {}
    count = max(len(v) for item in spectra for v in item.values())
    units, out = channel_units(names), {}
    for name in names:
        values = np.full((len(points), count), np.nan)
        for i, item in enumerate(spectra):
            values[i, :len(item.get(name, []))] = item.get(name, [])
        out[f"harmonic_{name}"] = (("point", "harmonic"), values,
                                   {"units": units[name], "long_name": f"amplitude of {name}'s cam harmonics 1..H"})
    return out


def branches_dataset(problem: Problem, records: list[list[dict]], bifurcations: list[dict],
                     method: str = "single shooting, pseudo-arclength continuation") -> xr.Dataset:
    """The branches as a Dataset over ``point`` (all branches one after the other, with
    their index in ``branch``), ``multiplier``, ``section`` (an orbit's Poincare points,
    NaN past its ``periods``), ``harmonic`` (the records' cam harmonics,
    ``harmonic_<channel>``) and ``bifurcation``; every variable carries ``units`` and
    ``long_name``; ``method`` names the method in the attributes."""
    points = [r for branch in records for r in branch]
    if not points:
        raise ParameterError("no orbit to store")
    size = max(len(r["multipliers"]) for r in points)
    mu = np.full((len(points), size), np.nan + 0j)
    for i, r in enumerate(points):
        mu[i, :len(r["multipliers"])] = [complex(a, b) for a, b in r["multipliers"]]
    unit = problem.unit or "1"

    def column(name, dtype=float, default=math.nan):
        return np.array([default if r.get(name) is None else r[name] for r in points], dtype=dtype)

    sections = [r.get("poincare") or [r["state"][0]] for r in points]
    poincare = np.full((len(points), max(len(v) for v in sections)), np.nan)
    for i, values in enumerate(sections):
        poincare[i, :len(values)] = values

    data = {
        "parameter": ("point", column("parameter"), {"units": unit, "long_name": problem.name}),
        "branch": ("point", np.array([i for i, b in enumerate(records) for _ in b], dtype=np.int32),
                   {"units": "1", "long_name": "branch index"}),
        "stable": ("point", column("stable", np.int8), {"units": "1", "long_name": "1 if every |multiplier| < 1"}),
        "period": ("point", column("period"), {"units": "s", "long_name": "orbit period"}),
        "periods": ("point", column("periods", np.int32, 1),
                    {"units": "1", "long_name": "forcing periods per orbit period"}),
        "min_normal_force": ("point", column("min_normal_force"),
                             {"units": "N", "long_name": "smallest Fn over the orbit, unclipped"}),
        "min_sliding_velocity": ("point", column("min_sliding_velocity"),
                                 {"units": "m/s", "long_name": "smallest sliding velocity in contact, signed by "
                                                              "the direction of sliding"}),
        "poincare_alpha": (("point", "section"), poincare,
                           {"units": "rad", "long_name": "follower angle once per forcing period (Poincare points)"}),
        "impacts_per_period": ("point", column("impacts_per_period", np.int32),
                               {"units": "1", "long_name": "impacts per orbit period"}),
        "max_normal_force": ("point", column("max_normal_force"), {"units": "N", "long_name": "largest Fn"}),
        "max_penetration": ("point", column("max_penetration"),
                            {"units": "m", "long_name": "largest contact penetration"}),
        "alpha": ("point", np.array([r["state"][0] for r in points]),
                  {"units": "rad", "long_name": "follower angle at the orbit's phase"}),
        "alpha_dot": ("point", np.array([r["state"][1] for r in points]),
                      {"units": "rad/s", "long_name": "follower angular velocity at the orbit's phase"}),
        "multiplier_real": (("point", "multiplier"), mu.real,
                            {"units": "1", "long_name": "Floquet multiplier, real part"}),
        "multiplier_imag": (("point", "multiplier"), mu.imag,
                            {"units": "1", "long_name": "Floquet multiplier, imaginary part"}),
        "bifurcation_kind": ("bifurcation", np.array([b["kind"] for b in bifurcations], dtype=str),
                             {"units": "1", "long_name": "fold, period-doubling, neimark-sacker, grazing, "
                                                          "contact-loss, sliding-reversal or multiplier-jump"}),
        "bifurcation_parameter": ("bifurcation", np.array([b["parameter"] for b in bifurcations], dtype=float),
                                  {"units": unit, "long_name": f"{problem.name} at the bifurcation"}),
        "bifurcation_branch": ("bifurcation", np.array([b["branch"] for b in bifurcations], dtype=np.int32),
                               {"units": "1", "long_name": "branch index"}),
    }
    data.update(_harmonic_variables(points))
    return xr.Dataset(data, attrs={"parameter_name": problem.name, "parameter_units": unit,
                                   "method": method,
                                   "rtol": problem.rtol, "atol": problem.atol})
