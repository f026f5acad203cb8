"""What every ``camdyn`` command shares: the console, the ``--set`` option, loading a
system from a preset or TOML file, grid and frequency parsing, JSON printing."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import typer
from rich.console import Console

from camdyn.errors import OutputError, ParameterError
from camdyn.params.config import load_system, parse_assignments
from camdyn.params.units import parse_quantity, parse_speed

console = Console()
SetOption = typer.Option(None, "--set", "-s", help="Override a parameter: KEY=VALUE, e.g. cam.runout=3.5mm.")


def load_source(source: str, assignments):
    """The system of a preset name or TOML file, with ``--set`` assignments applied."""
    return load_system(source, parse_assignments(assignments))


def parse_grid(text: str, what: str, unit: str | None = None) -> np.ndarray:
    """``START:STOP:COUNT`` (inclusive, COUNT points) or a comma list."""
    def value(s):
        return parse_speed(s, what) if unit == "Hz" else float(parse_quantity(s, "", what))
    try:
        if ":" in text:
            start, stop, count = text.split(":")
            n = int(count)
            if n < 1:
                raise ValueError
            return np.linspace(value(start), value(stop), n)
        return np.array([value(s) for s in text.split(",")])
    except ValueError:
        raise ParameterError(f"{what}: expected START:STOP:COUNT or a comma list, got {text!r}") from None


def parse_hertz(text: str) -> float:
    """A frequency [Hz]; a bare number is taken as Hz."""
    try:
        return float(text)
    except ValueError:
        return parse_quantity(text, "Hz", "frequency")


def print_json(obj) -> None:
    typer.echo(json.dumps(obj, indent=2, default=lambda o: o.item() if hasattr(o, "item") else str(o)))



def check_outputs(netcdf: Path | None = None, figure: Path | None = None, record: Path | None = None,
                  json_file: Path | None = None) -> None:
    """Refuse, before any work, output paths that cannot be written or whose suffix does
    not match their format: a netCDF result must end in ``.nc`` (or ``.nc4``, ``.h5``), a
    figure in an image format matplotlib writes, a record in a record format."""
    from camdyn.io.atomic import check_writable

    if netcdf is not None:
        if Path(netcdf).suffix.lower() not in (".nc", ".nc4", ".h5", ".hdf5"):
            raise OutputError(f"cannot write {netcdf}: results are netCDF files, so the name must end in .nc")
        check_writable(netcdf)
    if figure is not None:
        from camdyn.plotting import figure_format

        figure_format(figure)
        check_writable(figure)
    if record is not None:
        from camdyn.io.measurements import RECORD_SUFFIXES

        if Path(record).suffix.lower() not in RECORD_SUFFIXES:
            raise OutputError(f"cannot write {record}: a record is .csv, .nc/.h5 or .uff/.unv")
        check_writable(record)
    if json_file is not None:
        check_writable(json_file)
