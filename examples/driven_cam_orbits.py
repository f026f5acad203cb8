"""Figure of docs/continuation.md: the period doubling of the chapter 3 impact rig with its
cam on a DC motor, against the cam held at its speed.

- driven_cam_doubling.png: the rig (preset ``sundar2014-impact``) with its cam on a
  motor that stalls at 1 N m, continued in the motor's free speed from 15.5 to 18 Hz for
  three shaft inertias ``J``, and the cam-follower with its cam held at its speed,
  continued in that speed: (a) the real part of the Floquet multiplier that crosses -1
  (of all the orbit's multipliers, the smallest real part) against the orbit's mean cam
  speed (one turn over its period), with the located period doublings; (b) the
  coefficient of speed fluctuation over the orbit, ``(omega_max - omega_min) /
  omega_mean``.

Run: python examples/driven_cam_orbits.py [--data FILE]   (about 20 s; ``--data`` writes
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

import camdyn  # noqa: E402
from camdyn.continuation.mechanisms import trace_mechanism  # noqa: E402
from camdyn.continuation.orbits import flow  # noqa: E402
from camdyn.continuation.results import trace_branch  # noqa: E402
from camdyn.plotting.style import axis_label, legend_below, save_figure, styled  # noqa: E402
from camdyn.simulation.mechanisms import CamDrive, DrivenCamRig  # noqa: E402

OUT = Path(__file__).resolve().parent.parent / "docs" / "figures"
#: shaft inertias [kg m^2]
INERTIAS = (3e-4, 1e-3, 1e-2)
#: the motor's stall torque [N m] and its free speeds' range [Hz]
STALL, FREE = 1.0, (15.5, 18.0)
#: the held cam's speed range [Hz]
HELD = (15.0, 17.5)


def _branch_rows(problem, branch, driven: bool) -> dict:
    """Per orbit: the mean cam speed [Hz], the smallest real part of its multipliers and
    the largest modulus [-], the coefficient of speed fluctuation [-]; and the located
    period doublings [Hz]."""
    speed, lowest, modulus, fluctuation = [], [], [], []
    for orbit in branch.orbits:
        speed.append(orbit.periods / orbit.period)
        lowest.append(float(np.min(orbit.multipliers.real)))
        modulus.append(float(np.max(np.abs(orbit.multipliers))))
        if driven:                              # the cam's speed over the orbit, sampled in the cam angle
            run = flow(problem, orbit.state, orbit.parameter, orbit.periods, samples=512)
            omega = run.states[:, 2]
            fluctuation.append(float((omega.max() - omega.min()) / (2.0 * math.pi * speed[-1])))
    doublings = [b.orbit.periods / b.orbit.period for b in branch.bifurcations if b.kind == "period-doubling"]
    return {"speed_hz": speed, "lowest": lowest, "modulus": modulus, "fluctuation": fluctuation,
            "doubling_hz": doublings}


def data_doubling() -> dict:
    """The branches of the figure: one per shaft inertia and the held cam's."""
    system = camdyn.load_system("sundar2014-impact").with_values(**{"motion.speed": 15.0})
    out = {}
    for inertia in INERTIAS:
        rig = DrivenCamRig(system, CamDrive(inertia, "motor", stall_torque=STALL, free_speed=2.0 * math.pi * FREE[0]))
        problem, branch = trace_mechanism(rig, "drive.free_speed", 2.0 * math.pi * FREE[0], 2.0 * math.pi * FREE[1],
                                          step=0.01, max_points=80, transient=50)
        out[f"{inertia:g}"] = _branch_rows(problem, branch, True)
    problem, branch = trace_branch(system, "motion.speed", HELD[0], HELD[1], step=0.01, max_points=80)
    out["held"] = _branch_rows(problem, branch, False)
    return out


@styled
def draw_doubling(data: dict, path) -> Path:
    """The two panels of driven_cam_doubling.png."""
    fig, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(9.0, 4.0))
    for j, (name, rows) in enumerate(data.items()):
        label = "cam held at its speed" if name == "held" else f"motor, $J$ = {float(name):g} kg m$^2$"
        colour = "0.2" if name == "held" else f"C{j}"
        style = "-" if name == "held" else ("--", "-.", ":")[j % 3]
        ax_a.plot(rows["speed_hz"], rows["lowest"], color=colour, ls=style, label=label)
        for hz in rows["doubling_hz"]:
            ax_a.plot([hz], [-1.0], "o", color=colour, ms=4)
        if rows["fluctuation"]:
            ax_b.semilogy(rows["speed_hz"], rows["fluctuation"], color=colour, ls=style, label=label)
    ax_a.axhline(-1.0, color="0.6", lw=0.8)
    ax_a.set_xlabel(axis_label("mean cam speed", "Hz"))
    ax_a.set_ylabel(axis_label("smallest real part of the multipliers", "-"))
    ax_a.set_title("(a) stability of the period-1 orbit; dots: period doublings")
    ax_b.set_xlabel(axis_label("mean cam speed", "Hz"))
    ax_b.set_ylabel(axis_label("coefficient of speed fluctuation", "-"))
    ax_b.set_title("(b) the cam's speed over the orbit")
    legend_below(fig, ax_a, 2)
    return save_figure(fig, path)


def main(argv=None, out: Path = OUT) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, help="write the numbers the figure shows to this JSON file")
    args = parser.parse_args(argv)
    out.mkdir(parents=True, exist_ok=True)
    data = data_doubling()
    draw_doubling(data, out / "driven_cam_doubling.png")
    doublings = {name: rows["doubling_hz"] for name, rows in data.items()}
    print("period doublings [Hz of mean cam speed]: " + ", ".join(f"{k} {v}" for k, v in doublings.items()))
    if args.data:
        shown = {"driven_cam_doubling.png": {"doubling_hz": doublings,
                                             "points": {name: len(rows["speed_hz"]) for name, rows in data.items()}}}
        args.data.write_text(json.dumps(shown, indent=1))


if __name__ == "__main__":
    main()
