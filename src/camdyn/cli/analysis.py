"""``camdyn map`` (regime map over two parameters) and ``camdyn spectrum`` (spectra with
the cam harmonics and resonances marked)."""

from __future__ import annotations

from pathlib import Path
from typing import List, Optional

import numpy as np
import typer

from camdyn.cli.common import ForceOption, JsonOption, SetOption, console, load_source, notice_if_uncached
from camdyn.cli.outputs import announce, check_outputs, emit_json
from camdyn.errors import ParameterError

_ALIASES = {"speed": "motion.speed"}


def _axis(text: str, option: str, mechanism: bool = False) -> dict:
    """``KEY=START:STOP:COUNT`` or ``KEY=V1,V2,...`` (units as text) -> a [[vary]] table
    (over a mechanism, ``speed`` is its cam-follower's ``system.motion.speed``)."""
    key, sep, grid = text.partition("=")
    if not sep or not key.strip() or not grid.strip():
        raise ParameterError(f"{option}: expected KEY=START:STOP:COUNT or KEY=V1,V2,..., got {text!r}")
    key = _ALIASES.get(key.strip(), key.strip())
    if mechanism and key == "motion.speed":
        key = "system.motion.speed"
    if ":" in grid:
        parts = grid.split(":")
        if len(parts) != 3:
            raise ParameterError(f"{option}: expected START:STOP:COUNT, got {grid!r}")
        try:
            num = int(parts[2])
        except ValueError:
            raise ParameterError(f"{option}: COUNT must be a whole number, got {parts[2]!r}") from None
        return {"key": key, "start": parts[0], "stop": parts[1], "num": num}
    return {"key": key, "values": [v.strip() for v in grid.split(",")]}


def regime_map_command(source: str = typer.Argument(..., metavar="PRESET_OR_TOML"),
                       x: str = typer.Option(..., "--x", help="First axis: KEY=START:STOP:COUNT, e.g. "
                                                              "spring.stiffness=1000N/m:3000N/m:20."),
                       y: str = typer.Option("speed=60rpm:200rpm:30", "--y", help="Second axis, the same form "
                                                                                  "('speed' = motion.speed)."),
                       set_: Optional[List[str]] = SetOption,
                       revolutions: int = typer.Option(60, help="Cam periods simulated per point."),
                       discard: int = typer.Option(30, help="Of which the first are dropped (transient)."),
                       rtol: float = typer.Option(3e-7, help="Relative tolerance of the integrator."),
                       atol: float = typer.Option(1e-10, help="Absolute tolerance [rad, rad/s] (a mechanism "
                                                                 "runs with its own)."),
                       out: Path = typer.Option(Path("regime_map.nc"), help="Result file (.nc)."),
                       plot: Optional[Path] = typer.Option(None, help="Figure (default: the result's name, .png)."),
                       workers: Optional[int] = typer.Option(None, help="Worker processes (default every core)."),
                       dask: Optional[str] = typer.Option(None, help="'local' or a scheduler tcp://HOST:PORT."),
                       restart: bool = typer.Option(False, "--restart", help="Discard checkpoints instead of "
                                                                             "resuming."),
                       force: bool = ForceOption,
                       curve: Optional[List[str]] = typer.Option(
                           None, "--curve", help="A bifurcation followed over --x by two-parameter continuation "
                                                 "and drawn on the map: KIND=VALUE, KIND fold, period-doubling, "
                                                 "grazing or contact-loss, VALUE its --y value at the first --x "
                                                 "value (e.g. period-doubling=16Hz). Repeatable."),
                       quiet: bool = typer.Option(False, "--quiet", help="No progress bar.")):
    """Regime map over two parameters: every point simulated (contact kept, vr reversal, k
    impacts per revolution, irregular), beside the inverse-kinematics prediction."""
    from camdyn.params.config import parse_assignments
    from camdyn.params.mechanism import is_mechanism
    from camdyn.plotting import plot_regime_map
    from camdyn.sweeps import spec_from_dict
    from camdyn.sweeps.regime_map import regime_map

    check_outputs(netcdf=out, figure=plot or out.with_suffix(".png"), force=force)
    mechanism = is_mechanism(source)
    first, second = _axis(x, "--x", mechanism), _axis(y, "--y", mechanism)
    if first["key"] == second["key"]:
        raise ParameterError("--x and --y vary the same parameter")
    table = {"system": {"source": source, "set": parse_assignments(set_)},
             "vary": [first, second],
             "run": {"revolutions": revolutions, "discard": discard, "rtol": rtol, "atol": atol},
             "metrics": {"names": ["regime", "impacts", "residual", "max_force"]},
             "output": {"path": str(out)}}
    if mechanism:   # its own metrics, and the absolute tolerance of its entry
        del table["metrics"], table["run"]["atol"]
    spec = spec_from_dict(table, name=out.stem)
    from camdyn.sweeps.execution import check_dask_address
    from camdyn.sweeps.regime_map import map_curves, parse_curve

    requests = [parse_curve(text, spec) for text in curve or []]

    check_dask_address(dask)   # before the compile notice: bad input is refused before any work
    notice_if_uncached(sweeps=True)
    ds = regime_map(spec, workers=workers, dask=dask, progress=not quiet, restart=restart,
                    echo=lambda msg: console.print(msg, markup=False, highlight=False, soft_wrap=True))
    for kind, guess in requests:
        console.print(f"following the {kind} from {spec.vary[1].key} = {guess:.6g} {spec.vary[1].unit} over "
                      f"{spec.vary[0].key} ...", highlight=False, soft_wrap=True)
    if requests:
        ds = map_curves(spec, ds, requests)
        for name in (v for v in ds.data_vars if "curve_kind" in ds[v].attrs):
            console.print(f"{ds[name].attrs['curve_kind']}: {int(np.isfinite(ds[name].values).sum())} points; "
                          f"{ds[name].attrs['stopped']}", highlight=False, soft_wrap=True)
    announce(out)
    announce(plot_regime_map(ds, plot or out.with_suffix(".png")))
    a = {k[len("agreement_"):]: ds.attrs[k] for k in ds.attrs if k.startswith("agreement_")}
    console.print(f"simulation agrees with inverse kinematics at "
                  f"{a['kept_agree']}/{a['kept']} points kept in contact and {a['lost_agree']}/{a['lost']} "
                  f"beyond the loss of contact", highlight=False, soft_wrap=True)


def spectrum(source: str = typer.Argument(..., metavar="PRESET_OR_TOML"),
             set_: Optional[List[str]] = SetOption,
             speed: Optional[str] = typer.Option(None, help="Cam speed, e.g. 300rpm or 5Hz (default the preset's; "
                                                            "a mechanism's starting speed)."),
             revolutions: float = typer.Option(40.0, help="Cam periods simulated (of the starting speed)."),
             window: int = typer.Option(20, help="Whole revolutions at the end analysed (Hann window)."),
             variable: Optional[str] = typer.Option(None, help="alpha_ddot (the default where the model has it; "
                                                                 "else its first time series), alpha, Fn, Ff, Nx, "
                                                                 "Ny, cam_speed, ..."),
             follower: Optional[int] = typer.Option(None, help="Of two followers on one cam, the one analysed "
                                                               "(1 or 2; default both)."),
             sample_rate: str = typer.Option("20kHz", help="Output sample rate."),
             harmonics: int = typer.Option(10, help="Cam harmonics listed."),
             peaks: int = typer.Option(3, help="Largest peaks away from the cam harmonics listed (resonances)."),
             plot: Optional[Path] = typer.Option(None, help="Figure path (.png, .pdf, ...)."),
             force: bool = ForceOption,
             json_: bool = JsonOption):
    """Amplitude spectrum of a simulated response: cam harmonics, resonance peaks and the
    linearized natural frequency. A mechanism file (docs/mechanisms.md) is analysed per
    follower; a follower on a cam profile and a model of your own (FILE.py:NAME) in any
    of their time series."""
    from camdyn.analysis.spectra import spectrum_summary
    from camdyn.plotting import plot_spectrum

    check_outputs(figure=plot, force=force)
    runs = _spectrum_runs(source, set_, speed, revolutions, sample_rate, follower, window, plot is not None)
    summaries = []
    series = [k for k in runs[0][1].data_vars if runs[0][1][k].dims == ("time",)]
    variable = variable or ("alpha_ddot" if "alpha_ddot" in series else series[0])
    for number, ds in runs:
        if variable not in ds or ds[variable].dims != ("time",):
            raise ParameterError(f"--variable must be a time series of the result, one of "
                                 f"{sorted(k for k in ds.data_vars if ds[k].dims == ('time',))}, got {variable!r}")
        summary = spectrum_summary(ds, variable, window=window, harmonics=harmonics, peaks=peaks)
        if number is not None:
            summary["follower"] = number
        summaries.append(summary)
        if not json_:
            _print_spectrum(summary, variable, window)
    files = []
    if plot is not None:
        plot_spectrum(runs[0][1], plot, variable=variable, harmonics=harmonics, revolutions=window,
                      resonances=[p["frequency_hz"] for p in summaries[0]["peaks"]])
        files.append(announce(plot, json_))
    if json_:
        _emit_spectra(summaries, runs[0][1], files)


def _spectrum_runs(source: str, assignments, speed, revolutions: float, sample_rate: str, follower, window: int,
                   plot: bool) -> list:
    """The simulated runs a spectrum analyses, as ``(follower number or None, time
    series)`` (:func:`camdyn.analysis.spectra.follower_series`): the cam-follower's run,
    or a mechanism's per follower (one, or each of two unless ``follower`` picks one)."""
    from camdyn.analysis.spectra import follower_series
    from camdyn.cli.common import parse_hertz
    from camdyn.params.mechanism import is_mechanism

    rate = parse_hertz(sample_rate)
    if not is_mechanism(source):
        if follower not in (None, 1):
            raise ParameterError(f"--follower: {source} has one follower, got {follower}")
        from camdyn.io.sources import simulate_source
        from camdyn.params.config import parse_assignments

        ds = simulate_source(source, parse_assignments(assignments), speed, revolutions, rate)
        if ds is None:                # the thesis's follower
            from camdyn.simulation.runner import simulate
            ds = simulate(load_source(source, assignments), speed=speed, revolutions=revolutions, sample_rate=rate)
        return [(None, ds)]
    from camdyn.cli.mechanism import DEFAULT_RTOL
    from camdyn.io.mechanism_config import load_mechanism, simulate_mechanism
    from camdyn.params.config import parse_assignments
    from camdyn.params.units import parse_speed
    from camdyn.sweeps.mechanism_metrics import FOLLOWERS

    overrides = parse_assignments(assignments)
    if speed is not None:
        parse_speed(speed, "--speed")
        overrides["system.motion.speed"] = speed
    mechanism = load_mechanism(source, overrides)
    count = FOLLOWERS[mechanism.spec.kind]
    if follower is not None and not 1 <= follower <= count:
        raise ParameterError(f"--follower: the {mechanism.spec.kind} mechanism has {count} follower"
                             f"{'s' if count > 1 else ''}, got {follower}")
    numbers = [follower] if follower is not None else list(range(1, count + 1))
    if plot and len(numbers) > 1:
        raise ParameterError("--plot draws one follower's spectrum: give --follower 1 or 2")
    if not (revolutions > 0 and window >= 1):
        raise ParameterError(f"--revolutions must be positive and --window at least 1, got {revolutions}, {window}")
    ds = simulate_mechanism(mechanism, revolutions=revolutions, sample_rate=rate, rtol=DEFAULT_RTOL)
    extra = {}
    if mechanism.spec.kind == "flexible-pivot":
        from camdyn.simulation.flexible_pivot import natural_frequencies
        extra["natural_frequency_Hz"] = float(natural_frequencies(mechanism.system, mechanism.spec.pivot_stiffness)[0])
    label = (lambda k: k) if count > 1 else (lambda k: None)
    return [(label(k), follower_series(ds, k if count > 1 else None, window).assign_attrs(**extra)) for k in numbers]


def _emit_spectra(summaries: list, ds, files: list) -> None:
    """The ``camdyn.spectrum/1`` document: one follower's summary with its harmonics and
    peaks, or, for two, the shared keys and a ``followers`` list of each one's."""
    mechanism = {"mechanism": str(ds.attrs["mechanism"])} if "mechanism" in ds.attrs else {}
    if len(summaries) == 1:
        summary = dict(summaries[0], **mechanism)
        details = {k: summary.pop(k) for k in ("harmonics", "peaks")}
        emit_json("spectrum", summary, **details, files=files)
        return
    shared = ("variable", "units", "speed_hz", "window_revolutions", "peak_rule")
    each = [{k: v for k, v in s.items() if k not in shared} for s in summaries]
    emit_json("spectrum", dict({k: summaries[0][k] for k in shared}, **mechanism), followers=each, files=files)


def _print_spectrum(summary: dict, variable: str, window: int) -> None:
    unit = summary["units"]
    who = f"follower {summary['follower']}: " if "follower" in summary else ""
    natural = summary["natural_frequency_hz"]
    known = f" (linearized natural frequency {natural:.5g} Hz)" if np.isfinite(natural) else ""
    console.print(f"{who}{variable} at {summary['speed_hz']:.4g} Hz, last {window} revolutions{known}",
                  highlight=False)
    console.print("cam harmonics: " + ", ".join(f"{h['order']}x {h['amplitude']:.4g}"
                                               for h in summary["harmonics"]) + f" [{unit}]", highlight=False,
                  markup=False, soft_wrap=True)
    for p in summary["peaks"]:
        console.print(f"peak at {p['frequency_hz']:.5g} Hz: {p['amplitude']:.4g} {unit}", highlight=False)
