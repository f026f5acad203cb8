"""
Friction from a noisy record
============================

The friction estimator of the thesis's chapter 4 on a synthetic record: the chapter 4
rig with Coulomb friction mu = 0.3 at 11.55 Hz, sampled at 9460 Hz over 10 revolutions
with 1 % noise on each channel (pivot reactions ``Nx``, ``Ny`` and the follower's angular
acceleration). The estimator balances the cam harmonics of the three channels and
returns the coefficient of friction with the checks of its assumptions.
"""

import matplotlib.pyplot as plt

import camdyn
from camdyn.identification.friction import estimate_friction
from camdyn.plotting.style import axis_label, figure_style
from camdyn.records.synthesis import synthesize

rig = camdyn.load_system("sundar2014-friction", {"friction.coefficient": 0.3})
record = synthesize(rig, speed=11.55, revolutions=10, sample_rate=9460.0, noise=0.01, seed=1)
estimate = estimate_friction(rig, record)
print(f"mu = {estimate.mu:.4f} (true 0.3, error {100 * (estimate.mu / 0.3 - 1):+.2f} %), "
      f"from {estimate.revolutions} revolutions and {estimate.harmonics} harmonics")
for name, check in estimate.checks.items():
    print(f"  {name}: {'passed' if check['passed'] else 'FAILED'}")

# %%
# The record the estimator sees: two revolutions of each channel.

window = record.sel(time=slice(float(record.time[0]), float(record.time[0]) + 2 / 11.55))
symbols = {"Nx": "pivot reaction $N_x$", "Ny": "pivot reaction $N_y$", "alpha_ddot": r"$\ddot\alpha$"}
with figure_style():
    fig, axes = plt.subplots(3, 1, figsize=(8, 6), sharex=True)
    for ax, (name, symbol) in zip(axes, symbols.items()):
        ax.plot(1e3 * window["time"].values, window[name].values, lw=0.7)
        ax.set_ylabel(axis_label(symbol, record[name].attrs.get("units", "")))
    axes[-1].set_xlabel(axis_label("time $t$", "ms"))
    axes[0].set_title(rf"synthetic record, 1 % noise: $\mu$ estimated {estimate.mu:.4f}")
    fig.align_ylabels(axes)
