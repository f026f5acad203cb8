"""Figure of docs/mechanisms.md: a stick-slip cycle of the two-follower drum brake.

- two_followers_stick_slip.png: the drum brake (:func:`camdyn.simulation.two_followers.
  drum_brake`, two followers half a turn apart) with static friction ``mu_s = 0.4``
  under a slow PI speed controller (set point 2 rad/s): (a) the cam speed, sticking
  intervals of each follower shaded; (b) each follower's friction force over its normal
  force, with the cone ``+-mu_s`` and the kinetic ``+-mu_k``.

Run: python examples/two_followers.py [--data FILE]   (a few seconds once compiled;
``--data`` writes the numbers the figure shows)
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from camdyn.plotting.style import axis_label, legend_below, save_figure, styled  # noqa: E402
from camdyn.simulation.mechanisms import CamDrive  # noqa: E402
from camdyn.simulation.two_followers import drum_brake, simulate_two_followers  # noqa: E402

OUT = Path(__file__).resolve().parent.parent / "docs" / "figures"
STATIC = 0.4        # mu_s [-]
TARGET = 2.0        # the controller's set point [rad/s]
DURATION = 0.1      # [s]


def run():
    """The drum brake's stick-slip run (module docstring)."""
    rig = drum_brake()
    drive = CamDrive(shaft_inertia=2e-4, kind="controller", proportional=0.01, integral=0.5, target_speed=TARGET)
    return simulate_two_followers(rig.system, drive, second=rig.second, placement=rig.placement, duration=DURATION,
                                  sample_rate=20e3, initial_speed=TARGET, static_friction=STATIC, rtol=1e-10,
                                  atol=1e-12)


@styled
def draw(ds, path: Path) -> Path:
    """The two panels of the module docstring."""
    fig, (ax_a, ax_b) = plt.subplots(2, 1, figsize=(7.0, 6.0), sharex=True, layout="constrained")
    t = 1e3 * ds.time.values
    ax_a.plot(t, ds.cam_speed.values, color="k", label="cam speed")
    for k, colour in ((1, "C0"), (2, "C1")):
        stuck = ds.sticking.sel(follower=k).values == 1
        ax_a.fill_between(t, 0, 1, where=stuck, transform=ax_a.get_xaxis_transform(), color=colour, alpha=0.2,
                          step="mid", label=f"follower {k} sticks")
        f = ds.sel(follower=k)
        ratio = np.where(f.in_contact.values == 1, f.Ff.values / np.where(f.Fn.values > 0, f.Fn.values, np.nan),
                         np.nan)
        ax_b.plot(t, ratio, color=colour, label=f"follower {k}")
    mu_k = drum_brake().system.friction.coefficient
    for level, style, label in ((STATIC, "--", r"$\pm\mu_s$"), (mu_k, ":", r"$\pm\mu_k$")):
        ax_b.axhline(level, color="0.4", ls=style, label=label)
        ax_b.axhline(-level, color="0.4", ls=style)
    ax_a.set_ylabel(axis_label(r"cam speed $\dot\Theta$", "rad/s"))
    ax_a.set_title("(a) the cam stops, sticks and breaks loose under the PI controller")
    ax_a.legend(loc="upper right")
    ax_b.set_ylabel(r"friction over normal force $F_f / F_n$ [-]")
    ax_b.set_xlabel(axis_label("time $t$", "ms"))
    ax_b.set_title("(b) the friction each contact needs stays inside the cone while it sticks")
    legend_below(fig, ax_b, 4)
    return save_figure(fig, path)


def main(argv=None, out: Path = OUT) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, help="write the numbers the figure shows to this JSON file")
    args = parser.parse_args(argv)
    out.mkdir(parents=True, exist_ok=True)
    ds = run()
    draw(ds, out / "two_followers_stick_slip.png")
    kinds = ds.transition_kind.values
    counts = {kind: int(np.sum(kinds == kind)) for kind in ("stick", "slip", "reversal", "sprag")}
    first = float(ds.transition_time.values[kinds == "stick"][0])
    print(f"transitions: {counts}; first stick at {1e3 * first:.4f} ms; "
          f"cam speed {ds.cam_speed.values.min():.4g} to {ds.cam_speed.values.max():.4g} rad/s")
    if args.data:
        shown = {"two_followers_stick_slip.png": {"transitions": counts, "first_stick_s": first,
                                                  "cam_speed_min": float(ds.cam_speed.values.min()),
                                                  "cam_speed_max": float(ds.cam_speed.values.max())}}
        args.data.write_text(json.dumps(shown, indent=1))


if __name__ == "__main__":
    main()
