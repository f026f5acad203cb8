"""Chapter 4 figures: design maps (figs 4.4 and 4.10), contact conditions over a revolution
(fig 4.5, with the lambda ratio) and the modified Benedict-Kelley law (figs 4.8-4.9 style).

Run:  python examples/tribology_design.py   (writes docs/figures/*.png)
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import camdyn  # noqa: E402
from camdyn.plotting import figure_style, plot_contact_conditions, plot_design_map  # noqa: E402
from camdyn.tribology import contact_conditions, normalized_friction  # noqa: E402
from camdyn.tribology.benedict_kelley import benedict_kelley, operating_term  # noqa: E402
from camdyn.tribology.design import design_map  # noqa: E402

FIGURES = Path(__file__).resolve().parents[1] / "docs" / "figures"
A = 17.5e-3


def main():
    rig = camdyn.load_system("sundar2014-friction")
    circle = design_map(rig, "runout", np.linspace(0.05, 0.8, 31), np.linspace(5, 30, 51), lubricant="agma-4ep")
    plot_design_map(circle, FIGURES / "design_map_circle.png")
    print(f"fig 4.4: recommended e/a = {circle.attrs['recommended_ratio']:.3g} at "
          f"{circle.attrs['recommended_speed']:.3g} Hz; admissible points {int(circle['admissible'].sum())}")
    ellipse = design_map(rig.with_values(**{"cam.runout": 0.1 * A}), "axis_ratio", np.linspace(0.4, 1.0, 31),
                         np.linspace(8, 24, 41))
    plot_design_map(ellipse, FIGURES / "design_map_ellipse.png")
    print(f"fig 4.10: recommended b/a = {ellipse.attrs['recommended_ratio']:.3g} at "
          f"{ellipse.attrs['recommended_speed']:.3g} Hz")

    system = rig.with_values(**{"cam.runout": 0.116 * A})
    cc = contact_conditions(system, 11.55, "agma-4ep", "ground")
    plot_contact_conditions(cc, FIGURES / "contact_conditions.png")
    srr = cc["slide_to_roll"].values
    print(f"fig 4.5: slide-to-roll {srr.min():.3f} to {srr.max():.3f} (thesis 0.75 to 1.25); "
          f"lambda {np.nanmin(cc['lambda_ratio']):.3g} to {np.nanmax(cc['lambda_ratio']):.3g} (AGMA 4EP, ground)")

    # Benedict-Kelley with the thesis's constants at this operating point
    p_mean = float(cc["peak_pressure"].mean())
    velocity = float(np.mean(np.abs(cc["sliding_velocity"].values) * cc["sum_velocity"].values ** 2))
    rm = np.linspace(0.2e-6, 0.7e-6, 50)
    with figure_style():
        fig, axes = plt.subplots(1, 2, figsize=(10, 4))
        for name, eta, c1, c2 in (("AGMA 4EP", 0.034, 0.0288e-6, 2.03e-6), ("ISO 32", 0.012, 0.0509e-6, 1.6512e-6)):
            term = operating_term(p_mean, eta, velocity)
            axes[0].plot(rm * 1e6, benedict_kelley(rm, term, c1, c2), label=f"{name} (log term {term:.2f})")
            axes[1].plot(rm * 1e6, normalized_friction(rm, c1, c2), label=name)
        axes[0].set_ylabel(r"friction coefficient $\mu$ [-]")
        axes[1].set_ylabel(r"$\bar\mu = C_1/(C_2 - R_m)$ [-]")
        for ax in axes:
            ax.set_xlabel("mean roughness $R_m$ [µm]")
            ax.legend()
        fig.suptitle("modified Benedict-Kelley law with the thesis's constants (e/a = 0.116, 11.55 Hz)")
        fig.savefig(FIGURES / "benedict_kelley.png", dpi=120)
    print(f"Benedict-Kelley: <p> = {p_mean / 1e9:.3g} GPa, <|vr| ve^2> = {velocity:.3g} m^3/s^3")


if __name__ == "__main__":
    main()
