"""Figure of branches of periodic orbits (:mod:`camdyn.continuation`): the orbits'
Poincare points (over a brute-force bifurcation diagram when one is given), the largest
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
_MARKERS = {"fold": "s", "period-doubling": "o", "neimark-sacker": "D", "grazing": "^", "contact-loss": "v",
            "sliding-reversal": "P", "multiplier-jump": "x"}


def _runs(stable: np.ndarray) -> list[slice]:
    """Slices of equal stability, each overlapping the next by one point (no gaps)."""
    edges = [0, *(np.flatnonzero(np.diff(stable.astype(int))) + 1), stable.size]
    return [slice(max(a - 1, 0), b) for a, b in zip(edges[:-1], edges[1:]) if b > a]


def _diagram(ax, diagram: xr.Dataset, scale: float, angle: float) -> None:
    """The brute-force diagram's Poincare points, small grey dots, under the branches
    (``scale`` and ``angle``: the display factors of the parameter and of the angle,
    :func:`~camdyn.plotting.style.display_scale`)."""
    values = diagram["poincare_alpha"]
    x = np.asarray(values[values.dims[0]].values, dtype=float)
    ax.plot(np.repeat(x, values.shape[1]) * scale, values.values.ravel() * angle, ".", color="0.55", ms=1.5,
            label="brute force", zorder=1)


def _draw(axes, ds, index, scale, rows) -> None:
    """Branch ``index`` on every panel: ``rows`` (one array over points per curve and
    panel), stable runs solid and unstable runs dashed."""
    on = ds["branch"].values == index
    x = ds["parameter"].values[on] * scale
    stable = ds["stable"].values[on].astype(bool)
    for part in _runs(stable):
        style = "-" if stable[part.stop - 1] else "--"
        label = "stable" if stable[part.stop - 1] else "unstable"
        for ax, curves in zip(axes, rows):
            for curve in curves:
                ax.plot(x[part], curve[on][part], style, color=f"C{index % 10}", label=label, zorder=2)


@styled
def plot_branches(ds: xr.Dataset, path: str | Path, diagram: xr.Dataset | None = None) -> Path:
    """Draw the branches of ``ds`` (:func:`camdyn.continuation.results.branches_dataset`):
    the follower angle at the orbit's phase once per forcing period (its Poincare points)
    [deg], the largest normal force Fn [N] (when the system has one) and the largest
    multiplier modulus ``|mu|`` [-] (logarithmic) over the parameter [its unit]; stable
    solid, unstable dashed, bifurcations marked.

    Parameters
    ----------
    ds : xarray.Dataset
        The branches.
    path : str or Path
        The figure file.
    diagram : xarray.Dataset, optional
        A brute-force bifurcation diagram over the same parameter (a sweep with the
        ``poincare`` metric, :func:`camdyn.sweeps.run_sweep`): its Poincare points are
        drawn under the branches.
    """
    name = str(ds.attrs.get("parameter_name", "parameter"))
    scale, unit = display_scale(ds["parameter"])
    section = ds["poincare_alpha"] if "poincare_alpha" in ds else ds["alpha"].expand_dims("section", axis=1)
    angle, angle_unit = display_scale(section)
    force = ds["max_normal_force"]
    panels = 3 if np.isfinite(force.values).any() else 2
    fig, axes = plt.subplots(panels, 1, figsize=(7.0, 2.1 * panels + 0.9), sharex=True)
    modulus = np.hypot(ds["multiplier_real"].values, ds["multiplier_imag"].values)
    rows = [[section.values[:, j] * angle for j in range(section.shape[1])]]
    if panels == 3:
        force_scale, force_unit = display_scale(force)
        rows.append([force.values * force_scale])
    rows.append([np.nanmax(modulus, axis=1)])
    if diagram is not None:
        _diagram(axes[0], diagram, scale, angle)
    for index in np.unique(ds["branch"].values):
        _draw(axes, ds, index, scale, rows)
    axes[-1].set_yscale("log")
    axes[-1].axhline(1.0, color="k", lw=0.6, ls=":")
    for kind, value in zip(ds["bifurcation_kind"].values, ds["bifurcation_parameter"].values):
        for ax in axes:
            ax.axvline(value * scale, color="0.4", lw=0.6)
        axes[-1].plot([value * scale], [1.0], _MARKERS.get(str(kind), "x"), color="k", label=str(kind))
    axes[0].set_ylabel(axis_label(r"$\alpha_P$", angle_unit))
    if panels == 3:
        axes[1].set_ylabel(axis_label("max $F_n$", force_unit))
        tidy_axis(axes[1].yaxis, 5)
    axes[-1].set_ylabel(axis_label(r"max $|\mu|$", "-"))
    axes[-1].set_xlabel(axis_label(SYMBOLS.get(name, name), unit))
    tidy_axis(axes[0].yaxis, 5)
    handles = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, handle)
    axes[-1].legend(list(handles.values()), list(handles.keys()), loc="upper left", ncols=min(len(handles), 3))
    fig.align_ylabels(axes)
    return save_figure(fig, path)
