"""``camdyn continue PRESET_OR_TOML``: a branch of periodic orbits in one parameter, with
its stability and bifurcations (pseudo-arclength continuation of shooting solutions)."""

from __future__ import annotations

from pathlib import Path
from typing import List, Optional

import typer

from camdyn.cli.common import (
    ForceOption,
    JsonOption,
    SetOption,
    check_continue_settings,
    console,
    err_console,
    load_source,
)
from camdyn.cli.harmonic import (
    DoublingsOption,
    HarmonicsOption,
    MethodOption,
    continue_harmonic_command,
    method_settings,
)
from camdyn.cli.outputs import announce, check_outputs, emit_json
from camdyn.errors import ParameterError

_PARAMETER_HELP = ("Dotted key continued, e.g. motion.speed (the default), cam.runout (camdyn presets keys); for a "
                   "cam under its drive a drive key (default the one that sets its speed: drive.torque, "
                   "drive.free_speed or drive.target_speed).")


def _value(text: str, key: str, unit: str, parameter: str = "") -> float:
    """A value [SI] of ``parameter`` from text with its unit (a bare number only for a
    dimensionless parameter, as for ``--set``; a drive key's as a mechanism file reads it,
    an angular speed in Hz or rpm as turns); ``key`` names the option."""
    from camdyn.params.units import parse_quantity, parse_speed

    if parameter.startswith("drive."):
        from camdyn.params.mechanism import ANGULAR_SPEED, SCHEMA, angular_speed
        if SCHEMA[parameter].unit == ANGULAR_SPEED:
            return angular_speed(text, key)
        return float(parse_quantity(text, SCHEMA[parameter].unit, key))
    if unit == "Hz":
        return parse_speed(text, key)
    return float(parse_quantity(text, unit, key))


def continue_branch(source: str = typer.Argument(..., metavar="PRESET_OR_TOML"),
                    set_: Optional[List[str]] = SetOption,
                    parameter: Optional[str] = typer.Option(None, help=_PARAMETER_HELP),
                    start: str = typer.Option(..., "--from", help="First value, with a unit: 5Hz, 1.2mm."),
                    stop: str = typer.Option(..., "--to", help="Last value, with a unit."),
                    period: int = typer.Option(1, help="Forcing periods per orbit period (2 for period-2 orbits)."),
                    segments: int = typer.Option(1, help="Shooting segments per orbit period: more than 1 is "
                                                         "multiple shooting, for strongly unstable orbits."),
                    step: float = typer.Option(0.02, help="First arclength step, relative to the parameter's "
                                                          "start value [-]."),
                    max_points: int = typer.Option(200, help="Most orbits on the branch."),
                    transient: int = typer.Option(50, help="Cam periods simulated before the first orbit is "
                                                           "sought."),
                    doublings: Optional[int] = DoublingsOption,
                    method: str = MethodOption,
                    harmonics: Optional[str] = HarmonicsOption,
                    brute_force: int = typer.Option(0, "--brute-force",
                                                    help="Draw the brute-force bifurcation diagram under the "
                                                         "branches in --plot: a sweep of this many values over "
                                                         "the range, 300 cam periods each, 200 discarded "
                                                         "(0: none)."),
                    plot: Optional[Path] = typer.Option(None, help="Figure of the branch (.png, .pdf, ...)."),
                    out: Optional[Path] = typer.Option(None, help="Result file (.nc)."),
                    force: bool = ForceOption,
                    cover: bool = typer.Option(True, "--cover/--no-cover",
                                               help="Where a branch ends inside the range, restart past its end "
                                                    "from the orbit a short simulation settles on, and report "
                                                    "each gap left."),
                    max_time: Optional[str] = typer.Option(None, "--max-time",
                                                           help="Start no new branch after this wall-clock "
                                                                "time, e.g. 10min (default: no limit)."),
                    quiet: bool = typer.Option(False, "--quiet", help="No progress bar."),
                    json_: bool = JsonOption):
    """Continue periodic orbits over a parameter range: stability from the Floquet
    multipliers; folds, period doublings, Neimark-Sacker bifurcations, grazing, loss of
    contact and sliding reversal located on the way; the period-doubled branches
    followed (docs/continuation.md). Where a branch ends inside the range, the
    continuation restarts past its end and says which gaps it left (--no-cover: one
    branch). A translating follower (the preset alzate) is
    continued in motion.speed, its orbits taken at cam angle 0. A mechanism file (the
    flexible pivot, or two followers with drive.kind = 'prescribed') is continued in a
    system key or, for the flexible pivot, pivot.stiffness or pivot.damping; a cam under
    its drive (its orbits on the section at its starting angle, their period unknown) in
    a drive key (drive.free_speed, drive.shaft_inertia, ...) or the cam's or followers'."""
    from camdyn.continuation.coverage import STALL_POINTS, coverage_summary, covered_branches, gap_records
    from camdyn.continuation.results import bifurcation_records, branch_records, branches_dataset

    check_outputs(netcdf=out, figure=plot, force=force)
    from camdyn.params.profiles import is_translating

    if segments < 1:
        raise ParameterError(f"--segments must be at least 1, got {segments}")
    count, doublings = method_settings(method, harmonics, source, period, segments, doublings)
    if is_translating(source):
        if segments != 1:
            raise ParameterError("--segments is for the cam-follower; the translating follower is continued by "
                                 "single shooting")
        from camdyn.cli.translating import continue_translating_command
        continue_translating_command(source, set_, parameter or "motion.speed", start, stop, period, step, max_points,
                                     transient, doublings, brute_force, plot, out, quiet, json_, cover,
                                     _max_time(max_time))
        return
    limit = _max_time(max_time)
    system, parameter, unit, trace = _load(source, set_, parameter, brute_force)
    first, last = _value(start, "--from", unit, parameter), _value(stop, "--to", unit, parameter)
    if first == last:
        raise ParameterError("--from and --to must differ")
    check_continue_settings(period, max_points, transient, step, doublings, brute_force, plot)
    bar = _Bar(quiet or (json_ and not err_console.is_terminal), parameter, unit, first, last,
               max_points * (1 + doublings))
    if method == "harmonic-balance":
        return continue_harmonic_command(system, parameter, unit, first, last, count, step, max_points, plot, out,
                                         lambda: _brute_force(source, set_, parameter, first, last, brute_force,
                                                              quiet or json_), bar, json_)
    with bar:
        bar.phase(f"the first orbit ({transient} periods of transient, then Newton's method)")
        problem, branch = trace(system, parameter, first, last, period, step, max_points, transient,
                                progress=bar.orbit, segments=segments, stall=STALL_POINTS if cover else 0)
        coverage, branches = covered_branches(problem, branch, first, last, step, max_points, transient, doublings,
                                              cover, limit, progress=bar.orbit, phase=bar.phase, segments=segments)
    records = [branch_records(problem, b, count) for b in branches]
    gaps = gap_records(coverage)
    bifurcations = bifurcation_records(branches)
    files = []
    if out is not None:
        from camdyn.io.netcdf import save_netcdf
        files.append(announce(save_netcdf(branches_dataset(problem, records, bifurcations), out), json_))
    if plot is not None:
        from camdyn.plotting.branches import plot_branches
        diagram = _brute_force(source, set_, parameter, first, last, brute_force, quiet or json_)
        files.append(announce(plot_branches(branches_dataset(problem, records, bifurcations), plot, diagram),
                              json_))
    if json_:
        summary = {"parameter": parameter, "units": unit, **coverage_summary(coverage, branches),
                   "bifurcation_count": len(bifurcations)}
        emit_json("continue", summary, branches=records, bifurcations=bifurcations, gaps=gaps, files=files)
        return
    _print_branches(parameter, unit, branches, bifurcations, gaps)


def _print_branches(parameter: str, unit: str, branches, bifurcations: list[dict], gaps: list[dict]) -> None:
    """The branches, their bifurcations and the gaps between them, one line each."""
    for index, b in enumerate(branches):
        values = [o.parameter for o in b.orbits]
        console.print(f"branch {index}: {len(b.orbits)} orbits of period {b.orbits[0].periods} over {parameter} = "
                      f"{min(values):.6g} to {max(values):.6g} {unit}, {sum(o.stable for o in b.orbits)} stable; "
                      f"{b.stopped}", highlight=False, soft_wrap=True)
    for item in bifurcations:
        console.print(f"  {item['kind']} at {parameter} = {item['parameter']:.9g} {unit} (branch {item['branch']})",
                      highlight=False, soft_wrap=True)
    for gap in gaps:
        console.print(f"gap from {parameter} = {gap['start']:.6g} to {gap['stop']:.6g} {unit}: {gap['reason']}",
                      highlight=False, soft_wrap=True)


def _max_time(text: str | None) -> float:
    """``--max-time`` [s]: text with a unit of time, or no limit."""
    import math

    from camdyn.params.units import parse_quantity

    if text is None:
        return math.inf
    seconds = float(parse_quantity(text, "s", "--max-time"))
    if not (seconds > 0 and math.isfinite(seconds)):
        raise ParameterError(f"--max-time must be a positive time such as 10min, got {text!r}")
    return seconds


def _brute_force(source, set_, parameter, first, last, count, quiet):
    """The brute-force bifurcation diagram over ``count`` values of the parameter (a
    sweep with the Poincare metric, as ``camdyn bifurcation``), or None if ``count`` is 0."""
    if not count:
        return None
    import tempfile

    import numpy as np

    from camdyn.params.config import parse_assignments
    from camdyn.sweeps import run_sweep, spec_from_dict

    with tempfile.TemporaryDirectory() as folder:
        table = {"system": {"source": source, "set": parse_assignments(set_)},
                 "vary": [{"key": parameter, "values": [float(v) for v in np.linspace(first, last, count)]}],
                 "run": {"revolutions": 300, "discard": 200}, "metrics": {"names": ["poincare"]},
                 "output": {"path": str(Path(folder) / "diagram.nc")}}
        result = run_sweep(spec_from_dict(table, name="diagram"), progress=not quiet)
        diagram = result.load()
        result.close()
    return diagram


def _load(source, set_, parameter, brute_force):
    """``(system, parameter, unit, trace)``: the cam-follower, a mechanism's rig or a
    protocol model with its parameters, the continued parameter (its default where None),
    its unit, and the function that traces its branch (the signature of
    :func:`~camdyn.continuation.results.trace_branch`)."""
    from camdyn.continuation.autonomous import default_key, is_autonomous
    from camdyn.continuation.mechanisms import trace_mechanism
    from camdyn.continuation.problem import parameter_unit
    from camdyn.continuation.results import trace_branch, trace_model
    from camdyn.params.config import parse_assignments
    from camdyn.params.mechanism import is_mechanism
    from camdyn.systems.families import family_of
    from camdyn.systems.model_files import is_model_reference, load_model

    if family_of(source) == "rocking":
        raise ParameterError(f"{source}: a rocking roller or knife-edge arm on a profile has no periodic problem "
                             "(shooting) in camdyn yet, so camdyn continue does not take it; camdyn simulate and "
                             "camdyn spectrum do")
    if is_model_reference(source):
        if brute_force:
            raise ParameterError("--brute-force draws the cam-follower's diagram; for a model of your own run "
                                 "camdyn sweep over the same range")
        bound = load_model(source).bind(parse_assignments(set_))
        parameter = parameter or bound.model.speed
        units = {q.name: q.unit for q in bound.model.parameters}
        if parameter not in units:
            raise ParameterError(f"model {bound.model.name!r} has no parameter {parameter!r}; its parameters: "
                                 f"{', '.join(units)}")
        return bound, parameter, units[parameter], trace_model
    if not is_mechanism(source):
        system = load_source(source, set_)
        parameter = parameter or "motion.speed"
        return system, parameter, parameter_unit(system, parameter), trace_branch
    from camdyn.io.mechanism_config import load_mechanism, mechanism_rig

    if brute_force:
        raise ParameterError("--brute-force sweeps the cam-follower; it is not offered for a mechanism")
    rig = mechanism_rig(load_mechanism(source, parse_assignments(set_)))
    parameter = parameter or (default_key(rig) if is_autonomous(rig) else "motion.speed")
    return rig, parameter, _mechanism_unit(rig, parameter), trace_mechanism


def _mechanism_unit(rig, parameter: str) -> str:
    """The unit of a mechanism's continued parameter (a bearing key, a drive key or the
    system's)."""
    from camdyn.continuation.autonomous import DRIVE_KEYS, is_autonomous, key_unit
    from camdyn.continuation.mechanisms import BEARING_KEYS
    from camdyn.continuation.problem import parameter_unit
    from camdyn.simulation.flexible_pivot import FlexiblePivotRig

    if parameter in BEARING_KEYS:
        if not isinstance(rig, FlexiblePivotRig):
            raise ParameterError(f"{parameter} is a key of the flexible pivot only")
        return BEARING_KEYS[parameter]
    if is_autonomous(rig):
        return key_unit(rig, parameter)
    if parameter in DRIVE_KEYS:
        raise ParameterError(f"{parameter} is a key of a cam under its drive (the driven cam, or two followers "
                             "whose drive.kind is not 'prescribed')")
    return parameter_unit(rig.system, parameter)


class _Bar:
    """The progress of a continuation on standard error (nothing when ``quiet``): what it
    is doing, the parameter's way through the range, the orbits found and the time
    taken; after the first orbit, a notice when the point budget at that orbit's cost
    would take more than :data:`LONG_RUN` seconds."""

    def __init__(self, quiet: bool, parameter: str, unit: str, first: float, last: float, budget: int):
        self.quiet, self.parameter, self.unit = quiet, parameter, unit
        self.first, self.last, self.budget = first, last, budget
        self.count, self.progress, self.task, self.started = 0, None, None, 0.0

    def __enter__(self):
        import time

        self.started = time.monotonic()
        if self.quiet:
            return self
        from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

        self.progress = Progress(TextColumn("{task.description}"), BarColumn(), TextColumn("{task.fields[orbits]} "
                                 "orbits"), TimeElapsedColumn(), console=err_console, transient=True)
        self.progress.__enter__()
        self.task = self.progress.add_task(f"continuing in {self.parameter}", total=1.0, orbits=0)
        return self

    def __exit__(self, *exc):
        if self.progress is not None:
            self.progress.__exit__(*exc)
        return False

    def phase(self, text: str) -> None:
        """Say what the continuation does now."""
        if self.progress is not None and text:
            self.progress.update(self.task, description=f"{self.parameter}: {text}")

    def orbit(self, orbit) -> None:
        """One more orbit found."""
        import time

        self.count += 1
        if self.count == 1:
            cost = time.monotonic() - self.started
            if cost * self.budget > LONG_RUN and not self.quiet:
                err_console.print(f"note: the first orbit took {cost:.0f} s; up to {self.budget} orbits "
                                  f"(--max-points, --doublings) may take about {cost * self.budget / 3600:.1f} h. "
                                  "Ctrl-C stops it.", highlight=False, soft_wrap=True)
        if self.progress is None:
            return
        done = min(max((orbit.parameter - self.first) / (self.last - self.first), 0.0), 1.0)
        self.progress.update(self.task, completed=done, orbits=self.count,
                             description=f"{self.parameter} = {orbit.parameter:.6g} {self.unit}")


#: A continuation whose point budget at its first orbit's cost exceeds this [s] is announced.
LONG_RUN = 600.0
