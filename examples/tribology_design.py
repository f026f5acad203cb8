"""Chapter 4 figures: design maps (figs 4.4 and 4.10), contact conditions over a revolution
(fig 4.5, with the lambda ratio) and the modified Benedict-Kelley law (figs 4.8-4.9 style).

Run:  python examples/tribology_design.py [--data FILE]
Writes docs/figures/design_map_circle.png, design_map_ellipse.png, contact_conditions.png
and benedict_kelley.png and prints what each shows; with ``--data`` also the numbers each
figure shows, as JSON (tools/make_figures.py records them in docs/figures/figures.json).

Each figure is two functions (:data:`FIGURES`): ``data_*`` computes what it shows (the
design maps and the contact conditions as the datasets of :mod:`camdyn.tribology`, the
Benedict-Kelley curves as a dict of numbers) and a draw function in camdyn's figure style
(:mod:`camdyn.plotting.style`). tests/test_figures.py draws the design maps on coarse
grids and Benedict-Kelley from the numbers recorded in figures.json, and checks that no
text overlaps or leaves the figure.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

import camdyn  # noqa: E402
from camdyn.plotting import plot_contact_conditions, plot_design_map  # noqa: E402
from camdyn.plotting.style import axis_label, legend_below, save_figure, styled, tidy_axis  # noqa: E402
from camdyn.tribology import contact_conditions, normalized_friction  # noqa: E402
from camdyn.tribology.benedict_kelley import benedict_kelley, operating_term  # noqa: E402
from camdyn.tribology.design import design_map  # noqa: E402

FIGURES_DIR = Path(__file__).resolve().parents[1] / "docs" / "figures"
RIG = "sundar2014-friction"
#: semi-major axis of the rig's cam [m]
A = 17.5e-3
#: operating point of figs 4.5 and 4.8-4.9: runout ratio e/a [-], cam speed [Hz]
RUNOUT_RATIO = 0.116
SPEED_HZ = 11.55
#: lubricants of figs 4.8-4.9: name, viscosity eta [Pa s], constants C1 and C2 [m]
LUBRICANTS = (("AGMA 4EP", 0.034, 0.0288e-6, 2.03e-6), ("ISO 32", 0.012, 0.0509e-6, 1.6512e-6))
#: mean roughness Rm drawn [m]
ROUGHNESS_RANGE = (0.2e-6, 0.7e-6)


def _rounded(value):
    """A number (or a list of them) as recorded: floats to 6 significant digits."""
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_rounded(v) for v in value]
    return float(f"{float(value):.6g}")


def data_design_map_circle(ratios: int = 31, speeds: int = 51) -> xr.Dataset:
    """Fig 4.4: the circular cam's design map over e/a 0.05-0.8 and 5-30 Hz (``ratios`` by
    ``speeds`` points), with the film of AGMA 4EP."""
    rig = camdyn.load_system(RIG)
    return design_map(rig, "runout", np.linspace(0.05, 0.8, ratios), np.linspace(5.0, 30.0, speeds),
                      lubricant="agma-4ep")


def data_design_map_ellipse(ratios: int = 31, speeds: int = 41) -> xr.Dataset:
    """Fig 4.10: the elliptic cam's design map (e = 0.1 a) over b/a 0.4-1 and 8-24 Hz."""
    rig = camdyn.load_system(RIG).with_values(**{"cam.runout": 0.1 * A})
    return design_map(rig, "axis_ratio", np.linspace(0.4, 1.0, ratios), np.linspace(8.0, 24.0, speeds))


def data_contact_conditions() -> xr.Dataset:
    """Fig 4.5: contact conditions over a revolution at e/a = 0.116 and 11.55 Hz (AGMA 4EP,
    ground surfaces)."""
    rig = camdyn.load_system(RIG).with_values(**{"cam.runout": RUNOUT_RATIO * A})
    return contact_conditions(rig, SPEED_HZ, "agma-4ep", "ground")


def data_benedict_kelley(conditions: xr.Dataset | None = None, points: int = 50) -> dict:
    """Figs 4.8-4.9: the law with the thesis's constants at the operating point of
    ``conditions`` (default :func:`data_contact_conditions`): mean Hertz pressure [GPa],
    velocity term ``<|vr| ve^2>`` [m^3/s^3], mean roughness [µm] and, per lubricant, the
    operating term [-], mu [-] and mu_bar = C1/(C2 - Rm) [-] at ``points`` roughnesses."""
    conditions = data_contact_conditions() if conditions is None else conditions
    pressure = float(conditions["peak_pressure"].mean())
    velocity = float(np.mean(np.abs(conditions["sliding_velocity"].values) * conditions["sum_velocity"].values ** 2))
    roughness = np.linspace(*ROUGHNESS_RANGE, points)
    lubricants = {}
    for name, viscosity, c1, c2 in LUBRICANTS:
        term = operating_term(pressure, viscosity, velocity)
        lubricants[name] = {"log_term": _rounded(term), "mu": _rounded(benedict_kelley(roughness, term, c1, c2)),
                            "mu_bar": _rounded(normalized_friction(roughness, c1, c2))}
    return {"mean_pressure_GPa": _rounded(pressure / 1e9), "velocity_term_m3_s3": _rounded(velocity),
            "runout_ratio": RUNOUT_RATIO, "speed_hz": SPEED_HZ, "roughness_um": _rounded(roughness * 1e6),
            "lubricants": lubricants}


@styled
def draw_benedict_kelley(data: dict, path) -> Path:
    """The coefficient of friction mu [-] (eq 4.41) and mu_bar [-] (eq 4.43) against the
    mean roughness Rm [µm], one curve per lubricant."""
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 4.2))
    for name, curves in data["lubricants"].items():
        axes[0].plot(data["roughness_um"], curves["mu"], label=f"{name} (log term {curves['log_term']:.2f})")
        axes[1].plot(data["roughness_um"], curves["mu_bar"])
    axes[0].set_ylabel(axis_label(r"friction coefficient $\mu$", "-"))
    axes[1].set_ylabel(axis_label(r"$\bar\mu = C_1/(C_2 - R_m)$", "-"))
    for ax in axes:
        ax.set_xlabel(axis_label("mean roughness $R_m$", "µm"))
        tidy_axis(ax.xaxis, 6)
        tidy_axis(ax.yaxis, 6)
    axes[0].set_title("eq 4.41 at the rig's operating term")
    axes[1].set_title("eq 4.43, normalised")
    legend_below(fig, axes[0], 2)
    fig.suptitle(f"modified Benedict-Kelley law with the thesis's constants (e/a = {data['runout_ratio']:g}, "
                 f"{data['speed_hz']:g} Hz, " + r"$\langle p \rangle$" + f" = {data['mean_pressure_GPa']:.3g} GPa)")
    return save_figure(fig, path)


#: file name -> (data function, draw function)
FIGURES = {"design_map_circle.png": (data_design_map_circle, plot_design_map),
           "design_map_ellipse.png": (data_design_map_ellipse, plot_design_map),
           "contact_conditions.png": (data_contact_conditions, plot_contact_conditions),
           "benedict_kelley.png": (data_benedict_kelley, draw_benedict_kelley)}


def recorded(name: str, data) -> dict:
    """The numbers of a figure recorded in figures.json (the design maps' recommendation,
    the contact conditions' ranges, all of the Benedict-Kelley curves)."""
    if name.startswith("design_map"):
        return {"recommended_ratio": _rounded(data.attrs["recommended_ratio"]),
                "recommended_speed_hz": _rounded(data.attrs["recommended_speed"]),
                "admissible_points": int(data["admissible"].sum())}
    if name == "contact_conditions.png":
        srr, lam = data["slide_to_roll"].values, data["lambda_ratio"].values
        return {"runout_ratio": RUNOUT_RATIO, "speed_hz": SPEED_HZ,
                "slide_to_roll_range": _rounded([srr.min(), srr.max()]),
                "lambda_range": _rounded([np.nanmin(lam), np.nanmax(lam)])}
    return data


def report(data: dict) -> None:
    """Print what each figure shows (``data``: file name -> data)."""
    circle, ellipse = data["design_map_circle.png"], data["design_map_ellipse.png"]
    print(f"fig 4.4: recommended e/a = {circle.attrs['recommended_ratio']:.3g} at "
          f"{circle.attrs['recommended_speed']:.3g} Hz; admissible points {int(circle['admissible'].sum())}")
    print(f"fig 4.10: recommended b/a = {ellipse.attrs['recommended_ratio']:.3g} at "
          f"{ellipse.attrs['recommended_speed']:.3g} Hz")
    shown = recorded("contact_conditions.png", data["contact_conditions.png"])
    print("fig 4.5: slide-to-roll {:.3f} to {:.3f} (thesis 0.75 to 1.25); lambda {:.3g} to {:.3g} (AGMA 4EP, "
          "ground)".format(*shown["slide_to_roll_range"], *shown["lambda_range"]))
    bk = data["benedict_kelley.png"]
    print(f"Benedict-Kelley: <p> = {bk['mean_pressure_GPa']:.3g} GPa, "
          f"<|vr| ve^2> = {bk['velocity_term_m3_s3']:.3g} m^3/s^3")


def main(argv=None, out: Path = FIGURES_DIR) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, help="write the numbers each figure shows to this JSON file")
    args = parser.parse_args(argv)
    out.mkdir(parents=True, exist_ok=True)
    conditions = data_contact_conditions()
    data = {"design_map_circle.png": data_design_map_circle(), "design_map_ellipse.png": data_design_map_ellipse(),
            "contact_conditions.png": conditions, "benedict_kelley.png": data_benedict_kelley(conditions)}
    for name, shown in data.items():
        FIGURES[name][1](shown, out / name)
    report(data)
    if args.data:
        args.data.write_text(json.dumps({name: recorded(name, shown) for name, shown in data.items()}, indent=1)
                             + "\n")


if __name__ == "__main__":
    main()
