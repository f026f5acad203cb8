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

#: marker of each bifurcation kind
_MARKERS = {"fold": "s", "period-doubling": "o", "neimark-sacker": "D", "grazing": "^", "multiplier-jump": "x"}


def _draw_branches(ax, ds: xr.Dataset, name: str, scale: float) -> None:
    """Each branch's section points ``name`` (times ``scale``) against the speed [rpm],
    coloured by the orbit's period: runs of stable orbits solid, of unstable ones dashed,
    each run overlapping the next by one orbit."""
    periods = sorted(int(k) for k in np.unique(ds["periods"].values))
    for index in np.unique(ds["branch"].values).astype(int):
        on = ds["branch"].values == index
        rpm = ds["speed_rpm"].values[on]
        stable = ds["stable"].values[on].astype(bool)
        period = int(ds["periods"].values[on][0])
        values = ds[name].values[on] * scale
        edges = [0, *(np.flatnonzero(np.diff(stable.astype(int))) + 1), stable.size]
        for a, b in zip(edges[:-1], edges[1:]):
            part = slice(max(a - 1, 0), b)
            style = "-" if stable[b - 1] else "--"
            for j in range(period):
                ax.plot(rpm[part], values[part, j], style, color=f"C{periods.index(period) % 10}", lw=1.2, zorder=3,
                        label=f"period {period}, {'stable' if stable[b - 1] else 'unstable'}" if j == 0 else None)


def _mark_bifurcations(axes, ds: xr.Dataset) -> None:
    """The located bifurcations on the position panel, at each one's speed [rpm] and the
    nearest orbit of its branch, with a legend."""
    rpm_per_rad_s = 60.0 / (2.0 * math.pi)
    for kind, value, index in zip(ds["bifurcation_kind"].values, ds["bifurcation_parameter"].values,
                                  ds["bifurcation_branch"].values):
        on = np.flatnonzero(ds["branch"].values == index)
        if not on.size:
            continue
        nearest = on[int(np.argmin(np.abs(ds["parameter"].values[on] - value)))]
        for ax, name, scale in ((axes[0], "poincare_x", 1e3), (axes[1], "poincare_x_dot", 1.0)):
            ax.plot([value * rpm_per_rad_s], [ds[name].values[nearest, 0] * scale], _MARKERS.get(str(kind), "x"),
                    color="C3", ms=6, mfc="none", zorder=4,
                    label=f"{kind} {value * rpm_per_rad_s:.2f} rpm" if ax is axes[0] else None)
    handles = dict(zip(*reversed(axes[0].get_legend_handles_labels())))
    if handles:
        axes[0].legend(list(handles.values()), list(handles.keys()), loc="upper left", fontsize=7)


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
def plot_poincare_diagram(section: xr.Dataset | None, path: str | Path, marks: dict | None = None,
                          branches: xr.Dataset | None = None) -> Path:
    """The bifurcation diagram: the follower's position x [mm] and velocity x_dot [m/s]
    at cam angle 0 of every recorded revolution, against the cam speed [rpm], with the
    branches of periodic orbits over it (stable solid, unstable dashed, each orbit's
    points on the section; bifurcations marked).

    Parameters
    ----------
    section : xarray.Dataset or None
        :func:`camdyn.analysis.poincare.poincare_section`: ``x`` and ``x_dot`` over
        ``speed_rpm`` and ``revolution`` (None: the branches alone).
    path : str or Path
        Figure file; the format follows the suffix.
    marks : dict, optional
        Label -> cam speed [rpm] drawn as a vertical line with its label.
    branches : xarray.Dataset, optional
        :func:`camdyn.continuation.translating.translating_dataset`: ``poincare_x`` and
        ``poincare_x_dot`` over ``point`` and ``section``, ``speed_rpm``, ``branch``,
        ``stable`` and the bifurcations.
    """
    fig, axes = plt.subplots(2, 1, figsize=(7.5, 6.0), sharex=True)
    for ax, name, scale, symbol, unit in ((axes[0], "x", 1e3, "$x$", "mm"),
                                          (axes[1], "x_dot", 1.0, r"$\dot x$", "m/s")):
        if section is not None:
            values = section[name].values * scale
            ax.plot(np.repeat(section["speed_rpm"].values, values.shape[1]), values.reshape(-1), ",", color="k",
                    alpha=0.8 if branches is None else 0.35, rasterized=True)
        if branches is not None:
            _draw_branches(ax, branches, f"poincare_{name}", scale)
        ax.set_ylabel(axis_label(symbol, unit))
        tidy_axis(ax.yaxis, 5)
    if branches is not None:
        _mark_bifurcations(axes, branches)
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
