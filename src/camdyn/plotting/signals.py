"""Figures of one simulation over time and frequency."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from camdyn.analysis.harmonics import amplitude_spectrum, harmonic_amplitudes
from camdyn.analysis.spectra import NOISE_FLOOR, RELATIVE_FLOOR, peak_threshold, resonance_peaks
from camdyn.errors import ParameterError
from camdyn.plotting.style import axis_label, save_figure, speed_text, styled, tidy_axis

__all__ = ["HARMONIC_BAND", "NATURAL_BAND", "VARIABLE_SYMBOLS", "plot_time_history", "plot_spectrum",
           "spectrum_band"]

#: the "harmonics" band of a spectrum reaches this many times the highest cam harmonic listed [-]
HARMONIC_BAND = 2.0
#: the "natural" band reaches this many times the linearized natural frequency [-]
NATURAL_BAND = 1.5


@styled
def plot_time_history(ds: xr.Dataset, path: str | Path, revolutions: float = 3.0) -> Path:
    """Follower angle α [deg], angular acceleration α̈ [rad/s²], contact forces F_n, F_f
    and pivot reactions N_x, N_y [N] over the last ``revolutions`` cam periods, impacts as
    thin grey lines.

    Parameters
    ----------
    ds : xarray.Dataset
        A simulation (:func:`camdyn.simulate`).
    path : str or Path
        Figure file; the format follows the suffix.
    revolutions : float
        Cam periods shown, at the end of the record [-].
    """
    t = ds["time"].values
    speed = float(ds.attrs.get("speed_hz", 0.0)) or None
    t0 = t[-1] - revolutions / speed if speed else t[0]
    sel = ds.sel(time=slice(max(t0, t[0]), None))
    fig, axes = plt.subplots(4, 1, figsize=(7.5, 7.5), sharex=True)
    tt = sel["time"].values
    axes[0].plot(tt, np.degrees(sel["alpha"].values), color="C0")
    axes[0].set_ylabel(axis_label(r"$\alpha$", "deg"))
    axes[1].plot(tt, sel["alpha_ddot"].values, color="C1")
    axes[1].set_ylabel(axis_label(r"$\ddot\alpha$", sel["alpha_ddot"].attrs.get("units", "rad/s^2")))
    axes[2].plot(tt, sel["Fn"].values, color="C2", label="$F_n$")
    axes[2].plot(tt, sel["Ff"].values, color="C3", label="$F_f$")
    axes[2].set_ylabel(axis_label("$F$", "N"))
    axes[3].plot(tt, sel["Nx"].values, color="C4", label="$N_x$")
    axes[3].plot(tt, sel["Ny"].values, color="C5", label="$N_y$")
    axes[3].set_ylabel(axis_label("$N$", "N"))
    axes[3].set_xlabel(axis_label("$t$", "s"))
    for ax in axes[2:]:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
    for ax in axes:
        tidy_axis(ax.yaxis, 5)
    tidy_axis(axes[3].xaxis, 7)
    if "impact_time" in ds and ds.sizes.get("impact", 0):
        for ti in ds["impact_time"].values:
            if ti >= tt[0]:
                for ax in axes:
                    ax.axvline(ti, color="0.75", lw=0.5, zorder=0)
    fig.align_ylabels(axes)
    title = ds.attrs.get("title", "camdyn simulation")
    fig.suptitle(f"{title}, {speed_text(speed)}" if speed else title)
    return save_figure(fig, path)


def spectrum_band(band, speed: float, harmonics: int, natural: float, peaks=()) -> float:
    """Upper frequency of a spectrum figure [Hz].

    ``"harmonics"``: :data:`HARMONIC_BAND` times the highest cam harmonic listed;
    ``"natural"``: :data:`NATURAL_BAND` times the natural frequency (the harmonics band
    without one); ``"auto"``: the harmonics band, widened to 1.2 times the highest marked
    resonance peak; a number: that frequency [Hz].
    """
    harmonic_top = HARMONIC_BAND * harmonics * speed
    if isinstance(band, (int, float)) and not isinstance(band, bool):
        if not band > 0:
            raise ParameterError(f"the spectrum band must be a positive frequency [Hz], got {band!r}")
        return float(band)
    if band == "harmonics":
        return harmonic_top
    if band == "natural":
        return NATURAL_BAND * natural if natural == natural and natural > 0 else harmonic_top
    if band == "auto":
        return max([harmonic_top] + [1.2 * f for f in peaks])
    raise ParameterError(f"the spectrum band must be 'auto', 'harmonics', 'natural' or a frequency [Hz], "
                         f"got {band!r}")


#: label symbols of time-series variables
VARIABLE_SYMBOLS = {"alpha": r"\alpha", "alpha_dot": r"\dot\alpha", "alpha_ddot": r"\ddot\alpha", "Fn": "F_n",
                    "Ff": "F_f", "Nx": "N_x", "Ny": "N_y", "alpha_rigid": r"\alpha_{rigid}"}


def _spectrum(ds: xr.Dataset, variable: str, harmonics: int, revolutions: int | None, resonances, peaks: int):
    """Spectrum, window [rev], harmonic orders and amplitudes, peak threshold and marked
    peaks of ``variable``, all in the variable's units."""
    freq, amp = amplitude_spectrum(ds, variable, revolutions)
    speed = float(ds.attrs["speed_hz"])
    window = revolutions or max(1, int((ds["time"].values[-1] - ds["time"].values[0]) * speed // 2))
    orders = [k for k in range(1, harmonics + 1) if k * speed < freq[-1]]
    levels = list(harmonic_amplitudes(ds, variable, orders, revolutions=window)) if orders else []
    marked = resonance_peaks(freq, amp, speed, peaks) if resonances is None else \
        [(float(f), float(np.interp(f, freq, amp))) for f in resonances]
    return freq, amp, window, orders, levels, peak_threshold(freq, amp, speed), marked


@styled
def plot_spectrum(ds: xr.Dataset, path: str | Path, variable: str = "alpha_ddot", harmonics: int = 10,
                  revolutions: int | None = None, resonances=None, band="auto", peaks: int = 3) -> Path:
    """Amplitude spectrum of ``variable`` (log scale) over whole revolutions (Hann window).

    Marked: the first ``harmonics`` cam harmonics (grey lines, dots at their amplitudes),
    the linearized natural frequency (red dashed, when inside the band), the threshold a
    resonance peak must exceed (dotted: ``max(10 x median amplitude above the cam speed,
    1e-4 x largest cam harmonic)``, :func:`camdyn.analysis.spectra.peak_threshold`, stated
    in the legend) and the ``peaks`` largest resonance peaks above it (triangles: the list
    of :func:`camdyn.analysis.spectra.spectrum_summary`), or the frequencies
    ``resonances`` [Hz] when given. Angles are drawn in degrees.

    Parameters
    ----------
    ds : xarray.Dataset
        A simulation (:func:`camdyn.simulate`).
    path : str or Path
        Figure file; the format follows the suffix.
    variable : str
        A time series of ``ds``.
    harmonics : int
        Cam harmonics marked [-].
    revolutions : int, optional
        Whole revolutions at the end analysed [-] (default: half the record).
    resonances : sequence of float, optional
        Frequencies to mark [Hz] instead of the peaks found by the rule.
    peaks : int
        Largest resonance peaks marked [-].
    band : {"auto", "harmonics", "natural"} or float
        Frequency range shown (:func:`spectrum_band`): ``"auto"`` (default) the cam
        harmonics and every marked peak, ``"harmonics"`` twice the highest harmonic,
        ``"natural"`` 1.5 times the natural frequency, or the upper frequency [Hz].
    """
    freq, amp, window, orders, levels, threshold, marked = _spectrum(ds, variable, harmonics, revolutions,
                                                                     resonances, peaks)
    speed = float(ds.attrs["speed_hz"])
    unit = ds[variable].attrs.get("units", "-")
    scale, unit = (180.0 / np.pi, "deg") if unit == "rad" else (1.0, unit)
    fn = float(ds.attrs.get("natural_frequency_Hz", float("nan")) or float("nan"))
    top = min(freq[-1], spectrum_band(band, speed, harmonics, fn, [f for f, _ in marked]))
    inside = (freq > 0) & (freq <= top)
    fig, ax = plt.subplots(figsize=(8.0, 4.2))
    symbol = f"$|{VARIABLE_SYMBOLS.get(variable, variable)}|$" if variable in VARIABLE_SYMBOLS else f"|{variable}|"
    ax.semilogy(freq[inside], np.maximum(amp[inside], 1e-300) * scale, lw=0.8, color="C0", label=symbol)
    for k in orders:
        ax.axvline(k * speed, color="0.8", lw=0.5, zorder=0)
    clear = np.asarray(levels) > threshold
    for which, style in ((clear, {"color": "k"}), (~clear, {"mfc": "white", "mec": "0.4"})):
        if np.any(which):
            ax.plot(np.asarray(orders)[which] * speed, np.asarray(levels)[which] * scale, "o", ms=4, ls="none",
                    label="cam harmonics" + ("" if which is clear else "\nbelow the threshold"), **style)
    ax.axhline(threshold * scale, color="0.35", ls=":", lw=1.0,
               label=f"peak threshold {threshold * scale:.2g}:\nmax({NOISE_FLOOR:g} x median above Ω,\n"
                     f"{RELATIVE_FLOOR:.0e}".replace("e-0", "e-") + " x largest harmonic)")
    shown = [(f, a * scale) for f, a in marked if f <= top]
    ax.plot([f for f, _ in shown], [a for _, a in shown], "v", color="C3", ms=6, ls="none",
            label=f"resonance peaks ({len(shown)})" if shown else "resonance peaks:\nnone above the threshold")
    if fn == fn and 0 < fn <= top:
        ax.axvline(fn, color="C3", lw=0.8, ls="--", label=f"linearized $f_n$ = {fn:.0f} Hz")
    positive = amp[inside & (amp > 0)] * scale
    highest = max(float(positive.max()) if positive.size else 1.0, threshold * scale)
    ax.set_ylim(max(float(positive.min()) if positive.size else 0.0, highest * 1e-12) / 2, highest * 3)
    ax.set_xlim(0, top)
    tidy_axis(ax.xaxis, 8)
    ax.set_xlabel(axis_label("$f$", "Hz"))
    ax.set_ylabel(axis_label(symbol, unit))
    beyond = f"; linearized $f_n$ = {fn:.0f} Hz lies beyond the band" if fn == fn and fn > top else ""
    ax.set_title(f"{symbol} at {speed_text(speed)}, last {window} revolutions{beyond}")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return save_figure(fig, path)
