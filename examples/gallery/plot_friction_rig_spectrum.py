"""
Spectrum of the chapter 4 rig
=============================

The friction rig of the thesis's chapter 4 (preset ``sundar2014-friction``, e/a = 0.1)
keeps contact at 11.55 Hz. The follower's angular acceleration holds the cam harmonics,
which the friction estimator uses. The contact mode, near the linearized natural
frequency, is barely excited in steady contact: a hump seven orders of magnitude below
the first harmonic.
"""

import matplotlib.pyplot as plt

import camdyn
from camdyn.analysis.harmonics import amplitude_spectrum
from camdyn.analysis.spectra import spectrum_summary
from camdyn.plotting.style import axis_label, figure_style

rig = camdyn.load_system("sundar2014-friction")
ds = camdyn.simulate(rig, speed="11.55 Hz", revolutions=30)
freq, amp = amplitude_spectrum(ds, "alpha_ddot", revolutions=20)
summary = spectrum_summary(ds, "alpha_ddot", window=20, harmonics=10)

# %%
# The amplitude spectrum over the last 20 revolutions (Hann window, amplitude-corrected),
# the cam harmonics marked, and the linearized natural frequency of the equilibrium.

with figure_style():
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.semilogy(freq, amp, lw=0.8)
    for h in summary["harmonics"]:
        ax.plot(h["frequency_hz"], h["amplitude"], "o", color="C1", ms=4)
    ax.axvline(summary["natural_frequency_hz"], color="C3", ls="--", lw=0.8,
               label=f"linearized natural frequency {summary['natural_frequency_hz']:.0f} Hz")
    ax.set_xlim(0, 1500)
    ax.set_ylim(1e-10 * amp.max(), 5 * amp.max())
    ax.set_xlabel(axis_label("frequency $f$", "Hz"))
    ax.set_ylabel(axis_label(r"amplitude of $\ddot\alpha$", summary["units"]))
    ax.set_title("sundar2014-friction, e/a = 0.1, 11.55 Hz: cam harmonics (dots)")
    ax.legend(loc="upper right")

# %%
# The first cam harmonics, the values the friction estimator works from, and the
# largest peaks that are not cam harmonics.

for h in summary["harmonics"][:4]:
    print(f"order {h['order']}: {h['frequency_hz']:7.2f} Hz  {h['amplitude']:.4g} {summary['units']}")
for p in summary["peaks"]:
    print(f"resonance peak: {p['frequency_hz']:.1f} Hz  {p['amplitude']:.3g} {summary['units']}")
if not summary["peaks"]:
    print("no resonance peak stands out: the contact mode is hardly excited in steady contact")
