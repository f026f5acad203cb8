"""The demonstration run by ``camdyn demo`` (and ``make demo``).

1. Chapter 4 friction rig (preset ``sundar2014-friction``, at the thesis's chapter 4
   0-state, eqs 4.3-4.4): static equilibrium, natural frequency beside the thesis's
   1040 Hz (section 4.5.1), the loss-of-contact speed at e/a = 0.1, and the first two cam
   harmonics of the follower acceleration for e/a = 0.05 to 0.30 at 11.55 Hz, beside the
   thesis's table 4.5 (docs/thesis-comparison.md explains the differences). The runs
   start on the permanent-contact motion (``contact_start``): from rest at that 0-state
   the e/a = 0.25 and 0.30 runs would stay on an impacting motion.
2. Chapter 3 impact rig (preset ``sundar2014-impact``) at e/rc = 0.2 and 16 Hz:
   periodic impacts and the impact table.
Figures and results go to the output folder (about 80 MB, most of it the impact rig's
netCDF result at 204.8 kHz); existing files there are kept unless ``--force``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from rich.console import Console
from rich.table import Table

from camdyn.analysis.harmonics import harmonic_amplitudes
from camdyn.analysis.kinematics import contact_start, loss_of_contact_speed
from camdyn.cli.outputs import check_outputs, file_entry, human_size
from camdyn.io.atomic import check_writable, write_text
from camdyn.io.netcdf import save_netcdf
from camdyn.model.equilibrium import static_equilibrium
from camdyn.params.config import load_system
from camdyn.plotting import plot_spectrum, plot_time_history
from camdyn.simulation.runner import simulate

#: Display copy of the thesis's table 4.5 (section 4.8): e/a -> (first, second harmonic of
#: alpha_ddot [rad/s^2]) at 11.55 Hz.
TABLE_4_5 = {0.05: (52.5, 1.01), 0.10: (105.0, 4.02), 0.15: (157.5, 9.05), 0.20: (210.0, 16.1),
             0.25: (262.5, 25.1), 0.30: (315.1, 36.2)}
#: The thesis's linearized natural frequency of the chapter 4 rig [Hz] (section 4.5.1).
THESIS_NATURAL_FREQUENCY = 1040.0
#: The thesis's DC pivot forces (Nx, Ny) [N] at e/a = 0.3, 11.55 Hz (section 4.6).
THESIS_DC_FORCES = (-2.26, -12.7)
#: The files the demonstration writes into its folder.
DEMO_FILES = ("friction_rig.nc", "friction_rig_time.png", "friction_rig_spectrum.png", "impact_rig.nc",
              "impact_rig_time.png", "friction_record.csv", "contact_conditions.png", "impact_hysteresis.png",
              "demo.json")
#: About how much the demonstration writes [B] (most of it ``impact_rig.nc``).
DEMO_BYTES = 80_000_000


def check_demo_outputs(out: Path, force: bool = False) -> None:
    """Refuse, before any work, a folder that cannot take the demonstration's files: one
    of them exists (unless ``force``), the folder cannot be written, or its disk lacks
    :data:`DEMO_BYTES`."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        from camdyn.errors import OutputError
        raise OutputError(f"cannot write into {out}: it is a file, not a folder")
    check_outputs(others=[out / name for name in DEMO_FILES], force=force)
    check_writable(out / DEMO_FILES[0], DEMO_BYTES)


def run_demo(out: Path, console: Console | None = None) -> dict:
    """Run the demonstration; return its key numbers (also written as JSON)."""
    console = console or Console()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    console.print(f"the demonstration writes about {human_size(DEMO_BYTES)} into {out}/ (two simulation "
                  f"results, a record, figures)", markup=False, highlight=False, soft_wrap=True)
    results: dict = {}

    friction = load_system("sundar2014-friction")
    eq = static_equilibrium(friction)
    console.print(f"[bold]Chapter 4 rig[/bold] ({friction.citation})")
    loss = loss_of_contact_speed(friction)
    console.print(f"  0-state: {friction.motion.zero_state} (thesis eqs 4.3-4.4), Theta0 = "
                  f"{math.degrees(eq.cam_angle):.3f} deg; static equilibrium alpha* = "
                  f"{math.degrees(eq.angle):.4f} deg, contact force {eq.contact_force:.3f} N, "
                  f"linearized natural frequency {eq.natural_frequency:.1f} Hz "
                  f"(thesis: {THESIS_NATURAL_FREQUENCY:.0f} Hz, "
                  f"{100 * (eq.natural_frequency / THESIS_NATURAL_FREQUENCY - 1):+.1f} %)")
    console.print(f"  contact is lost above {loss:.2f} Hz at e/a = {friction.cam.runout / friction.cam.semi_major:.2f} "
                  f"(inverse kinematics; the thesis's table 4.6 keeps contact at 21 Hz)")
    variant = load_system("sundar2014-friction-ch3frame")
    eq3 = static_equilibrium(variant)
    console.print(f"  HYPOTHESIS without textual support, preset {variant.name} (chapter 3's PE and dy): "
                  f"natural frequency {eq3.natural_frequency:.1f} Hz, contact lost above "
                  f"{loss_of_contact_speed(variant):.2f} Hz (docs/thesis-comparison.md)")
    table = Table("e/a", "1st harmonic [rad/s^2]", "thesis", "diff", "2nd harmonic", "thesis", "diff",
                  title="alpha_ddot at 11.55 Hz (thesis table 4.5)")
    rows = []
    for ratio, (h1_ref, h2_ref) in TABLE_4_5.items():
        system = friction.with_values(**{"cam.runout": ratio * friction.cam.semi_major})
        ds = simulate(system, speed=11.55, revolutions=20, sample_rate=20e3,
                      initial_state=contact_start(system, 11.55))
        h1, h2 = harmonic_amplitudes(ds, "alpha_ddot", (1, 2), revolutions=10)
        rows.append({"e_over_a": ratio, "harmonic1": h1, "harmonic2": h2, "thesis1": h1_ref, "thesis2": h2_ref})
        table.add_row(f"{ratio:.2f}", f"{h1:.1f}", f"{h1_ref:.1f}", f"{100 * (h1 / h1_ref - 1):+.1f} %",
                      f"{h2:.2f}", f"{h2_ref:.2f}", f"{100 * (h2 / h2_ref - 1):+.1f} %")
        if abs(ratio - 0.1) < 1e-9:
            save_netcdf(ds, out / "friction_rig.nc")
            plot_time_history(ds, out / "friction_rig_time.png")
            plot_spectrum(ds, out / "friction_rig_spectrum.png")
            results["friction_rig_solver"] = {k[7:]: v for k, v in ds.attrs.items() if k.startswith("solver_")}
            results["friction_rig_elapsed_s"] = ds.attrs["elapsed_s"]
    console.print(table)
    results["table_4_5"] = rows
    results["friction_rig_equilibrium"] = {"zero_state": friction.motion.zero_state,
                                           "cam_angle_deg": math.degrees(eq.cam_angle),
                                           "angle_deg": math.degrees(eq.angle), "contact_force_N": eq.contact_force,
                                           "natural_frequency_Hz": eq.natural_frequency,
                                           "thesis_natural_frequency_Hz": THESIS_NATURAL_FREQUENCY,
                                           "loss_of_contact_speed_Hz": loss}

    impact = load_system("sundar2014-impact")
    ds = simulate(impact, speed=16.0, revolutions=40, sample_rate=204.8e3)
    n_imp = ds.sizes["impact"]
    last = {k: float(ds[f"impact_{k}"][-1]) for k in ("approach_velocity", "separation_velocity",
                                                     "peak_penetration", "peak_force", "duration")}
    console.print(f"[bold]Chapter 3 rig[/bold] at e/rc = 0.2, 16 Hz: {n_imp} impacts in 40 revolutions; last impact: "
                  f"approach {last['approach_velocity']:.4f} m/s, separation {last['separation_velocity']:.4f} m/s "
                  f"(e = {last['separation_velocity'] / last['approach_velocity']:.3f}), peak penetration "
                  f"{last['peak_penetration'] * 1e6:.2f} um, peak force {last['peak_force']:.0f} N, "
                  f"contact {last['duration'] * 1e3:.3f} ms; solved in {ds.attrs['elapsed_s'] * 1e3:.1f} ms")
    save_netcdf(ds, out / "impact_rig.nc")
    plot_time_history(ds, out / "impact_rig_time.png", revolutions=2)
    results["impact_rig"] = {"impacts": n_imp, "revolutions": 40, "last_impact": last,
                             "elapsed_s": ds.attrs["elapsed_s"]}
    results["friction_identification"] = _friction_demo(out, console)
    results["impact_identification"] = _impact_demo(out, console)
    write_text(out / "demo.json", json.dumps(results, indent=2))
    _announce_files(out, console)
    return results


def _announce_files(out: Path, console: Console) -> None:
    """One line: the files written, their sizes and the total."""
    entries = [file_entry(out / name) for name in DEMO_FILES if (out / name).is_file()]
    total = sum(e["bytes"] for e in entries)
    listing = ", ".join(f"{Path(e['path']).name} ({human_size(e['bytes'])})" for e in entries)
    console.print(f"wrote {len(entries)} files, {human_size(total)} in total, into {out}/: {listing}",
                  markup=False, highlight=False, soft_wrap=True)


def _friction_demo(out: Path, console: Console) -> dict:
    """The thesis's validation case (4.6): a simulated record with 1 % noise, mu back."""
    from camdyn.identification.friction import estimate_friction
    from camdyn.io.measurements import write_measurement
    from camdyn.plotting import plot_contact_conditions
    from camdyn.records.synthesis import synthesize
    from camdyn.tribology import contact_conditions

    system = load_system("sundar2014-friction", {"cam.runout": "5.25 mm"})
    clean = synthesize(system, 11.55, revolutions=10, sample_rate=9460.0)
    exact = estimate_friction(system, clean)
    true_dc = (float(clean["Nx"].mean()), float(clean["Ny"].mean()))
    record = synthesize(system, 11.55, revolutions=30, sample_rate=9460.0, noise=0.01)
    write_measurement(record, out / "friction_record.csv")
    est = estimate_friction(system, record)
    cc = contact_conditions(system, 11.55, "agma-4ep", "ground")
    plot_contact_conditions(cc, out / "contact_conditions.png")
    console.print(f"[bold]Friction identification[/bold] (e/a = 0.3, 11.55 Hz, 9460 Hz, true mu = 0.3): "
                  f"thesis validation case (10 revolutions) mu = {exact.mu:.5f} "
                  f"(error {100 * abs(exact.mu - 0.3) / 0.3:.3f} %; thesis 0.302, 0.7 %); with 1 % noise, "
                  f"30 revolutions: mu = {est.mu:.4f} (error {100 * abs(est.mu - 0.3) / 0.3:.2f} %), "
                  f"Nx_dc = {est.Nx_dc:.3f} N, Ny_dc = {est.Ny_dc:.3f} N (true {true_dc[0]:.3f}, {true_dc[1]:.3f} N; "
                  f"the thesis's model: {THESIS_DC_FORCES[0]}, {THESIS_DC_FORCES[1]} N); Hertz peak pressure "
                  f"{cc['peak_pressure'].max().item() / 1e9:.2f} GPa, lambda (AGMA 4EP, ground) "
                  f"{float(cc['lambda_ratio'].min()):.3f}-{float(cc['lambda_ratio'].max()):.3f}")
    return {"mu_validation_case": exact.mu, "mu": est.mu, "mu_true": 0.3, "Nx_dc_N": est.Nx_dc, "Ny_dc_N": est.Ny_dc,
            "Nx_dc_true_N": true_dc[0], "Ny_dc_true_N": true_dc[1], "thesis_dc_N": list(THESIS_DC_FORCES),
            "checks_passed": est.accepted}


def _impact_demo(out: Path, console: Console) -> dict:
    """Thesis 3.5-3.8 on a simulated record: beta with n = 1.5 fixed, and n free."""
    from camdyn.identification.impact_damping import estimate_impact_damping
    from camdyn.identification.impact_events import impact_events
    from camdyn.plotting import plot_impact_fit
    from camdyn.records.synthesis import synthesize

    system = load_system("sundar2014-impact", {"cam.runout": "3.5 mm"})
    record = synthesize(system, 15.0, revolutions=21, sample_rate=204.8e3, noise=0.01, settle=100)
    events = impact_events(system, record)
    fixed = estimate_impact_damping(system, None, events=[events], exponent=1.5, bootstrap=32)
    free = estimate_impact_damping(system, None, events=[events], bootstrap=32)
    plot_impact_fit(free, out / "impact_hysteresis.png")
    truth = system.contact.beta * free.peak_penetration ** 1.5
    console.print(f"[bold]Impact damping[/bold] (e/rc = 0.2, 15 Hz, 204.8 kHz, 1 % noise, {events.count} impacts, "
                  f"true beta = 24.7 GN s/m^2.5, n = 1.5): n fixed -> beta = {fixed.beta / 1e9:.3f} GN s/m^2.5 "
                  f"({100 * (fixed.beta / system.contact.beta - 1):+.2f} %); n free -> n = {free.exponent:.4f}, "
                  f"damping at the peak penetration {free.peak_penetration * 1e6:.1f} um = "
                  f"{free.damping_at_peak:.0f} N s/m ({100 * (free.damping_at_peak / truth - 1):+.2f} %)")
    return {"beta_n_fixed": fixed.beta, "n_free": free.exponent, "beta_n_free": free.beta,
            "damping_at_peak_N_s_per_m": free.damping_at_peak, "peak_penetration_m": free.peak_penetration}
