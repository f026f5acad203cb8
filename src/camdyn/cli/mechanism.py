"""``camdyn simulate`` and ``camdyn presets show`` for a mechanism's configuration (the
cam as a body on a driven shaft, the follower on a flexible pivot, two followers on one
driven cam): a TOML file with a ``[mechanism]`` table sends the commands here."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from rich.table import Table

from camdyn.cli.common import console
from camdyn.cli.outputs import report_run
from camdyn.errors import ParameterError
from camdyn.params.config import parse_assignments
from camdyn.params.units import parse_quantity, parse_speed

__all__ = ["simulate_mechanism_command", "show_mechanism", "mechanism_summary"]

#: The relative tolerance of a mechanism's run when --rtol is not given [-] (the entries' own).
DEFAULT_RTOL = 1e-9


def _count(kinds: np.ndarray, kind: str) -> int:
    return int(np.count_nonzero(kinds == kind))


def mechanism_summary(ds) -> dict:
    """The headline numbers of a mechanism's run, with their units in their names
    (schema ``camdyn.simulate-mechanism/1``)."""
    t = ds["time"].values
    kind = str(ds.attrs["mechanism"])
    out = {"preset": str(ds.attrs.get("name", "")), "mechanism": kind, "duration_s": float(t[-1] - t[0]),
           "elapsed_s": float(ds.attrs["elapsed_s"]),
           "solver": {key: int(ds.attrs[key]) for key in ("accepted_steps", "rejected_steps", "events")}}
    if kind in ("driven-cam", "two-followers"):
        speed = ds["cam_speed"].values
        out.update(drive=str(ds.attrs["drive_kind"]), shaft_inertia_kg_m2=float(ds.attrs["shaft_inertia"]),
                   revolutions=float(abs(ds["cam_angle"].values[-1] - ds["cam_angle"].values[0]) / (2 * math.pi)),
                   mean_speed_rpm=60.0 * float(ds.attrs["mean_cam_speed"]) / (2.0 * math.pi),
                   speed_min_rad_s=float(speed.min()), speed_max_rad_s=float(speed.max()),
                   coefficient_of_fluctuation=float(ds.attrs["coefficient_of_fluctuation"]),
                   drive_torque_max_N_m=float(np.abs(ds["drive_torque"].values).max()),
                   bearing_torque_max_N_m=float(np.abs(ds["bearing_torque"].values).max()))
    if kind == "driven-cam":
        out.update(contact_torque_max_N_m=float(np.abs(ds["contact_torque"].values).max()),
                   Fn_max_N=float(ds["Fn"].max()))
    elif kind == "two-followers":
        kinds = ds["transition_kind"].values
        out.update(Fn_max_N=[float(v) for v in ds["Fn"].max("time").values],
                   contact_fraction_per_follower=[float(v) for v in ds["in_contact"].mean("time").values],
                   sticks=_count(kinds, "stick"), slips=_count(kinds, "slip"), reversals=_count(kinds, "reversal"),
                   sprags=_count(kinds, "sprag"))
    else:
        force = np.hypot(ds["Nx"].values, ds["Ny"].values)
        out.update(revolutions=out["duration_s"] * float(ds.attrs["speed_hz"]),
                   pivot_stiffness_N_m=float(ds.attrs["pivot_stiffness"]),
                   pivot_damping_N_s_m=float(ds.attrs["pivot_damping"]),
                   bearing_force_max_N=float(force.max()),
                   pivot_displacement_max_m=float(np.hypot(ds["u"].values, ds["v"].values).max()),
                   Fn_max_N=float(ds["Fn"].max()))
    out.update(_common(ds, out["revolutions"]))
    return out


def _common(ds, revolutions: float) -> dict:
    """The keys every kind's ``camdyn simulate`` summary shares (docs/cli-json.md):
    ``speed_hz`` [Hz] (a driven shaft's mean cam speed), ``contact_fraction`` (of the
    samples; two followers: the mean of theirs), the landings seen in the samples and
    ``impacts_per_revolution`` [1/rev]."""
    contact = ds["in_contact"].values > 0.5
    if contact.ndim == 1:
        contact = contact[:, None]
    landings = int(np.count_nonzero(contact[1:] & ~contact[:-1]))
    if "mean_cam_speed" in ds.attrs:   # a driven shaft: its mean speed [rad/s]
        speed = abs(float(ds.attrs["mean_cam_speed"])) / (2.0 * math.pi)
    else:
        speed = float(ds.attrs["speed_hz"])
    return {"speed_hz": speed, "contact_fraction": float(contact.mean()), "impacts": landings,
            "impacts_per_revolution": landings / revolutions if revolutions else 0.0}


def _pair(values, fmt: str, unit: str) -> str:
    return " / ".join(f"{v:{fmt}}" for v in values) + f" {unit} (followers 1 / 2)"


def _print(out: dict) -> None:
    table = Table("quantity", "value", title=f"simulation of {out['preset']} ({out['mechanism']})")
    table.add_row("cam speed", f"{out['speed_hz']:.5g} Hz" + (" (mean)" if "drive" in out else ""))
    table.add_row("revolutions", f"{out['revolutions']:.4g}")
    table.add_row("landings (in the samples)",
                  f"{out['impacts']} ({out['impacts_per_revolution']:.3g} per revolution)")
    if "drive" in out:
        table.add_row("drive", f"{out['drive']}, shaft inertia {out['shaft_inertia_kg_m2']:.4g} kg m^2")
        table.add_row("mean cam speed", f"{out['mean_speed_rpm']:.5g} rpm")
        table.add_row("cam speed range", f"{out['speed_min_rad_s']:.5g} to {out['speed_max_rad_s']:.5g} rad/s")
        table.add_row("coefficient of speed fluctuation", f"{out['coefficient_of_fluctuation']:.4g}")
        table.add_row("peak drive / bearing torque",
                      f"{out['drive_torque_max_N_m']:.4g} / {out['bearing_torque_max_N_m']:.4g} N m")
    if out["mechanism"] == "driven-cam":
        table.add_row("peak contact torque on the cam", f"{out['contact_torque_max_N_m']:.4g} N m")
    if out["mechanism"] == "flexible-pivot":
        table.add_row("bearing", f"{out['pivot_stiffness_N_m']:.4g} N/m, {out['pivot_damping_N_s_m']:.4g} N s/m")
        table.add_row("peak bearing force", f"{out['bearing_force_max_N']:.5g} N")
        table.add_row("peak pivot displacement", f"{out['pivot_displacement_max_m'] * 1e6:.4g} um")
    if out["mechanism"] == "two-followers":
        table.add_row("peak normal force", _pair(out["Fn_max_N"], ".5g", "N"))
        table.add_row("time in contact", _pair([100 * f for f in out["contact_fraction_per_follower"]], ".1f", "%"))
        table.add_row("sticks / slips / reversals", f"{out['sticks']} / {out['slips']} / {out['reversals']}")
        table.add_row("sprags (self-locking)", f"{out['sprags']}")
    else:
        table.add_row("peak normal force", f"{out['Fn_max_N']:.5g} N")
        table.add_row("time in contact", f"{100 * out['contact_fraction']:.1f} %")
    s = out["solver"]
    table.add_row("solver", f"{s['accepted_steps']} steps ({s['rejected_steps']} rejected), {s['events']} events, "
                            f"{out['elapsed_s'] * 1e3:.1f} ms")
    console.print(table)


def simulate_mechanism_command(source: str, assignments, speed: str | None, revolutions: float, sample_rate: str,
                               out: Path | None, plot: Path | None, method: str, rtol: float | None,
                               json_out: bool) -> None:
    """Run ``camdyn simulate`` on a mechanism's configuration (the outputs are checked
    already); ``--speed`` sets the system's ``motion.speed``, the starting cam speed."""
    from camdyn.io.mechanism_config import load_mechanism, simulate_mechanism

    if not (isinstance(revolutions, (int, float)) and math.isfinite(revolutions) and revolutions > 0):
        raise ParameterError(f"--revolutions must be positive, got {revolutions!r}")
    overrides = parse_assignments(assignments)
    if speed is not None:
        parse_speed(speed, "--speed")
        overrides["system.motion.speed"] = speed
    fs = parse_quantity(sample_rate, "Hz", "--sample-rate")
    mechanism = load_mechanism(source, overrides)
    ds = simulate_mechanism(mechanism, revolutions=revolutions, sample_rate=fs,
                            rtol=DEFAULT_RTOL if rtol is None else rtol, method=method)
    summary = mechanism_summary(ds)
    draw = None
    if plot is not None:
        from camdyn.plotting.mechanisms import plot_mechanism_history as draw
    report_run(ds, summary, "simulate-mechanism", _print, out, json_out, plot, draw)


def show_mechanism(source: str) -> str:
    """The mechanism of a TOML file written back whole, every key in SI units
    (:func:`camdyn.io.mechanism_config.mechanism_to_toml`)."""
    from camdyn.io.mechanism_config import load_mechanism, mechanism_to_toml

    return mechanism_to_toml(load_mechanism(source))
