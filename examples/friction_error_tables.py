"""Thesis tables 4.5, 4.6 and 4.7: error of the friction estimator on simulated records.

Simulates the chapter 4 rig with Coulomb friction mu = 0.3, samples it at 9460 Hz over
10 cam revolutions (the thesis's 1.15 Hz resolution at 11.55 Hz), runs the estimator with
the thesis's one-harmonic truncation and with camdyn's default (20 harmonics), noise-free
and with 1 % noise, and writes docs/friction-errors-tables.md and docs/figures/friction_errors.png
(drawn by :func:`draw_errors` in camdyn's figure style; tests/test_figures.py draws it again
from the numbers recorded in docs/figures/figures.json and checks its layout).

Run:  python examples/friction_error_tables.py [--data FILE]
(``--data``: also write the numbers the figure shows, as JSON, for tools/make_figures.py)
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import camdyn  # noqa: E402
from camdyn.errors import CamdynError  # noqa: E402
from camdyn.identification.friction import estimate_friction  # noqa: E402
from camdyn.plotting.style import axis_label, legend_below, save_figure, styled, tidy_axis  # noqa: E402
from camdyn.records.synthesis import synthesize  # noqa: E402

MU = 0.3
FS = 9460.0
A = 17.5e-3
ROOT = Path(__file__).resolve().parents[1]

TABLE_4_5 = [(0.05, 5.3), (0.10, 4.7), (0.15, 4.0), (0.20, 2.8), (0.25, 1.3), (0.30, 0.7), (0.35, 3.1),
             (0.40, 6.0), (0.45, 9.4)]                       # e/a, thesis error [%] at 11.55 Hz
TABLE_4_6 = [(2, 6.7), (5, 6.3), (8, 5.7), (11, 5.0), (14, 4.0), (17, 2.7), (21, 1.0)]   # Hz, e/a = 0.1
TABLE_4_7 = [(0.0, 5.7), (0.31, 6.2), (0.44, 6.2), (0.53, 5.5), (0.6, 4.2)]            # eccentricity, 8.33 Hz


def error(system, speed, harmonics, noise, seed=1):
    """Percentage error of mu, or the refusal reason."""
    try:
        rec = synthesize(system, speed, revolutions=10, sample_rate=FS, noise=noise, seed=seed)
        est = estimate_friction(system, rec, harmonics=harmonics)
        return 100.0 * (est.mu - MU) / MU
    except CamdynError as exc:
        return str(exc).split(":")[0] if "refused" not in str(exc) else "refused: " + str(exc).split(": ", 1)[1][:60]


def row(label, system, speed, thesis):
    cells = [error(system, speed, 1, 0.0), error(system, speed, 20, 0.0), error(system, speed, 20, 0.01)]
    text = [f"{c:+.3f}" if isinstance(c, float) else c for c in cells]
    print(f"{label:>8} | thesis {thesis:4.1f} % | K=1 {text[0]:>10} | K=20 {text[1]:>8} | K=20 1% noise {text[2]:>8}",
          flush=True)
    return [label, f"{thesis:.1f}"] + text, cells


def misalignment(base):
    """Section 4.8: a force transducer turned by kappa, and a spring tilted by sigma,
    both left out of the estimator (which assumes kappa = sigma = 0)."""
    system = base.with_values(**{"cam.runout": 0.3 * A})
    lines = ["### Section 4.8: misalignment left out of the estimator (e/a = 0.3, 11.55 Hz)", "",
             "| misalignment | thesis error [%] (static analysis) | camdyn error [%] (dynamic simulation) |",
             "|---|---|---|"]
    rec = synthesize(system, 11.55, revolutions=10, sample_rate=FS, transducer_angle=math.radians(5.0))
    kappa = 100 * (estimate_friction(system, rec).mu - MU) / MU
    tilted = system.with_values(**{"spring.tilt": math.radians(1.0)})
    rec = synthesize(tilted, 11.55, revolutions=10, sample_rate=FS)
    try:
        estimate_friction(system, rec)
        refused = "accepted"
    except CamdynError as exc:
        refused = "refused: " + str(exc).split(": ", 1)[1]
    sigma = 100 * (estimate_friction(system, rec, enforce=False).mu - MU) / MU
    sigma_known = 100 * (estimate_friction(tilted, rec).mu - MU) / MU
    print(f"kappa 5 deg: {kappa:+.3f} %, sigma 1 deg: {sigma:+.3f} % ({refused}; "
          f"known to the estimator: {sigma_known:+.4f} %)")
    lines += [f"| transducer angle kappa = 5 deg (records Ny cos kappa) | 0.5 | {kappa:+.3f} |",
              f"| spring tilt sigma = 1 deg, not modelled | 9 | {sigma:+.3f} ({refused}) |",
              f"| spring tilt sigma = 1 deg, given to the estimator (`spring.tilt`) | - | {sigma_known:+.4f} |"]
    return "\n".join(lines)


#: the three tables' panels: short title, x-axis label
PANELS = {"Table 4.5": ("table 4.5: circle, 11.55 Hz", axis_label("$e/a$", "-")),
          "Table 4.6": ("table 4.6: circle, $e/a$ = 0.1", axis_label(r"$\Omega$", "Hz")),
          "Table 4.7": ("table 4.7: ellipse, $e$ = 0.1 $a$, 8.33 Hz", axis_label(r"$\sqrt{1 - b^2/a^2}$", "-"))}
#: the curves of each panel: key of the data, label, matplotlib format
CURVES = (("thesis_percent", "thesis", "ks--"), ("one_harmonic_percent", "camdyn, 1 harmonic (thesis method)", "o-"),
          ("default_percent", "camdyn default (20 harmonics)", "^-"),
          ("noisy_percent", "camdyn default, 1 % noise", "v:"))


@styled
def draw_errors(series: dict, path) -> Path:
    """Error of mu [%] (absolute value, log scale) of the thesis and of camdyn against
    each table's parameter; a missing point is a record the estimator refused."""
    fig, axes = plt.subplots(1, 3, figsize=(11.0, 3.8), sharey=True)
    for ax, (table, data) in zip(axes, series.items()):
        title, xlabel = PANELS[table]
        for key, label, fmt in CURVES:
            values = np.array([np.nan if v is None else abs(v) for v in data[key]])
            ax.plot(data["x"], values, fmt, ms=4, label=label)
        ax.set_yscale("log")
        ax.set_title(title)
        ax.set_xlabel(xlabel)
        ax.grid(True, which="major", alpha=0.3)
        tidy_axis(ax.xaxis, 6)
    axes[0].set_ylabel(axis_label(r"$|\Delta\mu/\mu|$", "%"))
    legend_below(fig, axes[0], 4)
    fig.suptitle(r"error of the friction estimate, $\mu$ = 0.3 (a missing point: record refused)")
    return save_figure(fig, path)


def main(argv=None, out=ROOT / "docs"):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, help="write the numbers the figure shows to this JSON file")
    args = parser.parse_args(argv)
    base = camdyn.load_system("sundar2014-friction")
    sections = []
    series = {}
    for title, rows, make in (
        ("Table 4.5: circular cam at 11.55 Hz, against e/a", TABLE_4_5,
         lambda x: (f"{x:.2f}", base.with_values(**{"cam.runout": x * A}), 11.55)),
        ("Table 4.6: circular cam, e/a = 0.1, against the cam speed [Hz]", TABLE_4_6,
         lambda x: (f"{x:g}", base.with_values(**{"cam.runout": 0.1 * A}), float(x))),
        ("Table 4.7: elliptic cam, e = 0.1 a, 8.33 Hz, against the eccentricity", TABLE_4_7,
         lambda x: (f"{x:.2f}", base.with_values(**{"cam.runout": 0.1 * A,
                                                    "cam.semi_minor": A * math.sqrt(1 - x * x)}), 8.33)),
    ):
        print(title)
        lines = [f"### {title}", "",
                 "| case | thesis error [%] | camdyn, 1 harmonic (thesis method) [%] | camdyn default [%] | "
                 "camdyn default, 1 % noise [%] |", "|---|---|---|---|---|"]
        data = {"x": [], **{key: [] for key, _, _ in CURVES}}
        for x, thesis in rows:
            label, system, speed = make(x)
            cells, raw = row(label, system, speed, thesis)
            lines.append("| " + " | ".join(cells) + " |")
            data["x"].append(x)
            for (key, _, _), value in zip(CURVES, (thesis, *raw)):
                data[key].append(round(value, 6) if isinstance(value, float) else None)
        sections.append("\n".join(lines))
        series[title.split(":")[0]] = data
    sections.append(misalignment(base))
    out.mkdir(parents=True, exist_ok=True)
    (out / "friction-errors-tables.md").write_text("\n\n".join(sections) + "\n")
    draw_errors(series, out / "figures" / "friction_errors.png")
    if args.data:
        args.data.write_text(json.dumps({"friction_errors.png": series}, indent=1) + "\n")


if __name__ == "__main__":
    sys.exit(main())
