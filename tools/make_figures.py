"""Regenerate the figures of the README and the docs (docs/figures/) from the current code,
and write docs/figures/figures.json: for every figure, the command that makes it, the key
numbers it shows and the SHA-256 of the PNG written with them.

Run:  make figures                     (about 6 minutes on 2 cores)
      python tools/make_figures.py [--only JOB ...] [--slow] [--list]

Jobs (default: all but the slow ones):

- ``demo``: ``camdyn demo`` -> impact_rig_time.png, friction_rig_spectrum.png;
- ``sweeps``: ``camdyn sweep examples/sweeps/bifurcation.toml`` and ``regime_map.toml`` ->
  sweep_bifurcation.png, sweep_regime_map.png;
- ``fig2_9``: ``python examples/chapter2_gallery.py 2.9`` -> fig2_9_regime_map.png;
- ``tribology``: ``python examples/tribology_design.py`` -> design maps, contact
  conditions, Benedict-Kelley;
- ``restitution``: ``python examples/restitution_laws.py`` -> restitution_laws.png;
- ``mechanisms``: ``python examples/mechanisms.py`` -> mechanisms_speed_fluctuation.png,
  stick_slip_cycle.png;
- ``siconos``: ``python examples/siconos_comparison.py`` -> siconos_camfollower.png (from
  tests/data/siconos_camfollower.json);
- ``flexible_pivot``: ``python examples/flexible_pivot.py`` -> flexible_pivot_resonance.png;
- ``two_followers``: ``python examples/two_followers.py`` -> two_followers_stick_slip.png;
- ``driven_cam``: ``python examples/driven_cam_orbits.py`` -> driven_cam_doubling.png;
- slow (``--slow``, about 26 minutes more): ``friction_tables``, ``impact_tables``,
  ``gallery`` (the rest of chapter 2) and ``translating`` (the bifurcation diagram of the
  translating follower's rig, translating_bifurcation.png). The first three also rewrite
  their tables in docs/.

``tribology``, ``friction_tables`` and ``gallery`` record the numbers their figures show
(``--data``), and restitution_laws.py writes its curves to docs/figures/restitution_laws.json;
tests/test_figures.py draws those figures again from these numbers to check their layout.

tests/test_figures.py recomputes some of the numbers with the current code and checks
the PNGs against their recorded hashes, so a figure that no longer matches the code, or a
PNG changed without this script, fails the tests.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FIGURES = ROOT / "docs" / "figures"
RECORD = FIGURES / "figures.json"
#: the command (as a user types it) that makes each committed figure
SOURCES = {
    "impact_rig_time.png": "camdyn demo --out DIR",
    "impact_methods_comparison.png": "python benchmarks/compare_impact_methods.py --figure FILE",
    "continuation_harmonic_balance.png": "camdyn continue sundar2014-friction --set cam.runout=0.875mm --method "
                                         "harmonic-balance --from 5Hz --to 25Hz --plot FILE",
    "friction_rig_spectrum.png": "camdyn demo --out DIR",
    "sweep_bifurcation.png": "camdyn sweep examples/sweeps/bifurcation.toml",
    "sweep_regime_map.png": "camdyn sweep examples/sweeps/regime_map.toml",
    "fig2_9_regime_map.png": "python examples/chapter2_gallery.py 2.9",
    "design_map_circle.png": "python examples/tribology_design.py",
    "design_map_ellipse.png": "python examples/tribology_design.py",
    "contact_conditions.png": "python examples/tribology_design.py",
    "benedict_kelley.png": "python examples/tribology_design.py",
    "work_precision.png": "make bench-peers (python benchmarks/bench_peers.py)",
    "restitution_laws.png": "python examples/restitution_laws.py",
    "mechanisms_speed_fluctuation.png": "python examples/mechanisms.py",
    "stick_slip_cycle.png": "python examples/mechanisms.py",
    "siconos_camfollower.png": "python examples/siconos_comparison.py",
    "flexible_pivot_resonance.png": "python examples/flexible_pivot.py",
    "continuation_curves.png": "camdyn map sundar2014-impact --x cam.runout=1.5mm:3.5mm:9 "
                               "--y speed=14Hz:17.5Hz:15 --curve period-doubling=16.99Hz",
    "two_followers_stick_slip.png": "python examples/two_followers.py",
    "driven_cam_doubling.png": "python examples/driven_cam_orbits.py",
    "translating_bifurcation.png": "python examples/translating_bifurcation.py",
    "translating_branches.png": "python examples/translating_bifurcation.py",
    "translating_branches_358.png": "python examples/translating_bifurcation.py",
    "friction_errors.png": "python examples/friction_error_tables.py",
    "impact_hysteresis.png": "python examples/impact_damping_tables.py",
    "impact_residue_landscape.png": "python examples/impact_damping_tables.py",
    "restitution_fit.png": "python examples/impact_damping_tables.py",
    **{f"fig2_{n}.png": "python examples/chapter2_gallery.py"
       for n in ("4_residual_damping_models", "7_8_energy_balance", "10_11_direction", "14_15_oscillating_cam",
                 "16_linear_vs_nonlinear")},
}
#: points of the sweeps whose numbers are recorded (flat indices)
BIFURCATION_POINTS = (40, 200, 360)
REGIME_MAP_POINTS = ((4, 10), (12, 20), (20, 30))


def run(args: list[str], work: Path) -> str:
    """Run a command in the repository root; return its output (raise on failure)."""
    start = time.perf_counter()
    proc = subprocess.run(args, cwd=ROOT, capture_output=True, text=True)
    shown = " ".join(str(a) for a in args).replace(sys.executable, "python")
    print(f"  {shown}: {time.perf_counter() - start:.0f} s", flush=True)
    with (work / "log.txt").open("a") as log:
        log.write(f"$ {shown}\n{proc.stdout}\n{proc.stderr}\n")
    if proc.returncode:
        raise SystemExit(f"{shown} failed ({proc.returncode}):\n{proc.stderr[-2000:]}")
    return re.sub(r"\s+", " ", proc.stdout)


def camdyn(*args) -> list[str]:
    return [sys.executable, "-m", "camdyn", *map(str, args)]


def _number(text: str, pattern: str) -> float:
    match = re.search(pattern, text)
    if not match:
        raise SystemExit(f"could not find {pattern!r} in the output")
    return float(match.group(1))


def job_demo(work: Path) -> dict:
    """``camdyn demo``: the impact rig's time history and the friction rig's spectrum."""
    import xarray as xr

    from camdyn.analysis.spectra import spectrum_summary
    from camdyn.plotting.signals import spectrum_band

    out = work / "demo"
    run(camdyn("demo", "--out", out), work)
    for name in ("impact_rig_time.png", "friction_rig_spectrum.png"):
        shutil.copyfile(out / name, FIGURES / name)
    with xr.open_dataset(out / "impact_rig.nc") as ds:
        speed = float(ds.attrs["speed_hz"])
        start = float(ds.time[-1]) - 2 / speed
        window = ds.sel(time=slice(start, None))
        impact = {"speed_hz": speed, "revolutions": 40, "impacts": int(ds.sizes["impact"]),
                  "impacts_in_the_last_2_revolutions": int((ds["impact_time"] >= start).sum()),
                  "alpha_deg_range": [math.degrees(float(window.alpha.min())),
                                      math.degrees(float(window.alpha.max()))],
                  "peak_Fn_N": float(window.Fn.max())}
    with xr.open_dataset(out / "friction_rig.nc") as ds:
        speed = float(ds.attrs["speed_hz"])
        revs = max(1, int((float(ds.time[-1]) - float(ds.time[0])) * speed // 2))
        summary = spectrum_summary(ds.load(), window=revs)
        band = spectrum_band("auto", speed, 10, summary["natural_frequency_hz"],
                             [p["frequency_hz"] for p in summary["peaks"]])
        spectrum = {"speed_hz": speed, "runout_ratio": 0.1, "window_revolutions": revs, "band_hz": band,
                    "harmonic_amplitudes_rad_s2": [h["amplitude"] for h in summary["harmonics"][:5]],
                    "peak_threshold_rad_s2": summary["peak_threshold"], "peaks": summary["peaks"],
                    "natural_frequency_hz": summary["natural_frequency_hz"]}
    return {"impact_rig_time.png": impact, "friction_rig_spectrum.png": spectrum}


def _regime_counts(ds) -> dict:
    from camdyn.sweeps.metrics import REGIMES
    return {name: int((ds["regime"] == code).sum()) for code, name in REGIMES.items()}


def job_sweeps(work: Path) -> dict:
    """``camdyn sweep`` of the two example specs."""
    import numpy as np
    import xarray as xr

    numbers = {}
    for name, figure in (("bifurcation", "sweep_bifurcation.png"), ("regime_map", "sweep_regime_map.png")):
        result, plot = work / f"{name}.nc", work / f"{name}.png"
        run(camdyn("sweep", f"examples/sweeps/{name}.toml", "--out", result, "--plot", plot, "--quiet"), work)
        shutil.copyfile(plot, FIGURES / figure)
        with xr.open_dataset(result) as ds:
            entry = {"points": int(ds["status"].size), "failed": int((ds["status"] != 0).sum()),
                     "regimes": _regime_counts(ds)}
            if name == "bifurcation":
                speed = ds["motion.speed"].values
                rate = ds["impacts_per_revolution"].values
                entry["first_impacting_speed_hz"] = float(speed[np.argmax(rate > 0)])
                entry["points_shown"] = [{"speed_hz": float(speed[i]), "impacts_per_revolution": float(rate[i]),
                                          "regime": int(ds["regime"].values[i]),
                                          "max_normal_force_N": float(ds["max_normal_force"].values[i])}
                                         for i in BIFURCATION_POINTS]
            else:
                entry["points_shown"] = [{"runout_m": float(ds["cam.runout"].values[i]),
                                          "speed_hz": float(ds["motion.speed"].values[j]),
                                          "impacts_per_revolution": float(ds["impacts_per_revolution"].values[i, j]),
                                          "regime": int(ds["regime"].values[i, j])} for i, j in REGIME_MAP_POINTS]
        numbers[figure] = entry
    return numbers


def job_fig2_9(work: Path) -> dict:
    """Thesis fig 2.9 from the chapter 2 gallery (the regime map beside inverse kinematics)."""
    text = run([sys.executable, "examples/chapter2_gallery.py", "2.9"], work)
    agree = re.search(r"at (\d+)/(\d+) points in contact and (\d+)/(\d+) beyond", text)
    if not agree:
        raise SystemExit("chapter2_gallery.py 2.9 printed no agreement counts")
    kept_agree, kept, lost_agree, lost = map(int, agree.groups())
    return {"fig2_9_regime_map.png": {"kept": kept, "kept_agree": kept_agree, "lost": lost, "lost_agree": lost_agree,
                                      "loss_of_contact_rpm_at_2000_N_per_m":
                                          _number(text, r"ks = 2000 N/m: (\d+) rpm")}}


def job_restitution(work: Path) -> dict:
    """Restitution-parameterised laws against their promise (examples/restitution_laws.py)."""
    text = run([sys.executable, "examples/restitution_laws.py"], work)
    laws = ("hunt-crossley", "lankarani-nikravesh", "flores", "gonthier", "hu-guo")
    return {"restitution_laws.png": {"error_percent_at_0.5": {
        law: _number(text, rf"{law}: .*?0\.50: ([-+\d.]+) %") for law in laws}}}


def job_curves(work: Path) -> dict:
    """``camdyn map --curve``: the chapter 3 rig's period-doubling curve over (runout, speed)
    on its brute-force regime map."""
    import numpy as np
    import xarray as xr

    result, plot = work / "curves.nc", work / "curves.png"
    run(camdyn("map", "sundar2014-impact", "--x", "cam.runout=1.5mm:3.5mm:9", "--y", "speed=14Hz:17.5Hz:15",
               "--curve", "period-doubling=16.99Hz", "--revolutions", 150, "--discard", 100, "--rtol", 1e-9,
               "--atol", 1e-11, "--out", result, "--plot", plot, "--quiet"), work)
    shutil.copyfile(plot, FIGURES / "continuation_curves.png")
    with xr.open_dataset(result) as ds:
        curve = ds["period_doubling_curve"]
        return {"continuation_curves.png": {
            "runout_m": [float(v) for v in ds["cam.runout"].values],
            "period_doubling_hz": [float(v) for v in curve.values], "stopped": curve.attrs["stopped"],
            "period_counts": {str(int(k)): int(n) for k, n in zip(*np.unique(ds["period"].values,
                                                                         return_counts=True))}}}


def _script(name: str, figures: tuple[str, ...], args: tuple[str, ...] = (), data: bool = False):
    """A job that runs ``examples/name``; with ``data``, the script's ``--data FILE`` gives
    the numbers each figure shows (recorded in figures.json; the tests draw from them)."""
    def job(work: Path) -> dict:
        numbers = work / f"{Path(name).stem}.json"
        run([sys.executable, f"examples/{name}", *args, *(("--data", numbers) if data else ())], work)
        shown = json.loads(numbers.read_text()) if data else {}
        return {figure: shown.get(figure, {}) for figure in figures}
    job.__doc__ = f"python examples/{name}"
    return job


JOBS = {"demo": job_demo, "sweeps": job_sweeps, "fig2_9": job_fig2_9,
        "tribology": _script("tribology_design.py", tuple(k for k, v in SOURCES.items() if v.endswith("design.py")),
                             data=True),
        "restitution": job_restitution,
        "mechanisms": _script("mechanisms.py", ("mechanisms_speed_fluctuation.png", "stick_slip_cycle.png"),
                              data=True),
        "siconos": _script("siconos_comparison.py", ("siconos_camfollower.png",), data=True),
        "flexible_pivot": _script("flexible_pivot.py", ("flexible_pivot_resonance.png",), data=True),
        "curves": job_curves,
        "two_followers": _script("two_followers.py", ("two_followers_stick_slip.png",), data=True),
        "driven_cam": _script("driven_cam_orbits.py", ("driven_cam_doubling.png",), data=True)}
SLOW = {"friction_tables": _script("friction_error_tables.py", ("friction_errors.png",), data=True),
        "impact_tables": _script("impact_damping_tables.py",
                                 ("impact_hysteresis.png", "impact_residue_landscape.png", "restitution_fit.png")),
        "gallery": _script("chapter2_gallery.py", tuple(k for k, v in SOURCES.items() if v.endswith("gallery.py")),
                           ("2.4", "2.7", "2.10", "2.14", "2.16"), data=True),
        "translating": _script("translating_bifurcation.py", ("translating_bifurcation.png",
                                                                    "translating_branches.png",
                                                                    "translating_branches_358.png"), data=True)}


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def write_record(numbers: dict, seconds: dict) -> None:
    """Merge the new figures' numbers into docs/figures/figures.json (figures not made in
    this run keep their entries)."""
    import camdyn

    record = json.loads(RECORD.read_text()) if RECORD.is_file() else {}
    figures = record.get("figures", {})
    for name, values in numbers.items():
        figures[name] = {"command": SOURCES[name], "camdyn": camdyn.__version__, "sha256": sha256(FIGURES / name),
                         "numbers": values}
    record = {"about": "made by tools/make_figures.py (make figures); tests/test_figures.py recomputes some "
                       "numbers and checks every PNG's sha256",
              "sources": SOURCES, "seconds": {**record.get("seconds", {}), **seconds},
              "figures": dict(sorted(figures.items()))}
    RECORD.write_text(json.dumps(record, indent=1) + "\n")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", action="append", choices=sorted({**JOBS, **SLOW}), help="run this job (repeat)")
    parser.add_argument("--slow", action="store_true", help="also run the slow example scripts (about 20 min)")
    parser.add_argument("--list", action="store_true", help="list the jobs and exit")
    args = parser.parse_args(argv)
    jobs = {**JOBS, **(SLOW if args.slow else {})}
    if args.list:
        for name, job in {**JOBS, **SLOW}.items():
            print(f"{name:16s} {(job.__doc__ or '').splitlines()[0]}{'' if name in JOBS else ' (slow)'}")
        return
    names = args.only or list(jobs)
    numbers, seconds = {}, {}
    with tempfile.TemporaryDirectory(prefix="camdyn-figures-") as tmp:
        for name in names:
            print(f"{name}:", flush=True)
            start = time.perf_counter()
            numbers.update({**JOBS, **SLOW}[name](Path(tmp)))
            seconds[name] = round(time.perf_counter() - start, 1)
    write_record(numbers, seconds)
    print(f"wrote {len(numbers)} figures and {RECORD.relative_to(ROOT)} in {sum(seconds.values()):.0f} s")


if __name__ == "__main__":
    main()
