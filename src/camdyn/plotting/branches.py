"""Figure of branches of periodic orbits (:mod:`camdyn.continuation`): the largest
normal force and the largest Floquet multiplier's modulus over the parameter, stable
orbits solid and unstable dashed, bifurcations marked."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from camdyn.plotting.style import SYMBOLS, axis_label, display_scale, save_figure, styled, tidy_axis

__all__ = ["plot_branches"]

#: marker of each bifurcation kind
_MARKERS = {"fold": "s", "period-doubling": "o", "neimark-sacker": "D", "grazing": "^"}


def _runs(stable: np.ndarray) -> list[slice]:
    """Slices of equal stability, each overlapping the next by one point (no gaps)."""
    edges = [0, *(np.flatnonzero(np.diff(stable.astype(int))) + 1), stable.size]
    return [slice(max(a - 1, 0), b) for a, b in zip(edges[:-1], edges[1:]) if b > a]


@styled
def plot_branches(ds: xr.Dataset, path: str | Path) -> Path:
    """Draw the branches of ``ds`` (:func:`camdyn.continuation.results.branches_dataset`):
    the largest normal force Fn [N] (the follower angle at the orbit's phase when there is
    no force) and the largest multiplier modulus ``|mu|`` [-] (logarithmic) over the parameter
    [its unit]; stable solid, unstable dashed."""
    name = str(ds.attrs.get("parameter_name", "parameter"))
    scale, unit = display_scale(ds["parameter"])
    force = ds["max_normal_force"]
    top = force if np.isfinite(force.values).any() else ds["alpha"]
    top_scale, top_unit = display_scale(top)
    fig, axes = plt.subplots(2, 1, figsize=(7.0, 5.0), sharex=True)
    modulus = np.hypot(ds["multiplier_real"].values, ds["multiplier_imag"].values)
    largest = np.nanmax(modulus, axis=1)
    for index in np.unique(ds["branch"].values):
        on = ds["branch"].values == index
        x = ds["parameter"].values[on] / scale
        stable = ds["stable"].values[on].astype(bool)
        for part in _runs(stable):
            style = "-" if stable[part.stop - 1] else "--"
            label = "stable" if stable[part.stop - 1] else "unstable"
            axes[0].plot(x[part], top.values[on][part] / top_scale, style, color=f"C{index % 10}", label=label)
            axes[1].plot(x[part], largest[on][part], style, color=f"C{index % 10}")
    axes[1].set_yscale("log")
    axes[1].axhline(1.0, color="k", lw=0.6, ls=":")
    for kind, value in zip(ds["bifurcation_kind"].values, ds["bifurcation_parameter"].values):
        for ax in axes:
            ax.axvline(value / scale, color="0.4", lw=0.6)
        axes[1].plot([value / scale], [1.0], _MARKERS.get(str(kind), "x"), color="k", label=str(kind))
    axes[0].set_ylabel(axis_label("max $F_n$" if top is force else r"$\alpha_0$", top_unit))
    axes[1].set_ylabel(axis_label(r"max $|\mu|$", "-"))
    axes[1].set_xlabel(axis_label(SYMBOLS.get(name, name), unit))
    tidy_axis(axes[0].yaxis, 5)
    handles = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, handle)
    holder = axes[1]
    holder.legend(list(handles.values()), list(handles.keys()), loc="upper left", ncols=min(len(handles), 3))
    fig.align_ylabels(axes)
    return save_figure(fig, path)
