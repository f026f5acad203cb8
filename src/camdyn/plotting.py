"""Figures of simulation results (matplotlib, headless)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402


def _label(da: xr.DataArray) -> str:
    return f"{da.attrs.get('long_name', da.name)} [{da.attrs.get('units', '-')}]"


def _save(fig, path) -> Path:
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_time_history(ds: xr.Dataset, path: str | Path, revolutions: float = 3.0) -> Path:
    """Plot alpha, alpha_ddot, the contact force and the pivot reactions over the last
    ``revolutions`` cam periods; write a PNG to ``path``."""
    t = ds["time"].values
    speed = float(ds.attrs.get("speed_hz", 0.0)) or None
    t0 = t[-1] - revolutions / speed if speed else t[0]
    sel = ds.sel(time=slice(max(t0, t[0]), None))
    fig, axes = plt.subplots(4, 1, figsize=(8, 9), sharex=True)
    tt = sel["time"].values
    axes[0].plot(tt, np.degrees(sel["alpha"].values), color="C0")
    axes[0].set_ylabel("follower angle alpha [deg]")
    axes[1].plot(tt, sel["alpha_ddot"].values, color="C1")
    axes[1].set_ylabel(_label(sel["alpha_ddot"]))
    axes[2].plot(tt, sel["Fn"].values, color="C2", label="Fn")
    axes[2].plot(tt, sel["Ff"].values, color="C3", label="Ff")
    axes[2].set_ylabel("contact forces [N]")
    axes[2].legend(loc="upper right")
    axes[3].plot(tt, sel["Nx"].values, label="Nx")
    axes[3].plot(tt, sel["Ny"].values, label="Ny")
    axes[3].set_ylabel("pivot reaction [N]")
    axes[3].legend(loc="upper right")
    axes[3].set_xlabel("time [s]")
    if "impact_time" in ds and ds.sizes.get("impact", 0):
        for ti in ds["impact_time"].values:
            if ti >= tt[0]:
                for ax in axes:
                    ax.axvline(ti, color="0.8", lw=0.5, zorder=0)
    fig.suptitle(ds.attrs.get("title", "camdyn simulation"))
    return _save(fig, path)


def plot_spectrum(ds: xr.Dataset, path: str | Path, variable: str = "alpha_ddot",
                  harmonics: int = 10) -> Path:
    """Amplitude spectrum of ``variable`` over whole revolutions, cam harmonics marked."""
    from camdyn.analysis.harmonics import amplitude_spectrum
    freq, amp = amplitude_spectrum(ds, variable)
    speed = float(ds.attrs.get("speed_hz", 0.0))
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.semilogy(freq, np.maximum(amp, 1e-12), lw=0.8)
    if speed:
        for k in range(1, harmonics + 1):
            ax.axvline(k * speed, color="0.8", lw=0.5, zorder=0)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel(f"|{variable}| [{ds[variable].attrs.get('units', '-')}]")
    fn = float(ds.attrs.get("natural_frequency_Hz", 0.0) or 0.0)
    if fn == fn and fn > 0:
        ax.axvline(fn, color="C3", lw=0.8, ls="--", label=f"linearized natural frequency {fn:.0f} Hz")
        ax.legend(loc="upper right", fontsize=8)
    upper = max(40 * speed, 1.5 * fn if fn == fn else 0.0) if speed else freq[-1]
    ax.set_xlim(0, min(freq[-1], upper))
    return _save(fig, path)
