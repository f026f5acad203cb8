"""Figures of a mechanism's run (the cam as a body on a driven shaft, the follower on a
flexible pivot, two followers on one cam): the bodies' motions and the forces over the
last cam revolutions, one panel per quantity, each in its own unit."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from camdyn.errors import ParameterError
from camdyn.plotting.style import axis_label, display_scale, save_figure, styled, tidy_axis

__all__ = ["plot_mechanism_history", "PANELS"]

#: The panels of each mechanism kind: (symbol, variables drawn in it, with their labels).
PANELS = {
    "driven-cam": [
        (r"$\dot\Theta$", [("cam_speed", None)]),
        (r"$\alpha$", [("alpha", None)]),
        ("$F_n$", [("Fn", None)]),
        ("torque", [("drive_torque", "drive"), ("bearing_torque", "bearing"), ("contact_torque", "contact")]),
    ],
    "flexible-pivot": [
        (r"$\alpha$", [("alpha", None)]),
        ("pivot", [("u", "$u$ (horizontal)"), ("v", "$v$ (vertical)")]),
        ("force", [("Fn", "contact $F_n$"), ("bearing_force", "bearing $|N|$")]),
    ],
    "two-followers": [
        (r"$\dot\Theta$", [("cam_speed", None)]),
        (r"$\alpha$", [("alpha", "follower")]),
        ("$F_n$", [("Fn", "follower")]),
        ("$F_f$", [("Ff", "follower")]),
    ],
}

#: Line style of each transition of the two-follower model's contacts.
_TRANSITIONS = {"stick": "-", "slip": "--", "sprag": ":"}


def _window(ds: xr.Dataset, revolutions: float) -> xr.Dataset:
    """The part of ``ds`` over its last ``revolutions`` cam revolutions (by the cam angle
    where it is a state, else by the prescribed speed ``speed_hz`` [Hz])."""
    t = ds["time"].values
    if "cam_angle" in ds and ds["cam_angle"].ndim == 1:
        angle = np.abs(ds["cam_angle"].values - ds["cam_angle"].values[-1])
        inside = angle <= 2.0 * math.pi * revolutions
        start = t[np.argmax(inside)]
    else:
        start = t[-1] - revolutions / float(ds.attrs["speed_hz"])
    return ds.sel(time=slice(max(start, t[0]), None))


def _variable(ds: xr.Dataset, name: str) -> xr.DataArray:
    """A drawn variable: a stored one, or the flexible pivot's bearing force magnitude [N]."""
    if name == "bearing_force":
        return xr.DataArray(np.hypot(ds["Nx"].values, ds["Ny"].values), dims=("time",), attrs={"units": "N"})
    return ds[name]


def _draw_panel(ax, ds: xr.Dataset, symbol: str, entries) -> None:
    """One panel: each variable of ``entries`` against time, in one unit (the first
    variable's, with the prefix that suits all of them: :func:`display_scale`)."""
    arrays = [(_variable(ds, name), label) for name, label in entries]
    units = {str(da.attrs.get("units", "")) for da, _ in arrays}
    if len(units) != 1:
        raise ParameterError(f"the panel {symbol} mixes units {sorted(units)}")
    joint = xr.DataArray(np.concatenate([np.ravel(da.values) for da, _ in arrays]), dims=("value",),
                         attrs={"units": units.pop()})
    factor, unit = display_scale(joint)
    t = ds["time"].values
    for index, (da, label) in enumerate(arrays):
        values = factor * np.asarray(da.values, dtype=float)
        if values.ndim == 2:
            for j in range(values.shape[1]):
                ax.plot(t, values[:, j], color=f"C{j}", label=f"{label} {j + 1}")
        else:
            ax.plot(t, values, color=f"C{index}", label=label)
    ax.set_ylabel(axis_label(symbol, unit))
    if len(arrays) > 1 or arrays[0][0].ndim == 2:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7)
    tidy_axis(ax.yaxis, 5)


@styled
def plot_mechanism_history(ds: xr.Dataset, path: str | Path, revolutions: float = 3.0) -> Path:
    """The bodies' motions and the forces of a mechanism's run over its last
    ``revolutions`` cam revolutions: for a driven cam its speed [rad/s], the follower angle,
    the normal force [N] and the drive, bearing and contact torques [N m]; for a flexible
    pivot the follower angle, the pivot's displacements and the contact and bearing forces;
    for two followers the cam speed and each follower's angle, normal and friction forces,
    with the contacts' sticks (solid), slips (dashed) and sprags (dotted) as thin lines.

    Parameters
    ----------
    ds : xarray.Dataset
        A run of :func:`camdyn.io.mechanism_config.simulate_mechanism` (its ``mechanism``
        attribute names the kind).
    path : str or Path
        Figure file; the format follows the suffix.
    revolutions : float
        Cam revolutions shown, at the end of the run [-].
    """
    kind = str(ds.attrs.get("mechanism", ""))
    if kind not in PANELS:
        raise ParameterError(f"no figure for the mechanism kind {kind!r}; known: {', '.join(PANELS)}")
    if not (math.isfinite(revolutions) and revolutions > 0):
        raise ParameterError(f"revolutions must be positive, got {revolutions!r}")
    sel = _window(ds, revolutions)
    panels = PANELS[kind]
    fig, axes = plt.subplots(len(panels), 1, figsize=(7.5, 1.7 * len(panels) + 0.8), sharex=True)
    for ax, (symbol, entries) in zip(axes, panels):
        _draw_panel(ax, sel, symbol, entries)
    if "transition_time" in ds:
        t = sel["time"].values
        for kind_name, style in _TRANSITIONS.items():
            times = ds["transition_time"].values[ds["transition_kind"].values == kind_name]
            for ti in times[(times >= t[0]) & (times <= t[-1])]:
                for ax in axes:
                    ax.axvline(ti, color="0.75", lw=0.5, ls=style, zorder=0)
    axes[-1].set_xlabel(axis_label("$t$", "s"))
    fig.align_ylabels(axes)
    fig.suptitle(f"{kind} ({ds.attrs.get('name', '')}), last {revolutions:g} revolutions")
    return save_figure(fig, path)
