"""The thesis's chapter 2 figures, regenerated on camdyn's stand-in rigs (docs/gallery.md).

The thesis gives no geometry for its chapter 2 rig, so these use the documented stand-ins
`alzate2007-standin` (sliding contact at 300 rpm, sections 2.6-2.8) and
`alzate2007-standin-impacting` (loses contact at 132 rpm like the thesis's rig, section
2.5). Trends carry over; absolute numbers are the stand-ins'.

Run: python examples/chapter2_gallery.py [FIGURE ...]   (default: all; about 12 minutes on 2 cores)
Writes docs/figures/fig2_*.png and prints what each shows.
"""

import math
import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import camdyn
from camdyn.analysis.harmonics import amplitude_spectrum
from camdyn.analysis.linear import linearize
from camdyn.analysis.restitution import energy_balance_residual
from camdyn.analysis.spectra import resonance_peaks, spectrum_summary
from camdyn.plotting import plot_regime_map
from camdyn.sweeps import run_sweep, spec_from_dict
from camdyn.sweeps.regime_map import regime_map

OUT = Path(__file__).resolve().parent.parent / "docs" / "figures"
WORK = Path(tempfile.mkdtemp(prefix="camdyn-gallery-"))
IMPACTING = "alzate2007-standin-impacting"
SLIDING = "alzate2007-standin"
#: identified damping of the thesis (2.5): law -> overrides
MODELS = {"A": {"contact.damping": "A", "contact.damping_ratio": "0.125"},
          "B": {"contact.damping": "B", "contact.beta": "3.25 s/m"},
          "C": {"contact.damping": "C", "contact.beta": "0.325 MN*s/m^1.25"},
          "D": {"contact.damping": "D", "contact.damping_ratio": "0.119", "contact.beta": "4.25 s/m"},
          "E": {"contact.damping": "E", "contact.damping_ratio": "0.096", "contact.beta": "0.325 MN*s/m^1.25"}}
#: the impacting stand-in rests on 0.4 nm of penetration: tolerances that resolve it
#: (camdyn.simulation.runner.penetration_resolution below 0.1)
TOLERANCES = {"rtol": 1.5e-8, "atol": 1e-11}
FIG_2_10 = {"contact.length": 1.6e-3, "contact.damping": "D", "contact.damping_ratio": 0.01, "contact.beta": 4.25}


def _speed_sweep(source, overrides, start, stop, num, name, revolutions=120, discard=80):
    spec = spec_from_dict({"system": {"source": source, "set": overrides},
                           "vary": [{"key": "motion.speed", "start": start, "stop": stop, "num": num}],
                           "run": {"revolutions": revolutions, "discard": discard, **TOLERANCES},
                           "metrics": {"names": ["residual", "regime", "impacts"]},
                           "output": {"path": str(WORK / f"{name}.nc")}}, name=name)
    return run_sweep(spec, progress=False).load()


def fig_2_4():
    """Residual response against speed for damping models A-E (thesis fig 2.4)."""
    fig, axes = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for law, overrides in MODELS.items():
        ds = _speed_sweep(IMPACTING, overrides, "100 rpm", "170 rpm", 36, f"fig2_4_{law}")
        rpm = ds["motion.speed"].values * 60
        axes[0].plot(rpm, ds.residual_rms, ".-", ms=3, lw=0.8, label=f"model {law}")
        axes[1].plot(rpm, ds.residual_peak_to_peak, ".-", ms=3, lw=0.8, label=f"model {law}")
        irregular = rpm[ds.regime.values == 3]
        print(f"  model {law}: irregular impacts at {len(irregular)} of 36 speeds"
              + (f", first at {irregular.min():.0f} rpm" if len(irregular) else ""))
    axes[0].set_ylabel("rms of alpha_r [rad]")
    axes[1].set_ylabel("peak-to-peak of alpha_r [rad]")
    axes[1].set_xlabel("cam speed [rpm]")
    axes[0].legend(fontsize=8)
    axes[0].set_title("fig 2.4: residual response, damping models A-E (impacting stand-in)", fontsize=9)
    fig.tight_layout()
    fig.savefig(OUT / "fig2_4_residual_damping_models.png", dpi=120)


def fig_2_7_8():
    """Energy-balance restitution estimate against the contact model (figs 2.7, 2.8)."""
    system = camdyn.load_system(IMPACTING, MODELS["D"])
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for ax, (start, stop, num, xis) in zip(axes, [(20, 160, 36, (0.05, 0.2, 0.4, 0.6)),
                                                  (100, 900, 41, (0.2, 0.6, 1.0))]):
        ds = _speed_sweep(IMPACTING, MODELS["D"], f"{start} rpm", f"{stop} rpm", num, f"fig2_8_{start}")
        rpm = ds["motion.speed"].values * 60
        ax.plot(rpm, ds.residual_peak_to_peak, "k.-", ms=4, lw=0.8, label="contact model (law D)")
        fine = np.linspace(start, stop, 200)
        for xi in xis:
            est = energy_balance_residual(system, fine / 60, xi)
            ax.plot(fine, est, lw=1, label=f"energy balance, xi = {xi:g}")
        ax.set_xlabel("cam speed [rpm]")
        ax.set_ylabel("peak-to-peak residual alpha_p^r [rad]")
        ax.legend(fontsize=7)
        below = rpm < 125
        if ax is axes[0]:
            match = {xi: float(np.max(np.abs(energy_balance_residual(system, rpm[below] / 60, xi)
                                               - ds.residual_peak_to_peak.values[below]))) for xi in xis}
            print("  below 125 rpm, largest gap energy balance - contact model [rad]: "
                  + ", ".join(f"xi {k:g}: {v:.3g}" for k, v in match.items()))
    axes[0].set_title("fig 2.7: low speeds", fontsize=9)
    axes[1].set_title("fig 2.8: broad range (the follower saturates near 90 degrees)", fontsize=9)
    fig.tight_layout()
    fig.savefig(OUT / "fig2_7_8_energy_balance.png", dpi=120)


def fig_2_9():
    """Contact regimes over spring stiffness and speed (fig 2.9)."""
    spec = spec_from_dict({"system": {"source": IMPACTING},
                           "vary": [{"key": "spring.stiffness", "start": "500 N/m", "stop": "5000 N/m", "num": 10},
                                    {"key": "motion.speed", "start": "40 rpm", "stop": "260 rpm", "num": 23}],
                           "run": {"revolutions": 40, "discard": 20, **TOLERANCES},
                           "metrics": {"names": ["regime", "impacts", "residual"]},
                           "output": {"path": str(WORK / "fig2_9.nc")}}, name="fig2_9")
    ds = regime_map(spec, progress=False)
    plot_regime_map(ds, OUT / "fig2_9_regime_map.png")
    print(f"  simulation agrees with inverse kinematics at {ds.attrs['agreement_kept_agree']}/"
          f"{ds.attrs['agreement_kept']} points in contact and {ds.attrs['agreement_lost_agree']}/"
          f"{ds.attrs['agreement_lost']} beyond; loss of contact at ks = 2000 N/m: "
          f"{float(ds.loss_of_contact_speed.interp({'spring.stiffness': 2000.0})) * 60:.0f} rpm")


def fig_2_10_11():
    """Spectra and Fn for de- and self-energizing rotation, line and point contact (figs 2.10, 2.11)."""
    base = camdyn.load_system(SLIDING)
    runs = {}
    for label, direction, kind in (("+300 rpm", 1, "line"), ("-300 rpm", -1, "line"),
                                   ("+300 rpm, point contact", 1, "point")):
        system = base.with_values(**FIG_2_10, **{"motion.direction": direction, "contact.kind": kind})
        runs[label] = camdyn.simulate(system, speed=5.0, revolutions=10, sample_rate=20e3)
    fig, axes = plt.subplots(1, 3, figsize=(14, 4))
    means = {}
    for label, ds in runs.items():
        summary = spectrum_summary(ds, window=8, peaks=1)
        f, a = amplitude_spectrum(ds, "alpha_ddot", 8)
        peak = resonance_peaks(f, a, 5.0, 1, relative=0.0)[0][0]   # however small against the harmonics
        axes[0].semilogy(f, a, lw=0.8, label=label)
        axes[1].semilogy(f, a, lw=0.8, label=f"{label}: peak {peak:.0f} Hz")
        win = ds.isel(time=slice(-4001, None))
        axes[2].plot((win.time - win.time[0]) * 5.0, win.Fn, lw=0.8, label=label)
        means[label] = float(win.Fn.mean())
        print(f"  {label}: mean Fn {means[label]:.3f} N, resonance {peak:.0f} Hz "
              f"(linearized {summary['natural_frequency_hz']:.0f} Hz)")
    axes[0].set_xlim(0, 60)
    axes[1].set_xlim(300, 2200)
    for ax in axes[:2]:
        ax.set_xlabel("frequency [Hz]")
        ax.set_ylabel("|alpha_ddot| [rad/s^2]")
        ax.legend(fontsize=8)
    axes[2].set_xlabel("time [revolutions]")
    axes[2].set_ylabel("Fn [N]")
    axes[2].legend(fontsize=8)
    axes[0].set_title("fig 2.10a: cam harmonics", fontsize=9)
    axes[1].set_title("fig 2.10b: contact resonance", fontsize=9)
    axes[2].set_title("fig 2.11: normal force, the two directions (and point contact)", fontsize=9)
    fig.tight_layout()
    fig.savefig(OUT / "fig2_10_11_direction.png", dpi=120)


def fig_2_14_15():
    """Oscillating cam: vr reverses; Coulomb against tanh friction (figs 2.14, 2.15)."""
    rig = camdyn.load_system(SLIDING)
    e = 0.7 * rig.cam.semi_major
    system = rig.with_values(**{"cam.runout": e, "cam.pivot_y": 0.5 * rig.follower.width + rig.cam.semi_major + e,
                                "spring.free_length": 0.085, "motion.kind": "oscillating",
                                "motion.amplitude": math.pi, "motion.frequency": 40 / 60})
    fig, axes = plt.subplots(3, 1, figsize=(7, 7), sharex=True)
    for law in ("coulomb", "tanh"):
        ds = camdyn.simulate(system.with_values(**{"friction.law": law}), revolutions=2, sample_rate=10e3)
        win = ds.isel(time=slice(ds.sizes["time"] // 2, None))
        t = (win.time - win.time[0]) * 40 / 60
        for ax, var in zip(axes, ("sliding_velocity", "Ff", "Nx")):
            ax.plot(t, win[var], lw=0.9, label=f"{law} friction")
            ax.set_ylabel(f"{var} [{win[var].attrs['units']}]")
        print(f"  {law}: vr > 0 for {float((win.sliding_velocity > 0).mean()) * 100:.0f} % of the cycle, "
              f"Ff from {float(win.Ff.min()):.2f} to {float(win.Ff.max()):.2f} N")
    axes[0].legend(fontsize=8)
    axes[-1].set_xlabel("time [oscillation periods]")
    axes[0].set_title("figs 2.14-2.15: oscillating cam, Theta_p = pi, 40 rpm, e = 0.7 rc", fontsize=9)
    fig.tight_layout()
    fig.savefig(OUT / "fig2_14_15_oscillating_cam.png", dpi=120)


def fig_2_16():
    """Linearized against nonlinear model (fig 2.16)."""
    system = camdyn.load_system(SLIDING).with_values(**FIG_2_10)
    nonlinear = camdyn.simulate(system, speed=5.0, revolutions=10, sample_rate=20e3)
    model = linearize(system, 5.0)
    linear = model.simulate(nonlinear.time.values, x0=float(nonlinear.alpha[0]) - model.equilibrium_angle)
    linear.attrs["speed_hz"] = 5.0
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for label, ds in (("nonlinear", nonlinear), ("linear", linear)):
        f, a = amplitude_spectrum(ds, "alpha_ddot", 8)
        for ax in axes:
            ax.semilogy(f, np.maximum(a, 1e-12), lw=0.8, label=label)
    axes[0].set_xlim(0, 60)
    axes[1].set_xlim(model.natural_frequency - 300, model.natural_frequency + 300)
    for ax in axes:
        ax.set_xlabel("frequency [Hz]")
        ax.set_ylabel("|alpha_ddot| [rad/s^2]")
        ax.legend(fontsize=8)
    axes[0].set_title("fig 2.16a: the linear model has no super-harmonics", fontsize=9)
    axes[1].set_title(f"fig 2.16b: near the natural frequency ({model.natural_frequency:.0f} Hz)", fontsize=9)
    fig.tight_layout()
    fig.savefig(OUT / "fig2_16_linear_vs_nonlinear.png", dpi=120)
    from camdyn.analysis.harmonics import harmonic_amplitudes
    hn = harmonic_amplitudes(nonlinear, orders=(1, 2, 3), revolutions=8)
    hl = harmonic_amplitudes(linear, orders=(1, 2, 3), revolutions=8, speed=5.0)
    print(f"  harmonics 1-3 of alpha_ddot: nonlinear {np.round(hn, 4)}, linear {np.round(hl, 4)} rad/s^2")


FIGURES = {"2.4": fig_2_4, "2.7": fig_2_7_8, "2.9": fig_2_9, "2.10": fig_2_10_11, "2.14": fig_2_14_15,
           "2.16": fig_2_16}

if __name__ == "__main__":
    OUT.mkdir(parents=True, exist_ok=True)
    for key in sys.argv[1:] or FIGURES:
        print(f"fig {key}: {FIGURES[key].__doc__}")
        FIGURES[key]()
