"""The driven cam's and the two followers' cost per revolution against the single
follower's, on camdyn's compiled core, at equal error in follower 1's angle.

Mechanisms (example files of examples/mechanisms/, all on the chapter 4 friction rig,
preset ``sundar2014-friction``, starting at 11.55 Hz from the static equilibrium):

- ``driven cam, motor``: ``driven_cam.toml`` (the cam on a DC motor, stall 1 N m, free
  speed 13.86 Hz, shaft 3e-4 kg m^2);
- ``driven cam, prescribed``: the same with ``drive.kind = "prescribed"`` (the shaft held
  at 11.55 Hz: the model's overhead without the shaft's dynamics);
- ``two followers, prescribed``: ``two_followers_prescribed.toml`` (two followers
  opposite on one cam held at 11.55 Hz, gravity off);
- ``two followers, motor``: the same on the motor of ``driven_cam.toml``.

Each is compared with the single follower (``driver.integrate`` on the cam-follower, as
``camdyn.simulate`` runs it) of the mechanism's own ``system`` (follower 1 and the cam) at
the mechanism's mean cam speed over its reference run. Every model runs over N cam
periods (of its starting speed; 30 unless ``--quick``), the follower angle sampled at 10
kHz, with DOP853 (the default), the largest step 1/32 of the period, ``atol = 1e-3
rtol``. Error: ``max |alpha - alpha_ref| / max |alpha_ref|`` of follower 1 against the
same model's own reference run at rtol 1e-12, atol 1e-15. Costs: CPU time of the call
(``time.process_time``, best of the interleaved rounds) and right-hand-side calls, per
revolution the cam turned; the ratio per state divides by the states under error control
(``registry.controlled_size``: 2, 5 and 7). At each error target the cost is
interpolated in log-log between the rungs around it (``bench_flexible_pivot.cost_at``).

Run: python benchmarks/bench_mechanisms.py [--quick]  (a few minutes; writes
benchmarks/mechanisms.json, or with ``--quick``, 5 periods, 3 rungs and 1 round, a smoke
check in the temporary directory)
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import tempfile
import time
from pathlib import Path

import numba
import numpy as np
from bench_flexible_pivot import cost_at
from bench_peers import machine, versions

from camdyn.integrator import driver
from camdyn.io.mechanism_config import load_mechanism
from camdyn.simulation.runner import prepare
from camdyn.simulation.two_followers import pack_two_followers
from camdyn.systems import registry as systems

HERE = Path(__file__).resolve().parent
EXAMPLES = HERE.parent / "examples" / "mechanisms"
PERIODS = 30
SAMPLE_RATE = 10e3  # [Hz]
RTOLS = (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
QUICK_RTOLS = (1e-6, 1e-8, 1e-10)
REFERENCE = (1e-12, 1e-15)  # rtol [-], atol [rad, rad/s]
TARGETS = (1e-6, 1e-8)      # relative error in alpha [-]
#: the motor of driven_cam.toml: stall torque [N m], free speed [rad/s] (13.86 Hz)
MOTOR = {"kind": "motor", "stall_torque": 1.0, "free_speed": 2.0 * math.pi * 13.86}
#: name -> (example file, changes to its drive)
CASES = {
    "driven cam, motor": ("driven_cam.toml", {}),
    "driven cam, prescribed": ("driven_cam.toml", {"kind": "prescribed", "stall_torque": 0.0,
                                                   "free_speed": math.inf}),
    "two followers, prescribed": ("two_followers_prescribed.toml", {}),
    "two followers, motor": ("two_followers_prescribed.toml", MOTOR),
}
#: the cam angle's and cam speed's state slots of each model
SHAFT = {systems.DRIVEN_CAM: (2, 3), systems.TWO_FOLLOWERS: (4, 5)}


@numba.njit
def _rhs_calls(system, p, states, modes, times, calls):
    """``calls`` calls of the model's compiled right-hand side, cycling over the states; a checksum."""
    f = np.empty(states.shape[1])
    y = states[0].copy()
    total = 0.0
    for i in range(calls):
        k = i % states.shape[0]
        for j in range(states.shape[1]):
            y[j] = states[k, j]
        systems.rhs(system, times[k], y, modes[k], p, f)
        total += f[1]
    return total


def best_ns(call, calls=200_000, rounds=5):
    """CPU time of one of ``call(calls)``'s calls [ns], best of rounds (after a warm-up)."""
    call(10)
    best = math.inf
    for _ in range(rounds):
        start = time.process_time()
        call(calls)
        best = min(best, (time.process_time() - start) / calls * 1e9)
    return best


class Model:
    """One model on the compiled core: system id, parameters, starting state, period [s],
    sample times [s], the reference angle [rad] and what its reference run measured."""

    def __init__(self, name, system_id, p, y0, period, periods):
        self.name, self.system_id, self.p, self.y0, self.period = name, system_id, p, y0, period
        self.states = int(systems.controlled_size(system_id))
        self.duration = periods * period
        self.t = np.arange(int(self.duration * SAMPLE_RATE) + 1) / SAMPLE_RATE
        self.room = 1000 + 200 * periods
        y, modes, counters = self.core(*REFERENCE)
        every = max(1, self.t.size // 500)
        self.samples = (y[::every].copy(), modes[::every].copy(), self.t[::every].copy())
        cam, speed = SHAFT.get(system_id, (None, None))
        #: revolutions the cam turned [-]
        self.revolutions = periods if cam is None else float(y[-1, cam] - y[0, cam]) / (2.0 * math.pi)
        self.mean_speed_hz = self.revolutions / self.duration
        self.reference = y[:, 0]
        self.scale = float(np.max(np.abs(self.reference)))
        self.diagnostics = {"states": self.states, "revolutions": self.revolutions,
                            "mean_speed_hz": self.mean_speed_hz, "alpha_scale_rad": self.scale,
                            **{f"reference_{k}_per_rev": v / self.revolutions for k, v in counters.items()}}
        if speed is not None:
            # the shaft over the last half of the run (past the start's transient)
            late = y[self.t >= self.duration / 2, speed]
            # coefficient of speed fluctuation (Norton, Design of Machinery, 2012, eq 11.18)
            self.diagnostics["speed_fluctuation"] = float(np.ptp(late) / abs(np.mean(late)))

    def core(self, rtol, atol, t=None):
        """camdyn's compiled core, DOP853, sampled at ``t`` [s] (default the sample times);
        returns the states, the modes and the counters."""
        t = self.t if t is None else t
        y, modes, _, counters = driver.integrate(self.system_id, self.p.copy(), self.y0.copy(), 0.0, self.duration,
                                                 t, float(rtol), float(atol), self.period / 32,
                                                 driver.METHOD_DOP853, 50_000_000, self.room, True, math.inf)
        if counters[driver.COUNT_STATUS] != driver.STATUS_OK:
            raise RuntimeError(driver.STATUS_MESSAGES[int(counters[driver.COUNT_STATUS])])
        names = {"accepted_steps": driver.COUNT_ACCEPTED, "rejected_steps": driver.COUNT_REJECTED,
                 "rhs_calls": driver.COUNT_RHS, "events": driver.COUNT_EVENTS}
        return y, modes, {name: int(counters[i]) for name, i in names.items()}

    def rhs_cost(self):
        """CPU time of one right-hand-side call [ns] at the reference run's samples (through
        the registry, as the driver calls it outside DOP853's stages)."""
        states, modes, times = self.samples
        return {"rhs_ns_per_call": best_ns(lambda n: _rhs_calls(self.system_id, self.p, states, modes, times, n))}

    def sparse_output_cost(self, rtol=1e-8, rounds=3):
        """CPU time [ms] and right-hand-side calls per revolution at ``rtol`` sampled once
        per period instead of at the sample rate (what the output's dense interpolation
        costs: DOP853's three extra stages in a step with an output time), best of rounds."""
        t = np.arange(0.0, self.duration, self.period)
        best = math.inf
        for _ in range(rounds):
            start = time.process_time()
            _, _, counters = self.core(rtol, 1e-3 * rtol, t)
            best = min(best, time.process_time() - start)
        return {"sparse_output_rtol": rtol, "sparse_output_cpu_ms_per_rev": 1e3 * best / self.revolutions,
                "sparse_output_rhs_calls_per_rev": counters["rhs_calls"] / self.revolutions}

    def run(self, rtol):
        """A rung: ``atol = 1e-3 rtol``; follower 1's angle [rad] and the counters."""
        y, _, counters = self.core(rtol, 1e-3 * rtol)
        return y[:, 0], counters

    def error(self, alpha):
        """Relative error [-]: max |alpha - alpha_ref| / max |alpha_ref|."""
        deviation = np.abs(np.asarray(alpha) - self.reference)
        return math.inf if not np.all(np.isfinite(deviation)) else float(np.max(deviation) / self.scale)


def mechanism_models(case, periods):
    """The mechanism of ``case`` and its single follower at the mechanism's mean speed."""
    source, changes = CASES[case]
    mechanism = load_mechanism(EXAMPLES / source)
    system, drive = mechanism.system, dataclasses.replace(mechanism.drive, **changes)
    speed = system.motion.angular_speed  # [rad/s]
    if mechanism.spec.kind == "driven-cam":
        prep = prepare(system)
        p = np.r_[prep.p, drive.slots()]
        y0 = np.array([prep.equilibrium.angle, 0.0, prep.theta0, speed, 0.0, 0.0, 0.0, 0.0])
        system_id = systems.DRIVEN_CAM
    else:
        p, y0 = pack_two_followers(system, mechanism.second, mechanism.spec.placement, drive)
        system_id = systems.TWO_FOLLOWERS
    period = 2.0 * math.pi / abs(speed)
    model = Model(case, system_id, p, y0, period, periods)
    single = system.with_values(**{"motion.speed": model.mean_speed_hz})
    prep = prepare(single)
    baseline = Model(f"{case}: single follower", systems.CAM_FOLLOWER, prep.p, prep.y0,
                     1.0 / model.mean_speed_hz, periods)
    return baseline, model


def measure(models, rtols, rounds):
    """Interleaved CPU timing: per rung, each model once per round, the best kept.
    Returns one list of rows per model."""
    for model in models:   # warm up, untimed
        model.run(rtols[0])
    curves = [[] for _ in models]
    for rtol in rtols:
        seconds, rows = [[] for _ in models], [None] * len(models)
        for _ in range(rounds):
            for i, model in enumerate(models):
                start = time.process_time()
                alpha, counters = model.run(rtol)
                seconds[i].append(time.process_time() - start)
                rows[i] = rows[i] or {"rtol": rtol, "error": model.error(alpha),
                                      **{k: v / model.revolutions for k, v in counters.items()}}
        for i, model in enumerate(models):
            rows[i]["cpu_ms_per_rev"] = 1e3 * min(seconds[i]) / model.revolutions
            curves[i].append(rows[i])
        print(f"  rtol {rtol:.0e}: " + ", ".join(
            f"{m.name} {r['cpu_ms_per_rev']:.3g} ms {r['rhs_calls']:.0f} calls {r['error']:.1e}"
            for m, r in zip(models, rows)), flush=True)
    return curves


def summarize(case, baseline, model):
    """Per error target: each model's cost and the mechanism/single ratios, plain and per state."""
    rows = []
    for target in TARGETS:
        row = {"case": case, "error": target, "states": model["states"]}
        for key in ("cpu_ms_per_rev", "rhs_calls", "accepted_steps"):
            a, b = cost_at(baseline["rungs"], target, key), cost_at(model["rungs"], target, key)
            row[f"single_{key}"], row[f"mechanism_{key}"] = a, b
            row[f"ratio_{key}"] = None if a is None or b is None else b / a
            row[f"ratio_per_state_{key}"] = (None if a is None or b is None
                                             else (b / model["states"]) / (a / baseline["states"]))
        rows.append(row)
    return rows


def table(rows):
    """The summary as a Markdown table."""
    text = lambda v, f: "-" if v is None else format(v, f)
    lines = ["| model | error | single ms/rev | calls/rev | model ms/rev | calls/rev | steps/rev (single, model) "
             "| ratio: time | calls | per state: time | calls |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['case']} ({r['states']} states) | {r['error']:.0e} | "
                     f"{text(r['single_cpu_ms_per_rev'], '.3g')} | {text(r['single_rhs_calls'], '.0f')} | "
                     f"{text(r['mechanism_cpu_ms_per_rev'], '.3g')} | {text(r['mechanism_rhs_calls'], '.0f')} | "
                     f"{text(r['single_accepted_steps'], '.0f')}, {text(r['mechanism_accepted_steps'], '.0f')} | "
                     f"{text(r['ratio_cpu_ms_per_rev'], '.2f')} | {text(r['ratio_rhs_calls'], '.2f')} | "
                     f"{text(r['ratio_per_state_cpu_ms_per_rev'], '.2f')} | "
                     f"{text(r['ratio_per_state_rhs_calls'], '.2f')} |")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="5 periods, 3 rungs, 1 round; to the temp dir")
    parser.add_argument("--cases", nargs="*", choices=list(CASES), help="run only these (default: all)")
    parser.add_argument("--out", type=Path, help="JSON file (default benchmarks/mechanisms.json)")
    args = parser.parse_args()
    periods, rtols, rounds = (5, QUICK_RTOLS, 1) if args.quick else (PERIODS, RTOLS, 3)
    out = args.out or (Path(tempfile.gettempdir()) / "mechanisms-quick.json" if args.quick
                       else HERE / "mechanisms.json")
    results = {"machine": machine(), "versions": versions(), "periods": periods,
               "settings": {"rtols": list(rtols), "rounds": rounds, "sample_rate_hz": SAMPLE_RATE,
                            "atol": "1e-3 rtol", "reference": REFERENCE, "method": "DOP853",
                            "timer": "time.process_time"},
               "cases": {}, "summary": []}
    for case in args.cases or CASES:
        print(case, flush=True)
        models = mechanism_models(case, periods)
        curves = measure(models, rtols, rounds)
        entry = {role: {**m.diagnostics, **m.rhs_cost(), **m.sparse_output_cost(), "rungs": rows}
                 for role, m, rows in zip(("single", "mechanism"), models, curves)}
        results["cases"][case] = entry
        results["summary"] += summarize(case, entry["single"], entry["mechanism"])
    out.write_text(json.dumps(results, indent=1))
    print(table(results["summary"]))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
