"""``camdyn simulate FILE.py:NAME``: a model of the model protocol in a file of the
user's (docs/user-models.md), simulated and summarised as the bundled models are."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from rich.table import Table

from camdyn.cli.common import console
from camdyn.cli.outputs import report_run
from camdyn.errors import ParameterError
from camdyn.params.config import parse_assignments
from camdyn.params.units import parse_quantity

__all__ = ["model_summary", "simulate_model_command"]


def model_summary(ds, model) -> dict:
    """The headline numbers of a protocol model's run, with their units in their names
    (schema ``camdyn.simulate-model/1``): the speed [Hz] and revolutions where the model
    has a speed, each guard's crossings (both ways) per revolution, and every state's and
    output channel's range."""
    t = ds["time"].values
    duration = float(t[-1] - t[0])
    out = {"model": model.name, "duration_s": duration, "elapsed_s": float(ds.attrs["elapsed_s"])}
    guards = ds["event_guard"].values
    counts = {name: int(np.count_nonzero(guards == name)) for name in model.guards}
    if "speed_hz" in ds.attrs:
        out["speed_hz"] = float(ds.attrs["speed_hz"])
        out["revolutions"] = duration * out["speed_hz"]
        out["events_per_revolution"] = {name: n / out["revolutions"] for name, n in counts.items()}
    else:
        out["events"] = counts
    out["ranges"] = {q.name: {"min": float(ds[q.name].min()), "max": float(ds[q.name].max()), "unit": q.unit}
                     for q in (*model.states, *model.outputs)}
    out["solver"] = {"accepted_steps": int(ds.attrs["steps"]), "rejected_steps": int(ds.attrs["rejected_steps"]),
                     "events": int(ds.sizes["event"])}
    return out


def _show(out: dict) -> None:
    title = f"simulation of {out['model']}" + (f" at {out['speed_hz']:.5g} Hz" if "speed_hz" in out else "")
    table = Table("quantity", "value", title=title)
    if "revolutions" in out:
        table.add_row("revolutions", f"{out['revolutions']:.4g}")
        for name, rate in out["events_per_revolution"].items():
            table.add_row(f"crossings of {name}", f"{rate:.4g} per revolution")
    else:
        table.add_row("duration", f"{out['duration_s']:.4g} s")
        for name, n in out["events"].items():
            table.add_row(f"crossings of {name}", str(n))
    for name, r in out["ranges"].items():
        table.add_row(name, f"{r['min']:.4g} to {r['max']:.4g} {r['unit']}")
    console.print(table)


def simulate_model_command(source: str, set_, speed, revolutions: float, sample_rate: str, out: Path | None,
                           plot: Path | None, rtol: float | None, json_out: bool) -> None:
    """``camdyn simulate`` of ``FILE.py:NAME``: the model with the ``--set`` values (its
    parameter names, numbers in SI units or text with units) at ``--speed``."""
    from camdyn.plotting.models import plot_model_history
    from camdyn.simulation.models import simulate_model
    from camdyn.systems.model_files import load_model

    model = load_model(source)
    bound = model.bind(parse_assignments(set_))
    if speed is not None and model.speed is None:
        raise ParameterError(f"model {model.name!r} has no speed parameter; leave --speed out")
    rate = parse_quantity(sample_rate, "Hz", key="--sample-rate")
    ds = simulate_model(bound, speed=speed, revolutions=revolutions, sample_rate=rate,
                        **({} if rtol is None else {"rtol": rtol}))
    report_run(ds, model_summary(ds, model), "simulate-model", _show, out, json_out, plot, plot_model_history)
