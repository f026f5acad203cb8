"""Figure of docs/mechanisms.md: the flexible pivot's effect on the contact resonance.

- flexible_pivot_resonance.png: the chapter 3 impact rig (preset ``sundar2014-impact``)
  on a pivot bearing of stiffness ``kp`` in ``x`` and ``y``: (a) the linearized natural
  frequencies of the follower on its contact and its bearing, at the static equilibrium,
  against ``kp``, with the rigid pivot's contact resonance; (b) the normal contact force
  over 0.6 ms from the follower's last landing on the cam in the fourth revolution at
  16 Hz, rigid pivot and two bearings (5 % damping ratio).

Run: python examples/flexible_pivot.py [--data FILE] [--cost]   (about 30 s; ``--data``
writes the numbers the figure shows; ``--cost`` also times the rigid and the flexible
pivot per revolution at equal accuracy)
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
from camdyn.plotting.style import axis_label, legend_below, save_figure, styled  # noqa: E402
from camdyn.simulation.flexible_pivot import (  # noqa: E402
    chapter3_flexible_pivot,
    natural_frequencies,
    simulate_flexible_pivot,
)
from camdyn.simulation.runner import prepare  # noqa: E402

OUT = Path(__file__).resolve().parent.parent / "docs" / "figures"
#: bearing stiffnesses [N/m] of panel (a)
LADDER = tuple(float(k) for k in np.logspace(5, 10, 26))
#: bearings of panel (b) [N/m] (the preset's 2e7 and a softer one)
SHOWN = (2e7, 2e6)
#: bearing damping ratio on the follower's mass [-]
RATIO = 0.05
#: revolutions run; the last landing of the last one is shown
REVOLUTIONS = 4
#: sampling rate [Hz] and length [s] of the window after the landing
RATE, WINDOW = 500e3, 0.6e-3


def _damping(kp: float, mass: float) -> float:
    return 2.0 * RATIO * math.sqrt(kp * mass)


def data_resonance() -> dict:
    """Panel (a): frequencies [Hz] per stiffness [N/m] and the rigid pivot's [Hz]; panel
    (b): time in the last revolution [s] and the normal force [N] of each pivot."""
    rig = chapter3_flexible_pivot().system
    frequencies = [natural_frequencies(rig, kp).tolist() for kp in LADDER]
    rigid_hz = prepare(rig).equilibrium.natural_frequency
    period = 1.0 / rig.motion.speed
    runs = {"rigid": camdyn.simulate(rig, revolutions=REVOLUTIONS, sample_rate=RATE)}
    for kp in SHOWN:
        runs[f"{kp:g}"] = simulate_flexible_pivot(rig, kp, _damping(kp, rig.follower.mass), revolutions=REVOLUTIONS,
                                                  sample_rate=RATE)
    forces, onsets = {}, {}
    for name, ds in runs.items():
        t, touching = ds.time.values, ds.in_contact.values > 0.5
        # the last landing of the last revolution: the first sample in contact after a flight
        landing = np.flatnonzero(touching[1:] & ~touching[:-1] & (t[1:] >= (REVOLUTIONS - 1) * period)) + 1
        start = landing[-1]
        window = slice(start, start + int(WINDOW * RATE))
        forces[name] = ds.Fn.values[window].tolist()
        onsets[name] = float(t[start] - (REVOLUTIONS - 1) * period)
    return {"a": {"stiffness": list(LADDER), "frequencies": frequencies, "rigid_hz": rigid_hz},
            "b": {"time": (np.arange(int(WINDOW * RATE)) / RATE).tolist(), "Fn": forces, "onset": onsets,
                  "speed_hz": rig.motion.speed}}


@styled
def draw_resonance(data: dict, path) -> Path:
    """The two panels of flexible_pivot_resonance.png."""
    fig, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(9.0, 4.0))
    a = data["a"]
    kp = np.asarray(a["stiffness"])
    freq = np.asarray(a["frequencies"])
    for j, style in enumerate(("-", "--", ":")):
        ax_a.loglog(kp, freq[:, j], color=f"C{j}", ls=style, label=f"mode {j + 1}")
    ax_a.axhline(a["rigid_hz"], color="0.4", lw=0.8, label=f"rigid pivot, {a['rigid_hz']:.0f} Hz")
    for stiffness in SHOWN:
        ax_a.axvline(stiffness, color="0.75", lw=0.8)
    ax_a.set_xlabel(axis_label("bearing stiffness $k_p$", "N/m"))
    ax_a.set_ylabel(axis_label("natural frequency $f$", "Hz"))
    ax_a.set_title("(a) linearized at the static equilibrium")
    ax_a.legend(loc="upper left")
    b = data["b"]
    styles = {"rigid": ("0.2", "-"), f"{SHOWN[0]:g}": ("C0", "--"), f"{SHOWN[1]:g}": ("C3", ":")}
    for name, values in b["Fn"].items():
        colour, style = styles[name]
        label = "rigid pivot" if name == "rigid" else f"$k_p$ = {float(name):.0e} N/m"
        ax_b.plot(1e3 * np.asarray(b["time"])[:len(values)], values, color=colour, ls=style, label=label)
    ax_b.set_xlabel(axis_label("time from the landing $t$", "ms"))
    ax_b.set_ylabel(axis_label("normal contact force $F_n$", "N"))
    ax_b.set_title(f"(b) the last landing at {b['speed_hz']:g} Hz, bearing damping ratio {RATIO:g}")
    legend_below(fig, ax_b, 3)
    return save_figure(fig, path)


def cost(repeats: int = 7) -> dict:
    """Wall time of the compiled call per revolution [ms] and per state [ms], best of
    ``repeats``, and accepted steps per revolution of the rigid
    and the preset's flexible pivot at 16 Hz over 10 revolutions, at the tolerances that
    give each model the same error in the follower angle (against its own run at rtol
    1e-12), and that error [rad]."""
    pivot = chapter3_flexible_pivot()
    rig, revolutions = pivot.system, 10

    def rigid(rtol):
        return camdyn.simulate(rig, revolutions=revolutions, sample_rate=2e3, rtol=rtol, atol=1e-3 * rtol)

    def flexible(rtol):
        return simulate_flexible_pivot(rig, pivot.pivot_stiffness, pivot.pivot_damping, revolutions=revolutions,
                                       sample_rate=2e3, rtol=rtol, atol=1e-3 * rtol)

    out = {}
    for name, run, states in (("rigid", rigid, 2), ("flexible", flexible, 6)):
        reference = run(1e-12).alpha.values
        for rtol in (1e-7, 1e-8, 1e-9, 1e-10):
            run(rtol)
            best = math.inf
            for _ in range(repeats):   # the compiled call's own time (the attribute elapsed_s)
                ds = run(rtol)
                best = min(best, ds.attrs["elapsed_s"])
            error = float(np.max(np.abs(ds.alpha.values - reference)))
            ms = 1e3 * best / revolutions
            steps = ds.attrs.get("solver_accepted_steps", ds.attrs.get("accepted_steps")) / revolutions
            out[f"{name} {rtol:g}"] = {"error_rad": error, "ms_per_revolution": ms, "ms_per_state": ms / states,
                                       "steps_per_revolution": steps}
    return out


def main(argv=None, out: Path = OUT) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, help="write the numbers the figure shows to this JSON file")
    parser.add_argument("--cost", action="store_true", help="time the rigid and flexible pivot per revolution")
    args = parser.parse_args(argv)
    out.mkdir(parents=True, exist_ok=True)
    data = data_resonance()
    draw_resonance(data, out / "flexible_pivot_resonance.png")
    lowest = {f"{k:g}": f[0] for k, f in zip(data["a"]["stiffness"], data["a"]["frequencies"])}
    print(f"rigid pivot: {data['a']['rigid_hz']:.1f} Hz; lowest mode: "
          + ", ".join(f"{k} N/m {v:.1f} Hz" for k, v in lowest.items()))
    print("last landing [ms into the fourth revolution]: "
          + ", ".join(f"{k} {1e3 * v:.3f}" for k, v in data["b"]["onset"].items()))
    if args.cost:
        for name, row in cost().items():
            print(f"{name}: error {row['error_rad']:.2e} rad, {row['ms_per_revolution']:.3f} ms/rev, "
                  f"{row['ms_per_state']:.3f} ms/rev/state, {row['steps_per_revolution']:.0f} steps/rev")
    if args.data:
        shown = {"flexible_pivot_resonance.png": {"rigid_hz": data["a"]["rigid_hz"],
                                                  "lowest_hz": lowest, "landing_s": data["b"]["onset"]}}
        args.data.write_text(json.dumps(shown, indent=1))


if __name__ == "__main__":
    main()
