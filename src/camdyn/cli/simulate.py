"""Commands for presets, the static equilibrium, simulation and the demonstration."""

from __future__ import annotations

import math
import warnings
from pathlib import Path
from typing import List, Optional

import typer
from rich.table import Table

from camdyn.cli.common import ForceOption, JsonOption, SetOption, console, load_source
from camdyn.cli.outputs import check_outputs, emit_json, report_run
from camdyn.errors import ParameterError
from camdyn.params.catalog import preset_file, preset_kind, preset_meta, preset_names
from camdyn.params.config import SCHEMA, system_to_toml
from camdyn.params.mechanism import is_mechanism
from camdyn.params.profiles import declared_kind, is_translating
from camdyn.params.units import parse_quantity, parse_speed
from camdyn.systems.model_files import is_model_reference


def presets_list(ctx: typer.Context):
    """List every bundled preset: its name (what a command takes in place of a file), its
    kind and its description. 'camdyn presets NAME' prints one."""
    if ctx.invoked_subcommand is not None:
        return
    names = preset_names()
    table = Table()
    table.add_column("preset", no_wrap=True, min_width=max(map(len, names)))
    table.add_column("kind", no_wrap=True, min_width=max(len(preset_kind(name)) for name in names))
    table.add_column("description")
    for name in names:
        table.add_row(name, preset_kind(name), str(preset_meta(name).get("description", "")))
    console.print(table)


def presets_show(name: str):
    """Print a preset's file as shipped (copy it to start your own configuration; a
    tabulated profile's CSV file lies beside it); given a TOML file, print it written
    back, a mechanism's whole, its system included, every key in SI units."""
    if name in preset_names():
        typer.echo(preset_file(name).read_text(encoding="utf-8"), nl=False)
        return
    if is_mechanism(name):
        from camdyn.cli.mechanism import show_mechanism
        typer.echo(show_mechanism(name))
        return
    typer.echo(system_to_toml(load_source(name, None)))


def presets_keys():
    """List every parameter key, its unit and meaning."""
    table = Table("key", "unit", "meaning")
    for key, (unit, text) in SCHEMA.items():
        table.add_row(key, unit, text)
    console.print(table)


def equilibrium(source: str = typer.Argument(..., metavar="PRESET_OR_TOML"),
                set_: Optional[List[str]] = SetOption,
                json_out: bool = JsonOption):
    """Static equilibrium angle, contact force and linearized natural frequency."""
    from camdyn.model.equilibrium import static_equilibrium
    system = load_source(source, set_)
    eq = static_equilibrium(system)
    out = {
        "angle_deg": math.degrees(eq.angle), "angle_rad": eq.angle,
        "cam_angle_deg": math.degrees(eq.cam_angle), "in_contact": eq.in_contact,
        "contact_force_N": eq.contact_force, "penetration_m": eq.penetration,
        "moment_arm_m": eq.moment_arm, "natural_frequency_Hz": eq.natural_frequency,
        "rotational_stiffness_N_m_per_rad": eq.stiffness,
    }
    if json_out:
        emit_json("equilibrium", {"preset": system.name, **out})
        return
    table = Table("quantity", "value", title=f"static equilibrium of {system.name}")
    table.add_row("follower angle alpha*", f"{out['angle_deg']:.5f} deg")
    table.add_row("cam angle Theta0", f"{out['cam_angle_deg']:.3f} deg")
    table.add_row("in contact", str(eq.in_contact))
    table.add_row("contact force Fn*", f"{eq.contact_force:.4g} N")
    table.add_row("penetration delta*", f"{eq.penetration * 1e6:.4g} um")
    table.add_row("moment arm chi*", f"{eq.moment_arm * 1e3:.4g} mm")
    table.add_row("natural frequency", f"{eq.natural_frequency:.5g} Hz")
    console.print(table)


def _summary(ds) -> dict:
    from camdyn.analysis.harmonics import harmonic_amplitudes
    speed = float(ds.attrs["speed_hz"])
    revs = (float(ds.time[-1]) - float(ds.time[0])) * speed
    out = {
        "preset": ds.attrs["title"].replace("camdyn simulation of ", ""),
        "speed_hz": speed,
        "revolutions": revs,
        "equilibrium_angle_deg": math.degrees(ds.attrs["equilibrium_angle_rad"]),
        "natural_frequency_Hz": ds.attrs["natural_frequency_Hz"],
        "Fn_min_N": float(ds.Fn.min()), "Fn_max_N": float(ds.Fn.max()),
        "contact_fraction": float(ds.in_contact.mean()),
        "impacts": int(ds.sizes.get("impact", 0)),
        "impacts_per_revolution": int(ds.sizes.get("impact", 0)) / revs if revs else 0.0,
        "elapsed_s": ds.attrs["elapsed_s"],
        "alpha_ddot_harmonic1_rad_s2": None, "alpha_ddot_harmonic2_rad_s2": None,
        "solver": {k[7:]: v for k, v in ds.attrs.items() if k.startswith("solver_")},
        "last_impact": None,
    }
    if revs >= 4 and speed > 0:
        n = max(1, int(min(10, revs // 2)))
        a1, a2 = harmonic_amplitudes(ds, "alpha_ddot", (1, 2), revolutions=n)
        out["alpha_ddot_harmonic1_rad_s2"] = float(a1)
        out["alpha_ddot_harmonic2_rad_s2"] = float(a2)
    if out["impacts"]:
        out["last_impact"] = {
            "approach_velocity_m_s": float(ds.impact_approach_velocity[-1]),
            "separation_velocity_m_s": float(ds.impact_separation_velocity[-1]),
            "peak_penetration_m": float(ds.impact_peak_penetration[-1]),
            "peak_force_N": float(ds.impact_peak_force[-1]),
            "duration_s": float(ds.impact_duration[-1]),
        }
    return out


def _print_summary(out: dict):
    table = Table("quantity", "value", title=f"simulation of {out['preset']}")
    table.add_row("cam speed", f"{out['speed_hz']:.4g} Hz ({out['speed_hz'] * 60:.4g} rpm)")
    table.add_row("revolutions", f"{out['revolutions']:.4g}")
    table.add_row("equilibrium angle", f"{out['equilibrium_angle_deg']:.4f} deg")
    table.add_row("linearized natural frequency", f"{out['natural_frequency_Hz']:.5g} Hz")
    table.add_row("normal force Fn", f"{out['Fn_min_N']:.4g} to {out['Fn_max_N']:.4g} N")
    table.add_row("time in contact", f"{100 * out['contact_fraction']:.1f} %")
    table.add_row("impacts", f"{out['impacts']} ({out['impacts_per_revolution']:.3g} per revolution)")
    if out["alpha_ddot_harmonic1_rad_s2"] is not None:
        table.add_row("alpha_ddot, 1st cam harmonic", f"{out['alpha_ddot_harmonic1_rad_s2']:.4g} rad/s^2")
        table.add_row("alpha_ddot, 2nd cam harmonic", f"{out['alpha_ddot_harmonic2_rad_s2']:.4g} rad/s^2")
    if out["last_impact"] is not None:
        li = out["last_impact"]
        table.add_row("last impact: approach / separation",
                      f"{li['approach_velocity_m_s']:.4g} / {li['separation_velocity_m_s']:.4g} m/s")
        table.add_row("last impact: peak penetration, force",
                      f"{li['peak_penetration_m'] * 1e6:.4g} um, {li['peak_force_N']:.4g} N")
    s = out["solver"]
    table.add_row("solver", f"{s['accepted_steps']} steps ({s['rejected_steps']} rejected), "
                            f"{s['rhs_calls']} rhs calls, {s['events']} events, {out['elapsed_s'] * 1e3:.1f} ms")
    console.print(table)


#: Keys of the simulate summary that are details, not headline numbers (JSON).
_DETAILS = ("last_impact", "solver")


def _check_revolutions(revolutions: float) -> None:
    """Refuse a run length that is not a positive, finite number of revolutions; warn
    about one shorter than a revolution (legitimate, but its summary is per revolution)."""
    if not (math.isfinite(revolutions) and revolutions > 0):
        raise ParameterError(f"--revolutions must be a positive, finite number of cam revolutions, got {revolutions!r}")
    if revolutions < 1:
        warnings.warn(f"--revolutions {revolutions:g} is less than one cam revolution: the run shows part of one, "
                      f"and the summary's per-revolution figures (impacts per revolution, harmonics) are not "
                      f"computed from a whole revolution", UserWarning, stacklevel=2)


def simulate(source: str = typer.Argument(..., metavar="PRESET_OR_TOML"),
             set_: Optional[List[str]] = SetOption,
             speed: Optional[str] = typer.Option(None, help="Cam speed, e.g. 11.55Hz or 693rpm."),
             revolutions: float = typer.Option(30.0, help="Number of cam revolutions."),
             sample_rate: str = typer.Option("20kHz", help="Output sampling rate."),
             out: Optional[Path] = typer.Option(None, help="Write the results to this netCDF file (.nc)."),
             plot: Optional[Path] = typer.Option(None, help="Write a time-history figure (.png, .pdf, .svg, ...)."),
             method: str = typer.Option("auto", help="auto, dop853, explicit, rosenbrock, radau or switching."),
             rtol: Optional[float] = typer.Option(None, help="Relative tolerance (default 1e-8; 1e-10 for a "
                                                            "translating follower)."),
             force: bool = ForceOption,
             json_out: bool = JsonOption):
    """Simulate the follower and summarise the response.

    FILE.py:NAME is a model of the model protocol in a file of yours (docs/user-models.md),
    --set taking its parameter names.

    A configuration whose [follower] says kind = "translating" (or the preset alzate) is a
    translating follower on a cam profile, kind = "rocking" a rocking roller or knife edge
    on one (docs/profiles.md). A file with a [mechanism] table is a mechanism: the cam
    on a driven shaft, the follower on a flexible pivot, or two followers on one cam
    (docs/mechanisms.md)."""
    from camdyn.simulation.runner import simulate as run
    _check_revolutions(revolutions)
    check_outputs(netcdf=out, figure=plot, force=force)
    if is_model_reference(source):
        from camdyn.cli.models import simulate_model_command
        simulate_model_command(source, set_, speed, revolutions, sample_rate, out, plot, rtol, json_out)
        return
    if is_mechanism(source):
        from camdyn.cli.mechanism import simulate_mechanism_command
        simulate_mechanism_command(source, set_, speed, revolutions, sample_rate, out, plot, method, rtol, json_out)
        return
    if is_translating(source):
        from camdyn.cli.translating import simulate_translating_command
        simulate_translating_command(source, set_, speed, revolutions, sample_rate, out, plot, method, rtol, json_out)
        return
    if declared_kind(source) == "rocking":
        from camdyn.cli.rocking import simulate_rocking_command
        simulate_rocking_command(source, set_, speed, revolutions, sample_rate, out, plot, method, rtol, json_out)
        return
    if declared_kind(source) is not None:
        raise ParameterError(f"{source}: follower.kind is {declared_kind(source)!r}; write 'translating' for a "
                             "translating follower, 'rocking' for a rocking roller or knife edge, or leave it "
                             "out for the rocking flat-faced one")
    rtol = 1e-8 if rtol is None else rtol
    system = load_source(source, set_)
    fs = parse_quantity(sample_rate, "Hz", "--sample-rate")
    if speed is not None:
        speed = parse_speed(speed, "--speed")
    ds = run(system, speed=speed, revolutions=revolutions, sample_rate=fs, method=method, rtol=rtol)
    summary = _summary(ds)
    draw = None
    if plot is not None:
        from camdyn.plotting import plot_time_history as draw
    report_run(ds, summary, "simulate", _print_summary, out, json_out, plot, draw, _DETAILS)


def demo(out: Path = typer.Option(Path("out"), help="Folder for the figures and results (about 80 MB)."),
         force: bool = ForceOption):
    """Run the demonstration on the bundled presets: print key results, write figures."""
    from camdyn.cli.demo import check_demo_outputs, run_demo
    check_demo_outputs(out, force)
    run_demo(out, console)
