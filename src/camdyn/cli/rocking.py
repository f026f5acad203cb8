"""``camdyn simulate`` for a rocking roller or knife-edge follower on a cam profile: the
configuration's ``[follower] kind = "rocking"`` sends the command here."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from rich.table import Table

from camdyn.cli.common import console
from camdyn.cli.outputs import report_run
from camdyn.cli.translating import DEFAULT_RTOL, add_friction_rows, add_run_rows, friction_summary, run_span
from camdyn.errors import ParameterError
from camdyn.params.config import parse_assignments

__all__ = ["simulate_rocking_command", "rocking_summary"]

def rocking_summary(ds, follower, name: str) -> dict:
    """The headline numbers of a rocking follower's run (schema
    ``camdyn.simulate-rocking/1``)."""
    from camdyn.simulation.rocking_roller import rocking_liftoff_speed

    speed = float(ds.attrs["speed_rad_s"])
    revolutions = float(ds["time"][-1] - ds["time"][0]) * speed / (2.0 * math.pi)
    kinds = ds["event_kind"].values
    count = {kind: int(np.count_nonzero(kinds == kind)) for kind in ("impact", "separation", "capture",
                                                                          "contact onset")}
    liftoff = rocking_liftoff_speed(follower)
    return {
        "preset": name,
        "speed_hz": speed / (2.0 * math.pi),
        "speed_rpm": 60.0 * speed / (2.0 * math.pi),
        "revolutions": revolutions,
        "impacts": count["impact"],
        "impacts_per_revolution": count["impact"] / revolutions if revolutions else 0.0,
        "separations": count["separation"],
        "captures": count["capture"],
        "contact_law": str(ds.attrs.get("contact_law", "rigid")),
        "contact_onsets": count["contact onset"],
        "contact_force_max_N": float(ds["contact_force"].max()),
        "gap_max_rad": float(ds["gap"].max()),
        "pressure_angle_max_deg": float(np.degrees(np.abs(ds["pressure_angle"]).max())),
        "contact_fraction": float(ds["in_contact"].mean()),
        "liftoff_speed_rpm": 60.0 * liftoff / (2.0 * math.pi) if math.isfinite(liftoff) else None,
        "elapsed_s": float(ds.attrs["elapsed_s"]),
        "solver": {k[7:]: v for k, v in ds.attrs.items() if k.startswith("solver_")},
    }


def _print(out: dict) -> None:
    table = Table("quantity", "value", title=f"simulation of {out['preset']} (rocking follower)")
    table.add_row("cam speed", f"{out['speed_rpm']:.5g} rpm")
    table.add_row("revolutions", f"{out['revolutions']:.4g}")
    table.add_row("impacts", f"{out['impacts']} ({out['impacts_per_revolution']:.3g} per revolution)")
    table.add_row("lift-off events (separations)", f"{out['separations']}")
    table.add_row("captures into sustained contact", f"{out['captures']}")
    if out["contact_law"] != "rigid":
        table.add_row(f"landings ({out['contact_law']} contact)", f"{out['contact_onsets']}")
    table.add_row("max contact force", f"{out['contact_force_max_N']:.5g} N")
    table.add_row("max gap (arm angle)", f"{math.degrees(out['gap_max_rad']):.4g} deg")
    table.add_row("max pressure angle", f"{out['pressure_angle_max_deg']:.4g} deg")
    add_friction_rows(table, out)
    add_run_rows(table, out)
    console.print(table)


def simulate_rocking_command(source: str, assignments, speed: str | None, revolutions: float, sample_rate: str,
                             out: Path | None, plot: Path | None, method: str, rtol: float | None,
                             json_out: bool) -> None:
    """Run ``camdyn simulate`` on a rocking roller or knife-edge follower (the outputs are
    checked already)."""
    from camdyn.io.rocking_config import load_rocking
    from camdyn.simulation.rocking_friction import simulate_rocking_friction
    from camdyn.simulation.rocking_roller import simulate_rocking
    from camdyn.simulation.sliding import friction_from_spec

    if method != "auto":
        raise ParameterError(f"--method {method}: the rocking roller is integrated with the automatic method only "
                             "(leave --method out)")
    if plot is not None:
        raise ParameterError("--plot is not offered for a rocking roller or knife-edge follower yet; write the "
                             "results with --out")
    follower, spec = load_rocking(source, parse_assignments(assignments))
    omega, duration, fs = run_span(spec.name, spec.profile.speed, speed, revolutions, sample_rate)
    friction = friction_from_spec(spec)
    tolerance = DEFAULT_RTOL if rtol is None else rtol
    cam = f"{float(omega)!r} rad/s"   # the entries read Hz or text with units; this keeps omega exactly
    if friction is None:
        ds = simulate_rocking(follower, cam, duration, sample_rate=fs, phase=spec.profile.phase, rtol=tolerance)
    else:
        ds = simulate_rocking_friction(follower, friction, cam, duration, sample_rate=fs,
                                       phase=spec.profile.phase, rtol=tolerance)
    ds.attrs["name"] = spec.name
    summary = rocking_summary(ds, follower, spec.name)
    if friction is not None:
        summary.update(friction_summary(ds))
    report_run(ds, summary, "simulate-rocking", _print, out, json_out)
