"""Work-precision of camdyn's steppers in sustained contact: DOP853, Radau IIA, and DOP853
switched to Radau IIA by stiffness detection (``method="switching"``).

Cases (``camdyn.simulate``, alpha sampled at 20 kHz):

- ``ch4 from rest``: the chapter 4 rig (preset ``sundar2014-friction``, runout 1.75 mm,
  11.55 Hz), 30 revolutions from the static equilibrium;
- ``ch4 steady``: the same rig, 10 revolutions started on the state it reaches after 30
  (the cam back at its starting angle);
- ``ch3 impacts``: the chapter 3 rig (``sundar2014-impact``, runout 3.5 mm, 16 Hz), 30
  revolutions from rest.

Error: max |alpha - alpha_true| / max |alpha_true| over the samples, against SciPy's
DOP853 with events at rtol 1e-13 (camdyn.testing.oracle.reference_simulate, cached in the
temporary directory). Time: best of 3 rounds, the methods interleaved in one process.
Writes benchmarks/implicit.json (``--quick``: 2 rungs, 1 round, to the temporary directory).
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

import camdyn
from camdyn.simulation.runner import prepare
from camdyn.testing.oracle import reference_simulate

SAMPLE_RATE = 20e3  # [Hz]
METHODS = ("dop853", "radau", "switching")
RTOLS = (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
TRUTH = {"method": "DOP853", "rtol": 1e-13, "atol": 1e-15}


class Case:
    """A system, its start and its truth at the samples."""

    def __init__(self, label, preset, runout, speed, revolutions, settle=0):
        self.label, self.revolutions = label, revolutions
        self.system = camdyn.load_system(preset, {"cam.runout": runout}).with_values(**{"motion.speed": speed})
        prep = prepare(self.system)
        self.theta0, self.viscous_c = prep.theta0, prep.viscous_c
        period = 1.0 / speed
        y0 = prep.y0.copy()
        if settle:   # the state after `settle` revolutions, from the oracle
            _, y, _ = self._oracle(y0, settle * period, np.array([settle * period]), f"{label}-settle")
            y0 = np.array([y[0, -1], y[1, -1], 0.0])
        self.initial_state = (float(y0[0]), float(y0[1]))
        self.t = np.arange(int(round(revolutions * period * SAMPLE_RATE)) + 1) / SAMPLE_RATE
        _, y, _ = self._oracle(y0, revolutions * period, self.t, label)
        self.alpha_true = y[0]
        self.scale = float(np.max(np.abs(self.alpha_true)))

    def _oracle(self, y0, t_end, t_eval, tag):
        path = Path(tempfile.gettempdir()) / f"camdyn_implicit_truth_{tag.replace(' ', '_')}.npz"
        key = repr(self.system) + repr(TRUTH) + repr(y0.tolist()) + repr(t_end)
        if path.exists():
            cached = np.load(path)
            if str(cached["key"]) == key and cached["t"].shape == t_eval.shape:
                return cached["t"], cached["y"], {}
        print(f"  truth of {tag!r} ...", flush=True)
        t, y, info = reference_simulate(self.system, self.theta0, y0[:2], t_end, t_eval, self.viscous_c, **TRUTH)
        np.savez(path, key=key, t=t, y=y)
        return t, y, info

    def run(self, method, rtol):
        """``(seconds, error, counters)`` of one simulate() call."""
        start = time.perf_counter()
        ds = camdyn.simulate(self.system, revolutions=self.revolutions, sample_rate=SAMPLE_RATE, rtol=rtol,
                             atol=rtol * 1e-4, method=method, initial_state=self.initial_state, variables=["alpha"])
        seconds = time.perf_counter() - start
        alpha = ds["alpha"].values
        n = min(alpha.shape[0], self.alpha_true.shape[0])
        error = float(np.max(np.abs(alpha[:n] - self.alpha_true[:n])) / self.scale)
        counters = {k[7:]: int(v) for k, v in ds.attrs.items() if k.startswith("solver_")}
        return seconds, error, counters


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    rtols = (1e-6, 1e-8) if args.quick else RTOLS
    rounds = 1 if args.quick else 3
    cases = [Case("ch4 from rest", "sundar2014-friction", "1.75 mm", 11.55, 30),
             Case("ch4 steady", "sundar2014-friction", "1.75 mm", 11.55, 10, settle=30),
             Case("ch3 impacts", "sundar2014-impact", "3.5 mm", 16.0, 30)]
    for case in cases:   # compile and warm
        for method in METHODS:
            case.run(method, 1e-6)
    results = []
    for case in cases:
        for rtol in rtols:
            best = {}
            for _ in range(rounds):
                for method in METHODS:
                    seconds, error, counters = case.run(method, rtol)
                    if method not in best or seconds < best[method][0]:
                        best[method] = (seconds, error, counters)
            for method, (seconds, error, counters) in best.items():
                row = {"case": case.label, "method": method, "rtol": rtol, "error": error,
                       "ms_per_rev": 1e3 * seconds / case.revolutions,
                       "steps_per_rev": counters["accepted_steps"] / case.revolutions,
                       "rhs_per_rev": counters["rhs_calls"] / case.revolutions,
                       "rejected": counters["rejected_steps"], "jacobians": counters["jacobians"],
                       "radau_steps": counters.get("radau_steps", 0), "events": counters["events"]}
                results.append(row)
                print(f"{case.label:14s} {method:10s} rtol {rtol:.0e}  error {error:.2e}  "
                      f"{row['ms_per_rev']:.3f} ms/rev  steps/rev {row['steps_per_rev']:.0f}  "
                      f"rhs/rev {row['rhs_per_rev']:.0f}  rejected {row['rejected']}  jac {row['jacobians']}  "
                      f"radau {row['radau_steps']}", flush=True)
    out = Path(tempfile.gettempdir() if args.quick else Path(__file__).parent) / "implicit.json"
    out.write_text(json.dumps({"rtols": list(rtols), "rounds": rounds, "results": results}, indent=1))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
