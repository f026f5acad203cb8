"""The CSV record reader (:func:`read_csv_record`), used by
:func:`camdyn.io.measurements.read_measurement`.

What it accepts beyond the plain layout (``# key = value`` metadata lines, a header row,
one comma-separated row per sample in SI units):

* a UTF-8 byte-order mark (as Excel writes "CSV UTF-8"), and UTF-16 text with or
  without its byte-order mark (Excel's "Unicode text");
* comment lines in another encoding than UTF-8: they are read as Windows-1252 (Latin-1)
  text, which is harmless since only the ``speed``, ``cam.runout``, ``preset`` and
  ``noise`` entries are used. A header or data row that is not UTF-8 is refused, naming
  the line;
* a semicolon, tab or blank delimiter instead of the comma, when the header row splits
  into known column names with it alone; with a semicolon, tab or blank delimiter a
  decimal comma (``0,25``) is read as a decimal point;
* units in the header (``time [ms]``, ``Nx (kN)``, ``time_ms``) or in a line
  ``# units: time ms, Nx kN`` (as :func:`~camdyn.io.measurements.write_measurement`
  writes it); columns without a unit are in SI units;
* column names in any letter case, in double quotes, and a trailing delimiter.

A time column with no stated unit whose sample spacing is implausible in seconds is
refused with the likely unit (:func:`camdyn.io.record_fields.check_time_unit`).
"""

from __future__ import annotations

import codecs
import re
from pathlib import Path

import numpy as np
import xarray as xr

from camdyn.errors import DataError
from camdyn.io.content import HEAD_BYTES, unmarked_utf16
from camdyn.io.record_fields import (
    check_time_unit,
    finished_record,
    metadata_item,
    time_unit_factor,
    unit_factor,
)
from camdyn.records.schema import CHANNEL_UNITS

__all__ = ["read_csv_record", "decode_text", "column_name"]

_NAMES = {name.lower(): name for name in ("time", *CHANNEL_UNITS)}
_BRACKETED = re.compile(r"(?P<name>.+?)\s*[\[(](?P<unit>[^\])]*)[\])]")
_BLANK_FIELDS = re.compile(r"[^\s\[(]+(?:\s*[\[(][^\])]*[\])])?")
_LINE_BREAK = re.compile(r"\r\n|\r|\n")
_BYTE_LINE_BREAK = re.compile(rb"\r\n|\r|\n")
_DELIMITERS = {",": "comma", ";": "semicolon", "\t": "tab", None: "blank"}


def decode_text(path: Path, raw: bytes) -> list[str]:
    """The lines of a text file: UTF-8 (with or without a byte-order mark), UTF-16 with
    a byte-order mark, or UTF-8 with comment lines in Windows-1252/Latin-1."""
    for mark, codec in ((codecs.BOM_UTF16_LE, "utf-16-le"), (codecs.BOM_UTF16_BE, "utf-16-be")):
        if raw.startswith(mark):
            try:
                return _LINE_BREAK.split(raw[len(mark):].decode(codec))
            except UnicodeDecodeError:
                raise DataError(f"{path}: starts with a UTF-16 byte-order mark but is not UTF-16 text; "
                                "save it as UTF-8 CSV") from None
    if raw.startswith(codecs.BOM_UTF8):
        raw = raw[len(codecs.BOM_UTF8):]
    codec = unmarked_utf16(raw[:HEAD_BYTES])
    if codec:
        try:
            return _LINE_BREAK.split(raw.decode(codec))
        except UnicodeDecodeError:
            raise DataError(f"{path}: starts as UTF-16 text without a byte-order mark but is not UTF-16 "
                            "throughout; save it as UTF-8 CSV") from None
    if b"\x00" in raw:
        line = raw[:raw.index(b"\x00")].count(b"\n") + 1
        raise DataError(f"{path}: binary file, not CSV text (a NUL byte on line {line})")
    try:
        return _LINE_BREAK.split(raw.decode("utf-8"))
    except UnicodeDecodeError:
        pass
    lines = []
    for number, line in enumerate(_BYTE_LINE_BREAK.split(raw), start=1):
        try:
            lines.append(line.decode("utf-8"))
        except UnicodeDecodeError as exc:
            if not line.lstrip().startswith(b"#"):
                raise DataError(f"{path}: line {number} is not UTF-8 text (byte 0x{line[exc.start]:02x} at "
                                f"column {exc.start + 1}, as Latin-1 or Windows-1252 files have); save the file "
                                "as UTF-8 (in Excel: 'CSV UTF-8')") from None
            try:
                lines.append(line.decode("cp1252"))
            except UnicodeDecodeError:
                lines.append(line.decode("latin-1"))
    return lines


def column_name(field: str) -> tuple[str, str | None] | None:
    """The channel (or ``"time"``) and unit a header field names, or None.

    ``"time"``, ``"Time [ms]"``, ``"time (ms)"``, ``"time_ms"`` and ``"Nx [kN]"`` are
    understood; a unit of None means SI units (or, for the time, not stated).
    """
    field = field.strip().strip('"').strip()
    match = _BRACKETED.fullmatch(field)
    base, unit = (match["name"].strip(), match["unit"].strip()) if match else (field, None)
    if base.lower() in _NAMES:
        return _NAMES[base.lower()], unit or None
    if unit is None:
        for known in sorted(_NAMES, key=len, reverse=True):
            if base.lower().startswith(known + "_") and len(base) > len(known) + 1:
                return _NAMES[known], base[len(known) + 1:]
    return None


def _is_number(text: str) -> bool:
    try:
        float(text.replace(",", "."))
    except ValueError:
        return False
    return True


def _split(line: str, delimiter: str | None) -> list[str]:
    if delimiter is None:
        return _BLANK_FIELDS.findall(line)
    return line.split(delimiter)


def _header(path: Path, line: str, number: int) -> tuple[str | None, list[tuple[str, str | None]], bool]:
    """The delimiter, the (name, unit) of each column of the header row, and whether the
    row ends with a delimiter."""
    candidates = [d for d in (",", ";", "\t") if d in line] or [None]
    readings = {}
    for delimiter in candidates:
        fields = _split(line.rstrip(), delimiter)
        if len(fields) > 1 and not fields[-1].strip():   # a trailing delimiter
            fields.pop()
        readings[delimiter] = (fields, [column_name(f) for f in fields])
    good = [d for d, (_, columns) in readings.items() if all(columns)]
    if not good:
        delimiter = max(readings, key=lambda d: len(readings[d][0]))
        fields, columns = readings[delimiter]
        unknown = [f.strip() for f, c in zip(fields, columns) if c is None]
        if all(_is_number(f) for f in fields):
            raise DataError(f"{path}: line {number} holds numbers where the header row with the column names "
                            f"belongs; add a header such as 'time,Nx,Ny,alpha_ddot' (units as in 'time [ms]')")
        if len(fields) == 1 and len(line.strip()) > 40:
            raise DataError(f"{path}: line {number} should be the header row with the column names, but it "
                            f"reads {line.strip()[:40]!r}...; expected names such as time, "
                            f"{', '.join(CHANNEL_UNITS)}")
        raise DataError(f"{path}: unknown columns {unknown} in the header (line {number}); known: time, "
                        f"{', '.join(CHANNEL_UNITS)}, each optionally with a unit as in 'time [ms]'")
    delimiter = good[0]
    columns = readings[delimiter][1]
    names = [c[0] for c in columns]
    for name in names:
        if names.count(name) > 1:
            raise DataError(f"{path}: the column {name} appears {names.count(name)} times in the header "
                            f"(line {number})")
    if "time" not in names:
        raise DataError(f"{path}: the header {names} (line {number}) has no 'time' column")
    return delimiter, columns, delimiter is not None and line.rstrip().endswith(delimiter)


def _preamble(path: Path, lines: list[str]) -> tuple[dict, dict, int]:
    """Metadata, units from a ``# units:`` line, and the index of the header row."""
    metadata, units = {}, {}
    for index, line in enumerate(lines):
        stripped = line.strip()
        if not stripped:
            continue
        if not stripped.startswith("#"):
            return metadata, units, index
        body = stripped.lstrip("#").strip()
        where = f"{path}: line {index + 1}"
        if body.lower().startswith("units:"):
            for item in re.split(r"[,;\t]", body[len("units:"):]):
                parts = item.split(None, 1)
                if not parts:
                    continue
                column = column_name(parts[0])
                if len(parts) < 2 or column is None:
                    raise DataError(f"{where}: cannot read the units entry {item.strip()!r}; write it as "
                                    "'# units: time ms, Nx N'")
                units[column[0]] = parts[1].strip().strip("[]()").strip()
        elif "=" in body:
            key, value = body.split("=", 1)
            item = metadata_item(key, value.strip(), where)
            if item:
                metadata[item[0]] = item[1]
    raise DataError(f"{path}: no header row with column names (the file holds only comments or blank lines)")


def _table(path: Path, rows: list[tuple[int, str]], delimiter: str | None, count: int,
           trailing: bool) -> np.ndarray:
    """The samples of the data rows as a (samples, columns) array; ``trailing``: each row
    may end with a delimiter, as the header does."""
    texts = [text.rstrip() for _, text in rows]
    if trailing:
        texts = [text.removesuffix(delimiter) for text in texts]
    if delimiter != "," and any("," in text for text in texts):
        texts = [text.replace(",", ".") for text in texts]    # a decimal comma
    if any('"' in text for text in texts):
        texts = [text.replace('"', "") for text in texts]     # quoted numbers
    try:
        table = np.loadtxt(texts, delimiter=delimiter, ndmin=2, comments=None, dtype=float)
        if table.shape[1] == count:
            return table
        problem = f"{table.shape[1]} columns of numbers"
    except ValueError as exc:
        problem = str(exc)
    for (number, _), text in zip(rows, texts):
        last = " (the last line: was the file cut short?)" if number == rows[-1][0] else ""
        fields = _split(text, delimiter)
        if len(fields) != count:
            raise DataError(f"{path}: line {number} has {len(fields)} value{'s' if len(fields) != 1 else ''} "
                            f"but the header names {count} columns (separated by {_DELIMITERS[delimiter]}s){last}")
        for field in fields[:count]:
            value = field.strip()
            try:
                float(value)
            except ValueError:
                detail = "an empty field (a missing sample?)" if not value else f"{value[:30]!r} is not a number"
                raise DataError(f"{path}: line {number}: {detail}{last}") from None
    raise DataError(f"{path}: cannot read the samples ({problem})")


def read_csv_record(path: Path, raw: bytes) -> xr.Dataset:
    """Read a CSV record from its bytes ``raw`` (see the module description)."""
    lines = decode_text(path, raw)
    metadata, units, index = _preamble(path, lines)
    delimiter, columns, trailing = _header(path, lines[index], index + 1)
    rows = [(number, line) for number, line in enumerate(lines[index + 1:], start=index + 2)
            if line.strip() and not line.lstrip().startswith("#")]
    if not rows:
        raise DataError(f"{path}: the header row (line {index + 1}) is followed by no samples: the file holds "
                        "column names but no data (was the export cut short?)")
    table = _table(path, rows, delimiter, len(columns), trailing)
    values = {}
    time_stated = False
    for position, (name, header_unit) in enumerate(columns):
        unit = header_unit or units.get(name)
        if header_unit and name in units and header_unit != units[name]:
            raise DataError(f"{path}: the header gives {name} in {header_unit} but the units line in "
                            f"{units[name]}")
        target = "s" if name == "time" else CHANNEL_UNITS[name][0]
        factor = unit_factor(unit, target, name, str(path)) if unit and name != "time" else 1.0
        if name == "time" and unit:
            factor, time_stated = time_unit_factor(unit, str(path)), True
        values[name] = table[:, position] * factor
    time = values.pop("time")
    if not time_stated:
        check_time_unit(time, metadata.get("speed_hz"), str(path))
    return finished_record(path, time, values, metadata)
