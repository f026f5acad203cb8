"""Bifurcation diagram of the Alzate / di Bernardo rig (preset ``alzate``, rigid contact)
over 100-750 rpm, for docs/profiles.md: the follower's position and velocity at cam angle 0
of every recorded revolution against the cam speed.

- translating_bifurcation.png: the diagram, with the lift-off speed and the 358 and 660
  rpm points marked;
- with ``--section FILE.nc``: the section itself (:func:`camdyn.analysis.poincare.poincare_section`);
- with ``--data FILE.json``: the numbers the figure's record keeps (speeds, settings,
  time taken, speeds whose runs stopped, revolutions run at a fallback tolerance).

Run: python examples/translating_bifurcation.py [--step RPM] [--transient N] [--revolutions N]
(about 6 minutes at the defaults here, two cores shared with other work)
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
from camdyn.io.lift_table import load_translating  # noqa: E402
from camdyn.io.netcdf import save_netcdf  # noqa: E402
from camdyn.plotting.translating import plot_poincare_diagram  # noqa: E402
from camdyn.simulation.translating import liftoff_speed  # noqa: E402

OUT = Path(__file__).resolve().parent.parent / "docs" / "figures"
#: cam speeds [rpm]: from, to, and the default step
LOWEST, HIGHEST, STEP = 100.0, 750.0, 2.0
#: revolutions dropped, then recorded, per speed, and the relative tolerance [-]
TRANSIENT, REVOLUTIONS, RTOL = 60, 40, 1e-10


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
    section = poincare_section(rig, speeds, args.transient, args.revolutions, RTOL)
    seconds = time.perf_counter() - start
    liftoff = liftoff_speed(rig) * 60.0 / (2.0 * math.pi)
    marks = {f"lift-off {liftoff:.2f} rpm": liftoff, "358 rpm": 358.0, "660 rpm": 660.0}
    args.out.mkdir(parents=True, exist_ok=True)
    plot_poincare_diagram(section, args.out / "translating_bifurcation.png", marks)
    if args.section is not None:
        save_netcdf(section, args.section)
    stopped = [f"{s:g}" for s, status in zip(speeds, section["status"].values) if status != "ok"]
    fallback = int(np.count_nonzero(np.isfinite(section["rtol"].values) & (section["rtol"].values != RTOL)))
    if args.data is not None:
        numbers = {"speeds_rpm": [float(speeds[0]), float(speeds[-1]), float(args.step)],
                   "transient": args.transient, "revolutions": args.revolutions, "rtol": RTOL,
                   "liftoff_rpm": round(liftoff, 4), "seconds": round(seconds, 1), "stopped": stopped,
                   "fallback_revolutions": fallback}
        args.data.write_text(json.dumps({"translating_bifurcation.png": numbers}, indent=1) + "\n")
    print(f"{speeds.size} speeds, {args.transient} + {args.revolutions} revolutions each, rtol {RTOL:g}: "
          f"{seconds:.0f} s; speeds stopped: {', '.join(stopped) or 'none'}; revolutions run at a fallback "
          f"tolerance: {fallback}")


if __name__ == "__main__":
    main()
