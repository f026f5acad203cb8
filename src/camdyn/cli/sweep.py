"""``camdyn sweep SPEC.toml`` (a parameter sweep, locally or on a Dask cluster), and the
bifurcation diagram and Lyapunov exponent built on it: ``camdyn bifurcation``, ``camdyn lyapunov``."""

from __future__ import annotations

from pathlib import Path
from typing import List, Optional

import typer

from camdyn.cli.common import (
    ForceOption,
    JsonOption,
    SetOption,
    console,
    err_console,
    notice_if_uncached,
    parse_grid,
)
from camdyn.cli.outputs import announce, check_outputs, emit_json
from camdyn.errors import ParameterError
from camdyn.sweeps.metrics import REGIMES


def sweep(spec_path: Path = typer.Argument(..., metavar="SPEC.toml", help="Sweep specification (docs/sweeps.md)."),
          workers: Optional[int] = typer.Option(None, help="Worker processes (default: every core; 0 runs inline). "
                                                           "With --dask local, the number of Dask workers."),
          dask: Optional[str] = typer.Option(None, help="'local' for a Dask LocalCluster, or a scheduler address "
                                                        "tcp://HOST:PORT."),
          threads: int = typer.Option(1, help="Numba threads per worker (prange over the points of a chunk)."),
          out: Optional[Path] = typer.Option(None, help="Result file (.nc); default the spec's \\[output] path, "
                                                        "relative to the working directory."),
          restart: bool = typer.Option(False, "--restart", help="Discard this output's checkpoints instead of "
                                                                "resuming."),
          keep_parts: bool = typer.Option(False, "--keep-parts", help="Keep the per-chunk checkpoint files."),
          plot: Optional[Path] = typer.Option(None, help="Figure path (default: the result's name with .png)."),
          no_plot: bool = typer.Option(False, "--no-plot", help="Write no figure."),
          force: bool = typer.Option(False, "--force", help="Overwrite an existing result and figure (checkpoints "
                                                            "are resumed, or discarded with --restart)."),
          quiet: bool = typer.Option(False, "--quiet", help="No progress bar."),
          json_: bool = JsonOption):
    """Run a parameter sweep; resume it from its checkpoints if it was interrupted.

    A relative result path in the spec (its output table) is taken relative to the
    working directory, not to the spec's folder."""
    import dataclasses

    from camdyn.plotting import plot_sweep
    from camdyn.sweeps import load_spec, run_sweep

    spec = load_spec(spec_path)
    if out is not None:
        spec = dataclasses.replace(spec, output=out)
    figure = None if no_plot else plot or spec.output.with_suffix(".png")
    check_outputs(netcdf=spec.output, figure=figure, force=force)
    from camdyn.sweeps.execution import check_dask_address

    check_dask_address(dask)   # before the compile notice: bad input is refused before any work
    notice_if_uncached(sweeps=True)
    ds = run_sweep(spec, workers=workers, dask=dask, threads=threads, progress=not (quiet or json_),
                   restart=restart, keep_parts=keep_parts, echo=_echo_err if json_ else _echo)
    failed = int((ds["status"] != 0).sum())
    files = [announce(spec.output, json_, detail=f": {spec.points} points, {failed} failed")]
    reasons = sorted(set(str(r) for r in ds["failure"].values.ravel() if str(r)))
    for reason in reasons[:5]:
        (err_console if json_ else console).print(f"  failed: {reason}", highlight=False, soft_wrap=True)
    if figure is not None:
        files.append(announce(plot_sweep(ds, figure), json_))
    if json_:
        summary = {"points": spec.points, "failed": failed, "mechanism": spec.mechanism or None}
        if "regime" in ds:
            summary["regimes"] = {name: int((ds["regime"] == code).sum()) for code, name in REGIMES.items()}
        emit_json("sweep", summary, swept={v.key: v.unit for v in spec.vary}, metrics=list(spec.metrics),
                  failures=reasons[:5], files=files)
    ds.close()


def _echo(message: str) -> None:
    console.print(message, markup=False, highlight=False, soft_wrap=True)


def _echo_err(message: str) -> None:
    err_console.print(message, markup=False, highlight=False, soft_wrap=True)


def bifurcation(source: str = typer.Argument(..., metavar="PRESET_OR_TOML"),
                set_: Optional[List[str]] = SetOption,
                speeds: str = typer.Option("5Hz:30Hz:200",
                                           help="START:STOP:COUNT cam speeds (inclusive), or a comma list."),
                revolutions: int = typer.Option(300, help="Cam periods simulated per speed."),
                discard: int = typer.Option(200, help="Of which the first are dropped (transient)."),
                out: Path = typer.Option(Path("bifurcation.nc"), help="Result file (.nc)."),
                plot: Optional[Path] = typer.Option(None, help="Figure (default: the result's name with .png)."),
                workers: Optional[int] = typer.Option(None, help="Worker processes (default every core)."),
                dask: Optional[str] = typer.Option(None, help="'local' or a scheduler address tcp://HOST:PORT."),
                restart: bool = typer.Option(False, "--restart", help="Discard checkpoints instead of resuming."),
                force: bool = ForceOption,
                quiet: bool = typer.Option(False, "--quiet", help="No progress bar.")):
    """Bifurcation diagram over cam speed: Poincare samples once per revolution, impacts per
    revolution, period and regime (a sweep; see 'camdyn sweep' for the general form). A
    mechanism held at its speed (the flexible pivot, two followers with a prescribed drive)
    is swept in system.motion.speed, a model of your own (FILE.py:NAME) in its speed, with
    their own metrics. For a translating follower (preset alzate, or [follower] kind =
    "translating"): its state at cam angle 0 of each revolution after --discard, in one
    process (docs/profiles.md)."""
    from camdyn.params.config import parse_assignments
    from camdyn.params.profiles import is_translating
    from camdyn.plotting import plot_sweep
    from camdyn.sweeps import run_sweep, spec_from_dict
    from camdyn.sweeps.families import family_of as sweep_family

    check_outputs(netcdf=out, figure=plot or out.with_suffix(".png"), force=force)
    if is_translating(source):
        from camdyn.cli.translating import bifurcation_translating_command
        bifurcation_translating_command(source, set_, speeds, revolutions, discard, out, plot, workers, dask, quiet)
        return
    grid = parse_grid(speeds, "--speeds", "Hz")
    family = sweep_family(source, parse_assignments(set_), Path.cwd())
    if not family.speed_key:
        raise ParameterError(f"{source}: its drive turns the cam, whose speed is the run's: vary a drive key "
                             "with camdyn sweep instead (docs/sweeps.md)")
    table = {"system": {"source": source, "set": parse_assignments(set_)},
             "vary": [{"key": family.speed_key, "values": [float(v) for v in grid]}],
             "run": {"revolutions": revolutions, "discard": discard},
             "metrics": {"names": list(family.diagram_metrics)},
             "output": {"path": str(out)}}
    spec = spec_from_dict(table, name=out.stem)
    from camdyn.sweeps.execution import check_dask_address

    check_dask_address(dask)   # before the compile notice: bad input is refused before any work
    notice_if_uncached(sweeps=True)
    ds = run_sweep(spec, workers=workers, dask=dask, progress=not quiet, restart=restart, echo=_echo)
    announce(out)
    announce(plot_sweep(ds, plot or out.with_suffix(".png")))
    if "regime" in ds:
        counts = {name: int((ds.regime == code).sum()) for code, name in REGIMES.items()}
        _echo("regimes: " + ", ".join(f"{k} {v}" for k, v in counts.items() if v))
    ds.close()


def lyapunov(source: str = typer.Argument(..., metavar="PRESET_OR_TOML"),
             set_: Optional[List[str]] = SetOption,
             speed: str = typer.Option(..., help="Cam speed, e.g. 18Hz or 1080rpm."),
             revolutions: int = typer.Option(400, help="Cam periods averaged."),
             transient: int = typer.Option(200, help="Cam periods dropped first."),
             spectrum: bool = typer.Option(False, "--spectrum", help="Also both exponents from the variational "
                                                                     "equations with saltation [1/s]."),
             json_: bool = JsonOption):
    """Largest Lyapunov exponent of the steady motion at one speed (two nearby trajectories
    through every impact, renormalised once per revolution); with --spectrum also the
    whole spectrum from the state-transition matrix, re-orthonormalised once per revolution,
    and whether the two largest exponents agree within their standard errors. Every
    family at a prescribed cam speed: the thesis's follower, the translating follower,
    the flexible pivot and two followers held at their speed, a model of your own
    (FILE.py:NAME)."""
    from camdyn.analysis.chaos import agreement
    from camdyn.params.units import parse_speed

    hz = parse_speed(speed)
    result, full = _lyapunov(source, set_, hz, revolutions, transient, spectrum)
    half = result.running[revolutions // 2 - 1] if revolutions >= 2 else float("nan")
    agree, verdict_text = agreement(result, full) if full is not None else (None, "")
    if json_:
        summary = {"speed_hz": result.speed, "exponent_per_s": result.exponent,
                   "exponent_error_per_s": result.error,
                   "per_revolution": result.per_revolution, "chaotic": bool(result.exponent > 0)}
        details = {}
        if full is not None:
            summary.update(spectrum_per_s=[float(x) for x in full.exponents],
                           spectrum_error_per_s=[float(x) for x in full.errors],
                           spectrum_per_revolution=[float(x) for x in full.per_period],
                           spectrum_sum_per_s=full.total, estimates_agree=agree)
            details = {"kaplan_yorke_dimension": full.kaplan_yorke_dimension, "spectrum_events": full.events,
                       "agreement": verdict_text}
        emit_json("lyapunov", summary, exponent_half_record_per_s=float(half), revolutions=revolutions,
                  transient=transient, **details)
        return
    verdict = "chaotic" if result.exponent > 0 else "not chaotic (attracting)"
    console.print(f"largest Lyapunov exponent at {result.speed:g} Hz: {result.exponent:.4g} +- {result.error:.2g} "
                  f"1/s (standard error; {result.per_revolution:.4g} per revolution; {float(half):.4g} 1/s over the "
                  f"first half): {verdict}", highlight=False, soft_wrap=True)
    if full is not None:
        values = ", ".join(f"{x:.4g} +- {e:.2g}" for x, e in zip(full.exponents, full.errors))
        console.print(f"Lyapunov spectrum (variational equations with saltation): {values} 1/s; sum "
                      f"{full.total:.4g} 1/s; Kaplan-Yorke dimension {full.kaplan_yorke_dimension:.3g}",
                      highlight=False, soft_wrap=True)
        console.print(verdict_text, highlight=False, soft_wrap=True)


def _lyapunov(source, set_, hz: float, revolutions: int, transient: int, spectrum: bool):
    """``(largest exponent, spectrum or None)`` of the configuration ``source`` at ``hz``
    [Hz]: the thesis's follower by its own compiled estimate, any other family through its
    periodic problem (:mod:`camdyn.continuation.lyapunov`)."""
    from camdyn.params.config import parse_assignments
    from camdyn.systems.families import family_of

    if family_of(source) == "cam-follower":
        from camdyn.analysis.chaos import lyapunov_exponent
        from camdyn.analysis.lyapunov import lyapunov_spectrum
        from camdyn.cli.common import load_source

        system = load_source(source, set_)
        result = lyapunov_exponent(system, speed=hz, revolutions=revolutions, transient=transient)
        full = lyapunov_spectrum(system, speed=hz, revolutions=revolutions, transient=transient) if spectrum else None
        return result, full
    from camdyn.cli.problems import source_problem
    from camdyn.continuation.lyapunov import orbit_lyapunov, orbit_spectrum

    problem = source_problem(source, parse_assignments(set_), hz)
    result = orbit_lyapunov(problem, revolutions=revolutions, transient=transient)
    return result, (orbit_spectrum(problem, revolutions=revolutions, transient=transient) if spectrum else None)
