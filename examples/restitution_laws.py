"""Error curve of each restitution-parameterised contact law (docs/restitution.md).

One impact of the chapter 3 follower on a frozen cam per point, gravity, spring and
friction removed; the measured coefficient of restitution against the one given to
the law. Writes docs/figures/restitution_laws.png and docs/figures/restitution_laws.json.
Run: python examples/restitution_laws.py
"""

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import camdyn
from camdyn.analysis.restitution import restitution_error_curve
from camdyn.plotting import figure_style

LAWS = ["hunt-crossley", "lankarani-nikravesh", "flores", "gonthier", "hu-guo"]


def main(out=Path(__file__).resolve().parent.parent / "docs" / "figures"):
    out.mkdir(parents=True, exist_ok=True)
    system = camdyn.load_system("sundar2014-impact")
    values = np.round(np.arange(0.1, 0.96, 0.05), 2)
    data = {}
    with figure_style():
        fig, ax = plt.subplots(figsize=(7, 4.5))
        for law in LAWS:
            e, measured, err = restitution_error_curve(system, law, values)
            data[law] = {"e": e.tolist(), "measured": measured.tolist(), "relative_error": err.tolist()}
            ax.plot(e, 100 * err, marker="o", ms=3, label=law)
        ax.axhspan(-5, 5, color="0.92", zorder=0, label="±5 %")
        ax.axhline(0, color="k", lw=0.5)
        ax.set_ylim(-30, 60)
        ax.set_xlabel("restitution given to the law $e$ [-]")
        ax.set_ylabel("error of the simulated $e$ [%]")
        ax.set_title("restitution-parameterised laws: one impact of the chapter 3 rig at 0.5 m/s")
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0))
        fig.savefig(out / "restitution_laws.png", dpi=120)
    (out / "restitution_laws.json").write_text(json.dumps(data, indent=1))
    for law in LAWS:
        row = ", ".join(f"{e:.2f}: {100 * r:+.1f} %" for e, r in zip(data[law]["e"], data[law]["relative_error"]))
        print(f"{law}: {row}")


if __name__ == "__main__":
    main()
