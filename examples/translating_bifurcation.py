"""Bifurcation diagram of the Alzate / di Bernardo rig (preset ``alzate``, rigid contact)
over 100-750 rpm, for docs/profiles.md and docs/continuation.md: the follower's position
and velocity at cam angle 0 of every recorded revolution against the cam speed, with the
continuation's branches of periodic orbits over it.

- translating_bifurcation.png: the diagram, with the lift-off speed and the 358 and 660
  rpm points marked, and the branches (:func:`branches`): the period-1 orbit from 700 rpm
  down to 640 and up to 760 rpm, the period-3 orbit from 358 rpm down to 300 and up to
  400 rpm, and the period-2 branch born at the period-1 orbit's period doubling;
- translating_branches.png and translating_branches_358.png: the branches over 640-760
  and 345-380 rpm, over diagrams of their own at finer speed steps (:data:`WINDOWS`);
- with ``--section FILE.nc``: the section itself (:func:`camdyn.analysis.poincare.poincare_section`);
- with ``--data FILE.json``: the numbers the figure's record keeps (speeds, settings,
  time taken, speeds whose runs stopped, revolutions run at a fallback tolerance).

Run: python examples/translating_bifurcation.py [--step RPM] [--transient N] [--revolutions N]
(about 6 minutes at the defaults here, two cores shared with other work; the branches take
seconds once compiled)
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402

from camdyn.analysis.poincare import poincare_section  # noqa: E402
from camdyn.continuation.switching import switch_branch  # noqa: E402
from camdyn.continuation.translating import RPM, trace_translating, translating_dataset  # noqa: E402
from camdyn.errors import CamdynError  # noqa: E402
from camdyn.io.lift_table import load_translating  # noqa: E402
from camdyn.io.netcdf import save_netcdf  # noqa: E402
from camdyn.plotting.translating import plot_poincare_diagram  # noqa: E402
from camdyn.simulation.translating import liftoff_speed, simulate_translating  # noqa: E402

OUT = Path(__file__).resolve().parent.parent / "docs" / "figures"
#: cam speeds [rpm]: from, to, and the default step
LOWEST, HIGHEST, STEP = 100.0, 750.0, 2.0
#: revolutions dropped, then recorded, per speed, and the relative tolerance [-]
TRANSIENT, REVOLUTIONS, RTOL = 60, 40, 1e-10
#: branches continued: (revolutions per period, start, stop) [rpm]
BRANCHES = ((1, 700.0, 640.0), (1, 700.0, 760.0), (3, 358.0, 300.0), (3, 358.0, 400.0))
#: revolutions from rest before the first orbit is sought, by its period: at 358 rpm the
#: chaotic transient outlasts 100 revolutions (Newton's method then lands on the unstable
#: period-3 orbit beyond the fold)
TRANSIENTS = {1: 100, 3: 300}
#: zoomed figures: file, first and last speed and step [rpm], revolutions dropped and recorded
WINDOWS = (("translating_branches.png", 640.0, 760.0, 1.0, 100, 30),
           ("translating_branches_358.png", 345.0, 380.0, 0.5, 100, 30))


def corner(rig, orbit):
    """The orbit's impact nearest to a joint of the cam profile: its cam angle [rad] and
    its distance from the joint [rad], from a simulation of one orbit period."""
    period = orbit.period
    ds = simulate_translating(rig, orbit.parameter / (2 * math.pi), period, sample_rate=64 * orbit.periods / period,
                              initial_state=orbit.state, rtol=RTOL)
    angles = (ds["event_time"].values[ds["event_kind"].values == "impact"] * orbit.parameter) % (2.0 * math.pi)
    joints = np.r_[rig.profile.joints, 2.0 * math.pi]
    distance = np.abs(angles[:, None] - joints[None, :])
    i, j = np.unravel_index(int(np.argmin(distance)), distance.shape)
    return f"impact at cam angle {angles[i]:.6f} rad, {distance[i, j]:.1e} rad from the joint at {joints[j]:.6f} rad"


def branches(rig):
    """The continued branches (:data:`BRANCHES`) and the period-doubled branches born on
    them within their range, as one dataset
    (:func:`camdyn.continuation.translating.translating_dataset`), and a line per branch:
    its range, why it ended and its bifurcations."""
    found, lines, problem = [], [], None
    for periods, start, stop in BRANCHES:
        problem, branch = trace_translating(rig, f"{start} rpm", f"{stop} rpm", periods, max_points=400,
                                            transient=TRANSIENTS[periods])
        found.append(branch)
        for item in branch.bifurcations:
            if item.kind != "period-doubling":
                continue
            try:
                found.append(switch_branch(problem, item, stop * RPM, step=0.01, max_step=0.05, max_points=400))
            except CamdynError as exc:
                lines.append(f"no switch at the doubling at {item.parameter / RPM:.3f} rpm: {exc}")
    for index, branch in enumerate(found):
        speeds = [o.parameter / RPM for o in branch.orbits]
        marks = ", ".join(f"{b.kind} {b.parameter / RPM:.4f} rpm" + (f" ({corner(rig, b.orbit)})"
                                                                        if b.kind == "multiplier-jump" else "")
                          for b in branch.bifurcations)
        lines.append(f"branch {index}: period {branch.orbits[0].periods}, {speeds[0]:.4f} to {speeds[-1]:.4f} rpm, "
                     f"{len(speeds)} orbits, {sum(o.stable for o in branch.orbits)} stable; {branch.stopped} "
                     f"({corner(rig, branch.orbits[-1])}); {marks or 'no bifurcation'}")
    return translating_dataset(problem, found), lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--step", type=float, default=STEP, help="speed step [rpm]")
    parser.add_argument("--transient", type=int, default=TRANSIENT, help="revolutions dropped")
    parser.add_argument("--revolutions", type=int, default=REVOLUTIONS, help="revolutions recorded")
    parser.add_argument("--out", type=Path, default=OUT, help="folder of the figure")
    parser.add_argument("--section", type=Path, help="write the section to this netCDF file")
    parser.add_argument("--data", type=Path, help="write the figure's numbers to this JSON file")
    args = parser.parse_args()
    rig, _ = load_translating("alzate")
    speeds = np.arange(LOWEST, HIGHEST + 0.5 * args.step, args.step)
    start = time.perf_counter()
    section = poincare_section(rig, speeds / 60.0, args.transient, args.revolutions, RTOL)
    seconds = time.perf_counter() - start
    liftoff = liftoff_speed(rig) * 60.0 / (2.0 * math.pi)
    marks = {f"lift-off {liftoff:.2f} rpm": liftoff, "358 rpm": 358.0, "660 rpm": 660.0}
    args.out.mkdir(parents=True, exist_ok=True)
    clock = time.perf_counter()
    continued, lines = branches(rig)
    branch_seconds = time.perf_counter() - clock
    print("\n".join(lines))
    plot_poincare_diagram(section, args.out / "translating_bifurcation.png", marks, branches=continued)
    for name, low, high, step, transient, revolutions in WINDOWS:
        near = poincare_section(rig, np.arange(low, high + 0.5 * step, step) / 60.0, transient, revolutions, RTOL)
        inside = (continued["speed_rpm"].values >= low - 5.0) & (continued["speed_rpm"].values <= high + 5.0)
        plot_poincare_diagram(near, args.out / name, None, branches=continued.isel(point=np.flatnonzero(inside)))
    if args.section is not None:
        save_netcdf(section, args.section)
    stopped = [f"{s:g}" for s, status in zip(speeds, section["status"].values) if status != "ok"]
    fallback = int(np.count_nonzero(np.isfinite(section["rtol"].values) & (section["rtol"].values != RTOL)))
    if args.data is not None:
        numbers = {"speeds_rpm": [float(speeds[0]), float(speeds[-1]), float(args.step)],
                   "transient": args.transient, "revolutions": args.revolutions, "rtol": RTOL,
                   "liftoff_rpm": round(liftoff, 4), "seconds": round(seconds, 1), "stopped": stopped,
                   "fallback_revolutions": fallback, "branches": lines, "branch_seconds": round(branch_seconds, 1)}
        args.data.write_text(json.dumps({"translating_bifurcation.png": numbers,
                                         **{name: {"window_rpm": [low, high, step]} for name, low, high, step, _, _ in
                                            WINDOWS}}, indent=1) + "\n")
    print(f"{speeds.size} speeds, {args.transient} + {args.revolutions} revolutions each, rtol {RTOL:g}: "
          f"{seconds:.0f} s; speeds stopped: {', '.join(stopped) or 'none'}; revolutions run at a fallback "
          f"tolerance: {fallback}")


if __name__ == "__main__":
    main()
