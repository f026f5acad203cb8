"""What one right-hand-side call costs, and what that leaves for the 2x speed goal.

Times, in one process and interleaved (best of ``--rounds``, ``--calls`` calls each), the
cam-follower's compiled right-hand side as camdyn's integrator calls it (through the
model registry, with the hybrid mode) and the peers' one (benchmarks/peer_models.py,
written independently; the one numbalsoda and CyRK call), at states of the two cases of
benchmarks/bench_peers.py: in sustained contact (chapter 4 rig) and in flight and in
contact (chapter 3 rig).

Then, from the work-precision results in benchmarks/peers.json (and adams.json where
present), the bound it sets: for camdyn to be twice as fast as the fastest peer at an
error, its whole time per revolution must be at most half the peer's; divided by the
cost of one call, that is the most right-hand-side calls per revolution camdyn may make
even if stepping, error control, events and output cost nothing, against the calls
camdyn's DOP853 (and its Adams method) needs at that error.

Usage:  python benchmarks/bench_rhs_cost.py [--calls N] [--rounds R]   (writes benchmarks/rhs_cost.json)
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import time
from pathlib import Path

import numba
import numpy as np
from peer_models import compiled_derivative, parameters

import camdyn
from camdyn.simulation.runner import prepare
from camdyn.systems import registry as systems

HERE = Path(__file__).resolve().parent
CAM_FOLLOWER = systems.CAM_FOLLOWER
CASES = {  # as bench_peers.CASES: preset, overrides, speed [Hz], times of the states [s]
    "ch4 sustained sliding contact": ("sundar2014-friction", {"cam.runout": "1.75 mm"}, 11.55, (0.5, 1.0, 1.5)),
    "ch3 impacts": ("sundar2014-impact", {"cam.runout": "3.5 mm"}, 16.0, (0.5, 1.0, 1.5)),
}
TARGETS = (1e-6, 1e-8)


@numba.njit
def _camdyn_calls(p, states, modes, times, calls):
    """``calls`` calls of camdyn's right-hand side, cycling over the states; a checksum."""
    f = np.empty(states.shape[1])
    y = states[0].copy()
    total = 0.0
    for i in range(calls):
        k = i % states.shape[0]
        for j in range(states.shape[1]):
            y[j] = states[k, j]
        systems.rhs_inline(CAM_FOLLOWER, times[k], y, modes[k], p, f)
        total += f[1]
    return total


@numba.njit
def _peer_calls(p, states, times, calls):
    """The same with the peers' right-hand side."""
    total = 0.0
    for i in range(calls):
        k = i % states.shape[0]
        total += compiled_derivative(times[k], states[k, 0], states[k, 1], p)[1]
    return total


def _case(preset, overrides, speed, at):
    """Parameters of both right-hand sides and the states (with modes) at times ``at`` [s]."""
    system = camdyn.load_system(preset, overrides).with_values(**{"motion.speed": speed})
    prep = prepare(system)
    ds = camdyn.simulate(system, duration=max(at) + 0.01, sample_rate=2e4, rtol=1e-10, atol=1e-13)
    rows = [int(np.searchsorted(ds["time"].values, t)) for t in at]
    times = ds["time"].values[rows].copy()
    states = np.array([[ds["alpha"].values[r], ds["alpha_dot"].values[r], 0.0] for r in rows])
    modes = np.zeros((len(rows), systems.mode_size(CAM_FOLLOWER)))
    for k in range(len(rows)):
        systems.initial_mode(CAM_FOLLOWER, times[k], states[k], prep.p, modes[k])
    f_camdyn, f_peer = np.empty(3), np.empty((len(rows), 3))
    for k in range(len(rows)):   # the two right-hand sides agree (else the timing compares nothing)
        systems.rhs(CAM_FOLLOWER, times[k], states[k], modes[k], prep.p, f_camdyn)
        f_peer[k] = compiled_derivative(times[k], states[k, 0], states[k, 1],
                                        parameters(system, prep.theta0, prep.viscous_c))
        if not np.allclose(f_camdyn[:2], f_peer[k, :2], rtol=1e-9, atol=1e-9):
            raise RuntimeError(f"the right-hand sides differ at t = {times[k]}: {f_camdyn} against {f_peer[k]}")
    contact = [bool(m[0] > 0.5) for m in modes]
    return prep.p, parameters(system, prep.theta0, prep.viscous_c), states, modes, times, contact


def cost(calls, rounds):
    """Per case: ns per call of camdyn's and the peers' right-hand side (best of rounds)."""
    out = {}
    for label, (preset, overrides, speed, at) in CASES.items():
        p, q, states, modes, times, contact = _case(preset, overrides, speed, at)
        _camdyn_calls(p, states, modes, times, 10)
        _peer_calls(q, states, times, 10)
        best = {"camdyn": math.inf, "peer": math.inf}
        for _ in range(rounds):
            start = time.perf_counter()
            _camdyn_calls(p, states, modes, times, calls)
            best["camdyn"] = min(best["camdyn"], (time.perf_counter() - start) / calls * 1e9)
            start = time.perf_counter()
            _peer_calls(q, states, times, calls)
            best["peer"] = min(best["peer"], (time.perf_counter() - start) / calls * 1e9)
        out[label] = {"camdyn_ns_per_call": best["camdyn"], "peer_ns_per_call": best["peer"],
                      "states_in_contact": contact}
        print(f"{label}: camdyn {best['camdyn']:.0f} ns per call, peers' {best['peer']:.0f} ns "
              f"(states in contact: {contact})", flush=True)
    return out


def _at(rows, error, key):
    """``key`` of the cheapest rung whose error, and every tighter rung's, is at most ``error``."""
    good = [r for r in rows if "error" in r and "ms_per_rev" in r]
    for i, row in enumerate(good):
        if all(r["error"] <= error for r in good[i:]):
            return row[key], row
    return math.nan, None


def bound(costs):
    """The most calls per revolution camdyn may make to be 2x the fastest peer, per target."""
    peers = json.loads((HERE / "peers.json").read_text())
    adams = json.loads((HERE / "adams.json").read_text()) if (HERE / "adams.json").exists() else None
    revolutions = peers["revolutions"]
    out = []
    for row in peers["summary"]:
        case, error = row["case"], row["error"]
        tools = peers["cases"][case]["tools"]
        peer_ms = row["peer_ms_per_rev"]
        ns = costs[case]["camdyn_ns_per_call"]
        allowed = 0.5 * peer_ms * 1e6 / ns
        calls, _ = _at(tools["camdyn core"], error, "rhs_calls")
        peer_calls, _ = _at(tools.get(row["fastest_peer"], []), error, "rhs_calls")
        entry = {"case": case, "error": error, "fastest_peer": row["fastest_peer"], "peer_ms_per_rev": peer_ms,
                 "peer_rhs_per_rev": peer_calls / revolutions if math.isfinite(peer_calls) else None,
                 "camdyn_ns_per_call": ns, "calls_per_rev_allowed_for_2x": allowed,
                 "camdyn_dop853_rhs_per_rev": calls / revolutions if math.isfinite(calls) else None}
        if adams and case in adams:              # adams.json stores its counters per revolution
            per_rev, _ = _at(adams[case]["timing"].get("camdyn core Adams", []), error, "rhs_calls")
            entry["camdyn_adams_rhs_per_rev"] = per_rev if math.isfinite(per_rev) else None
        out.append(entry)
        shown = {k: (f"{v:.3g}" if isinstance(v, float) else v) for k, v in entry.items()}
        print(shown, flush=True)
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=2_000_000)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    costs = cost(args.calls, args.rounds)
    result = {"machine": {"cpu": platform.processor() or platform.machine(), "python": platform.python_version()},
              "calls": args.calls, "rounds": args.rounds, "cost": costs, "bound": bound(costs)}
    (HERE / "rhs_cost.json").write_text(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
