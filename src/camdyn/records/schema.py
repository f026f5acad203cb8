"""The record schema: the channels a measured or synthetic record may hold, their SI
units, and the checks every record passes (uniform sampling, finite and unclipped
samples). Files are read and written by :mod:`camdyn.io.measurements`.

A record is an :class:`xarray.Dataset` over ``time`` [s]; the channels are listed in
:data:`CHANNEL_UNITS`. Optional metadata attributes: ``speed_hz`` [Hz], ``runout`` [m],
``preset``.
"""

from __future__ import annotations

import math
import os
import warnings

import numpy as np
import xarray as xr

from camdyn.errors import DataError, ParameterError

__all__ = ["CHANNEL_UNITS", "make_record", "check_sampling", "check_record", "angular_acceleration",
           "check_consistency", "require_record", "record_speed", "MAX_NOISE", "check_noise", "check_seed"]

#: Largest sensor noise a synthetic record may be given, as a fraction of each channel's
#: rms [-]: ten times the signal buries every harmonic an estimator reads.
MAX_NOISE = 10.0

#: SI unit and long name of every channel a record may hold.
CHANNEL_UNITS = {
    "Nx": ("N", "pivot reaction on the follower, horizontal"),
    "Ny": ("N", "pivot reaction on the follower, vertical"),
    "alpha_ddot": ("rad/s^2", "follower angular acceleration"),
    "a_t": ("m/s^2", "tangential acceleration at the accelerometer"),
    "force": ("N", "impulse-hammer force (impulse tests)"),
    "acceleration": ("m/s^2", "response acceleration (impulse tests)"),
}
def make_record(time, channels: dict, **attrs) -> xr.Dataset:
    """Build a checked record from ``time`` [s] and ``{name: samples}`` in SI units."""
    time = np.asarray(time, dtype=float)
    data = {}
    for name, values in channels.items():
        if name not in CHANNEL_UNITS:
            raise DataError(f"unknown channel {name!r}; known: {', '.join(CHANNEL_UNITS)}")
        unit, long_name = CHANNEL_UNITS[name]
        values = np.asarray(values, dtype=float)
        if values.shape != time.shape:
            raise DataError(f"channel {name} has {values.size} samples but time has {time.size}")
        data[name] = ("time", values, {"units": unit, "long_name": long_name})
    ds = xr.Dataset(data, coords={"time": ("time", time, {"units": "s", "long_name": "time"})})
    ds.attrs.update({k: v for k, v in attrs.items() if v is not None})
    check_sampling(ds)
    return ds


def check_sampling(ds: xr.Dataset) -> None:
    t = ds["time"].values
    if t.size < 16:
        raise DataError(f"the record holds only {t.size} samples")
    if not np.all(np.isfinite(t)):
        raise DataError("the time column holds NaN or infinite values")
    dt = np.diff(t)
    if np.any(dt <= 0):
        i = int(np.argmax(dt <= 0))
        raise DataError(f"time does not increase at sample {i + 1} (t = {t[i + 1]:.6g} s)")
    step = float(np.median(dt))
    jumps = np.nonzero(np.abs(dt - step) > 1e-3 * step + 1e-12)[0]
    if jumps.size:
        i = int(jumps[0])
        kind = "gap" if dt[i] > step else "irregular step"
        raise DataError(f"sampling is not uniform: a {kind} of {dt[i]:.6g} s at t = {t[i]:.6g} s "
                        f"(the usual step is {step:.6g} s); resample the record first")
    ds.attrs["sample_rate"] = 1.0 / step


def check_record(ds: xr.Dataset, channels=("Nx", "Ny", "alpha_ddot"), clip_run: int = 5) -> None:
    """Refuse a record missing ``channels``, or holding NaN, infinite or clipped samples.

    A channel counts as clipped when ``clip_run`` or more consecutive samples sit exactly
    at its largest or smallest value, as a saturated amplifier or ADC leaves them (a
    limit of exactly zero is exempt: a noise-free hammer force rests there).
    """
    for name in channels:
        if name not in ds:
            have = ", ".join(v for v in ds.data_vars) or "none"
            raise DataError(f"the record has no {name} channel (it has: {have})")
        x = ds[name].values
        bad = ~np.isfinite(x)
        if bad.any():
            i = int(np.argmax(bad))
            raise DataError(f"channel {name} holds {int(bad.sum())} NaN or infinite samples "
                            f"(the first at t = {ds['time'].values[i]:.6g} s)")
        for limit, word in ((x.max(), "upper"), (x.min(), "lower")):
            at = np.concatenate(([0], (x == limit).astype(np.int8), [0]))
            edges = np.diff(at)
            runs = np.nonzero(edges == -1)[0] - np.nonzero(edges == 1)[0]
            if runs.size and runs.max() >= clip_run and np.ptp(x) > 0 and limit != 0.0:
                raise DataError(f"channel {name} looks clipped at its {word} limit {limit:.6g} "
                                f"{ds[name].attrs.get('units', '')} ({int(runs.max())} consecutive samples)")


def angular_acceleration(ds: xr.Dataset, sensor_distance: float | None = None) -> xr.Dataset:
    """Add ``alpha_ddot = a_t / l_a`` [rad/s^2] when the record has only ``a_t``.

    Parameters
    ----------
    sensor_distance : float
        Accelerometer distance from the pivot ``l_a`` [m].
    """
    if "alpha_ddot" in ds or "a_t" not in ds:
        return ds
    if sensor_distance is None or not sensor_distance > 0:
        raise DataError("the record gives the tangential acceleration a_t; the accelerometer distance "
                        "follower.accelerometer_distance must be positive to convert it")
    out = ds.copy()
    unit, long_name = CHANNEL_UNITS["alpha_ddot"]
    out["alpha_ddot"] = ("time", ds["a_t"].values / sensor_distance, {"units": unit, "long_name": long_name})
    return out


def require_record(record, what: str = "record") -> xr.Dataset:
    """``record`` itself when it is an xarray Dataset; anything else (a file name, an
    array) is refused with a :class:`ParameterError` that says how to read a file."""
    if isinstance(record, xr.Dataset):
        return record
    hint = (f" (read the file first: camdyn.io.measurements.read_measurement({str(record)!r}))"
            if isinstance(record, (str, os.PathLike)) else "")
    raise ParameterError(f"expected a {what} (an xarray Dataset from camdyn.io.measurements.read_measurement), "
                         f"got {type(record).__name__} {record!r:.60}{hint}")


def check_noise(noise) -> float:
    """Refuse a noise level [fraction of each channel's rms] that is not a finite number
    from 0 to :data:`MAX_NOISE`; return it as a float."""
    if isinstance(noise, bool) or not isinstance(noise, (int, float, np.integer, np.floating)) \
            or not (math.isfinite(noise) and 0.0 <= noise <= MAX_NOISE):
        raise ParameterError(f"noise must be a fraction of each channel's rms from 0 to {MAX_NOISE:g} "
                             f"(0.01 is 1 %), got {noise!r}")
    return float(noise)


def check_seed(seed) -> None:
    """Refuse a noise seed that is neither None (fresh entropy) nor a whole number >= 0
    (numpy's generators take any such number, however many digits)."""
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0):
        raise ParameterError(f"the noise seed must be a whole number >= 0 (or None for fresh entropy), got {seed!r}")


def record_speed(speed, key: str = "speed") -> float | None:
    """A cam speed [Hz] given to an estimator: ``None``, a number of Hz, or text with a
    unit as :func:`camdyn.simulate` reads it (``"11.55 Hz"``, ``"693 rpm"``); refused
    unless finite and positive."""
    if speed is None:
        return None
    from camdyn.params.units import parse_speed

    hz = parse_speed(speed, key)
    if not (math.isfinite(hz) and hz > 0):
        raise ParameterError(f"{key} must be a positive, finite cam speed, got {speed!r}")
    return hz


def check_consistency(record: xr.Dataset, speed: float | None = None, runout: float | None = None,
                      preset: str | None = None, what: str = "the options") -> None:
    """Refuse a record whose metadata contradicts the settings it is analysed with.

    A record may carry ``speed_hz`` [Hz], ``runout`` [m] and ``preset`` attributes (CSV
    ``# key = value`` lines). An estimator given another speed or runout than the record
    states would fit a different rig with confidence, so a difference of more than 0.5 %
    in speed or 1 % in runout is refused; a different preset name only warns (a user's
    own TOML of the same rig has another name).

    Parameters
    ----------
    record : xarray.Dataset
        The record.
    speed : float, optional
        Cam speed the analysis uses [Hz].
    runout : float, optional
        Cam runout the analysis uses [m].
    preset : str, optional
        Name of the system the analysis uses.
    what : str
        Where those settings come from, for the message.

    Raises
    ------
    DataError
        With both values and how to reconcile them.
    """
    source = record.attrs.get("source", "the record")
    stated = record.attrs.get("speed_hz")
    if speed is not None and stated is not None and abs(float(stated) - speed) > 5e-3 * abs(float(stated)):
        raise DataError(f"{source} was taken at {float(stated):.6g} Hz (its metadata) but {what} give "
                        f"{speed:.6g} Hz; leave the speed out to use the record's, or correct the metadata")
    stated = record.attrs.get("runout")
    if runout is not None and stated is not None and abs(float(stated) - runout) > 1e-2 * abs(float(stated)):
        raise DataError(f"{source} was taken with cam.runout = {float(stated) * 1e3:.6g} mm (its metadata) but "
                        f"{what} give {runout * 1e3:.6g} mm; pass --set cam.runout={float(stated) * 1e3:.6g}mm, "
                        f"or correct the metadata")
    stated = record.attrs.get("preset")
    if preset is not None and stated is not None and str(stated) != preset:
        warnings.warn(f"{source} names the preset {stated!r} but it is analysed with {preset!r}", UserWarning,
                      stacklevel=2)
