"""Harmonic amplitudes of periodic responses over whole cam revolutions."""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from camdyn.errors import ParameterError

__all__ = ["harmonic_amplitudes", "amplitude_spectrum", "steady_window", "fit_harmonics", "synthesize_harmonics",
           "estimate_speed"]


#: ``variable`` of :func:`_checked` when no variable is needed.
_ANY = object()


def _checked(ds, variable, speed) -> float:
    """The cam speed [Hz] of a result ``ds`` (``speed`` given, or its ``speed_hz``
    attribute); a ParameterError for what is not a result over ``time`` holding
    ``variable``, or for a speed that is not positive and finite."""
    if not isinstance(ds, xr.Dataset) or "time" not in ds or ds.sizes.get("time", 0) < 2:
        raise ParameterError(f"expected a result over time (an xarray Dataset from camdyn.simulate or "
                             f"read_measurement), got {type(ds).__name__} {ds!r:.60}")
    if variable is not _ANY and (not isinstance(variable, str) or variable not in ds):
        raise ParameterError(f"the result holds no variable {variable!r}; it holds {', '.join(map(str, ds.data_vars))}")
    if speed is None:
        if ds.attrs.get("speed_hz") is None:
            raise ParameterError("the result has no speed_hz attribute: give the cam speed [Hz]")
        try:
            speed = float(ds.attrs["speed_hz"])
        except (TypeError, ValueError):
            raise ParameterError(f"the result's speed_hz attribute is not a number of Hz: "
                                 f"{ds.attrs['speed_hz']!r:.60}") from None
    if isinstance(speed, bool) or not isinstance(speed, (int, float, np.integer, np.floating)) or not (
            math.isfinite(speed) and speed > 0):
        raise ParameterError(f"the cam speed must be a positive, finite number of Hz, got {speed!r}")
    return float(speed)


def _revolutions(revolutions) -> float:
    if isinstance(revolutions, bool) or not isinstance(revolutions, (int, float, np.integer, np.floating)) or not (
            math.isfinite(revolutions) and revolutions > 0):
        raise ParameterError(f"revolutions must be a positive, finite number, got {revolutions!r}")
    return float(revolutions)


def steady_window(ds: xr.Dataset, revolutions: float, speed: float | None = None) -> xr.Dataset:
    """The last ``revolutions`` whole cam periods of a result (end point excluded)."""
    speed = _checked(ds, _ANY, speed)
    revolutions = _revolutions(revolutions)
    t = ds["time"].values
    fs = 1.0 / (t[1] - t[0])
    if not (math.isfinite(fs) and fs > 0):
        raise ParameterError("the result's time does not increase")
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
    speed = _checked(ds, variable, speed)
    try:
        orders = np.asarray(orders, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ParameterError(f"orders must be harmonic numbers, got {orders!r}") from None
    if orders.size == 0 or not np.all(np.isfinite(orders)):
        raise ParameterError(f"orders must be finite harmonic numbers, got {orders!r}")
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
    speed = _checked(ds, variable, None)
    t = ds["time"].values
    total = (t[-1] - t[0]) * speed
    revs = _revolutions(revolutions) if revolutions is not None else max(1, int(total // 2))
    win = steady_window(ds, revs, speed)
    x = win[variable].values - np.mean(win[variable].values)
    fs = 1.0 / (t[1] - t[0])
    window = np.hanning(x.size)
    amp = 2.0 * np.abs(np.fft.rfft(x * window)) / window.sum()
    freq = np.fft.rfftfreq(x.size, 1.0 / fs)
    return freq, amp


def fit_harmonics(time: np.ndarray, signal: np.ndarray, frequency: float, order: int) -> np.ndarray:
    """Complex amplitudes of the cam harmonics 0..``order`` by linear least squares.

    ``signal(t) ~ Re(sum_k c_k exp(i 2 pi k f t))`` with ``c_0`` the mean. Unlike an FFT
    bin, the fit sits exactly on each harmonic whatever the record length, so a record
    cut to whole revolutions (to within a sample) has no leakage between harmonics.

    Parameters
    ----------
    time : ndarray
        Sample times [s].
    signal : ndarray
        Samples [any unit]; the amplitudes come out in the same unit.
    frequency : float
        Fundamental (cam) frequency [Hz].
    order : int
        Highest harmonic [-].
    """
    phase = 2.0 * np.pi * frequency * (time - time[0])
    k = np.arange(1, order + 1)
    arg = np.outer(phase, k)
    design = np.hstack([np.ones((time.size, 1)), np.cos(arg), -np.sin(arg)])
    coef, *_ = np.linalg.lstsq(design, signal, rcond=None)
    out = np.empty(order + 1, dtype=complex)
    out[0] = coef[0]
    out[1:] = coef[1:order + 1] + 1j * coef[order + 1:]
    # referred to t = 0 rather than the first sample
    shift = np.exp(-1j * 2.0 * np.pi * frequency * time[0] * np.arange(order + 1))
    return out * shift


def synthesize_harmonics(coefficients: np.ndarray, frequency: float, time: np.ndarray) -> np.ndarray:
    """Evaluate ``Re(sum_k c_k exp(i 2 pi k f t))`` at ``time`` [s]."""
    k = np.arange(coefficients.size)
    return np.real(np.exp(1j * 2.0 * np.pi * frequency * np.outer(time, k)) @ coefficients)


def estimate_speed(time: np.ndarray, signal: np.ndarray, lowest: float = 0.5, highest: float | None = None) -> float:
    """Fundamental frequency [Hz] of a periodic record (the cam speed).

    The strongest peak of the Hann-windowed, zero-padded spectrum is refined by
    minimising the residual of a 5-harmonic least-squares fit. A cam whose higher
    harmonic dominates (an ellipse turns twice per revolution) would be mistaken for a
    faster one, so the sub-multiples ``f_peak / k`` (k <= 6) are tried too: the
    fundamental is the smallest ``k`` whose harmonic fit (up to the same frequency)
    leaves a residual within 1.5 times the best of them.
    """
    from scipy.optimize import minimize_scalar

    time = np.asarray(time, float)
    x = np.asarray(signal, float) - np.mean(signal)
    dt = time[1] - time[0]
    n = x.size
    pad = 1 << int(math.ceil(math.log2(4 * n)))
    amp = np.abs(np.fft.rfft(x * np.hanning(n), pad))
    freq = np.fft.rfftfreq(pad, dt)
    band = (freq >= lowest) & (freq <= (highest or freq[-1]))
    if not band.any():
        raise ParameterError("no frequencies in the search band for the cam speed")
    idx = np.nonzero(band)[0]
    peak = freq[idx[np.argmax(amp[idx])]]
    resolution = 1.0 / (n * dt)
    if peak * n * dt < 2:
        raise ParameterError(f"the record is too short to find the cam speed: it holds {peak * n * dt:.2f} "
                             "periods of its strongest component")

    # the fits below only need the low harmonics: thin long records to about 20 000 samples
    stride = max(1, n // 20000)
    tt, xx = time[::stride], x[::stride]

    def residual(f, order):
        c = fit_harmonics(tt, xx, f, order)
        return float(np.sum((xx - synthesize_harmonics(c, f, tt)) ** 2))

    nyquist = 0.45 / (dt * stride)
    res = minimize_scalar(lambda f: residual(f, max(1, min(5, int(nyquist / f)))),
                          bounds=(peak - resolution, peak + resolution), method="bounded",
                          options={"xatol": 1e-9 * peak})
    peak = float(res.x)
    trials = [(k, residual(peak / k, max(1, min(3 * k, int(nyquist * k / peak)))))
              for k in range(1, 7) if peak / k >= lowest]
    best = min(r for _, r in trials)
    k = min(k for k, r in trials if r <= 1.5 * best)
    return peak / k
