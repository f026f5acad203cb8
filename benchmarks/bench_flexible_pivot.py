"""The flexible pivot's cost per revolution against the rigid pivot's, for camdyn and for
the solvers a user could pick instead, at equal error in the follower angle.

Both models are the chapter 3 impact rig at 16 Hz (preset ``sundar2014-impact``, the
bearing of ``camdyn.simulation.flexible_pivot.chapter3_flexible_pivot``: 2e7 N/m, 5 %
damping), over 10 revolutions from the static equilibrium, the follower angle sampled at
10 kHz. Each model's error is ``max |alpha - alpha_ref| / max |alpha_ref|`` against its
own reference, camdyn's compiled core at rtol 1e-12, atol 1e-15 (the peers' own tightest
run is compared with it too: ``reference_agreement`` in the JSON).

Tools, on each model, along a ladder of tolerances (rtol 1e-5 to 1e-11, atol = 1e-3 rtol
in every state, or per state with ``--atol natural``):

- camdyn's compiled core (``driver.integrate``): DOP853 (the default) and RODAS4
  (``METHOD_ROSENBROCK``); events at every contact switch;
- SciPy ``solve_ivp``: DOP853, LSODA, Radau and BDF (the implicit ones with SciPy's own
  finite-difference Jacobian), a numba-compiled right-hand side behind a thin Python
  wrapper, camdyn's largest step (1/32 of the period);
- numbalsoda's LSODA, a ``numba.cfunc`` right-hand side, where numbalsoda is installed.

The peers' right-hand sides (benchmarks/flexible_peer_model.py, on
benchmarks/peer_models.py) are written from the documented equations, independently of
camdyn's compiled model, and have no events (they step through the contact and friction
switches). Costs: CPU time of the call (``time.process_time``; best of the interleaved
rounds) and right-hand-side calls, per revolution; the ratio per state divides by the
states under error control, 2 (``alpha``, ``alpha'``) and 6 (and ``u``, ``u'``, ``v``,
``v'``). At each error target a tool's cost is interpolated in log-log between the rungs
around it, on the worst error at that or any tighter rung.

Run: python benchmarks/bench_flexible_pivot.py [--quick] [--atol natural]  (about 10
minutes; writes benchmarks/flexible_pivot.json, or with ``--quick``, 3 revolutions and 3
rungs, a smoke check in the temporary directory)
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from bench_peers import machine, versions
from flexible_peer_model import (
    COUNT,
    flexible_parameters,
    numbalsoda_flexible,
    numbalsoda_rigid,
    scipy_rhs,
)
from peer_models import parameters
from scipy.integrate import solve_ivp

from camdyn.integrator import driver
from camdyn.simulation.flexible_pivot import chapter3_flexible_pivot, flexible_pivot_equilibrium
from camdyn.systems import registry as systems

HERE = Path(__file__).resolve().parent
REVOLUTIONS = 10
SAMPLE_RATE = 10e3  # [Hz]
RTOLS = (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11)
QUICK_RTOLS = (1e-6, 1e-8, 1e-10)
REFERENCE = (1e-12, 1e-15)  # rtol [-], atol
TARGETS = (1e-6, 1e-8)      # relative error in alpha [-]


class Model:
    """One model on its solvers: camdyn's system, parameters and initial state, the peers'
    parameters, the sample times [s], the reference angle [rad] and the states' sizes."""

    def __init__(self, name, flexible, revolutions, atol_policy):
        rig = chapter3_flexible_pivot()
        p, y0, prep = flexible_pivot_equilibrium(rig.system, rig.pivot_stiffness, rig.pivot_damping)
        peer = parameters(rig.system, prep.theta0, prep.viscous_c)
        self.name, self.atol_policy = name, atol_policy
        if flexible:
            self.system_id, self.p, self.y0, self.states = systems.FLEXIBLE_PIVOT, p, y0, 6
            self.peer = flexible_parameters(peer, rig.pivot_stiffness, rig.pivot_damping)
        else:
            self.system_id, self.p, self.y0, self.states = systems.CAM_FOLLOWER, prep.p, prep.y0, 2
            self.peer = flexible_parameters(peer, 0.0, 0.0)
        self.period = 1.0 / rig.system.motion.speed
        self.revolutions = revolutions
        self.duration = revolutions * self.period
        self.t = np.arange(int(self.duration * SAMPLE_RATE) + 1) / SAMPLE_RATE
        y, counters = self.core(0, *REFERENCE)
        self.reference = y[:, 0]
        self.reference_steps = counters["accepted_steps"] / revolutions
        self.scale = float(np.max(np.abs(self.reference)))
        #: each controlled state's largest magnitude over the reference run [rad, rad/s, m, m/s]
        self.size = np.max(np.abs(y[:, :self.states]), axis=0)

    def atol(self, rtol):
        """Absolute tolerances of the controlled states: ``1e-3 rtol`` [rad] for the angle,
        and for the others the same (``plain``) or scaled by their size against the
        angle's (``natural``)."""
        base = 1e-3 * rtol
        if self.atol_policy == "natural":
            return base * self.size / self.size[0]
        return np.full(self.states, base)

    def core(self, method, rtol, atol):
        """camdyn's compiled core; ``atol`` one number (or per state, if the core takes it)."""
        if np.ndim(atol):
            tolerance = np.zeros(self.y0.size)
            tolerance[:self.states] = atol
        else:
            tolerance = float(atol)
        y, _, _, counters = driver.integrate(self.system_id, self.p, self.y0.copy(), 0.0, self.duration, self.t,
                                             float(rtol), tolerance, self.period / 32, method, 50_000_000,
                                             64 + 16 * self.revolutions, True, math.inf)
        if counters[driver.COUNT_STATUS] != driver.STATUS_OK:
            raise RuntimeError(driver.STATUS_MESSAGES[int(counters[driver.COUNT_STATUS])])
        names = {"accepted_steps": driver.COUNT_ACCEPTED, "rejected_steps": driver.COUNT_REJECTED,
                 "rhs_calls": driver.COUNT_RHS, "jacobians": driver.COUNT_JACOBIANS}
        return y, {name: int(counters[i]) for name, i in names.items()}

    def error(self, alpha):
        """Relative error [-]: max |alpha - alpha_ref| / max |alpha_ref|."""
        deviation = np.abs(np.asarray(alpha) - self.reference)
        return math.inf if not np.all(np.isfinite(deviation)) else float(np.max(deviation) / self.scale)


def camdyn_tool(method, vector):
    """camdyn's core with ``method`` (driver.METHOD_*); the angle's atol as one number
    unless ``vector`` (the per-state tolerances)."""
    def run(model, rtol):
        atol = model.atol(rtol)
        y, counters = model.core(method, rtol, atol if vector else atol[0])
        return y[:, 0], counters
    return run


def scipy_tool(method):
    """``solve_ivp(method)`` on the peer right-hand side, per-state atol."""
    def run(model, rtol):
        data = model.peer.copy()
        sol = solve_ivp(scipy_rhs(model.states, data), (0.0, model.duration), model.y0[:model.states],
                        method=method, t_eval=model.t, rtol=rtol, atol=model.atol(rtol), max_step=model.period / 32)
        if sol.status != 0:
            raise RuntimeError(sol.message)
        return sol.y[0], {"rhs_calls": int(data[COUNT]), "jacobians": int(sol.njev)}
    return run


def numbalsoda_tool():
    """numbalsoda's LSODA on the peer right-hand side (its atol is one number: the angle's)."""
    from numbalsoda import lsoda

    def run(model, rtol):
        data = model.peer.copy()
        rhs = numbalsoda_flexible if model.states == 6 else numbalsoda_rigid
        usol, success = lsoda(rhs.address, model.y0[:model.states].copy(), model.t, data=data, rtol=rtol,
                              atol=model.atol(rtol)[0], mxstep=10_000_000)
        if not success:
            raise RuntimeError("numbalsoda reports a failure")
        return usol[:, 0], {"rhs_calls": int(data[COUNT])}
    return run


def tools(vector):
    """Name -> runner ``(model, rtol) -> (alpha [rad], counters)``."""
    found = {"camdyn DOP853": camdyn_tool(driver.METHOD_DOP853, vector),
             "camdyn RODAS4": camdyn_tool(driver.METHOD_ROSENBROCK, vector)}
    for method in ("DOP853", "LSODA", "Radau", "BDF"):
        found[f"SciPy {method}"] = scipy_tool(method)
    try:
        found["numbalsoda LSODA"] = numbalsoda_tool()
    except ImportError as exc:
        print(f"numbalsoda not available: {exc}", file=sys.stderr)
    return found


def measure(model, runners, rtols, rounds, budget):
    """Interleaved CPU timing: per rung, each tool once per round, the best kept; a tool
    whose best passes ``budget`` [s] skips tighter rungs. Returns name -> rows."""
    for run in runners.values():   # compile and warm up, untimed
        run(model, rtols[0])
    curves, dropped = {name: [] for name in runners}, set()
    for rtol in rtols:
        seconds, rows = {}, {}
        for _ in range(rounds):
            for name, run in runners.items():
                if name in dropped or "failure" in rows.get(name, {}):
                    continue
                start = time.process_time()
                try:
                    alpha, counters = run(model, rtol)
                except RuntimeError as exc:
                    rows[name] = {"rtol": rtol, "failure": str(exc)}
                    continue
                seconds.setdefault(name, []).append(time.process_time() - start)
                rows.setdefault(name, {"rtol": rtol, "error": model.error(alpha),
                                       **{k: v / model.revolutions for k, v in counters.items()}})
        for name, row in rows.items():
            if name in seconds:
                row["cpu_ms_per_rev"] = 1e3 * min(seconds[name]) / model.revolutions
                dropped.update([name] if min(seconds[name]) > budget else [])
            curves[name].append(row)
        print(f"  {model.name} rtol {rtol:.0e}: " + ", ".join(
            f"{n} {r['cpu_ms_per_rev']:.3g} ms {r['rhs_calls']:.0f} calls {r['error']:.1e}"
            for n, r in rows.items() if "cpu_ms_per_rev" in r), flush=True)
    return curves


def cost_at(rows, target, key):
    """``key`` (per revolution) at the error ``target`` [-]: interpolated in log-log between
    the rungs around it on the error envelope (each rung's error the worst at it or any
    tighter rung), or the cheapest rung at or below it; None if never reached."""
    ok = [r for r in rows if "cpu_ms_per_rev" in r]
    errors = [max(r["error"] for r in ok[i:]) for i in range(len(ok))]
    values = [r[key] for r in ok]
    found = [v for e, v in zip(errors, values) if e <= target]
    for (e0, v0), (e1, v1) in zip(zip(errors, values), zip(errors[1:], values[1:])):
        if e0 > target >= e1 > 0 and math.isfinite(e0):
            weight = math.log(target / e0) / math.log(e1 / e0)
            found.append(math.exp(math.log(v0) + weight * (math.log(v1) - math.log(v0))))
    return min(found) if found else None


def summarize(results):
    """Per tool and error target: cost of each model and the flexible/rigid ratio per state."""
    rows = []
    rigid, flexible = results["models"]["rigid"], results["models"]["flexible"]
    for name in rigid["tools"]:
        for target in TARGETS:
            row = {"tool": name, "error": target}
            for key in ("cpu_ms_per_rev", "rhs_calls"):
                a = cost_at(rigid["tools"][name], target, key)
                b = cost_at(flexible["tools"].get(name, []), target, key)
                row[f"rigid_{key}"], row[f"flexible_{key}"] = a, b
                row[f"ratio_per_state_{key}"] = None if a is None or b is None else (b / 6) / (a / 2)
            rows.append(row)
    return rows


def table(rows):
    """The summary as a Markdown table."""
    text = lambda v, f: "-" if v is None else format(v, f)
    lines = ["| tool | error | rigid ms/rev | rigid calls/rev | flexible ms/rev | flexible calls/rev "
             "| ratio per state (time) | ratio per state (calls) |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['tool']} | {r['error']:.0e} | {text(r['rigid_cpu_ms_per_rev'], '.3g')} | "
                     f"{text(r['rigid_rhs_calls'], '.0f')} | {text(r['flexible_cpu_ms_per_rev'], '.3g')} | "
                     f"{text(r['flexible_rhs_calls'], '.0f')} | {text(r['ratio_per_state_cpu_ms_per_rev'], '.1f')} | "
                     f"{text(r['ratio_per_state_rhs_calls'], '.1f')} |")
    return "\n".join(lines)


def agreement(model):
    """max |alpha_SciPy - alpha_ref| / max |alpha_ref| of SciPy's DOP853 at rtol 1e-12 (the
    peer right-hand side, no events) against camdyn's reference [-]."""
    alpha, _ = scipy_tool("DOP853")(model, REFERENCE[0])
    return model.error(alpha)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="3 revolutions, 3 rungs, 1 round; to the temp dir")
    parser.add_argument("--atol", choices=("plain", "natural"), default="plain",
                        help="atol = 1e-3 rtol in every state, or scaled by each state's size")
    parser.add_argument("--vector", action="store_true", help="give camdyn's core the per-state atol too")
    parser.add_argument("--budget", type=float, default=20.0, help="CPU seconds past which a tool stops [s]")
    parser.add_argument("--tools", nargs="*", help="run only the tools whose names are given (default: all)")
    parser.add_argument("--out", type=Path, help="JSON file (default benchmarks/flexible_pivot.json)")
    args = parser.parse_args()
    revolutions, rtols, rounds = (3, QUICK_RTOLS, 1) if args.quick else (REVOLUTIONS, RTOLS, 3)
    out = args.out or (Path(tempfile.gettempdir()) / "flexible_pivot-quick.json" if args.quick
                       else HERE / "flexible_pivot.json")
    runners = {name: run for name, run in tools(args.vector).items() if not args.tools or name in args.tools}
    results = {"machine": machine(), "versions": versions(), "revolutions": revolutions,
               "settings": {"rtols": list(rtols), "rounds": rounds, "sample_rate_hz": SAMPLE_RATE,
                            "atol": args.atol, "camdyn_atol_per_state": args.vector, "reference": REFERENCE,
                            "budget_cpu_s": args.budget, "timer": "time.process_time", "tools": list(runners)},
               "models": {}}
    for name, flexible in (("rigid", False), ("flexible", True)):
        model = Model(name, flexible, revolutions, args.atol)
        results["models"][name] = {"states": model.states, "alpha_scale_rad": model.scale,
                                   "state_size": model.size.tolist(), "reference_steps_per_rev": model.reference_steps,
                                   "reference_agreement": agreement(model),
                                   "tools": measure(model, runners, rtols, rounds, args.budget)}
    results["summary"] = summarize(results)
    out.write_text(json.dumps(results, indent=1))
    print(table(results["summary"]))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
