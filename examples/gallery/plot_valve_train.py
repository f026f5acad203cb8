"""
A valve train written outside camdyn
====================================

A model that is not in the package (``examples/models/valve_train.py``, explained in
:doc:`/user-models`): a cam drives a roller follower and a valve through a lash gap, the
valve spring's middle coil is a mass of its own so that the spring can surge, and the
valve lands on its seat as an impact. It runs through :func:`camdyn.simulate` like
camdyn's own models, on a driver compiled for it (once per machine).

Over a range of camshaft speeds the script finds where the valve leaves the cam in its
lift (valve float) and how high it bounces off its seat after landing, then runs the
same model on camdyn's sweep engine for its bifurcation diagram.
"""

import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import camdyn
from camdyn.plotting.style import axis_label, figure_style

HERE = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
sys.path.insert(0, str(HERE.parent / "models"))
from valve_train import VALVE_TRAIN  # noqa: E402

valve = VALVE_TRAIN.bind()
ds = camdyn.simulate(valve, speed="40 Hz", revolutions=3, sample_rate=40e3)
lash = valve["lash"]

# %%
# One revolution at 40 Hz (2400 camshaft rpm): the valve follows the cam's lift less the
# lash, lands, and bounces on its seat; the seat's force peaks at each landing.

last = ds.sel(time=slice(2 / 40.0, None))
t_ms = 1e3 * (last["time"].values - 2 / 40.0)
with figure_style():
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True)
    ax1.plot(t_ms, 1e3 * np.maximum(last["cam_lift"].values - lash, 0.0), color="0.5", label="cam lift - lash")
    ax1.plot(t_ms, 1e3 * last["x_v"].values, label="valve lift")
    ax1.set_ylabel(axis_label("lift", "mm"))
    ax1.legend(loc="upper right")
    ax2.plot(t_ms, last["seat_force"].values, color="C3", label="seat")
    ax2.plot(t_ms, last["cam_force"].values, color="C2", label="cam")
    ax2.set_ylabel(axis_label("force", last["seat_force"].attrs["units"]))
    ax2.set_xlabel(axis_label("time $t$", "ms"))
    ax2.legend(loc="upper right")
    fig.suptitle("valve train at 40 Hz")
    fig.align_ylabels((ax1, ax2))

# %%
# Valve float and seating bounce against the camshaft speed, from the last of three
# revolutions at each speed: the valve floats where the cam's force vanishes while the
# cam still lifts it, and bounces where it leaves its seat while the cam is on its base
# circle.

speeds = np.arange(30.0, 62.0, 2.0)
bounce, floating = [], []
for f in speeds:
    run = camdyn.simulate(valve, speed=float(f), revolutions=3, sample_rate=256 * f)
    run = run.sel(time=slice(2 / f, None))
    lifting = run["cam_lift"].values > lash + 0.1 * valve["cam.lift"]
    floating.append(bool(np.any(lifting & (run["mode_cam_contact"].values < 0.5))))
    closed = run["cam_lift"].values <= lash
    bounce.append(float(np.max(run["x_v"].values[closed], initial=0.0)))
float_speed = speeds[np.argmax(floating)] if any(floating) else np.nan
print(f"valve float from {float_speed:g} Hz ({60 * float_speed:g} camshaft rpm) in the speeds scanned")
print("seating bounce [um]:", ", ".join(f"{f:g} Hz {1e6 * b:.0f}" for f, b in zip(speeds, bounce)))

with figure_style():
    fig, ax = plt.subplots(figsize=(8, 3.5))
    ax.plot(speeds, 1e6 * np.array(bounce), "o-", label="seating bounce")
    if np.isfinite(float_speed):
        ax.axvline(float_speed, color="C3", ls="--", label=f"valve float from {float_speed:g} Hz")
    ax.set_xlabel(axis_label("camshaft speed", "Hz"))
    ax.set_ylabel(axis_label("largest lift off the seat", "µm"))
    ax.legend(loc="upper left")

# %%
# The same model on camdyn's sweep engine (:doc:`/sweeps`), named by its file: 31 speeds,
# 30 periods each with the first 20 dropped. The valve's lift at the start of each kept
# period (on its seat, about -12 µm under the preload) is the bifurcation diagram; the
# cam contact's crossings per period go from 2 (one closing, one opening) to 4 and more
# where the valve floats, and the seat's count the bounces.

import tempfile  # noqa: E402

from camdyn.sweeps import run_sweep, spec_from_dict  # noqa: E402

spec = spec_from_dict({
    "system": {"source": str(HERE.parent / "models" / "valve_train.py") + ":VALVE_TRAIN"},
    "vary": [{"key": "speed", "start": "30 Hz", "stop": "60 Hz", "num": 31}],
    "run": {"revolutions": 30, "discard": 20, "samples_per_revolution": 256},
    "output": {"path": str(Path(tempfile.mkdtemp()) / "valve_train_speed.nc")}})
swept = run_sweep(spec, workers=0, progress=False)
f_hz = swept["speed"].values
with figure_style():
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True)
    ax1.plot(np.repeat(f_hz, swept.sizes["revolution"]), 1e6 * swept["poincare_x_v"].values.ravel(), "k.", ms=3)
    ax1.set_ylabel(axis_label("valve lift once per period", "µm"))
    ax2.plot(f_hz, swept["events_cam_contact"].values, "o-", label="cam contact")
    ax2.plot(f_hz, swept["events_seat"].values, "s-", label="seat")
    ax2.set_ylabel(axis_label("crossings per period", "1/rev"))
    ax2.set_xlabel(axis_label("camshaft speed", "Hz"))
    ax2.legend(loc="upper left")
    fig.align_ylabels((ax1, ax2))
floating = f_hz[swept["events_cam_contact"].values > 2]
print(f"sweep: the valve leaves the cam during its lift from {floating.min():g} Hz" if floating.size else
      "sweep: the valve follows the cam at every speed")
