"""Spectra of simulated responses: cam harmonics and the resonance peaks between them
(thesis figs 2.10, 2.16).

A spectral peak counts as a resonance only when it stands clear of both the integration
noise and the cam harmonics' leakage: above :data:`NOISE_FLOOR` times the median
amplitude above the cam speed, and above :data:`RELATIVE_FLOOR` times the largest cam
harmonic (:func:`peak_threshold`). The same rule marks the peaks of the figures
(:func:`camdyn.plotting.plot_spectrum`) and lists them in :func:`spectrum_summary`.

A mechanism's run (:mod:`camdyn.io.mechanism_config`) goes through the same functions
one follower at a time: :func:`follower_series` takes that follower's series (and the
shaft's) and the cam speed the harmonics are counted from.
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy.signal import find_peaks

from camdyn.analysis.harmonics import amplitude_spectrum, harmonic_amplitudes
from camdyn.errors import ParameterError

__all__ = ["NOISE_FLOOR", "RELATIVE_FLOOR", "peak_rule", "peak_threshold", "resonance_peaks",
           "spectrum_summary", "follower_series"]

#: a resonance peak stands above this many times the median amplitude above the cam speed [-]
NOISE_FLOOR = 10.0
#: ... and above this fraction of the largest cam-harmonic amplitude [-]
RELATIVE_FLOOR = 1e-4


def peak_rule(floor: float = NOISE_FLOOR, relative: float = RELATIVE_FLOOR) -> str:
    """The peak rule in words (for figures and reports)."""
    return (f"peaks above {floor:g}x the median amplitude above the cam speed "
            f"and above {relative:g} of the largest cam harmonic")


def _near_harmonic(freq: np.ndarray, speed: float, guard: float) -> np.ndarray:
    order = freq / speed
    return (np.abs(order - np.round(order)) < guard) & (np.round(order) >= 1)


def peak_threshold(freq: np.ndarray, amp: np.ndarray, speed: float, floor: float = NOISE_FLOOR,
                   relative: float = RELATIVE_FLOOR, guard: float = 0.25) -> float:
    """Smallest amplitude a resonance peak must exceed [unit of ``amp``].

    ``max(floor * median(amp[freq > speed]), relative * A_max)``, with ``A_max`` the
    largest amplitude within ``guard`` cam orders of a cam harmonic (order 1 and up).

    Parameters
    ----------
    freq, amp : ndarray
        One-sided spectrum: frequencies [Hz] and amplitudes [any unit].
    speed : float
        Cam speed [Hz].
    floor, relative : float
        Multiple of the median [-] and fraction of the largest harmonic [-].
    guard : float
        Half-width of a harmonic's neighbourhood [cam orders].
    """
    above = freq > speed
    noise = floor * float(np.median(amp[above])) if np.any(above) else 0.0
    near = _near_harmonic(freq, speed, guard)
    largest = float(np.max(amp[near])) if np.any(near) else 0.0
    return max(noise, relative * largest)


def resonance_peaks(freq: np.ndarray, amp: np.ndarray, speed: float, count: int = 3,
                    guard: float = 0.25, floor: float = NOISE_FLOOR,
                    relative: float = RELATIVE_FLOOR) -> list[tuple[float, float]]:
    """The ``count`` largest spectral peaks that are not cam harmonics and stand above
    :func:`peak_threshold`.

    A peak within ``guard`` of a cam order (``|f/speed - k| < guard``) is a harmonic and
    is left out; so is a peak at or below ``max(floor x median amplitude above the cam
    speed, relative x largest cam harmonic)`` (integration noise, leakage). The rest are
    resonances (the contact mode, its side bands).

    Returns
    -------
    list of (frequency [Hz], amplitude [unit of ``amp``]), largest first.
    """
    idx, _ = find_peaks(amp)
    threshold = peak_threshold(freq, amp, speed, floor, relative, guard)
    keep = idx[~_near_harmonic(freq[idx], speed, guard) & (freq[idx] > speed * guard) & (amp[idx] > threshold)]
    keep = keep[np.argsort(amp[keep])[::-1][:count]]
    return [(float(freq[i]), float(amp[i])) for i in keep]


def spectrum_summary(ds: xr.Dataset, variable: str = "alpha_ddot", window: int = 20, harmonics: int = 10,
                     peaks: int = 3) -> dict:
    """Cam-harmonic amplitudes and resonance peaks of ``variable`` over the last
    ``window`` whole revolutions of a simulation (units of the variable).

    The peaks follow :func:`resonance_peaks` (the rule is in ``"peak_rule"``, the
    amplitude they had to exceed in ``"peak_threshold"``).
    """
    speed = float(ds.attrs["speed_hz"])
    total = (float(ds.time[-1]) - float(ds.time[0])) * speed
    if window < 1 or window > total - 1:
        raise ParameterError(f"the spectrum window must be 1 to {int(total) - 1} revolutions "
                             f"(the record holds {total:.3g}), got {window}")
    fs = 1.0 / float(ds.time[1] - ds.time[0])
    if harmonics * speed >= fs / 2:
        raise ParameterError(f"{harmonics} cam harmonics of {speed:g} Hz need a sample rate above "
                             f"{2 * harmonics * speed:g} Hz, got {fs:g} Hz")
    amps = harmonic_amplitudes(ds, variable, orders=range(1, harmonics + 1), revolutions=window)
    freq, amp = amplitude_spectrum(ds, variable, revolutions=window)
    return {"variable": variable, "units": ds[variable].attrs.get("units", "-"), "speed_hz": speed,
            "window_revolutions": window,
            "natural_frequency_hz": float(ds.attrs.get("natural_frequency_Hz", float("nan"))),
            "harmonics": [{"order": k, "frequency_hz": k * speed, "amplitude": float(a)}
                          for k, a in zip(range(1, harmonics + 1), amps)],
            "peak_rule": peak_rule(), "peak_threshold": peak_threshold(freq, amp, speed),
            "peaks": [{"frequency_hz": f, "amplitude": a} for f, a in resonance_peaks(freq, amp, speed, peaks)]}


def follower_series(ds: xr.Dataset, follower: int | None = None, window: int | None = None) -> xr.Dataset:
    """One follower's time series of a run, with the cam speed ``speed_hz`` [Hz] that
    :func:`spectrum_summary` and :func:`camdyn.plotting.plot_spectrum` count the cam
    harmonics from.

    A run of two followers (a ``follower`` dimension) gives follower ``follower`` (1 or
    2) and the shaft's series; any other run its own (``follower`` None or 1). Series
    over other dimensions (the event log) are left out. A run at a constant cam speed
    keeps it (``speed_hz``, or the constant ``cam_speed`` [rad/s] / 2 pi); for a cam
    turning as a body under a torque the speed is the mean over the last ``window``
    whole cam turns: ``window / (n dt)``, with ``n`` the samples before the last one
    over which the cam angle advanced by ``2 pi window`` (to within a sample), so that
    :func:`camdyn.analysis.harmonics.steady_window` takes those ``n`` samples. Its cam
    harmonics are then multiples of that mean speed, smeared by the speed's fluctuation.
    """
    if "follower" in ds.dims:
        if follower not in (1, 2):
            raise ParameterError(f"the run has two followers: give follower 1 or 2, got {follower!r}")
        ds = ds.sel(follower=follower)
    elif follower not in (None, 1):
        raise ParameterError(f"the run has one follower: follower must be 1, got {follower!r}")
    ds = ds.drop_dims([d for d in ds.dims if d != "time"])
    if "speed_hz" in ds.attrs:
        return ds
    speed = ds["cam_speed"].values
    if np.ptp(speed) == 0.0:
        return ds.assign_attrs(speed_hz=abs(float(speed[0])) / (2.0 * np.pi))
    if window is None or window < 1:
        raise ParameterError(f"a cam under a torque needs a window of one or more whole turns, got {window!r}")
    turned = np.abs(ds["cam_angle"].values[-1] - ds["cam_angle"].values) / (2.0 * np.pi)
    reached = np.nonzero(turned[:-1] >= window)[0]
    if reached.size == 0:
        raise ParameterError(f"the cam turned {float(turned.max()):.3g} times in the run; the window needs {window}")
    samples = turned.size - 1 - int(reached[-1])
    step = float(ds["time"].values[1] - ds["time"].values[0])
    return ds.assign_attrs(speed_hz=window / (samples * step))
