"""Harmonic amplitudes of periodic responses over whole cam revolutions."""

from __future__ import annotations

import numpy as np
import xarray as xr

from camdyn.errors import ParameterError

__all__ = ["harmonic_amplitudes", "amplitude_spectrum", "steady_window"]


def steady_window(ds: xr.Dataset, revolutions: float, speed: float | None = None) -> xr.Dataset:
    """The last ``revolutions`` whole cam periods of a result (end point excluded)."""
    speed = speed or float(ds.attrs["speed_hz"])
    t = ds["time"].values
    fs = 1.0 / (t[1] - t[0])
    n = int(round(revolutions * fs / speed))
    if n < 8 or n > t.size - 1:
        raise ParameterError(f"the record holds {t.size} samples; {revolutions} revolutions need {n}")
    return ds.isel(time=slice(t.size - 1 - n, t.size - 1))


def harmonic_amplitudes(ds: xr.Dataset, variable: str = "alpha_ddot", orders=(1, 2), revolutions: int = 10,
                        speed: float | None = None) -> np.ndarray:
    """Single-sided amplitudes [unit of the variable] of the cam harmonics ``orders``.

    Computed by a discrete Fourier projection over ``revolutions`` whole cam periods at
    the end of the record, so the transient is left out and there is no leakage when
    the window holds a whole number of samples per revolution (true to within one
    sample otherwise).
    """
    speed = speed or float(ds.attrs["speed_hz"])
    win = steady_window(ds, revolutions, speed)
    t = win["time"].values
    x = win[variable].values
    if np.isnan(x).any():
        raise ParameterError(f"{variable} holds NaN samples")
    # exact length of the window in periods (sample-rounded)
    return np.array([2.0 * abs(np.mean(x * np.exp(-2j * np.pi * k * speed * t))) for k in orders])


def amplitude_spectrum(ds: xr.Dataset, variable: str = "alpha_ddot", revolutions: int | None = None):
    """Single-sided amplitude spectrum (frequency [Hz], amplitude [unit of the variable])
    over whole revolutions, Hann-windowed (amplitude-corrected) against leakage."""
    speed = float(ds.attrs["speed_hz"])
    t = ds["time"].values
    total = (t[-1] - t[0]) * speed
    revs = revolutions or max(1, int(total // 2))
    win = steady_window(ds, revs, speed)
    x = win[variable].values - np.mean(win[variable].values)
    fs = 1.0 / (t[1] - t[0])
    window = np.hanning(x.size)
    amp = 2.0 * np.abs(np.fft.rfft(x * window)) / window.sum()
    freq = np.fft.rfftfreq(x.size, 1.0 / fs)
    return freq, amp
