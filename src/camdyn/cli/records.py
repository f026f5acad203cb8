"""Commands for identification, tribology and experiment design, registered on the
main ``camdyn`` app by :mod:`camdyn.cli.app`."""

from __future__ import annotations

import math
from pathlib import Path
from typing import List, Optional

import numpy as np
import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

from camdyn.cli.common import (
    ForceOption,
    JsonOption,
    SetOption,
    console,
    load_source,
    parse_grid,
    parse_hertz,
)
from camdyn.cli.outputs import announce, check_outputs, emit_json
from camdyn.errors import ParameterError
from camdyn.params.units import parse_quantity, parse_speed


def synthesize(source: str = typer.Argument(..., metavar="PRESET_OR_TOML"),
               set_: Optional[List[str]] = SetOption,
               speed: Optional[str] = typer.Option(None, help="Cam speed, e.g. 16Hz or 960rpm."),
               revolutions: float = typer.Option(40.0, help="Revolutions kept in the record."),
               sample_rate: str = typer.Option("20kHz", "--sample-rate", help="Sampling rate."),
               noise: float = typer.Option(0.0, help="Gaussian noise per channel, fraction of its rms (0.01 = 1 %)."),
               settle: float = typer.Option(20.0, help="Revolutions simulated and dropped first (transient)."),
               seed: int = typer.Option(0, help="Noise seed."),
               channels: str = typer.Option("Nx,Ny,alpha_ddot", help="Channels: Nx, Ny, alpha_ddot, a_t."),
               restitution_gamma: Optional[str] = typer.Option(
                   None, "--restitution-gamma", help="Simulate instantaneous impacts xi = 1 - gamma v_a "
                                                     "(simulation S3) with this gamma, e.g. 0.8s/m; "
                                                     "records alpha_ddot only."),
               out: Path = typer.Option(..., help="Output file: .csv, .nc or .uff."),
               force: bool = ForceOption):
    """Simulate a measurement record (steady state, optional noise) and write it."""
    from camdyn.io.measurements import write_measurement
    from camdyn.records.synthesis import synthesize as make
    from camdyn.records.synthesis import synthesize_impact_map

    check_outputs(record=out, force=force)
    system = load_source(source, set_)
    rate = parse_hertz(sample_rate)
    if restitution_gamma is not None:
        gamma = parse_quantity(restitution_gamma, "s/m", "restitution gamma")
        rec = synthesize_impact_map(system, parse_speed(speed) if speed else None, revolutions=revolutions,
                                    sample_rate=rate, gamma=gamma, noise=noise, settle=settle, seed=seed)
    else:
        rec = make(system, parse_speed(speed) if speed else None, revolutions=revolutions, sample_rate=rate,
                   noise=noise, settle=settle, seed=seed, channels=tuple(c.strip() for c in channels.split(",")))
    path = write_measurement(rec, out)
    announce(path, detail=f"{_format_note(out)}: {rec.sizes['time']} samples at {rate:g} Hz, {revolutions:g} "
                          f"revolutions at {rec.attrs['speed_hz']:g} Hz, noise {noise:g}")


def synthesize_impulse(damping: float = typer.Option(0.02, help="Damping ratio of the lower mode [-]."),
                       duration: float = typer.Option(1.0, help="Record length [s]."),
                       sample_rate: str = typer.Option("20kHz", "--sample-rate"),
                       noise: float = typer.Option(0.0, help="Noise fraction of each channel's rms."),
                       out: Path = typer.Option(..., help="Output file: .csv, .nc or .uff."),
                       force: bool = ForceOption):
    """Write a synthetic two-mass impulse test (force, acceleration) with a known damping ratio."""
    from camdyn.identification.modal import synthesize_impulse_test
    from camdyn.io.measurements import write_measurement

    check_outputs(record=out, force=force)
    rec = synthesize_impulse_test(damping_ratios=(damping, 0.02), duration=duration,
                                  sample_rate=parse_hertz(sample_rate), noise=noise)
    write_measurement(rec, out)
    fn = ", ".join(f"{f:.1f}" for f in rec.attrs["natural_frequencies"])
    announce(out, detail=f"{_format_note(out)}: modes at {fn} Hz, lower-mode damping {100 * damping:g} %")


def _format_note(out: Path) -> str:
    """`` as CSV text`` for a record whose suffix does not name its format (``.txt``),
    else nothing: ``--out y11.txt`` writes CSV, and says so."""
    from camdyn.io.measurements import record_format

    return f" as {record_format(out)}" if Path(out).suffix.lower() == ".txt" else ""


#: Keys of the friction estimate that are details, not headline numbers (JSON).
_FRICTION_DETAILS = ("sliding_sign", "amplitudes", "checks")


def identify_friction(source: str = typer.Argument(..., metavar="PRESET_OR_TOML"),
                      data: Path = typer.Argument(...,
                                         help="Record: .csv, .nc/.h5 or .uff (Nx, Ny, alpha_ddot or a_t)."),
                      set_: Optional[List[str]] = SetOption,
                      speed: Optional[str] = typer.Option(None, help="Cam speed; default from the file or estimated."),
                      harmonics: Optional[int] = typer.Option(
                          None, help="Cam harmonics per signal: in the force balance (default 20; 1 = the "
                                     "thesis's truncation), or compared by the orbit fit (default 4)."),
                      method: str = typer.Option("force-balance", help="force-balance (thesis 4.6) or orbit: "
                                                 "fit the harmonic-balance orbit's harmonics to the record's."),
                      fit: Optional[List[str]] = typer.Option(None, "--fit", help="With --method orbit: a "
                                                               "parameter fitted (repeat for more; default "
                                                               "friction.coefficient)."),
                      json_out: bool = JsonOption):
    """Coefficient of friction from pivot forces and acceleration (thesis 4.6)."""
    from camdyn.identification.friction import estimate_friction
    from camdyn.io.measurements import read_measurement

    if method not in ("force-balance", "orbit"):
        raise ParameterError(f"--method must be force-balance or orbit, got {method!r:.40}")
    if fit and method != "orbit":
        raise ParameterError("--fit goes with --method orbit")
    system = load_source(source, set_)
    rec = read_measurement(data)
    if method == "orbit":
        _identify_by_orbit(system, rec, speed, 4 if harmonics is None else harmonics,
                           tuple(fit or ("friction.coefficient",)), json_out)
        return
    harmonics = 20 if harmonics is None else harmonics
    est = estimate_friction(system, rec, speed=parse_speed(speed) if speed else None, harmonics=harmonics)
    if json_out:
        full = est.to_dict()
        details = {k: full.pop(k) for k in _FRICTION_DETAILS}
        emit_json("identify-friction", full, **details)
        return
    table = Table("quantity", "value")
    table.add_row("coefficient of friction mu", f"{est.mu:.5g}")
    table.add_row("mean pivot reaction Nx_dc", f"{est.Nx_dc:.4g} N")
    table.add_row("mean pivot reaction Ny_dc", f"{est.Ny_dc:.4g} N")
    table.add_row("cam speed", f"{est.speed_hz:.6g} Hz ({est.speed_source})")
    table.add_row("revolutions analysed", str(est.revolutions))
    table.add_row("Coulomb misfit over the waveform", f"{100 * est.coulomb_misfit:.3g} %")
    console.print(table)
    for name, c in est.checks.items():
        mark = "ok" if c["passed"] else ("FAILED" if c.get("enforced", True) else "note")
        console.print(f"  [{mark}] {name}: {c['detail']}")


def _identify_by_orbit(system, rec, speed, harmonics: int, keys: tuple, json_out: bool) -> None:
    """``identify friction --method orbit``: :func:`camdyn.steady.record_fit.fit_record`."""
    from camdyn.steady.record_fit import fit_record

    result = fit_record(system, rec, keys=keys, speed=parse_speed(speed) if speed else None, harmonics=harmonics)
    if json_out:
        full = result.to_dict()
        summary = {"values": full.pop("values"), "standard_errors": full.pop("standard_errors"),
                   **{k: full.pop(k) for k in ("speed_hz", "harmonics", "residual", "evaluations")}}
        emit_json("identify-orbit-fit", summary, **full)
        return
    table = Table("quantity", "value")
    for key, value in result.values.items():
        table.add_row(key, f"{value:.6g} ± {result.standard_errors[key]:.2g} {result.units[key]}".rstrip())
    table.add_row("cam speed", f"{result.speed_hz:.6g} Hz")
    table.add_row("channels, harmonics compared", f"{', '.join(result.channels)}; mean and 1..{result.harmonics}")
    table.add_row("rms residual over each channel's rms", f"{result.residual:.3g}")
    table.add_row("orbits balanced", str(result.evaluations))
    console.print(table)


def identify_modal(data: Path = typer.Argument(..., help="Impulse test: force [N] and acceleration [m/s^2]."),
                   band: Optional[str] = typer.Option(None, help="Search band, e.g. 700:1200 (Hz)."),
                   plot: Optional[Path] = typer.Option(None, help="Write the accelerance plot (.png, .pdf, ...)."),
                   force: bool = ForceOption,
                   json_out: bool = JsonOption):
    """Modal damping ratio by the half-power bandwidth of the accelerance peak (thesis 4.5.2)."""
    from camdyn.identification.modal import accelerance, half_power_damping
    from camdyn.io.measurements import read_measurement

    check_outputs(figure=plot, force=force)
    rec = read_measurement(data)
    freq, h = accelerance(rec)
    limits = None
    if band:
        parts = band.split(":")
        if len(parts) != 2:
            raise ParameterError(f"--band: expected LOW:HIGH in Hz, got {band!r}")
        limits = (parse_hertz(parts[0]), parse_hertz(parts[1]))
    est = half_power_damping(freq, h, limits)
    if not json_out:
        console.print(f"natural frequency {est.natural_frequency:.2f} Hz, damping ratio "
                      f"{100 * est.damping_ratio:.3f} % (half-power band {est.lower:.2f}-{est.upper:.2f} Hz, "
                      f"{est.lines} lines)")
    files = []
    if plot:
        from camdyn.plotting import plot_accelerance
        plot_accelerance(freq, h, est, plot)
        files.append(announce(plot, json_out))
    if json_out:
        full = est.to_dict()
        emit_json("identify-modal-damping", {k: full[k] for k in ("natural_frequency", "damping_ratio", "lower",
                                                                  "upper")},
                  peak=full["peak"], lines=full["lines"], resolution=full["resolution"], files=files)


def tribology(source: str = typer.Argument(..., metavar="PRESET_OR_TOML"),
              set_: Optional[List[str]] = SetOption,
              speed: Optional[str] = typer.Option(None, help="Cam speed, e.g. 11.55Hz."),
              lubricant: str = typer.Option("agma-4ep", help="Lubricant: agma-4ep, iso-32, or none."),
              finish: str = typer.Option("ground", help="Surface finish: ground or sand-blasted."),
              plot: Optional[Path] = typer.Option(None, help="Write the contact-conditions plot (.png, .pdf, ...)."),
              force: bool = ForceOption,
              json_out: bool = JsonOption):
    """Hertz pressure, velocities, slide-to-roll ratio, film thickness and lubrication regime."""
    from camdyn.tribology import contact_conditions, lubrication_regime

    check_outputs(figure=plot, force=force)
    system = load_source(source, set_)
    ds = contact_conditions(system, parse_speed(speed) if speed else None,
                            None if lubricant == "none" else lubricant, finish)
    if not ds.attrs["contact_kept"]:
        raise ParameterError("the follower loses contact at this speed, so the contact conditions are undefined; "
                             "lower the speed or the runout")
    rows = [("peak_pressure", "Pa", 1e-9, "GPa"), ("contact_radius", "m", 1e6, "um"), ("Fn", "N", 1, "N"),
            ("sliding_velocity", "m/s", 1, "m/s"), ("sum_velocity", "m/s", 1, "m/s"), ("slide_to_roll", "1", 1, "-")]
    if "film_thickness" in ds:
        rows += [("film_thickness", "m", 1e6, "um"), ("lambda_ratio", "1", 1, "-")]
    quantities = {name: {"min": float(np.nanmin(ds[name].values)), "mean": float(np.nanmean(ds[name].values)),
                         "max": float(np.nanmax(ds[name].values)), "units": unit} for name, unit, _, _ in rows}
    lam = quantities.get("lambda_ratio", {}).get("min")
    summary = {"speed_hz": float(ds.attrs["speed_hz"]),
               "lubricant": ds.attrs.get("lubricant") if lam is not None else None, "finish": finish,
               "regime": str(lubrication_regime(lam)) if lam is not None else None, "lambda_ratio_min": lam,
               "peak_pressure_max_Pa": quantities["peak_pressure"]["max"]}
    if not json_out:
        table = Table("quantity", "min", "mean", "max", "unit")
        for name, _, scale, shown in rows:
            v = quantities[name]
            table.add_row(name, *(f"{v[k] * scale:.4g}" for k in ("min", "mean", "max")), shown)
        console.print(table)
        if summary["regime"]:
            console.print(f"lubrication regime at the thinnest film: {summary['regime']} ({summary['lubricant']}, "
                          f"{finish})")
    files = []
    if plot:
        from camdyn.plotting import plot_contact_conditions
        plot_contact_conditions(ds, plot)
        files.append(announce(plot, json_out))
    if json_out:
        emit_json("tribology", summary, quantities=quantities, files=files)


def design(source: str = typer.Argument(..., metavar="PRESET_OR_TOML"),
           set_: Optional[List[str]] = SetOption,
           axis: str = typer.Option("runout", help="runout (e/a) or axis_ratio (b/a, elliptic cam)."),
           ratios: str = typer.Option("0.05:0.5:10", help="Ratios, START:STOP:COUNT or a list."),
           speeds: str = typer.Option("5Hz:30Hz:26", help="Cam speeds, START:STOP:COUNT or a list."),
           lubricant: Optional[str] = typer.Option(None, help="agma-4ep or iso-32: adds the lambda ratio."),
           finish: str = typer.Option("ground", help="Surface finish for the lambda ratio."),
           regime: Optional[str] = typer.Option(None, help="Required regime: boundary, mixed or EHL."),
           harmonic_margin: float = typer.Option(0.2, help="Largest 5 f_cam / f_n."),
           out: Optional[Path] = typer.Option(None, help="Write the map as netCDF (.nc)."),
           plot: Optional[Path] = typer.Option(None, help="Write the map figure (.png, .pdf, ...); default "
                                                          "design.png, none with --json."),
           force: bool = ForceOption,
           json_out: bool = JsonOption):
    """Map the design criteria of the friction experiment and recommend an operating window (thesis 4.4)."""
    from camdyn.tribology.design import check_design_size, design_map

    if plot is None and not json_out:
        plot = Path("design.png")
    check_outputs(netcdf=out, figure=plot, force=force)
    system = load_source(source, set_)
    grid_r = _design_grid(ratios, "ratios")
    grid_s = _design_grid(speeds, "speeds", "Hz")
    check_design_size(grid_r.size * grid_s.size)
    with Progress(TextColumn("design map"), BarColumn(), TextColumn("{task.completed}/{task.total}"),
                  TimeRemainingColumn(), console=Console(stderr=True), transient=True,
                  disable=json_out) as bar:
        task = bar.add_task("map", total=grid_r.size * grid_s.size)
        ds = design_map(system, axis, grid_r, grid_s, lubricant=lubricant, roughness=finish, regime=regime,
                        harmonic_margin=harmonic_margin, progress=lambda d, t: bar.update(task, completed=d))
    adm = ds["admissible"].values
    window = {}
    for i, r in enumerate(ds["ratio"].values):
        ok = ds["speed"].values[adm[i]]
        if ok.size:
            window[f"{r:.4g}"] = [float(ok.min()), float(ok.max())]
    summary = {"axis": axis, "recommended_ratio": ds.attrs["recommended_ratio"],
               "recommended_speed_hz": ds.attrs["recommended_speed"], "admissible_points": int(adm.sum()),
               "points": int(adm.size)}
    if not json_out:
        _print_design(ds, window, summary)
    files = _write_design(ds, out, plot, json_out)
    if json_out:
        emit_json("design", summary, admissible_speeds_hz=window, files=files)


def _design_grid(text: str, what: str, unit: str | None = None) -> np.ndarray:
    """:func:`parse_grid` of a design axis, its COUNT refused before the grid is made
    when it alone exceeds the design map's size (:func:`check_design_size`)."""
    from camdyn.tribology.design import check_design_size

    parts = text.split(":")
    if len(parts) == 3:
        try:
            count = float(parts[2])
        except ValueError:
            count = None   # parse_grid says what is wrong
        if count is not None:
            check_design_size(count)
    return parse_grid(text, what, unit)


def _print_design(ds, window: dict, summary: dict) -> None:
    table = Table(ds["ratio"].attrs["long_name"], "admissible speeds [Hz]")
    for r, (lo, hi) in window.items():
        table.add_row(r, f"{lo:.3g} - {hi:.3g}")
    console.print(table)
    if math.isfinite(summary["recommended_ratio"]):
        console.print(f"recommended: {ds['ratio'].attrs['long_name']} = {summary['recommended_ratio']:.4g} at "
                      f"{summary['recommended_speed_hz']:.4g} Hz (strongest first harmonic with a contact margin)")
    else:
        console.print("no grid point meets every criterion")


def _write_design(ds, out: Optional[Path], plot: Optional[Path], json_out: bool) -> list:
    """Write the design map's netCDF and figure, as asked; return their file entries."""
    files = []
    if out:
        from camdyn.io.netcdf import save_netcdf
        stored = ds.copy()
        for name in [k for k in ds.data_vars if ds[k].dtype == bool]:
            stored[name] = ds[name].astype("int8")
        save_netcdf(stored, out)
        files.append(announce(out, json_out))
    if plot:
        from camdyn.plotting import plot_design_map
        plot_design_map(ds, plot)
        files.append(announce(plot, json_out))
    return files
