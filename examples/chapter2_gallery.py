"""The thesis's chapter 2 figures, regenerated on camdyn's stand-in rigs (docs/gallery.md).

The thesis gives no geometry for its chapter 2 rig, so these use the documented stand-ins
`alzate2007-standin` (sliding contact at 300 rpm, sections 2.6-2.8) and
`alzate2007-standin-impacting` (loses contact at 132 rpm like the thesis's rig, section
2.5). Trends carry over; absolute numbers are the stand-ins'.

Run: python examples/chapter2_gallery.py [FIGURE ...] [--data FILE]
(FIGURE: 2.4, 2.7, 2.9, 2.10, 2.14, 2.16; default all, about 12 minutes on 2 cores).
Writes docs/figures/fig2_*.png and prints what each shows; with ``--data`` also the
numbers each figure shows, as JSON (tools/make_figures.py records them in
docs/figures/figures.json).

Each figure is two functions: ``data_*`` computes what it shows (a dict: lists are the
recorded numbers, numpy arrays the long curves that are not recorded; angles in degrees,
speeds in rpm, frequencies in Hz, forces in N) and ``draw_*`` draws it in camdyn's figure
style (:mod:`camdyn.plotting.style`). tests/test_figures.py draws figs 2.4 and 2.7-2.8 (the
long sweeps) from the numbers recorded in figures.json and the others from their data
functions (a second each), and checks that no text overlaps or leaves the figure.
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import camdyn  # noqa: E402
from camdyn.analysis.harmonics import amplitude_spectrum, harmonic_amplitudes  # noqa: E402
from camdyn.analysis.kinematics import loss_of_contact_speed  # noqa: E402
from camdyn.analysis.linear import linearize  # noqa: E402
from camdyn.analysis.restitution import energy_balance_residual  # noqa: E402
from camdyn.analysis.spectra import spectrum_summary  # noqa: E402
from camdyn.plotting import plot_regime_map  # noqa: E402
from camdyn.plotting.style import axis_label, legend_below, save_figure, styled, tidy_axis  # noqa: E402
from camdyn.sweeps import run_sweep, spec_from_dict  # noqa: E402
from camdyn.sweeps.regime_map import regime_map  # noqa: E402

OUT = Path(__file__).resolve().parent.parent / "docs" / "figures"
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
#: figs 2.10-2.11 run where their spectra are converged near the contact resonance: at
#: the default rtol 1e-8 the integration error fills that band (on the point-contact run
#: the step size dwelling at 0.33 ms once per revolution puts a line at 3030 Hz above
#: everything between 300 Hz and 4 kHz); at rtol 1e-12 the resonant cam harmonics change
#: by under 5 % from rtol 1e-11 and match the SciPy reference model's (docs/gallery.md)
RESONANCE_TOLERANCES = {"rtol": 1e-12, "atol": 1e-14}
#: the contact resonance is sought among the cam harmonics within this fraction of the
#: linearized natural frequency [-]
RESONANCE_BAND = 0.3
#: the file each figure is written to
NAMES = {"2.4": "fig2_4_residual_damping_models.png", "2.7": "fig2_7_8_energy_balance.png",
         "2.9": "fig2_9_regime_map.png", "2.10": "fig2_10_11_direction.png",
         "2.14": "fig2_14_15_oscillating_cam.png", "2.16": "fig2_16_linear_vs_nonlinear.png"}
ALPHA_DDOT = axis_label(r"$|\ddot\alpha|$", "rad/s^2")
RPM = axis_label(r"$\Omega$", "rpm")
HZ = axis_label("$f$", "Hz")


def _rounded(values) -> list:
    """Numbers as recorded: a list of floats to 6 significant digits, None where not finite
    (a sweep point whose simulation failed)."""
    return [float(f"{v:.6g}") if np.isfinite(v) else None for v in np.asarray(values, dtype=float)]


def _failures(ax, x, failed, color) -> None:
    """Crosses on the x axis at the sweep points whose simulation failed (no value)."""
    failed = np.asarray(failed, dtype=bool)
    if failed.any():
        ax.plot(np.asarray(x)[failed], np.zeros(failed.sum()), "x", color=color, ms=5, mew=1.0)


def recorded(data: dict) -> dict:
    """The part of a figure's data recorded in figures.json: everything but numpy arrays."""
    return {k: recorded(v) if isinstance(v, dict) else v for k, v in data.items() if not isinstance(v, np.ndarray)}


def speed_sweep(source, overrides, start, stop, num, name, revolutions=120, discard=80, work=None, workers=None):
    """A sweep over the cam speed (``start`` and ``stop`` as text: "100 rpm") of residual,
    regime and impacts, written under ``work`` (default: a new temporary folder)."""
    work = Path(work or tempfile.mkdtemp(prefix="camdyn-gallery-"))
    spec = spec_from_dict({"system": {"source": source, "set": overrides},
                           "vary": [{"key": "motion.speed", "start": start, "stop": stop, "num": num}],
                           "run": {"revolutions": revolutions, "discard": discard, **TOLERANCES},
                           "metrics": {"names": ["residual", "regime", "impacts"]},
                           "output": {"path": str(work / f"{name}.nc")}}, name=name)
    return run_sweep(spec, workers=workers, progress=False).load()


# --- fig 2.4 -----------------------------------------------------------------------------


def data_2_4(speeds: int = 36) -> dict:
    """Residual rms and peak-to-peak [deg] against speed [rpm] for damping models A-E."""
    models = {}
    for law, overrides in MODELS.items():
        ds = speed_sweep(IMPACTING, overrides, "100 rpm", "170 rpm", speeds, f"fig2_4_{law}")
        rpm = ds["motion.speed"].values * 60
        irregular = rpm[ds.regime.values == 3]
        models[law] = {"residual_rms_deg": _rounded(np.degrees(ds.residual_rms.values)),
                       "residual_peak_to_peak_deg": _rounded(np.degrees(ds.residual_peak_to_peak.values)),
                       "irregular": [bool(v) for v in ds.regime.values == 3],
                       "failed": [bool(v) for v in ds.status.values != 0]}
        print(f"  model {law}: irregular impacts at {len(irregular)} of {speeds} speeds"
              + (f", first at {irregular.min():.0f} rpm" if len(irregular) else ""))
    loss = 60 * loss_of_contact_speed(camdyn.load_system(IMPACTING))
    return {"speed_rpm": _rounded(rpm), "loss_of_contact_rpm": round(loss, 2), "models": models}


@styled
def draw_2_4(data: dict, path) -> Path:
    """Thesis fig 2.4: residual rms and peak-to-peak [deg] against speed [rpm], models A-E;
    irregular impacts (no period up to 16 revolutions) as open markers."""
    fig, axes = plt.subplots(2, 1, figsize=(8.0, 6.0), sharex=True)
    rpm = np.asarray(data["speed_rpm"])
    for i, (law, model) in enumerate(data["models"].items()):
        irregular = np.asarray(model["irregular"], dtype=bool)
        for ax, key in zip(axes, ("residual_rms_deg", "residual_peak_to_peak_deg")):
            values = np.asarray(model[key], dtype=float)
            ax.plot(rpm, values, "-", color=f"C{i}", lw=0.8, label=f"model {law}")
            ax.plot(rpm[~irregular], values[~irregular], "o", color=f"C{i}", ms=3, mew=0)
            ax.plot(rpm[irregular], values[irregular], "o", mfc="white", mec=f"C{i}", ms=4.5, mew=0.9)
            _failures(ax, rpm, model["failed"], f"C{i}")
    for ax in axes:
        ax.axvline(data["loss_of_contact_rpm"], color="k", ls="--", lw=0.8,
                   label=f"loss of contact ({data['loss_of_contact_rpm']:.0f} rpm, inverse kinematics)")
        tidy_axis(ax.yaxis, 5)
    axes[1].plot([], [], "o", mfc="white", mec="0.3", ms=4.5, mew=0.9, label="irregular impacts")
    if any(any(model["failed"]) for model in data["models"].values()):
        axes[1].plot([], [], "x", color="0.3", ms=5, mew=1.0, label="simulation failed")
    axes[0].set_ylabel(axis_label(r"$\alpha_r$ rms", "deg"))
    axes[1].set_ylabel(axis_label(r"$\alpha_r$ p-p", "deg"))
    axes[1].set_xlabel(RPM)
    tidy_axis(axes[1].xaxis, 8)
    legend_below(fig, axes[1], 4)
    fig.align_ylabels(axes)
    fig.suptitle("fig 2.4: residual response $\\alpha_r$, damping models A-E (impacting stand-in)")
    return save_figure(fig, path)


# --- figs 2.7 and 2.8 --------------------------------------------------------------------

#: the two panels: first and last speed [rpm], number of speeds, restitutions xi [-]
PANELS_2_7_8 = ((20, 160, 36, (0.05, 0.2, 0.4, 0.6)), (100, 900, 41, (0.2, 0.6, 1.0)))


def energy_balance_curves(start: float, stop: float, xis, points: int = 60) -> dict:
    """Energy-balance residual [deg] (eqs 2.30-2.33) from ``start`` to ``stop`` [rpm]."""
    system = camdyn.load_system(IMPACTING, MODELS["D"])
    rpm = np.linspace(start, stop, points)
    return {"speed_rpm": _rounded(rpm),
            "residual_deg": {f"{xi:g}": _rounded(np.degrees(energy_balance_residual(system, rpm / 60, xi)))
                             for xi in xis}}


def data_2_7_8() -> dict:
    """Contact model (law D) against the energy-balance estimate: peak-to-peak residual
    [deg] against speed [rpm], at low speeds (fig 2.7) and over a broad range (fig 2.8)."""
    system = camdyn.load_system(IMPACTING, MODELS["D"])
    panels = []
    for start, stop, num, xis in PANELS_2_7_8:
        ds = speed_sweep(IMPACTING, MODELS["D"], f"{start} rpm", f"{stop} rpm", num, f"fig2_8_{start}")
        rpm = ds["motion.speed"].values * 60
        contact = np.degrees(ds.residual_peak_to_peak.values)   # NaN where the simulation failed
        panels.append({"speed_rpm": _rounded(rpm), "contact_model_deg": _rounded(contact),
                       "failed": [bool(v) for v in ds.status.values != 0],
                       "energy_balance": energy_balance_curves(start, stop, xis)})
        if start == 20:
            below = rpm < 125
            gaps = {xi: np.nanmax(np.abs(np.degrees(energy_balance_residual(system, rpm[below] / 60, xi))
                                      - contact[below])) for xi in xis}
            print("  below 125 rpm, largest gap energy balance - contact model [deg]: "
                  + ", ".join(f"xi {k:g}: {v:.3g}" for k, v in gaps.items()))
    return {"panels": panels}


@styled
def draw_2_7_8(data: dict, path) -> Path:
    """Thesis figs 2.7 and 2.8: peak-to-peak residual [deg] of the contact model against
    the energy-balance estimate for several restitutions xi, against speed [rpm]."""
    fig, axes = plt.subplots(1, 2, figsize=(10.5, 4.2))
    titles = ("fig 2.7: low speeds", "fig 2.8: broad range")
    for ax, panel, title in zip(axes, data["panels"], titles):
        contact = np.asarray(panel["contact_model_deg"], dtype=float)
        ax.plot(panel["speed_rpm"], contact, "k.-", ms=4, lw=0.8, label="contact model (law D)")
        if any(panel["failed"]):
            _failures(ax, panel["speed_rpm"], panel["failed"], "k")
            ax.plot([], [], "kx", ms=5, mew=1.0, label="contact model: simulation failed")
        curves = panel["energy_balance"]
        for i, (xi, values) in enumerate(curves["residual_deg"].items()):
            ax.plot(curves["speed_rpm"], values, color=f"C{i}", label=rf"energy balance, $\xi$ = {xi}")
        ax.set_xlabel(RPM)
        ax.set_ylabel(axis_label(r"$\alpha_r$ p-p", "deg"))
        ax.set_title(title)
        ax.legend(loc="upper left")
        tidy_axis(ax.xaxis, 8)
        tidy_axis(ax.yaxis, 6)
    fig.suptitle("energy-balance restitution estimate against the contact model (impacting stand-in)")
    return save_figure(fig, path)


# --- fig 2.9 -----------------------------------------------------------------------------


def fig_2_9(path) -> None:
    """Contact regimes over spring stiffness and speed (fig 2.9), drawn by camdyn.plotting."""
    work = Path(tempfile.mkdtemp(prefix="camdyn-gallery-"))
    spec = spec_from_dict({"system": {"source": IMPACTING},
                           "vary": [{"key": "spring.stiffness", "start": "500 N/m", "stop": "5000 N/m", "num": 10},
                                    {"key": "motion.speed", "start": "40 rpm", "stop": "260 rpm", "num": 23}],
                           "run": {"revolutions": 40, "discard": 20, **TOLERANCES},
                           "metrics": {"names": ["regime", "impacts", "residual"]},
                           "output": {"path": str(work / "fig2_9.nc")}}, name="fig2_9")
    ds = regime_map(spec, progress=False)
    plot_regime_map(ds, path)
    print(f"  simulation agrees with inverse kinematics at {ds.attrs['agreement_kept_agree']}/"
          f"{ds.attrs['agreement_kept']} points in contact and {ds.attrs['agreement_lost_agree']}/"
          f"{ds.attrs['agreement_lost']} beyond; loss of contact at ks = 2000 N/m: "
          f"{float(ds.loss_of_contact_speed.interp({'spring.stiffness': 2000.0})) * 60:.0f} rpm")


# --- figs 2.10 and 2.11 ------------------------------------------------------------------


def data_2_10_11() -> dict:
    """Spectra of alpha_ddot [rad/s^2] and Fn [N] over one revolution, de- and
    self-energizing rotation with line contact, and point contact (figs 2.10, 2.11).
    Runs at :data:`RESONANCE_TOLERANCES`; each run's contact resonance is its largest cam
    harmonic near the linearized natural frequency (:func:`resonant_harmonic`)."""
    base = camdyn.load_system(SLIDING)
    runs = {}
    for label, direction, kind in (("+300 rpm, line contact", 1, "line"), ("−300 rpm, line contact", -1, "line"),
                                   ("+300 rpm, point contact", 1, "point")):
        system = base.with_values(**FIG_2_10, **{"motion.direction": direction, "contact.kind": kind})
        ds = camdyn.simulate(system, speed=5.0, revolutions=10, sample_rate=20e3, **RESONANCE_TOLERANCES)
        natural = spectrum_summary(ds, window=8, peaks=1)["natural_frequency_hz"]
        f, a = amplitude_spectrum(ds, "alpha_ddot", 8)
        peak, level, noise = resonant_harmonic(f, a, 5.0, natural)
        win = ds.isel(time=slice(-4001, None))
        runs[label] = {"peak_hz": round(peak, 1), "natural_hz": round(natural, 1),
                       "mean_Fn_N": round(float(win.Fn.mean()), 4), "frequency_hz": f, "amplitude": a,
                       "revolution": ((win.time - win.time[0]) * 5.0).values, "Fn": win.Fn.values}
        print(f"  {label}: mean Fn {runs[label]['mean_Fn_N']:.3f} N, resonant cam harmonic {peak:.0f} Hz "
              f"(linearized {natural:.0f} Hz), {level:.3g} rad/s^2 against {noise:.2g} between the harmonics")
    return {"speed_rpm": 300.0, "runs": runs}


def resonant_harmonic(freq, amp, speed: float, natural: float, band: float = RESONANCE_BAND):
    """The contact resonance in the spectrum ``freq`` [Hz], ``amp`` of a run in steady
    contact at ``speed`` [Hz]: the largest cam harmonic within ``band`` of the linearized
    natural frequency ``natural`` [Hz]. The steady response is periodic, so the resonance
    shows as the cam harmonics it amplifies; what lies between them is integration error
    (or round-off) and does not count.

    Returns
    -------
    (frequency [Hz], its amplitude, the largest amplitude between harmonics in the band),
    amplitudes in the unit of ``amp``.
    """
    orders = np.arange(math.ceil((1 - band) * natural / speed), math.floor((1 + band) * natural / speed) + 1)
    levels = np.interp(orders * speed, freq, amp)
    offset = np.abs(freq / speed - np.round(freq / speed))
    between = (freq >= orders[0] * speed) & (freq <= orders[-1] * speed) & (offset >= 0.25)
    best = int(np.argmax(levels))
    return float(orders[best] * speed), float(levels[best]), float(amp[between].max())


@styled
def draw_2_10_11(data: dict, path) -> Path:
    """Thesis figs 2.10 and 2.11: spectra of alpha_ddot [rad/s^2] (cam harmonics; contact
    resonance, peaks marked) and the normal force Fn [N] over one cam revolution."""
    fig, axes = plt.subplots(1, 3, figsize=(12.0, 4.2))
    for i, (label, run) in enumerate(data["runs"].items()):
        f, a = run["frequency_hz"], run["amplitude"]
        axes[0].semilogy(f, a, lw=0.8, color=f"C{i}")
        axes[1].semilogy(f, a, lw=0.6, color=f"C{i}", label=f"{label} (peak {run['peak_hz']:.0f} Hz)")
        axes[1].plot(run["peak_hz"], np.interp(run["peak_hz"], f, a) * 3, "v", color=f"C{i}", ms=6)
        axes[2].plot(run["revolution"], run["Fn"], color=f"C{i}")
    axes[0].set_xlim(0, 60)
    axes[1].set_xlim(300, 2200)
    for ax in axes[:2]:
        ax.set_xlabel(HZ)
        ax.set_ylabel(ALPHA_DDOT)
        tidy_axis(ax.xaxis, 6)
    axes[2].set_xlabel(axis_label(r"$\Theta$", "rev"))
    axes[2].set_ylabel(axis_label("$F_n$", "N"))
    tidy_axis(axes[2].xaxis, 5)
    axes[0].set_title("fig 2.10a: cam harmonics")
    axes[1].set_title("fig 2.10b: resonant cam harmonics ▼")
    axes[2].set_title("fig 2.11: normal force over a revolution")
    legend_below(fig, axes[1], 3)
    fig.suptitle("friction direction and contact model, sliding stand-in at 300 rpm")
    return save_figure(fig, path)


# --- figs 2.14 and 2.15 ------------------------------------------------------------------


def data_2_14_15() -> dict:
    """Oscillating cam (swing 180 deg peak to peak, 40 rpm, e = 0.7 rc): sliding velocity
    [m/s], friction force Ff and pivot reaction Nx [N] over one oscillation, Coulomb and
    tanh friction (figs 2.14, 2.15)."""
    rig = camdyn.load_system(SLIDING)
    e = 0.7 * rig.cam.semi_major
    system = rig.with_values(**{"cam.runout": e, "cam.pivot_y": 0.5 * rig.follower.width + rig.cam.semi_major + e,
                                "spring.free_length": 0.085, "motion.kind": "oscillating",
                                "motion.amplitude": math.pi, "motion.frequency": 40 / 60})
    laws = {}
    for law in ("coulomb", "tanh"):
        ds = camdyn.simulate(system.with_values(**{"friction.law": law}), revolutions=2,
                             sample_rate=10e3)
        win = ds.isel(time=slice(ds.sizes["time"] // 2, None))
        positive = float((win.sliding_velocity > 0).mean())
        laws[law] = {"vr_positive_fraction": round(positive, 4), "Ff_range_N": _rounded([win.Ff.min(), win.Ff.max()]),
                     "period": ((win.time - win.time[0]) * 40 / 60).values,
                     **{var: win[var].values for var in ("sliding_velocity", "Ff", "Nx")}}
        print(f"  {law}: vr > 0 for {positive * 100:.0f} % of the cycle, "
              f"Ff from {float(win.Ff.min()):.2f} to {float(win.Ff.max()):.2f} N")
    return {"swing_deg": 180.0, "frequency_rpm": 40.0, "runout_ratio": 0.7,
            "smoothing_s_per_m": system.friction.smoothing, "laws": laws}


@styled
def draw_2_14_15(data: dict, path) -> Path:
    """Thesis figs 2.14 and 2.15: sliding velocity vr [m/s], friction force Ff [N] and
    pivot reaction Nx [N] over one oscillation of the cam, Coulomb against tanh friction."""
    fig, axes = plt.subplots(3, 1, figsize=(7.5, 6.5), sharex=True)
    names = {"coulomb": "Coulomb", "tanh": rf"tanh, $\sigma$ = {data['smoothing_s_per_m']:g} s/m"}
    for i, (law, run) in enumerate(data["laws"].items()):
        for ax, var in zip(axes, ("sliding_velocity", "Ff", "Nx")):
            ax.plot(run["period"], run[var], color=f"C{i}", label=names[law])
    for ax, symbol, unit in zip(axes, ("$v_r$", "$F_f$", "$N_x$"), ("m/s", "N", "N")):
        ax.set_ylabel(axis_label(symbol, unit))
        ax.axhline(0.0, color="k", lw=0.5)
        tidy_axis(ax.yaxis, 5)
    axes[-1].set_xlabel(axis_label("$t f_o$", "-"))
    tidy_axis(axes[-1].xaxis, 8)
    axes[0].legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.align_ylabels(axes)
    fig.suptitle(rf"figs 2.14-2.15: oscillating cam, $\Theta_p$ = {data['swing_deg']:g}°, "
                 rf"$f_o$ = {data['frequency_rpm']:g} rpm, $e$ = {data['runout_ratio']:g} $r_c$")
    return save_figure(fig, path)


# --- fig 2.16 ----------------------------------------------------------------------------


def data_2_16() -> dict:
    """Spectra of alpha_ddot [rad/s^2], linearized (eqs 2.36-2.38) against nonlinear model,
    sliding stand-in at 300 rpm (fig 2.16), at :data:`RESONANCE_TOLERANCES` as figs
    2.10-2.11 (at the default rtol 1e-8 the band near the natural frequency is integration
    error, over 100 times the resonant harmonics)."""
    system = camdyn.load_system(SLIDING).with_values(**FIG_2_10)
    nonlinear = camdyn.simulate(system, speed=5.0, revolutions=10, sample_rate=20e3, **RESONANCE_TOLERANCES)
    model = linearize(system, 5.0)
    linear = model.simulate(nonlinear.time.values, x0=float(nonlinear.alpha[0]) - model.equilibrium_angle)
    linear.attrs["speed_hz"] = 5.0
    spectra = {label: amplitude_spectrum(ds, "alpha_ddot", 8)
               for label, ds in (("nonlinear", nonlinear), ("linearized", linear))}
    hn = harmonic_amplitudes(nonlinear, orders=(1, 2, 3), revolutions=8)
    hl = harmonic_amplitudes(linear, orders=(1, 2, 3), revolutions=8, speed=5.0)
    print(f"  harmonics 1-3 of alpha_ddot: nonlinear {np.round(hn, 4)}, linear {np.round(hl, 4)} rad/s^2")
    return {"natural_hz": round(float(model.natural_frequency), 1),
            "harmonics_rad_s2": {"nonlinear": _rounded(hn), "linearized": _rounded(hl)},
            **{f"{label}_{k}": v for label, (f, a) in spectra.items() for k, v in (("hz", f), ("amplitude", a))}}


@styled
def draw_2_16(data: dict, path) -> Path:
    """Thesis fig 2.16: spectra of alpha_ddot [rad/s^2] of the nonlinear and the linearized
    model, cam harmonics and near the natural frequency."""
    fig, axes = plt.subplots(1, 2, figsize=(10.5, 4.0))
    fn = data["natural_hz"]
    for i, label in enumerate(("nonlinear", "linearized")):
        for ax in axes:
            ax.semilogy(data[f"{label}_hz"], np.maximum(data[f"{label}_amplitude"], 1e-300), lw=0.8, color=f"C{i}",
                        label=label + (" (eqs 2.36-2.38)" if label == "linearized" else ""))
    axes[0].set_xlim(0, 60)
    axes[1].set_xlim(fn - 300, fn + 300)
    axes[1].axvline(fn, color="C3", ls="--", lw=0.8, label=f"linearized $f_n$ = {fn:.0f} Hz")
    for ax in axes:
        ax.set_ylim(1e-11, None)   # the linearized model's spectrum falls to the rounding error off its lines
        ax.set_yticks([10.0 ** k for k in range(-10, 3, 2)])   # none below the axis, by the x labels
        ax.set_xlabel(HZ)
        ax.set_ylabel(ALPHA_DDOT)
        tidy_axis(ax.xaxis, 7)
    axes[0].set_title("fig 2.16a: the linear model has no super-harmonics")
    axes[1].set_title("fig 2.16b: near the natural frequency")
    legend_below(fig, axes[1], 3)
    fig.suptitle("linearized against nonlinear model, sliding stand-in at 300 rpm")
    return save_figure(fig, path)


#: figure key -> (data function, draw function)
FIGURES = {"2.4": (data_2_4, draw_2_4), "2.7": (data_2_7_8, draw_2_7_8), "2.10": (data_2_10_11, draw_2_10_11),
           "2.14": (data_2_14_15, draw_2_14_15), "2.16": (data_2_16, draw_2_16)}


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("figures", nargs="*", metavar="FIGURE",
                        help=f"figures to make: {', '.join(NAMES)} (default: all)")
    parser.add_argument("--data", type=Path, help="write the numbers each figure shows to this JSON file")
    args = parser.parse_args(argv)
    unknown = sorted(set(args.figures) - set(NAMES))
    if unknown:
        parser.error(f"unknown figure {', '.join(unknown)}; choose from {', '.join(NAMES)}")
    OUT.mkdir(parents=True, exist_ok=True)
    numbers = {}
    for key in args.figures or NAMES:
        if key == "2.9":
            print(f"fig {key}: {fig_2_9.__doc__.splitlines()[0]}", flush=True)
            fig_2_9(OUT / NAMES[key])
            continue
        compute, draw = FIGURES[key]
        print(f"fig {key}: {compute.__doc__.splitlines()[0]}", flush=True)
        data = compute()
        draw(data, OUT / NAMES[key])
        numbers[NAMES[key]] = recorded(data)
    if args.data:
        args.data.write_text(json.dumps(numbers, indent=1) + "\n")


if __name__ == "__main__":
    main()
