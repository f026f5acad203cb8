"""What the commands write: output paths checked before any work, each written file
announced with its size, and JSON documents in the shape docs/cli-json.md describes.

Rules every command follows:

* an output goes where the user says, or to the working directory;
* its format follows its suffix, or it is refused: a result ``.nc`` (netCDF), a figure
  any image format matplotlib writes, a record ``.csv``, ``.nc`` or ``.uff``;
* an existing file is not overwritten without ``--force``, and neither is one that
  another process creates while the command runs (the file is published by an exclusive
  link: :func:`camdyn.io.atomic.expect_new`);
* an output that is one of the command's inputs is refused, even with ``--force``;
* every written file is announced as ``wrote PATH (SIZE)``: on standard output, or on
  standard error with ``--json`` so that standard output stays one JSON document.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable
from pathlib import Path

import numpy as np
import typer

from camdyn.cli.common import console, err_console, refuse_inputs_as_outputs
from camdyn.errors import OutputError

#: Suffixes of a netCDF result file.
NETCDF_SUFFIXES = (".nc",)
#: The version of every JSON schema (docs/cli-json.md); bumped when a key changes meaning.
SCHEMA_VERSION = 1
#: The schemas past version 1: ``simulate-mechanism`` 2 gives ``contact_fraction`` of two
#: followers as one number (their list is ``contact_fraction_per_follower``).
SCHEMA_VERSIONS = {"simulate-mechanism": 2}


def _refuse_existing(path: Path, force: bool) -> None:
    if path.is_dir():
        raise OutputError(f"cannot write {path}: it is a folder")
    if path.exists() and not force:
        raise OutputError(f"{path} exists; pass --force to overwrite")


def check_outputs(netcdf: Path | None = None, figure: Path | None = None, record: Path | None = None,
                  json_file: Path | None = None, figures: Iterable[Path] = (), others: Iterable[Path] = (),
                  force: bool = False, expected_bytes: int | None = None) -> None:
    """Refuse, before any work, output paths that cannot be written, whose suffix does
    not match their format, or that exist (unless ``force``): a netCDF result must end in
    ``.nc``, a figure (``figure``, ``figures``) in an image format matplotlib writes, a
    record in a record format (``.csv``, ``.nc``, ``.uff``); ``json_file`` and ``others``
    have no suffix rule. ``expected_bytes`` [B] also refuses a netCDF result larger than
    the free space of its disk. An output that is one of the command's inputs (its
    positional arguments) is refused even with ``force``; without ``force``, each output
    is registered with :func:`camdyn.io.atomic.expect_new`, so that a file of that name
    created by another process during the work is not replaced either."""
    from camdyn.io.atomic import check_writable, expect_new

    checks = []
    if netcdf is not None:
        if Path(netcdf).suffix.lower() not in NETCDF_SUFFIXES:
            raise OutputError(f"cannot write {netcdf}: results are netCDF files, so the name must end in .nc")
        checks.append((Path(netcdf), expected_bytes))
    for path in [figure, *figures]:
        if path is not None:
            from camdyn.plotting import figure_format

            figure_format(path)
            checks.append((Path(path), None))
    if record is not None:
        from camdyn.io.measurements import RECORD_SUFFIXES

        if Path(record).suffix.lower() not in RECORD_SUFFIXES:
            raise OutputError(f"cannot write {record}: a record is .csv (or .txt, written as CSV text), .nc/.h5 "
                              f"or .uff/.unv")
        checks.append((Path(record), None))
    checks += [(Path(p), None) for p in [json_file, *others] if p is not None]
    refuse_inputs_as_outputs(path for path, _ in checks)
    for path, size in checks:
        _refuse_existing(path, force)
        check_writable(path, size)
    for path, _ in checks:
        expect_new(path, not force)


def human_size(n: int) -> str:
    """``n`` bytes as text with a decimal unit: ``850 B``, ``85 kB``, ``3.2 MB``."""
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            value = n / scale
            return f"{value:.1f} {unit}" if value < 10 else f"{value:.0f} {unit}"
    return f"{n} B"


def announce(path: Path | str, json_out: bool = False, detail: str = "") -> dict:
    """Print ``wrote PATH (SIZE)`` and ``detail`` (standard error with ``--json``); return
    the file's entry of a JSON document's ``files`` list."""
    entry = file_entry(path)
    target = err_console if json_out else console
    target.print(f"wrote {path} ({human_size(entry['bytes'])}){detail}", markup=False, highlight=False,
                 soft_wrap=True)
    return entry


def file_entry(path: Path | str) -> dict:
    """``{"path": ..., "bytes": ...}`` of a written file."""
    return {"path": str(path), "bytes": Path(path).stat().st_size}


def _plain(obj):
    """``obj`` with numpy values as Python ones and non-finite numbers as None (JSON has no NaN)."""
    if isinstance(obj, dict):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_plain(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _plain(obj.tolist())
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if obj is None or isinstance(obj, (str, int, float, bool)):
        return obj
    return str(obj)


def _dumps(obj, level: int = 0) -> str:
    """Indented JSON, with a list of plain values on one line (a per-impact column is one
    line, not one line per number)."""
    pad, end = "  " * (level + 1), "  " * level
    if isinstance(obj, dict) and obj:
        items = [f"{pad}{json.dumps(k)}: {_dumps(v, level + 1)}" for k, v in obj.items()]
        return "{\n" + ",\n".join(items) + f"\n{end}}}"
    if isinstance(obj, list) and any(isinstance(v, (dict, list)) for v in obj):
        return "[\n" + ",\n".join(pad + _dumps(v, level + 1) for v in obj) + f"\n{end}]"
    return json.dumps(obj, allow_nan=False)


def print_json(obj) -> None:
    """Print ``obj`` as one JSON document on standard output."""
    typer.echo(_dumps(_plain(obj)))


def emit_json(command: str, summary: dict, **details) -> dict:
    """Print ``{"schema": "camdyn.COMMAND/1", "summary": {...}, ...details}`` (the
    headline numbers first, then the details); return it."""
    version = SCHEMA_VERSIONS.get(command, SCHEMA_VERSION)
    document = {"schema": f"camdyn.{command}/{version}", "summary": summary, **details}
    print_json(document)
    return document


def report_run(ds, summary: dict, command: str, show, out: Path | None, json_out: bool, plot: Path | None = None,
               draw=None, details: tuple = ("solver",)) -> None:
    """The end of a ``simulate`` command: ``show(summary)`` (a table; not with ``--json``),
    the result ``ds`` written to ``out`` and the figure ``draw(ds, plot)``, each where
    asked and announced, then with ``--json`` the document of ``command`` whose
    ``details`` keys leave the summary for entries of their own."""
    if not json_out:
        show(summary)
    files = []
    if out is not None:
        from camdyn.io.netcdf import save_netcdf
        save_netcdf(ds, out)
        files.append(announce(out, json_out))
    if plot is not None:
        draw(ds, plot)
        files.append(announce(plot, json_out))
    if json_out:
        emit_json(command, {k: v for k, v in summary.items() if k not in details},
                  **{k: summary[k] for k in details}, files=files)
