"""Benchmark: friction estimation from a 10 s record at 10 kHz (issue 4 asks < 1 s), with
and without the cam speed given, and the half-power damping estimate.

Usage:  python benchmarks/bench_identify.py   (writes benchmarks/identify.json)
"""

from __future__ import annotations

import json
import platform
import time
from pathlib import Path

import camdyn
from camdyn.identification.friction import estimate_friction
from camdyn.identification.modal import accelerance, half_power_damping, synthesize_impulse_test
from camdyn.synthesis import synthesize


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
    result = {
        "machine": platform.processor() or platform.machine(),
        "record": f"{record.sizes['time']} samples ({record.sizes['time'] / 10e3:.2f} s at 10 kHz)",
        "friction_speed_given_s": given, "friction_speed_estimated_s": estimated,
        "mu_given": est.mu, "mu_estimated_speed": est2.mu, "half_power_s": modal,
    }
    for k, v in result.items():
        print(f"{k:32s} {v:.4g}" if isinstance(v, float) else f"{k:32s} {v}")
    Path(__file__).with_name("identify.json").write_text(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
