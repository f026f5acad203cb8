"""The time history of a model of the model protocol (:func:`camdyn.simulate` on a
``Model.bind()``): one panel per state and per output channel, each in its unit, with
the events of each guard marked on the time axis."""

from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import xarray as xr

from camdyn.plotting.style import axis_label, display_values, save_figure, styled, tidy_axis

__all__ = ["plot_model_history"]


@styled
def plot_model_history(ds: xr.Dataset, path: str | Path) -> Path:
    """Figure of a protocol model's run: its states and output channels against time
    [s], the events of each guard as ticks at the foot of every panel."""
    channels = [name for name in ds.data_vars if ds[name].dims == ("time",) and not str(name).startswith("mode_")]
    fig, axes = plt.subplots(len(channels), 1, figsize=(8.0, 1.6 * len(channels) + 0.9), sharex=True,
                             squeeze=False)
    t, t_unit = display_values(ds["time"])
    guards = ds["event_guard"].values if "event_guard" in ds else np.array([])
    times = ds["event_time"].values * (t[-1] / ds["time"].values[-1] if ds["time"].values[-1] else 1.0)
    names = list(dict.fromkeys(str(g) for g in guards))
    for ax, name in zip(axes[:, 0], channels):
        values, unit = display_values(ds[name])
        ax.plot(t, values, lw=0.9)
        ax.set_ylabel(axis_label(str(name), unit))
        for k, guard in enumerate(names):
            ax.plot(times[guards == guard], np.full(np.count_nonzero(guards == guard), 0.0), "|", ms=6,
                    color=f"C{k + 1}", transform=ax.get_xaxis_transform(), label=f"event: {guard}")
        tidy_axis(ax.yaxis, 4)
    if names:
        axes[0, 0].legend(loc="upper right", fontsize="small")
    axes[-1, 0].set_xlabel(axis_label("time $t$", t_unit))
    fig.suptitle(f"{ds.attrs.get('model', 'model')}" + (f" at {ds.attrs['speed_hz']:.4g} Hz"
                                                         if "speed_hz" in ds.attrs else ""))
    fig.align_ylabels(axes[:, 0])
    return save_figure(fig, path)
