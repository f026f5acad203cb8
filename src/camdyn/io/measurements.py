"""Measured vibration records: CSV, netCDF/HDF5 and UFF dataset 58 readers and writers.

A record is an :class:`xarray.Dataset` over ``time`` [s] with any of the channels

============== ========= ==============================================================
channel         unit      meaning
============== ========= ==============================================================
``Nx``          N         pivot reaction on the follower, horizontal
``Ny``          N         pivot reaction on the follower, vertical
``alpha_ddot``  rad/s^2   follower angular acceleration
``a_t``         m/s^2     tangential accelerometer signal at the sensor distance ``l_a``
``force``       N         impulse-hammer force (impulse tests)
``acceleration`` m/s^2    response acceleration (impulse tests)
============== ========= ==============================================================

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
    columns, then one row per sample; SI units, ``time`` in seconds.
netCDF / HDF5 (``.nc``, ``.h5``, ``.hdf5``)
    Variables over a ``time`` coordinate, each with a ``units`` attribute (converted to
    the units above with pint).
UFF 58 (``.uff``, ``.unv``)
    One dataset 58 per channel, named by ``id1``; the time axis from ``abscissa_min``
    and ``abscissa_inc``; units from ``ordinate_axis_units_lab``; metadata as
    ``key=value`` pairs separated by ``;`` in ``id4``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from camdyn.errors import DataError, UnitError
from camdyn.io.atomic import atomic_output
from camdyn.params.units import parse_quantity, parse_speed
from camdyn.records.schema import (
    CHANNEL_UNITS,
    angular_acceleration,
    check_record,
    make_record,
)

__all__ = ["CHANNEL_UNITS", "read_measurement", "write_measurement", "check_record", "make_record",
           "angular_acceleration"]

_PINT_UNITS = {"N": "N", "rad/s^2": "rad/s**2", "m/s^2": "m/s**2"}
_METADATA = {"speed": "speed_hz", "speed_hz": "speed_hz", "cam.runout": "runout", "runout": "runout",
             "preset": "preset", "noise": "noise"}


def _metadata(key: str, value) -> tuple[str, object] | None:
    key = key.strip()
    if key not in _METADATA:
        return None
    name = _METADATA[key]
    if name == "speed_hz":
        return name, parse_speed(value)
    if name == "runout":
        return name, parse_quantity(value, "m", key)
    if name == "noise":
        return name, float(value)
    return name, str(value).strip().strip('"')


def _convert(name: str, values: np.ndarray, unit: str | None, where: str) -> np.ndarray:
    target = CHANNEL_UNITS[name][0]
    if unit is None or unit.strip() in ("", target):
        if unit is None:
            raise DataError(f"{where}: channel {name} has no units attribute (expected {target})")
        return values
    try:
        factor = parse_quantity(f"1 {unit}", _PINT_UNITS[target], f"{where} {name}")
    except UnitError as exc:
        raise DataError(f"{where}: channel {name} has units {unit!r}, not convertible to {target} ({exc})") from None
    return values * factor


def _read_csv(path: Path) -> xr.Dataset:
    meta = {}
    header = None
    skip = 0
    with path.open() as fh:
        for line in fh:
            stripped = line.strip()
            skip += 1
            if not stripped:
                continue
            if stripped.startswith("#"):
                body = stripped.lstrip("#").strip()
                if "=" in body:
                    k, v = body.split("=", 1)
                    item = _metadata(k, v.strip())
                    if item:
                        meta[item[0]] = item[1]
                continue
            header = [c.strip() for c in stripped.split(",")]
            break
    if header is None:
        raise DataError(f"{path}: no header row with column names")
    if "time" not in header:
        raise DataError(f"{path}: the header {header} has no 'time' column")
    unknown = [c for c in header if c != "time" and c not in CHANNEL_UNITS]
    if unknown:
        raise DataError(f"{path}: unknown columns {unknown}; known: time, {', '.join(CHANNEL_UNITS)}")
    try:
        table = np.loadtxt(path, delimiter=",", skiprows=skip, ndmin=2)
    except ValueError as exc:
        raise DataError(f"{path}: cannot read the samples ({exc})") from None
    if table.shape[1] != len(header):
        raise DataError(f"{path}: {table.shape[1]} columns of numbers but {len(header)} names in the header")
    cols = {name: table[:, i] for i, name in enumerate(header)}
    return make_record(cols.pop("time"), cols, source=str(path), **meta)


def _read_netcdf(path: Path) -> xr.Dataset:
    try:
        raw = xr.load_dataset(path, engine="h5netcdf")
    except (OSError, ValueError) as exc:
        raise DataError(f"{path}: not a readable netCDF/HDF5 file ({exc})") from None
    if "time" not in raw.coords and "time" not in raw:
        raise DataError(f"{path}: no 'time' coordinate")
    time = raw["time"].values.astype(float)
    unit = raw["time"].attrs.get("units", "s")
    time = time * parse_quantity(f"1 {unit}", "s", "time")
    cols = {name: _convert(name, raw[name].values.astype(float), raw[name].attrs.get("units"), str(path))
            for name in CHANNEL_UNITS if name in raw}
    meta = {}
    for k, v in raw.attrs.items():
        item = _metadata(k, v)
        if item:
            meta[item[0]] = item[1]
    return make_record(time, cols, source=str(path), **meta)


def _read_uff(path: Path) -> xr.Dataset:
    import pyuff  # optional dependency (extra "measurements")

    try:
        sets = pyuff.UFF(str(path)).read_sets()
    except Exception as exc:  # pyuff raises bare Exceptions on malformed files
        raise DataError(f"{path}: not a readable UFF file ({exc})") from None
    if isinstance(sets, dict):
        sets = [sets]
    time = None
    cols = {}
    meta = {}
    for s in sets:
        if s.get("type") != 58:
            continue
        name = str(s.get("id1", "")).strip()
        if name not in CHANNEL_UNITS:
            continue
        data = np.asarray(s["data"], dtype=float)
        t = float(s.get("abscissa_min", 0.0)) + float(s["abscissa_inc"]) * np.arange(data.size)
        if time is None:
            time = t
        elif t.size != time.size or not np.allclose(t, time, rtol=0, atol=1e-9 * max(1.0, abs(time[-1]))):
            raise DataError(f"{path}: channel {name} has a different time axis from the others")
        cols[name] = _convert(name, data, str(s.get("ordinate_axis_units_lab", "")).strip() or None, str(path))
        for pair in str(s.get("id4", "")).split(";"):
            if "=" in pair:
                item = _metadata(*pair.split("=", 1))
                if item:
                    meta[item[0]] = item[1]
    if time is None:
        raise DataError(f"{path}: no dataset 58 named {', '.join(CHANNEL_UNITS)} (in id1)")
    return make_record(time, cols, source=str(path), **meta)


#: File suffixes of the record formats (CSV, netCDF/HDF5, UFF 58).
RECORD_SUFFIXES = {".csv", ".txt", ".nc", ".h5", ".hdf5", ".nc4", ".uff", ".unv"}


def read_measurement(path: str | Path) -> xr.Dataset:
    """Read a record from CSV, netCDF/HDF5 or UFF 58, by the file's suffix."""
    path = Path(path)
    if not path.is_file():
        raise DataError(f"no such file: {path}")
    suffix = path.suffix.lower()
    if suffix in (".csv", ".txt"):
        return _read_csv(path)
    if suffix in (".nc", ".h5", ".hdf5", ".nc4"):
        return _read_netcdf(path)
    if suffix in (".uff", ".unv"):
        return _read_uff(path)
    raise DataError(f"{path}: unknown measurement format {suffix!r} (use .csv, .nc/.h5 or .uff/.unv)")


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
        out.to_netcdf(path, engine="h5netcdf")
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
