"""Pieces shared by the record readers: metadata entries, unit factors of the time axis
and the channels, the check of a time axis with no stated unit, and the final record."""

from __future__ import annotations

import math
import re

import numpy as np
import xarray as xr

from camdyn.errors import CamdynError, DataError
from camdyn.params.units import parse_quantity, parse_speed
from camdyn.records.schema import CHANNEL_UNITS, make_record

__all__ = ["METADATA_KEYS", "metadata_item", "unit_factor", "time_unit_factor", "check_time_unit",
           "numeric_samples", "finished_record", "MINIMUM_SAMPLES_PER_REVOLUTION", "MINIMUM_SAMPLE_RATE"]

#: Metadata keys a record file may give, and the record attribute each one sets.
METADATA_KEYS = {"speed": "speed_hz", "speed_hz": "speed_hz", "cam.runout": "runout", "runout": "runout",
                 "preset": "preset", "noise": "noise"}

#: A time axis of unstated unit with fewer samples per cam revolution than this, read in
#: seconds, is refused as probably being in milliseconds or microseconds [-].
MINIMUM_SAMPLES_PER_REVOLUTION = 8.0

#: The same for a record without a cam speed: the least plausible sample rate [Hz].
MINIMUM_SAMPLE_RATE = 100.0

_PINT_UNITS = {"N": "N", "rad/s^2": "rad/s**2", "m/s^2": "m/s**2", "s": "s"}


def metadata_item(key: str, value: object, where: str) -> tuple[str, object] | None:
    """The record attribute and value of one metadata entry, or None for a key that
    camdyn does not use.

    Parameters
    ----------
    key, value : str
        For example ``"speed"`` and ``"16 Hz"``, or ``"cam.runout"`` and ``"3.5 mm"``.
    where : str
        The file (and line) the entry comes from, for error messages.
    """
    key = str(key).strip()
    if key not in METADATA_KEYS:
        return None
    name = METADATA_KEYS[key]
    if isinstance(value, bytes):
        value = value.decode("utf-8", errors="replace")
    if isinstance(value, np.ndarray):
        if value.size != 1:
            raise DataError(f"{where}: the metadata entry {key} holds {value.size} values; expected one")
        value = value.item()
    if isinstance(value, np.generic):
        value = value.item()
    if name != "preset" and isinstance(value, str) and re.search(r"\d,\d", value):
        raise DataError(f"{where}: the metadata entry {key} = {value.strip()!r} has a comma in its number; "
                        "write it with a decimal point")
    try:
        if name == "speed_hz":
            return name, parse_speed(value if isinstance(value, (int, float)) else str(value), key)
        if name == "runout":
            return name, parse_quantity(value if isinstance(value, (int, float)) else str(value), "m", key)
        if name == "noise":
            return name, float(value)
    except (CamdynError, TypeError, ValueError) as exc:
        raise DataError(f"{where}: the metadata entry {key} = {str(value).strip()!r} cannot be read ({exc})") from None
    return name, str(value).strip().strip('"')


def unit_factor(unit: str, target: str, what: str, where: str) -> float:
    """The factor that converts values in ``unit`` to ``target`` (a channel's SI unit, or
    ``"s"`` for the time axis); ``what`` names the column in error messages."""
    try:
        factor = parse_quantity(f"1 {unit.strip()}", _PINT_UNITS.get(target, target), what)
    except CamdynError as exc:
        raise DataError(f"{where}: {what} has the unit {unit.strip()!r}, not convertible to {target} ({exc})") from None
    if not (math.isfinite(factor) and factor > 0):
        raise DataError(f"{where}: {what} has the unit {unit.strip()!r}, which is not a usable unit of {target}")
    return factor


def time_unit_factor(unit: str, where: str) -> float:
    """The factor from the time unit ``unit`` to seconds; the ``since DATE`` part of a
    netCDF time unit (``"seconds since 2024-01-01"``) is dropped."""
    return unit_factor(unit.split(" since ")[0], "s", "the time axis", where)


def check_time_unit(time: np.ndarray, speed_hz: float | None, where: str) -> None:
    """Refuse a time axis whose unit the file does not state when its sample spacing read
    in seconds is implausible for a vibration record: fewer than
    :data:`MINIMUM_SAMPLES_PER_REVOLUTION` samples per cam revolution at the stated speed
    ``speed_hz`` [Hz], or, with no speed, a sample rate below :data:`MINIMUM_SAMPLE_RATE`.
    The message says which unit (ms or us) would make it plausible."""
    if time.size < 2:
        return
    steps = np.diff(time)
    steps = steps[np.isfinite(steps) & (steps > 0)]
    if steps.size == 0:
        return
    step = float(np.median(steps))

    def plausible(factor: float) -> bool:
        if speed_hz is not None and speed_hz > 0:
            return 1.0 / (speed_hz * step * factor) >= MINIMUM_SAMPLES_PER_REVOLUTION
        return 1.0 / (step * factor) >= MINIMUM_SAMPLE_RATE

    if plausible(1.0):
        return
    rate = f"a sample rate of {1.0 / step:.4g} Hz"
    if speed_hz is not None and speed_hz > 0:
        rate += f", {1.0 / (speed_hz * step):.3g} samples per cam revolution at the stated {speed_hz:.6g} Hz"
    guess = next((f"; it looks like {word}" for factor, word in ((1e-3, "milliseconds"), (1e-6, "microseconds"))
                  if plausible(factor)), "")
    raise DataError(f"{where}: the time column steps by {step:.6g} per sample and states no unit; read in "
                    f"seconds that is {rate}, too slow for a vibration record{guess}. State the unit: a header "
                    f"'time [ms]' or 'time_ms', or a line '# units: time ms' (or s, us)")


def numeric_samples(values: object, name: str, where: str) -> np.ndarray:
    """``values`` as a 1-D float array, refusing text, complex or multi-dimensional data."""
    array = np.asarray(values)
    if array.dtype.kind == "c":
        raise DataError(f"{where}: {name} holds complex values (a frequency response?); a record holds "
                        "real samples over time")
    if array.dtype.kind not in "biuf":
        raise DataError(f"{where}: {name} holds {array.dtype} values, not numbers")
    if array.ndim != 1:
        raise DataError(f"{where}: {name} has the shape {array.shape}; a record channel is one row of samples")
    return array.astype(float)


def finished_record(path: object, time: np.ndarray, channels: dict, metadata: dict) -> xr.Dataset:
    """The checked record (:func:`camdyn.records.schema.make_record`), with the file
    named in the message of a refusal."""
    if not channels:
        raise DataError(f"{path}: no channel camdyn knows; known: {', '.join(CHANNEL_UNITS)}")
    try:
        return make_record(time, channels, source=str(path), **metadata)
    except DataError as exc:
        raise DataError(f"{path}: {exc}") from None
