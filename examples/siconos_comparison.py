"""Figure of docs/profiles.md: the Alzate / di Bernardo rig in camdyn's event-driven
solution and in Siconos's Moreau-Jean time stepping (tests/data/siconos_camfollower.json,
written by benchmarks/siconos_camfollower.py).

- siconos_camfollower.png: (a) at 358 rpm over the first second from rest on the cam,
  the follower's lift ``x`` [mm] of both and the cam's lift ``s``; (b) at 660 rpm, the
  Poincare section at the end of the base dwell (gap ``x - s`` [mm] and relative velocity
  ``x' - s'`` [m/s] once per revolution) of camdyn over 2000 revolutions and of Siconos
  at its three steps over 100 revolutions each.

Run: python examples/siconos_comparison.py [--data FILE]   (about 10 s; ``--data`` writes
the numbers the figure shows)
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from camdyn.plotting.style import axis_label, legend_below, save_figure, styled, tidy_axis  # noqa: E402
from camdyn.simulation.translating import alzate_rig, simulate_translating  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "docs" / "figures"
SICONOS = ROOT / "tests" / "data" / "siconos_camfollower.json"
#: the cam angle where the runs start, the end of the base dwell [rad]
PHASE = math.pi / 2
#: revolutions of camdyn's Poincare section at 660 rpm, after a transient of 200
SECTION_REVOLUTIONS = 2000


def data(siconos: dict) -> dict:
    """Panel (a): time [s], camdyn's and Siconos's follower lift x [m] and the cam lift s
    [m] at 358 rpm; panel (b): the sections (gap [m], relative velocity [m/s]) at 660 rpm."""
    series = siconos["figures"]["358"]
    w = 358 * 2 * math.pi / 60
    ds = simulate_translating(alzate_rig(), w / (2 * math.pi), 1.0, sample_rate=4e3, phase=PHASE, rtol=1e-12,
                              atol=1e-14)
    panel_a = {"time": ds.time.values.tolist(), "camdyn": ds.x.values.tolist(), "lift": ds.lift.values.tolist(),
               "siconos_time": series["time_s"],
               "siconos": (np.asarray(series["gap_m"]) + np.asarray(series["lift_m"])).tolist(),
               "steps_per_revolution": max(int(k) for k in siconos["speeds"]["358"])}
    w = 660 * 2 * math.pi / 60
    period = 2 * math.pi / w
    ds = simulate_translating(alzate_rig(), w / (2 * math.pi), (200 + SECTION_REVOLUTIONS) * period,
                              sample_rate=4 / period,
                              phase=PHASE)
    ours = np.c_[ds.gap.values[::4], (ds.x_dot.values - ds.lift_rate.values)[::4]][200:]
    panel_b = {"camdyn": ours.tolist(),
               "siconos": {steps: run["section"] for steps, run in siconos["speeds"]["660"].items()}}
    return {"a": panel_a, "b": panel_b}


@styled
def draw(shown: dict, path) -> Path:
    """The two panels of siconos_camfollower.png."""
    fig, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(9.0, 4.0))
    a = shown["a"]
    ax_a.plot(a["time"], 1e3 * np.asarray(a["lift"]), color="0.6", lw=1.0, label="cam lift $s$")
    ax_a.plot(a["time"], 1e3 * np.asarray(a["camdyn"]), color="C0", label="camdyn, event-driven")
    ax_a.plot(a["siconos_time"], 1e3 * np.asarray(a["siconos"]), color="C3", ls="--",
              label=f"Siconos, {a['steps_per_revolution']} steps/rev")
    ax_a.set_xlabel(axis_label("time $t$", "s"))
    ax_a.set_ylabel(axis_label("follower lift $x$", "mm"))
    ax_a.set_title("(a) 358 rpm from rest on the cam")
    tidy_axis(ax_a.xaxis)
    b = shown["b"]
    ours = np.asarray(b["camdyn"])
    ax_b.plot(1e3 * ours[:, 0], ours[:, 1], ls="none", marker=".", ms=2, color="C0", label="camdyn")
    runs = sorted(b["siconos"].items(), key=lambda item: int(item[0]))
    for (steps, points), marker, color in zip(runs, "xo+", ("C1", "C2", "C3")):
        points = np.asarray(points)
        ax_b.plot(1e3 * points[:, 0], points[:, 1], ls="none", marker=marker, ms=3, mfc="none", color=color,
                  label=f"Siconos {steps}/rev")
    ax_b.set_xlabel(axis_label("gap $x - s$", "mm"))
    ax_b.set_ylabel(axis_label(r"relative velocity $\dot x - \dot s$", "m/s"))
    ax_b.set_title("(b) 660 rpm, Poincaré section")
    legend_below(fig, ax_b, 4)
    return save_figure(fig, path)


def main(argv=None, out: Path = OUT) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, help="write the numbers the figure shows to this JSON file")
    args = parser.parse_args(argv)
    out.mkdir(parents=True, exist_ok=True)
    shown = data(json.loads(SICONOS.read_text()))
    draw(shown, out / "siconos_camfollower.png")
    points = {steps: len(section) for steps, section in shown["b"]["siconos"].items()}
    print(f"358 rpm: {len(shown['a']['time'])} camdyn samples; 660 rpm: {len(shown['b']['camdyn'])} camdyn "
          f"section points, Siconos {points}")
    if args.data:
        numbers = {"siconos_camfollower.png": {"section_points_camdyn": len(shown["b"]["camdyn"]),
                                               "section_points_siconos": points}}
        args.data.write_text(json.dumps(numbers, indent=1))


if __name__ == "__main__":
    main()
