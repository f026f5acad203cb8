"""
A small bifurcation diagram
===========================

A parameter sweep over the cam speed of the chapter 3 rig (e/rc = 0.2), 20 speeds from
12 to 20 Hz, run inline in this process (``workers=0``). The sweep keeps, per speed, the
follower angle once per cam revolution (the Poincare section) after the transient, and
the number of impacts per revolution. The full diagram (400 speeds) is
``camdyn sweep examples/sweeps/bifurcation.toml``.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from camdyn.plotting.style import axis_label, figure_style, tidy_axis
from camdyn.sweeps import run_sweep, spec_from_dict

folder = Path(tempfile.mkdtemp())
spec = spec_from_dict({
    "system": {"source": "sundar2014-impact", "set": {"cam.runout": "3.5 mm"}},
    "vary": [{"key": "motion.speed", "start": "12 Hz", "stop": "20 Hz", "num": 20}],
    "run": {"revolutions": 150, "discard": 100, "samples_per_revolution": 32, "chunk": 5},
    "metrics": {"names": ["poincare", "impacts", "regime"], "harmonics": 4},
    "output": {"path": str(folder / "bifurcation.nc")},
}, base_dir=folder, name="bifurcation")
ds = run_sweep(spec, workers=0, progress=False).load()

# %%
# Period 1 (one impact per revolution, a single Poincare point) up to about 16 Hz, then
# period doubling into an irregular band near 18 Hz.

speed = ds["motion.speed"].values  # [Hz]
alpha = np.degrees(ds["poincare_alpha"].values)  # [deg], (speed, revolution)
with figure_style():
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True)
    ax1.plot(np.repeat(speed, alpha.shape[1]), alpha.ravel(), ".", ms=2, color="k")
    ax1.set_ylabel(axis_label(r"$\alpha$ once per revolution", "deg"))
    ax2.plot(speed, ds["impacts_per_revolution"].values, "o-", ms=4)
    ax2.set_ylabel(axis_label("impacts", ds["impacts_per_revolution"].attrs["units"]))
    ax2.set_xlabel(axis_label(r"cam speed $\Omega$", "Hz"))
    tidy_axis(ax2.yaxis, 5, integer=True)
    ax1.set_title("sundar2014-impact, e = 3.5 mm: bifurcation diagram")
    fig.align_ylabels((ax1, ax2))

# %%
# The regime of each speed as the sweep classifies it (the metrics are defined in
# :doc:`/sweeps`).

names = {0: "contact kept", 1: "contact kept, sliding reverses", 2: "periodic impacts", 3: "irregular impacts",
         -1: "failed"}
for flag, count in ds["regime"].to_series().value_counts().sort_index().items():
    print(f"{names[int(flag)]}: {count} speeds")
