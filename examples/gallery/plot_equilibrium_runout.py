"""
Static equilibrium over the runout
==================================

:func:`camdyn.static_equilibrium` finds the follower angle at which the spring, gravity
and the Hertz contact balance, and the linearized natural frequency there. Here for the
chapter 4 rig with the cam's runout e from 0.5 to 8 mm: the contact force and the
stiffness of the contact change with the geometry, and so does the contact resonance.
"""

import matplotlib.pyplot as plt
import numpy as np

import camdyn
from camdyn.plotting.style import axis_label, figure_style

runouts = np.linspace(0.5, 8.0, 16)  # [mm]
angle, force, frequency = [], [], []
for e in runouts:
    rig = camdyn.load_system("sundar2014-friction", {"cam.runout": f"{e} mm"})
    eq = camdyn.static_equilibrium(rig)
    angle.append(np.degrees(eq.angle))
    force.append(eq.contact_force)
    frequency.append(eq.natural_frequency)

# %%

labels = (axis_label(r"equilibrium angle $\alpha^*$", "deg"), axis_label("contact force $F_n$", "N"),
          axis_label("natural frequency $f_n$", "Hz"))
with figure_style():
    fig, axes = plt.subplots(3, 1, figsize=(7, 7), sharex=True)
    for ax, values, label in zip(axes, (angle, force, frequency), labels):
        ax.plot(runouts, values, "o-", ms=4)
        ax.set_ylabel(label)
    axes[0].ticklabel_format(axis="y", useOffset=False)  # the angle changes in its fifth digit
    axes[-1].set_xlabel(axis_label("cam runout $e$", "mm"))
    axes[0].set_title("sundar2014-friction: static equilibrium against the runout")
    fig.align_ylabels(axes)

print(f"e = {runouts[0]:.1f} mm: {frequency[0]:.1f} Hz; e = {runouts[-1]:.1f} mm: {frequency[-1]:.1f} Hz")
