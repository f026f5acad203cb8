"""Comparison of the three impact-damping methods (residue, direct, output-error) on
records from the independent event-driven SciPy model of tests/test_impact_direct.py
(no camdyn synthesis): bias and spread of ``n`` and of the damping at the peak
penetration ``beta delta_peak^n`` against the noise, the sample rate, the number of
impacts and a wrong preset (the Hertz coefficient K 5 % high, the cam runout 2 % high).

The chapter 3 rig at 15 Hz, runout 4.375 mm, frictionless, ``beta = 24.7e9 N s/m^2.5``,
``n = 1.5``; the model starts 20 mrad off the cam at rest. Direct and output-error get the
record from its start (impacts of different approach velocity: the first ``N`` impacts);
the residue method, which needs periodic impacts one per revolution, gets ``N`` steady
impacts from 0.4 s on, its point estimate (no bootstrap) with ``n`` free. Each cell is
``SEEDS`` noise realisations: bias = mean error, spread = standard deviation of the
errors [%]; a method that refuses the record is counted, with its reason.

Usage:  python benchmarks/compare_impact_methods.py [--seeds N]
        (writes benchmarks/compare_impact_methods.json)
        python benchmarks/compare_impact_methods.py --table
        (prints the markdown table of docs/impact-damping.md from that JSON)
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

import camdyn
from camdyn.errors import CamdynError
from camdyn.identification.impact_damping import estimate_impact_damping
from camdyn.identification.impact_direct import estimate_impact_damping_direct
from camdyn.identification.impact_output_error import estimate_impact_damping_output_error
from camdyn.records.schema import make_record

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))
from test_impact_direct import E_RUN, SPEED, simulate_independent  # noqa: E402

BETA, N = 24.7e9, 1.5
RATE = 204.8e3
BASE = {"noise": 0.005, "rate": RATE, "impacts": 9, "preset": "right"}
CONDITIONS = ([("noise", x) for x in (0.001, 0.02, 0.05)] + [("rate", x) for x in (25.6e3, 51.2e3, 102.4e3)]
              + [("impacts", x) for x in (5, 18)] + [("preset", x) for x in ("K +5 %", "runout +2 %")])


def rig(preset: str):
    """The rig as the estimator believes it: right, K 5 % high (both Young's moduli, eq
    3.11: K is proportional to E*), or the runout 2 % high."""
    base = camdyn.load_system("sundar2014-impact")
    values = {"cam.runout": E_RUN, "friction.coefficient": 0.0}
    if preset == "K +5 %":
        values |= {"cam.youngs_modulus": 1.05 * base.cam.youngs_modulus,
                   "follower.youngs_modulus": 1.05 * base.follower.youngs_modulus}
    elif preset == "runout +2 %":
        values["cam.runout"] = 1.02 * E_RUN
    return base.with_values(**values)


def cut(t, channels, start, stop, step, noise, seed, runout):
    """Samples ``start <= t < stop`` [s], every ``step``-th, with Gaussian noise of
    ``noise`` times each channel's rms about its mean; the record's runout attribute [m]."""
    keep = np.flatnonzero((t >= start) & (t < stop))[::step]
    rng = np.random.default_rng(seed)
    out = {k: v[keep] + noise * np.std(v[keep]) * rng.standard_normal(keep.size) for k, v in channels.items()}
    return make_record(t[keep] - t[keep][0], out, speed_hz=SPEED, runout=runout)


def run_method(name, system, record):
    """Errors of n and of the damping at the peak [-], and the CPU time [s]; or the
    reason for a refusal."""
    call = {"direct": lambda: estimate_impact_damping_direct(system, record),
            "output-error": lambda: estimate_impact_damping_output_error(system, record),
            "residue": lambda: estimate_impact_damping(system, record, bootstrap=0)}[name]
    clock = time.process_time()
    try:
        est = call()
    except CamdynError as exc:
        return {"refused": str(exc).split(":")[0][:120]}
    return {"n_error": est.exponent / N - 1, "damping_error": est.damping_at_peak / (BETA * est.peak_penetration ** N)
            - 1, "cpu_s": time.process_time() - clock}


def cell(t, channels, setting, seeds):
    """One condition: every method on ``seeds`` noise realisations, summarised."""
    step = int(round(RATE / setting["rate"]))
    runout = E_RUN
    system = rig(setting["preset"])
    if setting["preset"] == "runout +2 %":
        runout = 1.02 * E_RUN
    k = setting["impacts"]
    windows = {"direct": (0.0, (k + 0.5) / SPEED), "output-error": (0.0, (k + 0.5) / SPEED),
               "residue": (0.4, 0.4 + (k + 1.5) / SPEED)}
    out = {}
    for name, (a, b) in windows.items():
        rows = [run_method(name, system, cut(t, channels, a, b, step, setting["noise"], seed, runout))
                for seed in range(seeds)]
        ok = [r for r in rows if "refused" not in r]
        summary = {"fits": len(ok), "refused": len(rows) - len(ok)}
        if len(ok) < len(rows):
            summary["reason"] = next(r["refused"] for r in rows if "refused" in r)
        for key in ("n_error", "damping_error"):
            x = np.array([r[key] for r in ok]) * 100
            summary[key.replace("error", "bias_pct")] = float(x.mean()) if x.size else None
            summary[key.replace("error", "spread_pct")] = float(x.std(ddof=1)) if x.size > 1 else None
        summary["cpu_s"] = float(np.median([r["cpu_s"] for r in ok])) if ok else None
        out[name] = summary
    return out


def _label(row) -> str:
    s = row["setting"]
    return {"baseline": "baseline", "noise": f"noise {s['noise'] * 100:g} %",
            "rate": f"{s['rate'] / 1e3:g} kHz", "impacts": f"{s['impacts']} impacts",
            "preset": s["preset"]}[row["condition"]]


def table(doc) -> str:
    """Markdown table: per condition and method, bias and spread of n and of the damping
    at the peak [%], median CPU time [s]."""
    lines = ["| condition | method | n: bias, spread | `beta delta_peak^n`: bias, spread | CPU |",
             "|---|---|---|---|---|"]
    for row in doc["rows"]:
        for i, (name, m) in enumerate(row["methods"].items()):
            first = _label(row) if i == 0 else ""
            if not m["fits"]:
                lines.append(f"| {first} | {name} | refused: {m['reason']} | | |")
                continue
            spread = lambda key: "" if m[key] is None else f", {m[key]:.2f} %"
            lines.append(f"| {first} | {name} | {m['n_bias_pct']:+.2f} %{spread('n_spread_pct')} | "
                         f"{m['damping_bias_pct']:+.2f} %{spread('damping_spread_pct')} | {m['cpu_s']:.2f} s |")
    return "\n".join(lines)


def figure(doc, path: str) -> None:
    """Bias of n and of the damping at the peak [%] of each method under each condition
    (the JSON written before), its spread over the seeds as error bars."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = doc["rows"]
    labels = [_label(r) for r in rows]
    names = list(rows[0]["methods"])
    fig, axes = plt.subplots(2, 1, figsize=(8.0, 6.0), sharex=True, layout="constrained")
    width = 0.8 / len(names)
    x = np.arange(len(rows))
    for ax, key, title in ((axes[0], "n", "exponent n"), (axes[1], "damping", "damping at the peak penetration")):
        for i, name in enumerate(names):
            bias = [r["methods"][name].get(f"{key}_bias_pct") for r in rows]
            spread = [r["methods"][name].get(f"{key}_spread_pct") or 0.0 for r in rows]
            ax.bar(x + (i - (len(names) - 1) / 2) * width, [np.nan if b is None else b for b in bias], width,
                   yerr=spread, label=name, capsize=2)
        ax.axhline(0.0, color="0.3", lw=0.8)
        ax.set_yscale("symlog", linthresh=0.1)
        ax.set_ylabel(f"bias of {title} [%]")
        ax.grid(axis="y", alpha=0.3)
    fig.legend(*axes[0].get_legend_handles_labels(), ncols=len(names), loc="outside upper center", frameon=False)
    axes[1].set_xticks(x, labels, rotation=30, ha="right")
    axes[0].set_title(f"impact damping from records of an independent model (beta = {doc['law']['beta']:.3g}, "
                      f"n = {doc['law']['n']:g}; {doc['seeds']} noise seeds)", fontsize=10)
    fig.savefig(path, dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--out", default=str(HERE / "compare_impact_methods.json"))
    parser.add_argument("--table", action="store_true", help="print the table of the JSON written before")
    parser.add_argument("--figure", help="draw the JSON written before into this figure file")
    args = parser.parse_args()
    if args.table:
        print(table(json.loads(Path(args.out).read_text())))
        return
    if args.figure:
        figure(json.loads(Path(args.out).read_text()), args.figure)
        return
    duration = 0.4 + (max(x for k, x in CONDITIONS if k == "impacts") + 2) / SPEED
    t, channels, _ = simulate_independent(BETA, N, duration=duration)
    estimate_impact_damping_output_error(rig("right"), cut(t, channels, 0.0, 0.6, 1, 0.005, 99, E_RUN))  # warm-up
    rows = []
    for key, value in [("baseline", None)] + CONDITIONS:
        setting = dict(BASE) if key == "baseline" else BASE | {key: value}
        result = cell(t, channels, setting, args.seeds)
        rows.append({"condition": key, "setting": setting, "methods": result})
        print(key, value, json.dumps(result), flush=True)
    doc = {"law": {"beta": BETA, "n": N}, "speed_hz": SPEED, "runout_m": E_RUN, "seeds": args.seeds,
           "base": BASE, "rows": rows}
    Path(args.out).write_text(json.dumps(doc, indent=2))


if __name__ == "__main__":
    main()
