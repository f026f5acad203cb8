"""
Impacts of the chapter 3 rig
============================

The impact-damping rig of the thesis's chapter 3 (preset ``sundar2014-impact``, circular
cam, e/rc = 0.2) at 16 Hz loses contact once per revolution and lands with an impact.
camdyn locates every contact onset as an event; the impact table (dimension ``impact``)
lists each one with its approach velocity and peak force.
"""

import matplotlib.pyplot as plt
import numpy as np

import camdyn
from camdyn.plotting.style import axis_label, figure_style

rig = camdyn.load_system("sundar2014-impact")
ds = camdyn.simulate(rig, speed="16 Hz", revolutions=40)

# %%
# The follower angle and the normal contact force over the last two revolutions, with the
# located impacts as thin grey lines. Between impacts the follower flies free (zero force).

last = ds.sel(time=slice(float(ds.time[-1]) - 2 / 16.0, None))
impacts = ds["impact_time"].values
impacts = impacts[impacts >= float(last.time[0])]

t_ms = 1e3 * last["time"].values
with figure_style():
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True)
    ax1.plot(t_ms, np.degrees(last["alpha"].values))
    ax1.set_ylabel(axis_label(r"follower angle $\alpha$", "deg"))
    ax2.plot(t_ms, last["Fn"].values, color="C3")
    ax2.set_ylabel(axis_label("normal contact force $F_n$", last["Fn"].attrs["units"]))
    ax2.set_xlabel(axis_label("time $t$", "ms"))
    for ax in (ax1, ax2):
        for t in impacts:
            ax.axvline(1e3 * t, color="0.6", lw=0.6)
    fig.suptitle("sundar2014-impact, e/rc = 0.2, 16 Hz")
    fig.align_ylabels((ax1, ax2))

# %%
# The impact table: one row per located impact. After the start-up transient the motion
# settles on one impact per revolution. 16 Hz is where the period doubling of this rig
# begins (see the bifurcation example), so the approach velocity alternates slightly.

columns = ["impact_time", "impact_approach_velocity", "impact_separation_velocity", "impact_peak_force"]
for name in columns:
    print(f"{name} [{ds[name].attrs.get('units', '-')}]: {ds[name].attrs.get('long_name', '')}")
table = ds[columns].to_dataframe().rename(columns=lambda name: name.removeprefix("impact_"))
print(f"\n{ds.sizes['impact']} impacts in 40 revolutions; the last five:")
print(table.tail(5).to_string(float_format=lambda x: f"{x:.4g}"))
