"""Benchmark: friction estimation from a 10 s record at 10 kHz (target: under 1 s), with
and without the cam speed given; the half-power damping estimate; and the impact damping
(beta, n) from 20 impacts at 204.8 kHz (target: under 30 s on 2 cores), whose
per-impact simulations run batched in the compiled core.

Usage:  python benchmarks/bench_identify.py   (writes benchmarks/identify.json)
"""

from __future__ import annotations

import json
import platform
import time
from pathlib import Path

import camdyn
from camdyn.identification.friction import estimate_friction
from camdyn.identification.impact_damping import estimate_impact_damping
from camdyn.identification.impact_events import impact_events
from camdyn.identification.modal import (
    accelerance,
    half_power_damping,
    synthesize_impulse_test,
)
from camdyn.records.synthesis import synthesize


def best_of(fn, repeat=5):
    fn()  # warm: numba caches, pint registry
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def main():
    system = camdyn.load_system("sundar2014-friction", {"cam.runout": "5.25 mm"})
    record = synthesize(system, 11.55, revolutions=115.5, sample_rate=10e3, noise=0.01)
    given, est = best_of(lambda: estimate_friction(system, record))
    bare = record.copy()
    bare.attrs.pop("speed_hz")
    estimated, est2 = best_of(lambda: estimate_friction(system, bare))
    impulse = synthesize_impulse_test(damping_ratios=(0.02, 0.02), noise=0.01)
    modal, _ = best_of(lambda: half_power_damping(*accelerance(impulse), (500, 1400)))
    rig = camdyn.load_system("sundar2014-impact", {"cam.runout": "3.5 mm"})
    impacts = synthesize(rig, 15.0, revolutions=21, sample_rate=204.8e3, noise=0.01, settle=100)
    events, _ = best_of(lambda: impact_events(rig, impacts), repeat=2)
    ev = impact_events(rig, impacts)
    fixed, est_fixed = best_of(lambda: estimate_impact_damping(rig, impacts, exponent=1.5, bootstrap=64), repeat=2)
    free, est_free = best_of(lambda: estimate_impact_damping(rig, impacts, bootstrap=64), repeat=2)
    fit_only, _ = best_of(lambda: estimate_impact_damping(rig, None, events=[ev], bootstrap=0), repeat=2)
    result = {
        "machine": platform.processor() or platform.machine(),
        "record": f"{record.sizes['time']} samples ({record.sizes['time'] / 10e3:.2f} s at 10 kHz)",
        "friction_speed_given_s": given, "friction_speed_estimated_s": estimated,
        "mu_given": est.mu, "mu_estimated_speed": est2.mu, "half_power_s": modal,
        "impacts": ev.count,
        "impact_events_s": events,
        "impact_damping_n_fixed_s": fixed, "beta_n_fixed": est_fixed.beta,
        "impact_damping_n_free_s": free, "beta_n_free": est_free.beta, "n_free": est_free.exponent,
        "impact_damping_fit_only_s": fit_only,
    }
    for k, v in result.items():
        print(f"{k:32s} {v:.4g}" if isinstance(v, float) else f"{k:32s} {v}")
    Path(__file__).with_name("identify.json").write_text(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
