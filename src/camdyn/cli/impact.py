"""CLI commands of the impact studies (thesis chapter 3): ``camdyn identify
impact-damping`` and ``camdyn identify restitution``, registered on the ``identify``
group by :mod:`camdyn.cli.app`."""

from __future__ import annotations

import math
from contextlib import nullcontext
from pathlib import Path
from typing import List, Optional

import numpy as np
import typer
from rich.table import Table

from camdyn.cli.common import ForceOption, JsonOption, SetOption, console, err_console, load_source
from camdyn.cli.outputs import announce, check_outputs, emit_json
from camdyn.errors import ParameterError
from camdyn.params.units import parse_quantity, parse_speed


def _per_record(values: Optional[List[str]], count: int, what: str, parse) -> list:
    if not values:
        return [None] * count
    out = [parse(v) for v in values]
    if len(out) == 1:
        return out * count
    if len(out) != count:
        raise ParameterError(f"give one {what} for all records or one per record ({count}), got {len(out)}")
    return out


def _check_distinct(paths: List[Path]) -> None:
    """Refuse a record named twice (by the same or another path to the same file)."""
    seen: dict = {}
    for path in paths:
        key = Path(path).resolve()
        if key in seen:
            raise ParameterError(f"the record {path} is given twice (as {seen[key]} before): each record must be "
                                 f"a different operating point (a record given twice counts its impacts twice)")
        seen[key] = path


#: Headline keys of the impact-damping estimate (JSON ``summary``); the rest are details,
#: with the per-impact table last.
_IMPACT_SUMMARY = ("method", "beta", "beta_units", "n", "mode", "residue", "residue_used", "impacts_used",
                   "records", "correlation", "damping_at_peak", "damping_at_peak_units", "peak_penetration",
                   "peak_penetration_units")


def _impact_figures(plot_dir: Optional[Path], free: bool) -> list:
    if plot_dir is None:
        return []
    return [Path(plot_dir) / "impact_force.png"] + ([Path(plot_dir) / "residue_landscape.png"] if free else [])


#: Methods of ``camdyn identify impact-damping``: the thesis's residues of trial
#: simulations (the default), the direct restoring-force regression, and the output-error
#: fit of the impacts' force histories started from the direct estimate.
IMPACT_METHODS = ("residue", "direct", "output-error")
#: Headline keys of the direct estimate (JSON ``summary``).
_DIRECT_SUMMARY = ("method", "beta", "beta_units", "n", "mode", "correlation", "identifiable", "impacts_used",
                   "records", "damping_at_peak", "damping_at_peak_units", "peak_penetration",
                   "peak_penetration_units")


def _check_method(method: str, residue, bootstrap, plot_dir, fit_stiffness: bool) -> str:
    """Refuse an unknown method, or an option the chosen method does not take."""
    method = method.strip().lower()
    if method not in IMPACT_METHODS:
        raise ParameterError(f"unknown method {method!r}: choose one of {', '.join(IMPACT_METHODS)}")
    only = {"residue": {"--residue": residue is not None, "--bootstrap": bootstrap is not None,
                        "--plot-dir": plot_dir is not None},
            "direct": {"--fit-stiffness": fit_stiffness}}
    for owner, options in only.items():
        given = [name for name, used in options.items() if used]
        if owner != method and given:
            raise ParameterError(f"{given[0]} applies to --method {owner} only, not to --method {method}")
    return method


def identify_impact_damping(
        source: str = typer.Argument(..., metavar="PRESET_OR_TOML"),
        data: List[Path] = typer.Argument(..., help="Records (one per operating point): Nx, Ny, alpha_ddot or a_t."),
        set_: Optional[List[str]] = SetOption,
        speed: Optional[List[str]] = typer.Option(None, metavar="SPEED", help="Cam speed (once, or once per "
                                                  "record); default from each file's metadata."),
        runout: Optional[List[str]] = typer.Option(None, metavar="LENGTH", help="Cam runout e (once, or per "
                                                   "record); default from each file's metadata, else the preset's."),
        method: str = typer.Option("residue", metavar="METHOD", help="residue (the thesis's trial simulations, "
                                   "default), direct (restoring-force regression on the rebuilt contact force) or "
                                   "output-error (the impacts' force histories fitted by simulation, one record)."),
        fix_n: Optional[float] = typer.Option(None, "--fix-n", help="Fix the exponent n (e.g. 1.5, 1.45; "
                                                                    "0 = viscous)."),
        residue: Optional[str] = typer.Option(None, help="Residue minimised: lambda1, lambda2, lambda3 or combined "
                                                         "(default lambda1 with n fixed, combined with n free; "
                                                         "residue method)."),
        bootstrap: Optional[int] = typer.Option(None, help="Bootstrap replicates over impacts (0: none; "
                                                           "default 64; residue method)."),
        fit_stiffness: bool = typer.Option(False, "--fit-stiffness", help="Fit a factor on the Hertz "
                                           "coefficient K as well (direct method)."),
        plot_dir: Optional[Path] = typer.Option(None, "--plot-dir", help="Write the force, hysteresis and "
                                                "residue-landscape figures here (residue method)."),
        force: bool = ForceOption,
        json_out: bool = JsonOption):
    """Impact damping beta, n of Fn = K delta^1.5 + beta delta^n delta_dot (thesis 3.5)."""
    from camdyn.identification.impact_damping import check_bootstrap
    from camdyn.io.measurements import read_measurement

    method = _check_method(method, residue, bootstrap, plot_dir, fit_stiffness)
    bootstrap = 64 if bootstrap is None else bootstrap
    check_bootstrap(bootstrap)
    _check_distinct(data)
    targets = _impact_figures(plot_dir, fix_n is None)
    check_outputs(figures=targets, force=force)
    system = load_source(source, set_)
    records = [read_measurement(p) for p in data]
    speeds = _per_record(speed, len(records), "speed", lambda s: parse_speed(s))
    runouts = _per_record(runout, len(records), "runout", lambda s: parse_quantity(s, "m", "cam.runout"))
    if method == "output-error" and len(records) != 1:
        raise ParameterError(f"--method output-error fits one record at a time, got {len(records)}")
    if method in ("direct", "output-error"):
        _identify_direct(system, records, speeds, runouts, fix_n, fit_stiffness, json_out, method)
    else:
        _identify_residue(system, records, speeds, runouts, fix_n, residue, bootstrap, targets, json_out)


def _identify_direct(system, records, speeds, runouts, fix_n, fit_stiffness, json_out, method) -> None:
    """The direct method, or the output-error fit started from it."""
    from camdyn.identification.impact_direct import estimate_impact_damping_direct
    from camdyn.identification.impact_output_error import estimate_impact_damping_output_error

    with err_console.status(f"identifying the impact damping ({method}) ...") if not json_out else nullcontext():
        if method == "direct":
            est = estimate_impact_damping_direct(system, records, speed=speeds, runout=runouts, exponent=fix_n,
                                                 fit_stiffness=fit_stiffness)
        else:
            est = estimate_impact_damping_output_error(system, records[0], speed=speeds[0], runout=runouts[0],
                                                       exponent=fix_n)
    if not json_out:
        _print_direct_table(est)
        return
    full = est.to_dict()
    summary = {k: full.pop(k) for k in _DIRECT_SUMMARY if k in full}
    per_impact = full.pop("per_impact")
    emit_json("identify-impact-damping", summary, **full, files=[], per_impact=per_impact)


def _bootstrap_correlation(est) -> float:
    """Correlation of the bootstrap replicates' ``beta`` and ``n`` [-] (NaN with ``n``
    fixed or fewer than 3 replicates)."""
    boot = np.asarray(est.bootstrap, float)
    if est.mode != "free" or boot.ndim != 2 or boot.shape[0] < 3:
        return math.nan
    boot = boot[np.all(np.isfinite(boot), axis=1)]
    if boot.shape[0] < 3 or np.ptp(boot[:, 0]) == 0 or np.ptp(boot[:, 1]) == 0:
        return math.nan
    return float(np.corrcoef(boot[:, 0], boot[:, 1])[0, 1])


def _identify_residue(system, records, speeds, runouts, fix_n, residue, bootstrap, targets, json_out) -> None:
    from camdyn.identification.impact_damping import estimate_impact_damping, residue_landscape

    with err_console.status("identifying the impact damping ...") if not json_out else nullcontext():
        est = estimate_impact_damping(system, records, speed=speeds, runout=runouts, exponent=fix_n,
                                      residue=residue, bootstrap=bootstrap)
    if not json_out:
        _print_impact_table(est)
    files = []
    if targets:
        from camdyn.plotting import plot_impact_fit, plot_residue_landscape
        files.append(announce(plot_impact_fit(est, targets[0]), json_out))
        if est.mode == "free":
            land = residue_landscape(est, points=15)
            files.append(announce(plot_residue_landscape(land, est, targets[1]), json_out))
    if json_out:
        full = est.to_dict() | {"method": "residue", "correlation": _bootstrap_correlation(est)}
        summary = {k: full.pop(k) for k in _IMPACT_SUMMARY}
        per_impact = full.pop("per_impact")
        emit_json("identify-impact-damping", summary, **full, files=files, per_impact=per_impact)


def _print_impact_table(est) -> None:
    table = Table("quantity", "value", "95 % bootstrap interval")
    ci = est.confidence
    table.add_row("beta", f"{est.beta:.5g} {est.beta_units}", f"{ci['beta'][0]:.4g} - {ci['beta'][1]:.4g}")
    table.add_row("n", f"{est.exponent:.5g}" + (" (fixed)" if est.mode != "free" else ""),
                  f"{ci['n'][0]:.4g} - {ci['n'][1]:.4g}")
    table.add_row("damping at the peak penetration", f"{est.damping_at_peak:.5g} N*s/m",
                  f"{ci['damping_at_peak'][0]:.4g} - {ci['damping_at_peak'][1]:.4g}")
    table.add_row("peak penetration", f"{est.peak_penetration * 1e6:.4g} um", "")
    for name, value in est.residues.items():
        table.add_row(f"mean |{name}| per impact", f"{value:.3g}", "")
    table.add_row("impacts used", f"{est.impacts_used} from {est.records} record(s)", "")
    console.print(table)


def _print_direct_table(est) -> None:
    direct = not hasattr(est, "evaluations")
    table = Table("quantity", "value", "95 % interval (impact-clustered)" if direct else "95 % interval (Jacobian)")
    ci = est.confidence
    table.add_row("method", "direct (restoring-force regression)" if direct
                  else "output-error (force histories simulated per impact)", "")
    table.add_row("beta", f"{est.beta:.5g} {est.beta_units}", f"{ci['beta'][0]:.4g} - {ci['beta'][1]:.4g}")
    table.add_row("n", f"{est.exponent:.5g}" + (" (fixed)" if est.mode != "free" else ""),
                  f"{ci['n'][0]:.4g} - {ci['n'][1]:.4g}")
    table.add_row("damping at the peak penetration", f"{est.damping_at_peak:.5g} N*s/m",
                  f"{ci['damping_at_peak'][0]:.4g} - {ci['damping_at_peak'][1]:.4g}")
    table.add_row("peak penetration", f"{est.peak_penetration * 1e6:.4g} um", "")
    if est.mode == "free":
        table.add_row("correlation of beta and n", f"{est.correlation:.5f}", "")
        if direct:
            table.add_row("n identifiable", "yes" if est.identifiable else "no", "")
    table.add_row("rms force residual", f"{est.rms_residual:.3g} N", "")
    table.add_row("impacts used", f"{est.impacts_used} from {est.records} record(s)", "")
    if not direct:
        table.add_row("start (direct)", f"beta {est.start['beta']:.5g}, n {est.start['n']:.5g}", "")
    console.print(table)
    if direct and not est.identifiable:
        err_console.print(f"warning: n is not identifiable: {est.diagnosis}")


def identify_restitution(
        source: str = typer.Argument(..., metavar="PRESET_OR_TOML"),
        data: Path = typer.Argument(..., help="Record with alpha_ddot or a_t (forces not needed)."),
        set_: Optional[List[str]] = SetOption,
        speed: Optional[str] = typer.Option(None, help="Cam speed; default from the file's metadata."),
        plot: Optional[Path] = typer.Option(None, help="Write the xi against v_a figure here (.png, .pdf, ...)."),
        force: bool = ForceOption,
        json_out: bool = JsonOption):
    """Equivalent restitution xi = 1 - gamma v_a and its Hunt-Crossley damping (thesis 3.8)."""
    from camdyn.identification.restitution import estimate_restitution
    from camdyn.io.measurements import read_measurement

    check_outputs(figure=plot, force=force)
    system = load_source(source, set_)
    est = estimate_restitution(system, read_measurement(data), speed=parse_speed(speed) if speed else None)
    if not json_out:
        table = Table("quantity", "value")
        table.add_row("gamma", f"{est.gamma:.5g} s/m")
        table.add_row("Hunt-Crossley beta = 1.5 gamma K", f"{est.beta_hunt_crossley:.5g} N*s/m^2.5")
        table.add_row("Hertz coefficient K", f"{est.stiffness:.5g} N/m^1.5")
        table.add_row("mean restitution xi", f"{est.mean_restitution:.4g}")
        table.add_row("mean approach velocity", f"{est.approach_velocity.mean():.4g} m/s")
        table.add_row("rms misfit of xi", f"{est.residual:.3g}")
        table.add_row("impacts used", str(est.impacts_used))
        console.print(table)
    files = []
    if plot is not None:
        from camdyn.plotting import plot_restitution
        plot_restitution(est, plot)
        files.append(announce(plot, json_out))
    if json_out:
        full = est.to_dict()
        per_impact = full.pop("per_impact")
        emit_json("identify-restitution", full, files=files, per_impact=per_impact)
