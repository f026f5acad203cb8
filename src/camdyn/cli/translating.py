"""``camdyn simulate`` for a translating follower on a cam profile: the configuration's
``[follower] kind = "translating"`` (or the preset ``alzate``) sends the command here."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from rich.table import Table

from camdyn.cli.common import console
from camdyn.cli.outputs import announce, emit_json, report_run
from camdyn.errors import ParameterError
from camdyn.params.config import parse_assignments
from camdyn.params.units import parse_quantity, parse_speed

__all__ = ["simulate_translating_command", "bifurcation_translating_command", "continue_translating_command",
           "translating_summary"]

#: The tolerance of a translating follower's run when --rtol is not given [-].
DEFAULT_RTOL = 1e-10


def translating_summary(ds, follower) -> dict:
    """The headline numbers of a translating follower's run (docs/cli-json.md)."""
    from camdyn.simulation.translating import liftoff_speed

    speed = float(ds.attrs["speed_rad_s"])
    revolutions = float(ds["time"][-1] - ds["time"][0]) * speed / (2.0 * math.pi)
    kinds = ds["event_kind"].values
    count = {kind: int(np.count_nonzero(kinds == kind)) for kind in ("impact", "separation", "capture", "graze",
                                                                     "contact onset")}
    impacts = count["impact"] + count["contact onset"]
    liftoff = liftoff_speed(follower, samples=20_000)
    return {
        "preset": ds.attrs.get("name", ""),
        "speed_hz": speed / (2.0 * math.pi),
        "speed_rpm": 60.0 * speed / (2.0 * math.pi),
        "revolutions": revolutions,
        "contact": ds.attrs["contact"],
        "impacts": impacts,
        "impacts_per_revolution": impacts / revolutions if revolutions else 0.0,
        "separations": count["separation"] if ds.attrs["contact"] == "rigid" else int(
            np.count_nonzero(kinds == "contact end")),
        "captures": count["capture"],
        "contact_force_max_N": float(ds["contact_force"].max()),
        "gap_max_m": float(ds["gap"].max()),
        "contact_fraction": float(ds["in_contact"].mean()),
        "liftoff_speed_rpm": 60.0 * liftoff / (2.0 * math.pi) if math.isfinite(liftoff) else None,
        "elapsed_s": float(ds.attrs["elapsed_s"]),
        "solver": {k[7:]: v for k, v in ds.attrs.items() if k.startswith("solver_")},
    }


def run_span(name: str, default_speed: float | None, speed: str | None, revolutions: float,
             sample_rate: str) -> tuple[float, float, float]:
    """The cam's angular speed [rad/s] (``--speed``, else the configuration's), the run's
    duration [s] and its sample rate [Hz] for ``camdyn simulate`` on a follower of a
    profile configuration (translating or rocking), refused before any work."""
    omega = 2.0 * math.pi * parse_speed(speed, "--speed") if speed is not None else default_speed
    if omega is None:
        raise ParameterError(f"{name} gives no cam speed: add motion.speed to the file or pass --speed")
    if not (isinstance(revolutions, (int, float)) and math.isfinite(revolutions) and revolutions > 0):
        raise ParameterError(f"--revolutions must be positive, got {revolutions!r}")
    return omega, revolutions * 2.0 * math.pi / omega, parse_quantity(sample_rate, "Hz", "--sample-rate")


def friction_summary(ds) -> dict:
    """The friction's headline numbers of a run with friction at the cam contact."""
    kinds = ds["event_kind"].values
    return {"friction": {"static": float(ds.attrs["static_friction"]), "kinetic": float(ds.attrs["kinetic_friction"]),
                         "friction_force_max_N": float(np.abs(ds["friction_force"]).max()),
                         "slip_velocity_max_m_per_s": float(np.abs(ds["slip_velocity"]).max()),
                         "friction_heat_J": float(ds["friction_heat"][-1]),
                         "rolling_fraction": float(ds["rolling"].mean()),
                         "rolling_starts": int(np.count_nonzero(kinds == "rolling")),
                         "slips": int(np.count_nonzero(kinds == "slip"))}}


def add_run_rows(table: Table, out: dict) -> None:
    """The summary table's last rows, shared by the profile followers: time in contact,
    lift-off speed and the solver's counts."""
    table.add_row("time in contact", f"{100 * out['contact_fraction']:.1f} %")
    liftoff = out["liftoff_speed_rpm"]
    table.add_row("lift-off speed of the cam", "never" if liftoff is None else f"{liftoff:.5g} rpm")
    s = out["solver"]
    table.add_row("solver", f"{s['accepted_steps']} steps ({s['rejected_steps']} rejected), {s['events']} events, "
                            f"{out['elapsed_s'] * 1e3:.1f} ms")


def _print(out: dict) -> None:
    table = Table("quantity", "value", title=f"simulation of {out['preset']} (translating follower)")
    table.add_row("cam speed", f"{out['speed_rpm']:.5g} rpm")
    table.add_row("revolutions", f"{out['revolutions']:.4g}")
    table.add_row("contact law", out["contact"])
    table.add_row("impacts", f"{out['impacts']} ({out['impacts_per_revolution']:.3g} per revolution)")
    table.add_row("lift-off events (separations)", f"{out['separations']}")
    table.add_row("captures into sustained contact", f"{out['captures']}")
    table.add_row("max contact force", f"{out['contact_force_max_N']:.5g} N")
    table.add_row("max gap (flight height)", f"{out['gap_max_m'] * 1e3:.4g} mm")
    add_friction_rows(table, out)
    add_run_rows(table, out)
    console.print(table)


def add_friction_rows(table: Table, out: dict) -> None:
    """The friction's rows of a summary table, where the run had friction."""
    if "friction" not in out:
        return
    f = out["friction"]
    table.add_row("friction mu_s / mu_k", f"{f['static']:.4g} / {f['kinetic']:.4g}")
    table.add_row("max friction force", f"{f['friction_force_max_N']:.5g} N")
    table.add_row("max slip velocity", f"{f['slip_velocity_max_m_per_s']:.4g} m/s")
    table.add_row("heat of friction", f"{f['friction_heat_J']:.5g} J")
    table.add_row("roller rolling", f"{100 * f['rolling_fraction']:.1f} % of the time ({f['rolling_starts']} "
                                    f"starts, {f['slips']} slips)")


def simulate_translating_command(source: str, assignments, speed: str | None, revolutions: float,
                                 sample_rate: str, out: Path | None, plot: Path | None, method: str,
                                 rtol: float | None, json_out: bool) -> None:
    """Run ``camdyn simulate`` on a translating follower (the outputs are checked already)."""
    from camdyn.io.lift_table import load_translating
    from camdyn.simulation.sliding import friction_from_spec, simulate_sliding
    from camdyn.simulation.translating import simulate_translating

    if method != "auto":
        raise ParameterError(f"--method {method}: the translating follower is integrated with the automatic "
                             "method only (leave --method out)")
    follower, spec = load_translating(source, parse_assignments(assignments))
    omega, duration, fs = run_span(spec.name, spec.speed, speed, revolutions, sample_rate)
    friction = friction_from_spec(spec)
    tolerance = DEFAULT_RTOL if rtol is None else rtol
    cam = f"{float(omega)!r} rad/s"   # the entries read Hz or text with units; this keeps omega exactly
    if friction is None:
        ds = simulate_translating(follower, cam, duration, sample_rate=fs, phase=spec.phase, rtol=tolerance)
    else:
        ds = simulate_sliding(follower, friction, cam, duration, sample_rate=fs, phase=spec.phase, rtol=tolerance)
    ds.attrs["name"] = spec.name
    summary = translating_summary(ds, follower)
    if friction is not None:
        summary.update(friction_summary(ds))
    draw = None
    if plot is not None:
        from camdyn.plotting.translating import plot_translating_history as draw
    report_run(ds, summary, "simulate-translating", _print, out, json_out, plot, draw)


def _without_friction(source: str, assignments, command: str):
    """The follower and its configuration, refused where the configuration has friction
    at the cam contact: the diagram and the continuation integrate the follower without
    it, so their results would not be this configuration's."""
    from camdyn.io.lift_table import load_translating
    from camdyn.simulation.sliding import friction_from_spec

    follower, spec = load_translating(source, parse_assignments(assignments))
    if friction_from_spec(spec) is not None:
        raise ParameterError(f"{command} does not take friction at the cam contact yet ({spec.name} has a "
                             "[friction] table); camdyn simulate runs it with its friction")
    return follower, spec


def bifurcation_translating_command(source: str, assignments, speeds: str, revolutions: int, discard: int,
                                    out: Path, plot: Path | None, workers: int | None, dask: str | None,
                                    quiet: bool) -> None:
    """Run ``camdyn bifurcation`` on a translating follower: its Poincaré section at cam
    angle 0 (:func:`camdyn.analysis.poincare.poincare_section`), one process, written to
    ``out`` and drawn to ``plot`` (the outputs are checked already)."""
    from camdyn.analysis.poincare import poincare_section
    from camdyn.cli.common import parse_grid
    from camdyn.io.netcdf import save_netcdf
    from camdyn.plotting.translating import plot_poincare_diagram
    from camdyn.simulation.translating import liftoff_speed

    if workers is not None or dask is not None:
        raise ParameterError("--workers and --dask: the translating follower's diagram runs in one process")
    if not 0 <= discard < revolutions:
        raise ParameterError(f"--discard ({discard}) must be at least 0 and below --revolutions ({revolutions})")
    follower, spec = _without_friction(source, assignments, "camdyn bifurcation")
    hz = parse_grid(speeds, "--speeds", "Hz")
    rpm = 60.0 * hz
    section = poincare_section(follower, hz, transient=discard, revolutions=revolutions - discard)
    section.attrs["name"] = spec.name
    save_netcdf(section, out)
    announce(out)
    liftoff = 60.0 * liftoff_speed(follower, samples=20_000) / (2.0 * math.pi)
    marks = {f"lift-off {liftoff:.5g} rpm": liftoff} if rpm.min() <= liftoff <= rpm.max() else {}
    figure = plot or out.with_suffix(".png")
    plot_poincare_diagram(section, figure, marks)
    announce(figure)
    if not quiet:
        stopped = int(np.count_nonzero(section["status"].values != "ok"))
        console.print(f"{rpm.size} speeds, {discard} + {revolutions - discard} revolutions each: "
                      f"{section.attrs['total_elapsed_s']:.1f} s; speeds whose runs stopped: {stopped}",
                      markup=False, highlight=False)


def continue_translating_command(source: str, assignments, parameter: str, start: str, stop: str, period: int,
                                 step: float, max_points: int, transient: int, doublings: int, brute_force: int,
                                 plot: Path | None, out: Path | None, quiet: bool, json_out: bool,
                                 cover: bool = True, max_time: float = math.inf) -> None:
    """Run ``camdyn continue`` on a translating follower: its branch of periodic orbits in
    the cam speed, the orbits' state at cam angle 0 (the section of ``camdyn
    bifurcation``), the period-doubled branches born on it, and with ``--brute-force N``
    the Poincaré section at N speeds under the branches of ``--plot`` (the outputs are
    checked already); with ``cover``, restarts past where a branch ends inside the range
    (:func:`~camdyn.continuation.coverage.covered_branches`)."""
    from camdyn.cli.common import check_continue_settings
    from camdyn.continuation.coverage import STALL_POINTS, coverage_summary, covered_branches, gap_records
    from camdyn.continuation.translating import RPM, SPEED_KEY, trace_translating, translating_dataset

    if parameter != SPEED_KEY:
        raise ParameterError(f"--parameter {parameter}: a translating follower is continued in {SPEED_KEY} only")
    first, last = 2.0 * math.pi * parse_speed(start, "--from"), 2.0 * math.pi * parse_speed(stop, "--to")
    if not (first > 0 and last > 0 and math.isfinite(first) and math.isfinite(last)) or first == last:
        raise ParameterError(f"--from and --to must be two different positive cam speeds, got {start} and {stop}")
    check_continue_settings(period, max_points, transient, step, doublings, brute_force, plot)
    follower, spec = _without_friction(source, assignments, "camdyn continue")
    problem, branch = trace_translating(follower, f"{float(first)!r} rad/s", f"{float(last)!r} rad/s", period,
                                        step=step, max_points=max_points, transient=transient,
                                        stall=STALL_POINTS if cover else 0)
    coverage, branches = covered_branches(problem, branch, first, last, step, max_points, transient, doublings,
                                          cover, max_time)
    ds = translating_dataset(problem, branches)
    ds.attrs["name"] = spec.name
    files = []
    if out is not None:
        from camdyn.io.netcdf import save_netcdf
        files.append(announce(save_netcdf(ds, out), json_out))
    if plot is not None:
        from camdyn.plotting.translating import plot_poincare_diagram
        section = None
        if brute_force:
            from camdyn.analysis.poincare import poincare_section
            section = poincare_section(follower, np.linspace(first, last, brute_force) / (2.0 * math.pi), transient=200,
                                       revolutions=40)
        files.append(announce(plot_poincare_diagram(section, plot, None, branches=ds), json_out))
    found = [{"kind": str(k), "parameter": float(v), "speed_rpm": float(v) / RPM, "branch": int(b)}
             for k, v, b in zip(ds["bifurcation_kind"].values, ds["bifurcation_parameter"].values,
                                ds["bifurcation_branch"].values)]
    if json_out:
        summary = {"parameter": SPEED_KEY, "units": "rad/s", **coverage_summary(coverage, branches),
                   "bifurcation_count": len(found)}
        emit_json("continue", summary, branches=_orbit_records(ds, len(branches)), bifurcations=found,
                  gaps=gap_records(coverage), files=files)
        return
    for index, item in enumerate(branches):
        rpm = [o.parameter / RPM for o in item.orbits]
        console.print(f"{len(rpm)} orbits of period {item.orbits[0].periods} over {SPEED_KEY} = {rpm[0]:.6g} to "
                      f"{rpm[-1]:.6g} rpm, {sum(o.stable for o in item.orbits)} stable; {item.stopped}"
                      + ("" if index == 0 else f" (branch {index})"), highlight=False, soft_wrap=True)
    for item in found:
        console.print(f"  {item['kind']} at {SPEED_KEY} = {item['speed_rpm']:.9g} rpm (branch {item['branch']})",
                      highlight=False, soft_wrap=True)
    for gap in coverage.gaps:
        console.print(f"gap from {SPEED_KEY} = {gap.start / RPM:.6g} to {gap.stop / RPM:.6g} rpm: {gap.reason}",
                      highlight=False, soft_wrap=True)


def _orbit_records(ds, count: int) -> list[list[dict]]:
    """Per branch, per orbit of a translating follower's branches dataset: ``parameter``
    [rad/s], ``speed_rpm``, ``stable``, ``multipliers`` (``[re, im]`` pairs), ``periods``,
    ``impacts_per_period``, ``state`` (``[x [m], x_dot [m/s]]`` at cam angle 0) and
    ``poincare`` (x [m] once per revolution of the orbit)."""
    records = [[] for _ in range(count)]
    for i in range(ds.sizes["point"]):
        k = int(ds["periods"].values[i])
        records[int(ds["branch"].values[i])].append({
            "parameter": float(ds["parameter"].values[i]), "speed_rpm": float(ds["speed_rpm"].values[i]),
            "stable": bool(ds["stable"].values[i]),
            "multipliers": [[float(a), float(b)] for a, b in zip(ds["multiplier_real"].values[i],
                                                                  ds["multiplier_imag"].values[i])],
            "periods": k, "impacts_per_period": int(ds["impacts_per_period"].values[i]),
            "state": [float(ds["poincare_x"].values[i, 0]), float(ds["poincare_x_dot"].values[i, 0])],
            "poincare": [float(v) for v in ds["poincare_x"].values[i, :k]]})
    return records
