"""Figures over swept parameters: sweeps (bifurcation diagrams, regime and impact maps),
regime maps beside inverse kinematics, and experiment-design maps."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr
from matplotlib.colors import ListedColormap

from camdyn.plotting.style import (
    SYMBOLS,
    axis_label,
    display_scale,
    display_values,
    legend_below,
    save_figure,
    styled,
    tidy_axis,
)

__all__ = ["METRIC_SYMBOLS", "coordinate_label", "plot_sweep", "plot_regime_map", "plot_design_map"]

#: axis symbols of the sweep metrics (units come from the data: angles in degrees)
METRIC_SYMBOLS = {
    "poincare_alpha": r"$\alpha_P$", "poincare_alpha_dot": r"$\dot\alpha_P$",
    "impacts_per_revolution": "impacts", "residual_rms": r"$\alpha_r$ rms",
    "residual_peak_to_peak": r"$\alpha_r$ p-p", "max_normal_force": r"$F_{n,\max}$", "period": "period",
    "peak_frequency": r"$f_{peak}$", "peak_amplitude": r"$|\ddot\alpha|_{peak}$",
}
_REGIME_COLOURS = {-1: "#000000", 0: "#2ca02c", 1: "#ff7f0e", 2: "#1f77b4", 3: "#d62728"}
_REGIME_NAMES = {-1: "failed", 0: "contact kept", 1: "vr reversal", 2: "periodic impacts", 3: "irregular impacts"}
_RATIO_SYMBOLS = {"runout ratio e/a": "$e/a$", "axis ratio b/a": "$b/a$"}


def _coordinate(ds: xr.Dataset, dim: str) -> xr.DataArray:
    """The coordinate drawn along ``dim``: the swept parameter of that name, else the
    first parameter zipped along it, else the index."""
    if dim in ds.variables and ds[dim].attrs.get("long_name", "").startswith("swept parameter"):
        return ds[dim]
    for name, var in ds.coords.items():
        if var.dims == (dim,) and name != dim and var.attrs.get("long_name", "").startswith("swept parameter"):
            return var
    return ds[dim]


def coordinate_label(da: xr.DataArray) -> str:
    """Axis label of a swept coordinate: its symbol (:data:`camdyn.plotting.style.SYMBOLS`,
    else its name) and the unit it is drawn in."""
    name = str(da.name)
    symbol = SYMBOLS.get(name) or _RATIO_SYMBOLS.get(da.attrs.get("long_name", ""), name)
    if name == "speed" and da.attrs.get("units") == "Hz":
        symbol = r"$\Omega$"
    return axis_label(symbol, display_scale(da)[1])


def _metric_label(da: xr.DataArray) -> str:
    return axis_label(METRIC_SYMBOLS.get(str(da.name), str(da.name)), display_scale(da)[1])


def _sweep_line(ds: xr.Dataset, dims: list, path) -> Path:
    """One swept dimension: bifurcation diagram and metrics against the parameter."""
    first = _coordinate(ds, dims[0])
    x, _ = display_values(first)
    panels = _line_panels(ds)
    fig, axes = plt.subplots(len(panels), 1, figsize=(7.0, 1.9 * len(panels) + 0.8), sharex=True, squeeze=False)
    for ax, name in zip(axes[:, 0], panels):
        values, _ = display_values(ds[name])
        if name.startswith("poincare_"):
            ax.plot(np.repeat(x, ds.sizes["revolution"]), values.ravel(), ",", color="k", alpha=0.6)
            ax.set_title(r"bifurcation diagram: follower angle $\alpha_P$ once per cam revolution"
                         if name == "poincare_alpha" else f"bifurcation diagram: {ds[name].attrs['long_name']}")
        else:
            ax.plot(x, values, ".-", lw=0.8, ms=2.5)
        ax.set_ylabel(_metric_label(ds[name]))
        tidy_axis(ax.yaxis, 4)
    tidy_axis(axes[-1, 0].xaxis, 8)
    axes[-1, 0].set_xlabel(coordinate_label(first))
    fig.align_ylabels(axes[:, 0])
    return save_figure(fig, path)


def _line_panels(ds: xr.Dataset) -> list[str]:
    """The panels of a sweep over one dimension: the cam-follower's metrics, or, for a
    model of the model protocol, its first state's section, each guard's events per period
    and its first state's largest value."""
    panels = [n for n in ("poincare_alpha", "impacts_per_revolution", "residual_rms", "max_normal_force") if n in ds]
    if panels:
        return panels
    names = [str(n) for n in ds.data_vars]
    return ([n for n in names if n.startswith("poincare_")][:1] + [n for n in names if n.startswith("events_")]
            + [n for n in names if n.startswith("max_")][:1]) or ["status"]


def _cell_edges(values: np.ndarray) -> tuple[np.ndarray, bool]:
    """Edges of the cells centred on the swept ``values`` (in order), and whether the axis is
    logarithmic: for positive values spanning a factor of 10 or more the cells meet at the
    geometric means (a linear axis would stretch the smallest cell below zero)."""
    v = np.asarray(values, dtype=float)
    log = v.size > 1 and bool(np.all(v > 0)) and v.max() / v.min() >= 10.0
    w = np.log(v) if log else v
    if w.size == 1:
        inner, first, last = np.array([]), w[0] - 0.5, w[0] + 0.5
    else:
        inner = 0.5 * (w[1:] + w[:-1])
        first, last = w[0] - (inner[0] - w[0]), w[-1] + (w[-1] - inner[-1])
    edges = np.concatenate([[first], inner, [last]])
    return (np.exp(edges) if log else edges), log


@styled
def plot_sweep(ds: xr.Dataset, path: str | Path) -> Path:
    """Figure of a sweep result (:func:`camdyn.sweeps.run_sweep`).

    One swept dimension: the bifurcation diagram (follower angle α [deg] once per cam
    revolution against the parameter), impacts per revolution, the rms residual [deg] and
    the largest normal force, as far as the metrics hold them. Two or more: maps of the
    regime and of impacts per revolution over the first two swept dimensions (later
    dimensions at their first value). Swept parameters are drawn in the unit the spec
    gave them in. A sweep over two followers is drawn for follower 1.
    """
    if "follower" in ds.dims:
        ds = ds.isel(follower=0)
    dims = list(ds["status"].dims)
    if len(dims) == 1:
        return _sweep_line(ds, dims, path)
    sel = {d: 0 for d in dims[2:]}
    first, second = _coordinate(ds, dims[0]), _coordinate(ds, dims[1])
    x, _ = display_values(first)
    y, _ = display_values(second)
    names = [n for n in ("regime", "impacts_per_revolution") if n in ds] or [n for n in ("period",) if n in ds] \
        or ["status"]
    fig, axes = plt.subplots(1, len(names), figsize=(5.2 * len(names) + 0.6, 4.6), squeeze=False)
    (x_edges, x_log), (y_edges, y_log) = _cell_edges(x), _cell_edges(y)
    for ax, name in zip(axes[0], names):
        values = ds[name].isel(sel).transpose(dims[1], dims[0]).values.astype(float)
        if name == "regime":
            codes = sorted(_REGIME_COLOURS)
            ax.pcolormesh(x_edges, y_edges, values, shading="flat", vmin=-1.5, vmax=3.5,
                          cmap=ListedColormap([_REGIME_COLOURS[c] for c in codes]))
            present = set(np.unique(values[np.isfinite(values)]).astype(int))
            for c in codes:
                if c in present:
                    ax.plot([], [], "s", color=_REGIME_COLOURS[c], label=_REGIME_NAMES[c], markersize=8)
            ax.set_title("regime")
        else:
            mesh = ax.pcolormesh(x_edges, y_edges, values, shading="flat", cmap="viridis")
            fig.colorbar(mesh, ax=ax, label=_metric_label(ds[name]))
            ax.set_title("impacts per cam revolution" if name == "impacts_per_revolution" else name)
        ax.set_xlabel(coordinate_label(first))
        ax.set_ylabel(coordinate_label(second))
        ax.grid(False)
        for axis, log, scale in ((ax.xaxis, x_log, ax.set_xscale), (ax.yaxis, y_log, ax.set_yscale)):
            if log:
                scale("log")
            else:
                tidy_axis(axis, 6)
    if "regime" in names:
        legend_below(fig, axes[0, 0], 5)
    return save_figure(fig, path)


def _map_categories(ds: xr.Dataset):
    """Simulation regions of a regime map: codes and labels (periodic impacts banded by
    impacts per revolution)."""
    regime = ds["regime"].values
    rate = ds["impacts_per_revolution"].values
    codes = np.full(regime.shape, -1, dtype=int)
    labels = {-1: "failed", 0: "contact kept", 1: "contact kept, vr reversal", 2: "irregular impacts"}
    codes[regime == 0] = 0
    codes[regime == 1] = 1
    codes[regime == 3] = 2
    periodic = regime == 2
    bands = [(0.0, 0.999, "periodic, < 1 impact/rev\n(subharmonic)"), (0.999, 1.001, "periodic, 1 impact/rev"),
             (1.001, 5.0, "periodic, 1-5 impacts/rev"), (5.0, np.inf, "periodic, > 5 impacts/rev\n(chattering)")]
    for i, (low, high, label) in enumerate(bands):
        codes[periodic & (rate > low) & (rate <= high)] = 3 + i
        labels[3 + i] = label
    return codes, labels


def _kinematic_lines(ax, ds: xr.Dataset, dims: list, x: np.ndarray, y: np.ndarray, scales) -> None:
    """The inverse-kinematics loss-of-contact curve (solid) and vr-reversal boundary (dashed)."""
    if "loss_of_contact_speed" in ds:
        curve = ds["loss_of_contact_speed"]
        label = "loss of contact\n(inverse kinematics)"
        if curve.dims[0] == dims[0]:
            ax.plot(x, curve.values * scales[1], "k-", lw=1.5, label=label)
        else:
            ax.plot(curve.values * scales[0], y, "k-", lw=1.5, label=label)
    kin = ds["kinematic_regime"].values.astype(float)
    if np.any(kin == 1) and kin.shape[0] > 1 and kin.shape[1] > 1:
        ax.contour(x, y, (kin == 1).T.astype(float), levels=[0.5], colors="k", linestyles="--", linewidths=1.0)
        ax.plot([], [], "k--", label="vr reversal\n(inverse kinematics)")


@styled
def plot_regime_map(ds: xr.Dataset, path: str | Path) -> Path:
    """Regime map (:func:`camdyn.sweeps.regime_map.regime_map`): simulated regions over
    the two swept parameters (in the units the spec gave), with the inverse-kinematics
    loss-of-contact curve (solid) and the boundary of sliding-velocity reversal (dashed);
    over two followers, follower 1's impacts band the periodic regions."""
    if "follower" in ds.dims:
        ds = ds.isel(follower=0)
    dims = list(ds["regime"].dims)
    xc, yc = _coordinate(ds, dims[0]), _coordinate(ds, dims[1])
    (fx, _), (fy, _) = display_scale(xc), display_scale(yc)
    x, y = np.asarray(xc.values, float) * fx, np.asarray(yc.values, float) * fy
    codes, labels = _map_categories(ds)
    fixed = ["#000000", "#2ca02c", "#ff7f0e", "#d62728"]
    colours = fixed + [tuple(c) for c in plt.get_cmap("Blues")(np.linspace(0.35, 0.95, 4))]
    fig, ax = plt.subplots(figsize=(7.5, 4.8))
    ax.pcolormesh(x, y, codes.T, shading="nearest", vmin=-1.5, vmax=len(colours) - 1.5,
                  cmap=ListedColormap(colours))
    present = set(np.unique(codes))
    for c, label in labels.items():
        if c in present:
            ax.plot([], [], "s", color=colours[c + 1], label=label, markersize=8)
    _kinematic_lines(ax, ds, dims, x, y, (fx, fy))
    if "period" in ds and min(codes.shape) > 1:               # the simulation's period-1 / period-k boundary
        multiple = ((ds["period"].values > 1) & (ds["regime"].values == 2)).astype(float)
        if 0 < multiple.sum() < multiple.size:
            ax.contour(x, y, multiple.T, levels=[0.5], colors="#7f7f7f", linestyles=":", linewidths=1.5)
            ax.plot([], [], ":", color="#7f7f7f", label="Poincare period > 1\n(simulation)")
    for name in (v for v in ds.data_vars if "curve_kind" in ds[v].attrs and ds[v].dims == (dims[0],)):
        ax.plot(x, ds[name].values * fy, "o-", color="#e377c2", lw=1.8, ms=4,
                label=f"{ds[name].attrs['curve_kind']}\n(continuation)")
    agree = {k[len("agreement_"):]: ds.attrs[k] for k in ds.attrs if k.startswith("agreement_")}
    if agree:
        ax.set_title(f"simulation agrees with inverse kinematics at {agree['kept_agree']}/{agree['kept']} "
                     f"points in contact\nand at {agree['lost_agree']}/{agree['lost']} points beyond the loss "
                     f"of contact")
    ax.set_xlim(x.min(), x.max())
    ax.set_ylim(y.min(), y.max())
    ax.grid(False)
    tidy_axis(ax.xaxis, 7)
    tidy_axis(ax.yaxis, 7)
    ax.set_xlabel(coordinate_label(xc))
    ax.set_ylabel(coordinate_label(yc))
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return save_figure(fig, path)


@styled
def plot_design_map(ds: xr.Dataset, path: str | Path) -> Path:
    """Regime map of a design study (figs 4.4, 4.10): loss of contact, sliding reversal,
    harmonics too close to resonance, wrong lubrication regime, and the admissible
    window (the legend lists the regions present), with the recommended point starred."""
    code = np.full(ds["admissible"].shape, 4, dtype=float)           # admissible
    code[~ds["regime_ok"].values] = 3
    code[~ds["harmonics_clear"].values] = 2
    code[ds["sliding_reversal"].values] = 1
    code[~ds["contact_kept"].values] = 0
    names = ["loss of contact", "vr reversal", "harmonics near\nresonance", "other lubrication\nregime",
             "admissible"]
    colours = ["#d62728", "#ff7f0e", "#7f7f7f", "#bcbd22", "#2ca02c"]
    fig, ax = plt.subplots(figsize=(7.0, 4.6))
    ax.pcolormesh(ds["ratio"].values, ds["speed"].values, code.T, cmap=ListedColormap(colours), vmin=-0.5,
                  vmax=4.5, shading="nearest")
    present = set(np.unique(code).astype(int))
    for i, (c, n) in enumerate(zip(colours, names)):
        if i in present:
            ax.plot([], [], "s", color=c, label=n, markersize=8)
    if np.isfinite(ds.attrs.get("recommended_ratio", np.nan)):
        ax.plot(ds.attrs["recommended_ratio"], ds.attrs["recommended_speed"], "*", color="white",
                markeredgecolor="black", markersize=14, label="recommended")
    ax.grid(False)
    tidy_axis(ax.xaxis, 7)
    tidy_axis(ax.yaxis, 6)
    ax.set_xlabel(coordinate_label(ds["ratio"]))
    ax.set_ylabel(coordinate_label(ds["speed"]))
    ax.set_title(f"design map, {ds.attrs.get('system', '')}")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
    return save_figure(fig, path)
