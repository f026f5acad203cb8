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

runouts = np.linspace(0.5, 8.0, 16)  # [mm]
angle, force, frequency = [], [], []
for e in runouts:
    rig = camdyn.load_system("sundar2014-friction", {"cam.runout": f"{e} mm"})
    eq = camdyn.static_equilibrium(rig)
    angle.append(np.degrees(eq.angle))
    force.append(eq.contact_force)
    frequency.append(eq.natural_frequency)

# %%

fig, axes = plt.subplots(3, 1, figsize=(7, 7), sharex=True)
for ax, values, label in zip(axes, (angle, force, frequency),
                             ("equilibrium angle [deg]", "contact force [N]", "natural frequency [Hz]")):
    ax.plot(runouts, values, "o-", ms=4)
    ax.set_ylabel(label)
axes[-1].set_xlabel("cam runout e [mm]")
axes[0].set_title("sundar2014-friction: static equilibrium against the runout")
fig.tight_layout()

print(f"e = {runouts[0]:.1f} mm: {frequency[0]:.1f} Hz; e = {runouts[-1]:.1f} mm: {frequency[-1]:.1f} Hz")
