"""Error curve of each restitution-parameterised contact law (docs/restitution.md).

One impact of the chapter 3 follower on a frozen cam per point (gravity, spring and
friction removed, approach velocity 0.5 m/s): the measured coefficient of restitution
against the one given to the law. Writes docs/figures/restitution_laws.png (drawn by
:func:`draw_restitution_laws` in camdyn's figure style) and
docs/figures/restitution_laws.json, the numbers it shows: per law, the restitution given
``e`` [-], the one measured [-] and the relative error ``(measured - e)/e`` [-].
tests/test_figures.py draws the figure again from that file and checks its layout.

Run: python examples/restitution_laws.py
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import camdyn  # noqa: E402
from camdyn.analysis.restitution import restitution_error_curve  # noqa: E402
from camdyn.plotting.style import axis_label, legend_below, save_figure, styled, tidy_axis  # noqa: E402

OUT = Path(__file__).resolve().parent.parent / "docs" / "figures"
LAWS = ("hunt-crossley", "lankarani-nikravesh", "flores", "gonthier", "hu-guo")
#: restitution given to each law [-]
VALUES = tuple(float(v) for v in np.round(np.arange(0.1, 0.96, 0.05), 2))
#: range of the error axis [%]; Hunt-Crossley and Lankarani-Nikravesh leave it below e = 0.45
ERROR_RANGE_PERCENT = (-35.0, 60.0)
#: the band of errors taken as accurate [%]
BAND_PERCENT = 5.0


def data_restitution_laws(values=VALUES, laws=LAWS) -> dict:
    """Per law: ``e`` given [-], ``measured`` [-] and ``relative_error`` [-] of one impact of
    the chapter 3 follower (preset ``sundar2014-impact``) at each restitution in ``values``."""
    system = camdyn.load_system("sundar2014-impact")
    data = {}
    for law in laws:
        given, measured, relative = restitution_error_curve(system, law, values)
        data[law] = {"e": given.tolist(), "measured": measured.tolist(), "relative_error": relative.tolist()}
    return data


@styled
def draw_restitution_laws(data: dict, path) -> Path:
    """Error of the simulated restitution [%] against the restitution given [-], one curve
    per law, with the ±5 % band."""
    fig, ax = plt.subplots(figsize=(7.0, 4.8))
    for law, curve in data.items():
        ax.plot(curve["e"], 100.0 * np.asarray(curve["relative_error"]), marker="o", ms=3, label=law)
    ax.axhspan(-BAND_PERCENT, BAND_PERCENT, color="0.92", zorder=0, label=f"±{BAND_PERCENT:g} %")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_ylim(*ERROR_RANGE_PERCENT)
    ax.set_xlabel(axis_label("restitution given to the law $e$", "-"))
    ax.set_ylabel(axis_label(r"error of the simulated $e$", "%"))
    tidy_axis(ax.xaxis, 8)
    ax.set_title("restitution-parameterised laws: one impact of the chapter 3 rig at 0.5 m/s")
    legend_below(fig, ax, 3)
    return save_figure(fig, path)


def main(argv=None, out: Path = OUT) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.parse_args(argv)
    out.mkdir(parents=True, exist_ok=True)
    data = data_restitution_laws()
    draw_restitution_laws(data, out / "restitution_laws.png")
    (out / "restitution_laws.json").write_text(json.dumps(data, indent=1))
    for law in LAWS:
        row = ", ".join(f"{e:.2f}: {100 * r:+.1f} %" for e, r in zip(data[law]["e"], data[law]["relative_error"]))
        print(f"{law}: {row}")


if __name__ == "__main__":
    main()
