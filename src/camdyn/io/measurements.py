"""Measured vibration records: CSV, netCDF/HDF5 and UFF dataset 58 readers and writers.

A record is an :class:`xarray.Dataset` over ``time`` [s] with any of the channels

================ ========= ==============================================================
channel          unit      meaning
================ ========= ==============================================================
``Nx``           N         pivot reaction on the follower, horizontal
``Ny``           N         pivot reaction on the follower, vertical
``alpha_ddot``   rad/s^2   follower angular acceleration
``a_t``          m/s^2     tangential accelerometer signal at the sensor distance ``l_a``
``force``        N         impulse-hammer force (impulse tests)
``acceleration`` m/s^2     response acceleration (impulse tests)
================ ========= ==============================================================

and optional metadata attributes (``speed_hz`` [Hz], ``runout`` [m], ``preset``). A record
holding ``a_t`` but not ``alpha_ddot`` gets ``alpha_ddot = a_t / l_a`` from
:func:`angular_acceleration`. Every reader checks the sampling (uniform, no gaps), and
:func:`check_record` refuses NaN, infinite and clipped samples with a message that says
where they are.

File layouts
------------
CSV
    Comment lines ``# key = value`` (metadata, values may carry units, e.g.
    ``# speed = 16 Hz``, ``# cam.runout = 3.5 mm``), then a header row naming the
    columns, then one row per sample; SI units and ``time`` in seconds unless the header
    (``time [ms]``, ``time_ms``) or a line ``# units: time ms, Nx N`` says otherwise.
    Byte-order marks, semicolon or tab delimiters and Latin-1 comments are accepted
    (:mod:`camdyn.io.csv_records`).
netCDF / HDF5 (``.nc``, ``.h5``, ``.hdf5``, ``.nc4``)
    Variables over a ``time`` dimension and coordinate, each with a ``units`` attribute
    (converted to the units above with pint). Classic netCDF-3 files are read too.
UFF 58 (``.uff``, ``.unv``)
    One dataset 58 per channel, named by ``id1``; the time axis from ``abscissa_min``
    and ``abscissa_inc`` (or the stored abscissa of an unevenly spaced dataset) in the
    unit ``abscissa_axis_units_lab``; units from ``ordinate_axis_units_lab``; metadata
    as ``key=value`` pairs separated by ``;`` in ``id4``.

Refusals
--------
Every refusal is a :class:`~camdyn.errors.DataError` of one line that names the file and
says what was found: an empty file; binary data, or a file whose first bytes show
another format than its suffix (netCDF saved as ``.csv``: "it looks like a
netCDF-4/HDF5 file; rename it to .nc"); a header without samples; a row that is not
UTF-8 or not numbers (with its line number); an HDF5 file without netCDF dimensions; a
truncated or damaged netCDF or UFF file; a time axis of unstated unit whose spacing
suggests milliseconds or microseconds; and records with gaps, irregular sampling, or
too few samples.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from camdyn.errors import DataError, ParameterError
from camdyn.io.atomic import atomic_output
from camdyn.io.content import KIND_NAMES, file_kind, one_line, read_head
from camdyn.io.csv_records import read_csv_record
from camdyn.io.record_fields import (
    check_time_unit,
    finished_record,
    metadata_item,
    numeric_samples,
    time_unit_factor,
    unit_factor,
)
from camdyn.records.schema import (
    CHANNEL_UNITS,
    angular_acceleration,
    check_record,
    make_record,
)

__all__ = ["CHANNEL_UNITS", "RECORD_SUFFIXES", "read_measurement", "write_measurement", "check_record",
           "make_record", "angular_acceleration", "record_format"]

#: File suffixes of the record formats (CSV, netCDF/HDF5, UFF 58).
RECORD_SUFFIXES = {".csv", ".txt", ".nc", ".h5", ".hdf5", ".nc4", ".uff", ".unv"}

_FORMATS = {".csv": "csv", ".txt": "csv", ".nc": "netcdf", ".h5": "netcdf", ".hdf5": "netcdf", ".nc4": "netcdf",
            ".uff": "uff", ".unv": "uff"}
_FORMAT_KINDS = {"csv": {"text"}, "netcdf": {"hdf5", "netcdf3"}, "uff": {"uff"}}
_FORMAT_NAMES = {"csv": "CSV text", "netcdf": "a netCDF/HDF5 file", "uff": "a UFF file"}


def record_format(path: str | Path) -> str:
    """The format a record named ``path`` is written in, by its suffix: ``"CSV text"``,
    ``"a netCDF/HDF5 file"`` or ``"a UFF file"`` (a suffix of none: a DataError)."""
    family = _FORMATS.get(Path(path).suffix.lower())
    if family is None:
        raise DataError(f"{path}: unknown record format {Path(path).suffix or '(no suffix)'!r} (use .csv, "
                        f".nc/.h5 or .uff)")
    return _FORMAT_NAMES[family]
_RENAME = {"hdf5": "; rename it to .nc", "netcdf3": "; rename it to .nc", "uff": "; rename it to .uff",
           "text": "; if it is a CSV record, rename it to .csv",
           "zip": "; export the sheet as CSV (comma-separated, UTF-8)",
           "xls": "; export the sheet as CSV (comma-separated, UTF-8)"}
_CHANNELS = {name.lower(): name for name in CHANNEL_UNITS}
_UNSTATED_UNITS = {"", "none", "unknown"}


def _channel_factor(name: str, unit: str | None, where: str, field: str = "units attribute") -> float:
    if unit is None:
        raise DataError(f"{where}: channel {name} has no {field} (expected {CHANNEL_UNITS[name][0]})")
    if unit.strip() == CHANNEL_UNITS[name][0]:
        return 1.0
    return unit_factor(unit, CHANNEL_UNITS[name][0], f"channel {name}", where)


def _text(value: object) -> str:
    if isinstance(value, bytes):
        return value.decode("utf-8", errors="replace")
    if isinstance(value, np.ndarray) and value.size == 1:
        return str(value.item())
    return str(value)


def _load_netcdf(path: Path, kind: str) -> xr.Dataset:
    options = {"engine": "scipy"} if kind == "netcdf3" else {"engine": "h5netcdf", "phony_dims": "access"}
    try:
        if kind == "hdf5":
            # h5py first: a damaged root attribute makes h5netcdf fail half-built, and the
            # half-built object prints a traceback when it is collected
            import h5py

            with h5py.File(path, "r") as handle:
                handle.attrs.get("_nc3_strict")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return xr.load_dataset(path, decode_times=False, decode_timedelta=False, **options)
    except Exception as exc:  # noqa: BLE001 - h5py, h5netcdf and scipy raise many types on damaged files
        raise DataError(f"{path}: {KIND_NAMES[kind]} that cannot be read, probably truncated or damaged "
                        f"({type(exc).__name__}: {one_line(exc, 160)}); write or copy it again") from None


def _read_netcdf(path: Path, kind: str) -> xr.Dataset:
    raw = _load_netcdf(path, kind)
    if "time" not in raw.dims or "time" not in raw.variables:
        found = ", ".join(f"{name}{raw[name].dims}" for name in raw.variables) or "none"
        plain = not raw.dims or any(str(dim).startswith("phony_dim") for dim in raw.dims)
        what = "an HDF5 file without netCDF dimensions/time coordinate" if plain else \
            "a netCDF file without a 'time' dimension and coordinate"
        raise DataError(f"{path}: {what} (its datasets: {found}); write it with xarray, "
                        "Dataset.to_netcdf(path, engine='h5netcdf'), or with netCDF4 and a 'time' dimension and "
                        "coordinate variable, or save it as CSV")
    where = str(path)
    metadata = {}
    for key, value in raw.attrs.items():
        item = metadata_item(key, value, where)
        if item:
            metadata[item[0]] = item[1]
    if raw["time"].dims != ("time",):
        raise DataError(f"{where}: the time coordinate has the dimensions {raw['time'].dims}, expected (time,)")
    time = numeric_samples(raw["time"].values, "the time coordinate", where)
    unit = raw["time"].attrs.get("units")
    if unit is None or not _text(unit).strip():
        check_time_unit(time, metadata.get("speed_hz"), where)
    else:
        time = time * time_unit_factor(_text(unit), where)
    channels = {}
    for variable in raw.data_vars:
        name = _CHANNELS.get(str(variable).lower())
        if name is None:
            continue
        if name in channels:
            raise DataError(f"{where}: two variables name the channel {name} (letter case aside)")
        if raw[variable].dims != ("time",):
            raise DataError(f"{where}: channel {name} has the dimensions {raw[variable].dims}, expected (time,)")
        unit = raw[variable].attrs.get("units")
        values = numeric_samples(raw[variable].values, f"channel {name}", where)
        channels[name] = values * _channel_factor(name, None if unit is None else _text(unit), where)
    return finished_record(path, time, channels, metadata)


def _uff_delimiters(raw: bytes) -> list[int]:
    """Offsets of the ``    -1`` lines that delimit UFF datasets (as pyuff finds them)."""
    found, at = [], raw.find(b"    -1")
    while at != -1:
        end = at + 6
        if end == len(raw) or raw[end] in (10, 13) or raw[end:at + 80] == b" " * 74:
            found.append(at)
        at = raw.find(b"    -1", at + 1)
    return found


def _uff_sets(path: Path, raw: bytes) -> list[dict]:
    delimiters = _uff_delimiters(raw)
    if not delimiters:
        raise DataError(f"{path}: not a UFF file: no dataset delimiter lines ('    -1', four blanks then -1)")
    if len(delimiters) % 2:
        start, end = raw[:delimiters[-1]].count(b"\n") + 1, raw.count(b"\n") + 1
        raise DataError(f"{path}: a truncated UFF file: the dataset that starts on line {start} has no closing "
                        f"'    -1' line before the file ends (line {end}); export or copy it again")
    import pyuff  # optional dependency (extra "measurements")

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            sets = pyuff.UFF(str(path)).read_sets()
    except Exception as exc:  # noqa: BLE001 - pyuff raises bare Exceptions on malformed files
        raise DataError(f"{path}: a damaged UFF file ({one_line(exc, 160)})") from None
    return [sets] if isinstance(sets, dict) else list(sets)


def _uff_number(dataset: dict, key: str, where: str) -> float:
    try:
        return float(dataset[key])
    except (KeyError, TypeError, ValueError):
        raise DataError(f"{where}: the header field {key} is missing or not a number") from None


def _read_uff(path: Path, raw: bytes) -> xr.Dataset:
    time, time_stated, channels, metadata = None, True, {}, {}
    for number, dataset in enumerate(_uff_sets(path, raw), start=1):
        name = _CHANNELS.get(str(dataset.get("id1", "")).strip().lower())
        if dataset.get("type") != 58 or name is None:
            continue
        where = f"{path}: dataset {number} ({name})"
        if name in channels:
            raise DataError(f"{where}: a second dataset named {name}")
        data = numeric_samples(dataset.get("data"), "the data", where)
        announced = _uff_number(dataset, "num_pts", where)
        if announced != data.size:
            raise DataError(f"{where}: announces {announced:.0f} values but holds {data.size}; the file is "
                            "truncated or damaged")
        stamps = numeric_samples(dataset.get("x"), "the abscissa", where)
        if stamps.size != data.size:
            raise DataError(f"{where}: {stamps.size} abscissa values for {data.size} samples")
        unit = _text(dataset.get("abscissa_axis_units_lab", "")).strip()
        if unit.lower() not in _UNSTATED_UNITS:
            stamps = stamps * time_unit_factor(unit, where)
        if time is None:
            time, time_stated = stamps, unit.lower() not in _UNSTATED_UNITS
        elif stamps.size != time.size or not np.allclose(
                stamps, time, rtol=0, atol=1e-9 * max(1.0, float(np.max(np.abs(time), initial=0.0)))):
            raise DataError(f"{where}: a different time axis from the other channels")
        unit = _text(dataset.get("ordinate_axis_units_lab", "")).strip()
        unit = None if unit.lower() in _UNSTATED_UNITS else unit
        channels[name] = data * _channel_factor(name, unit, where, "ordinate unit label")
        for pair in _text(dataset.get("id4", "")).split(";"):
            if "=" in pair:
                item = metadata_item(*pair.split("=", 1), where)
                if item:
                    metadata[item[0]] = item[1]
    if time is None:
        raise DataError(f"{path}: no dataset 58 named {', '.join(CHANNEL_UNITS)} (in id1)")
    if not time_stated:
        check_time_unit(time, metadata.get("speed_hz"), str(path))
    return finished_record(path, time, channels, metadata)


def _format_mismatch(path: Path, family: str, kind: str) -> DataError:
    looks = f"it looks like {KIND_NAMES[kind]}{_RENAME.get(kind, '')}"
    if family == "csv" and kind == "binary":
        return DataError(f"{path}: binary file, not CSV text")
    if family == "csv" and kind != "uff":
        return DataError(f"{path}: binary file, not CSV text: {looks}")
    return DataError(f"{path}: not {_FORMAT_NAMES[family]}: {looks}")


def read_measurement(path: str | Path) -> xr.Dataset:
    """Read a record from CSV, netCDF/HDF5 or UFF 58, by the file's suffix.

    The file's first bytes are checked against its suffix first: an empty file, binary
    data named ``.csv``, or a file in another format than its suffix says is refused with
    a message that says what the file looks like. The CSV reader's tolerances (byte-order
    marks, delimiters, units in the header) are listed in :mod:`camdyn.io.csv_records`.

    Raises
    ------
    DataError
        The file is missing, unreadable, in the wrong format, or its samples are unusable.
    ParameterError
        ``path`` is not a file name (text or a path).
    """
    if isinstance(path, bytes) or not isinstance(path, (str, os.PathLike)):
        raise ParameterError(f"read_measurement expects the record's file name (text or a pathlib.Path), got "
                             f"{type(path).__name__} {path!r:.60}")
    path = Path(path)
    try:
        is_dir, is_file = path.is_dir(), path.is_file()
    except (OSError, ValueError) as exc:   # a name too long to look up, a NUL byte
        reason = getattr(exc, "strerror", None) or exc
        raise DataError(f"{str(path)[:80]!r}: not a usable file name ({reason})") from None
    if is_dir:
        raise DataError(f"{path} is a folder, not a measurement file")
    if not is_file:
        raise DataError(f"no such file: {path}")
    try:
        head = read_head(path)
    except OSError as exc:
        raise DataError(f"{path}: cannot read the file ({exc.strerror or exc})") from None
    kind = file_kind(head)
    suffix = path.suffix.lower()
    family = _FORMATS.get(suffix)
    if kind == "empty":
        raise DataError(f"{path}: the file is empty (0 bytes); was the export or the copy interrupted?")
    if family is None:
        raise DataError(f"{path}: unknown measurement format {suffix or '(no suffix)'!r} (use .csv, .nc/.h5 or "
                        f".uff/.unv); its content looks like {KIND_NAMES[kind]}{_RENAME.get(kind, '')}")
    if kind not in _FORMAT_KINDS[family]:
        raise _format_mismatch(path, family, kind)
    if family == "netcdf":
        return _read_netcdf(path, kind)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise DataError(f"{path}: cannot read the file ({exc.strerror or exc})") from None
    if family == "csv":
        return read_csv_record(path, raw)
    return _read_uff(path, raw)


def _meta_pairs(ds: xr.Dataset) -> list[tuple[str, str]]:
    out = []
    if "speed_hz" in ds.attrs:
        out.append(("speed", f"{float(ds.attrs['speed_hz']):.12g} Hz"))
    if "runout" in ds.attrs:
        out.append(("cam.runout", f"{float(ds.attrs['runout']) * 1e3:.12g} mm"))
    for key in ("preset", "noise"):
        if key in ds.attrs:
            out.append((key, str(ds.attrs[key])))
    return out


def write_measurement(ds: xr.Dataset, path: str | Path) -> Path:
    """Write a record as CSV, netCDF or UFF 58, by the suffix of ``path`` (atomically: an
    existing file of that name is replaced only once the new one is complete)."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in RECORD_SUFFIXES:
        raise DataError(f"{path}: unknown record format {suffix or '(no suffix)'!r}; "
                        f"use one of {', '.join(sorted(RECORD_SUFFIXES))}")
    names = [n for n in CHANNEL_UNITS if n in ds]
    expected = ds["time"].size * (len(names) + 1) * 18
    with atomic_output(path, expected) as tmp:
        _write_record(ds, names, suffix, tmp)
    return path


def _write_record(ds: xr.Dataset, names: list[str], suffix: str, path: Path) -> None:
    if suffix in (".csv", ".txt"):
        with path.open("w") as fh:
            for k, v in _meta_pairs(ds):
                fh.write(f"# {k} = {v}\n")
            fh.write("# units: time s, " + ", ".join(f"{n} {CHANNEL_UNITS[n][0]}" for n in names) + "\n")
            table = np.column_stack([ds["time"].values] + [ds[n].values for n in names])
            np.savetxt(fh, table, delimiter=",", fmt="%.10g", header=",".join(["time"] + names), comments="")
    elif suffix in (".nc", ".h5", ".hdf5", ".nc4"):
        out = ds[names].copy()
        out.attrs = {k: v for k, v in ds.attrs.items() if isinstance(v, (int, float, str))}
        from camdyn.io.netcdf import write_netcdf

        write_netcdf(out, path)   # built in memory: a full disk cannot crash HDF5
    elif suffix in (".uff", ".unv"):
        import pyuff

        t = ds["time"].values
        meta = ";".join(f"{k}={v}" for k, v in _meta_pairs(ds))
        uff = pyuff.UFF(str(path))
        for n in names:
            uff.write_sets(pyuff.prepare_58(
                binary=0, id1=n, id2="camdyn record", id3="", id4=meta, id5="", func_type=1, ver_num=0,
                load_case_id=0, rsp_ent_name="follower", rsp_node=1, rsp_dir=1, ref_ent_name="NONE", ref_node=0,
                ref_dir=0, abscissa_spacing=1, abscissa_min=float(t[0]), abscissa_inc=float(t[1] - t[0]),
                z_axis_value=0.0, abscissa_spec_data_type=17, abscissa_len_unit_exp=0,
                abscissa_force_unit_exp=0, abscissa_temp_unit_exp=0, abscissa_axis_units_lab="s",
                ordinate_spec_data_type=0, ordinate_len_unit_exp=0, ordinate_force_unit_exp=0,
                ordinate_temp_unit_exp=0, ordinate_axis_units_lab=CHANNEL_UNITS[n][0],
                orddenom_spec_data_type=0, orddenom_len_unit_exp=0, orddenom_force_unit_exp=0,
                orddenom_temp_unit_exp=0, orddenom_axis_units_lab="", z_axis_spec_data_type=0,
                z_axis_len_unit_exp=0, z_axis_force_unit_exp=0, z_axis_temp_unit_exp=0, z_axis_axis_units_lab="",
                data=ds[n].values.astype(float), x=t), mode="add")
