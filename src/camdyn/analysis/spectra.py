"""Spectra of simulated responses: cam harmonics and the resonance peaks between them
(thesis figs 2.10, 2.16)."""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy.signal import find_peaks

from camdyn.analysis.harmonics import amplitude_spectrum, harmonic_amplitudes
from camdyn.errors import ParameterError

__all__ = ["resonance_peaks", "spectrum_summary"]


def resonance_peaks(freq: np.ndarray, amp: np.ndarray, speed: float, count: int = 3,
                    guard: float = 0.25, floor: float = 10.0) -> list[tuple[float, float]]:
    """The ``count`` largest spectral peaks that are not cam harmonics.

    A peak within ``guard`` of a cam order (``|f/speed - k| < guard``) is a harmonic and
    is left out; so is a peak less than ``floor`` times the spectrum's median amplitude
    above the cam speed (integration noise). The rest are resonances (the contact mode,
    its side bands).

    Returns
    -------
    list of (frequency [Hz], amplitude [unit of ``amp``]), largest first.
    """
    idx, _ = find_peaks(amp)
    order = freq[idx] / speed
    noise = floor * np.median(amp[freq > speed]) if np.any(freq > speed) else 0.0
    keep = idx[(np.abs(order - np.round(order)) >= guard) & (amp[idx] > noise)]
    keep = keep[np.argsort(amp[keep])[::-1][:count]]
    return [(float(freq[i]), float(amp[i])) for i in keep]


def spectrum_summary(ds: xr.Dataset, variable: str = "alpha_ddot", window: int = 20, harmonics: int = 10,
                     peaks: int = 3) -> dict:
    """Cam-harmonic amplitudes and resonance peaks of ``variable`` over the last
    ``window`` whole revolutions of a simulation (units of the variable)."""
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
            "peaks": [{"frequency_hz": f, "amplitude": a} for f, a in resonance_peaks(freq, amp, speed, peaks)]}
