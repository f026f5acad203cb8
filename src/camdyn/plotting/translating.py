"""Figures of the translating follower: a run over time, and the bifurcation diagram of
its Poincaré section against cam speed."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from camdyn.plotting.style import axis_label, save_figure, styled, tidy_axis

__all__ = ["plot_translating_history", "plot_poincare_diagram"]


@styled
def plot_translating_history(ds: xr.Dataset, path: str | Path, revolutions: float = 3.0) -> Path:
    """Follower position x and cam lift s [mm], and the contact force N [N], over the last
    ``revolutions`` cam periods; impacts as thin grey lines, separations as dashed ones.

    Parameters
    ----------
    ds : xarray.Dataset
        A run of :func:`camdyn.simulation.translating.simulate_translating`.
    path : str or Path
        Figure file; the format follows the suffix.
    revolutions : float
        Cam periods shown, at the end of the run [-].
    """
    t = ds["time"].values
    speed = float(ds.attrs["speed_rad_s"]) / (2.0 * math.pi)
    sel = ds.sel(time=slice(max(t[-1] - revolutions / speed, t[0]), None))
    tt = sel["time"].values
    fig, axes = plt.subplots(2, 1, figsize=(7.5, 5.0), sharex=True)
    axes[0].plot(tt, 1e3 * sel["lift"].values, color="0.55", lw=1.6, label="cam lift $s$")
    axes[0].plot(tt, 1e3 * sel["x"].values, color="C0", label="follower $x$")
    axes[0].set_ylabel(axis_label("$x$, $s$", "mm"))
    axes[0].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
    axes[1].plot(tt, sel["contact_force"].values, color="C2")
    axes[1].set_ylabel(axis_label("$N$", "N"))
    axes[1].set_xlabel(axis_label("$t$", "s"))
    kinds = ds["event_kind"].values
    times = ds["event_time"].values
    for kind, style in (("impact", "-"), ("separation", "--")):
        for ti in times[(kinds == kind) & (times >= tt[0])]:
            for ax in axes:
                ax.axvline(ti, color="0.75", lw=0.5, ls=style, zorder=0)
    for ax in axes:
        tidy_axis(ax.yaxis, 5)
    fig.align_ylabels(axes)
    fig.suptitle(f"translating follower, {60.0 * speed:.4g} rpm")
    return save_figure(fig, path)


@styled
def plot_poincare_diagram(section: xr.Dataset, path: str | Path, marks: dict | None = None) -> Path:
    """The bifurcation diagram: the follower's position x [mm] and velocity x_dot [m/s]
    at cam angle 0 of every recorded revolution, against the cam speed [rpm].

    Parameters
    ----------
    section : xarray.Dataset
        :func:`camdyn.analysis.poincare.poincare_section`: ``x`` and ``x_dot`` over
        ``speed_rpm`` and ``revolution``.
    path : str or Path
        Figure file; the format follows the suffix.
    marks : dict, optional
        Label -> cam speed [rpm] drawn as a vertical line with its label.
    """
    rpm = section["speed_rpm"].values
    fig, axes = plt.subplots(2, 1, figsize=(7.5, 6.0), sharex=True)
    for ax, name, scale, symbol, unit in ((axes[0], "x", 1e3, "$x$", "mm"),
                                          (axes[1], "x_dot", 1.0, r"$\dot x$", "m/s")):
        values = section[name].values * scale
        ax.plot(np.repeat(rpm, values.shape[1]), values.reshape(-1), ",", color="k", alpha=0.8,
                rasterized=True)
        ax.set_ylabel(axis_label(symbol, unit))
        tidy_axis(ax.yaxis, 5)
    for label, speed in (marks or {}).items():
        for ax in axes:
            ax.axvline(speed, color="C3", lw=0.6, ls="--", zorder=0)
        axes[0].annotate(label, (speed, 1.0), xycoords=("data", "axes fraction"), xytext=(2, -2),
                         textcoords="offset points", va="top", ha="left", color="C3", fontsize=7.5,
                         rotation=90)
    axes[1].set_xlabel(axis_label(r"$\Omega$", "rpm"))
    tidy_axis(axes[1].xaxis, 8)
    fig.align_ylabels(axes)
    fig.suptitle("Poincaré section at cam angle 0 against cam speed")
    return save_figure(fig, path)
