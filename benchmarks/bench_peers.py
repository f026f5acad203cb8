"""Work-precision benchmark: camdyn against the compiled solvers a user could pick instead.

Every tool integrates the same equations (the cam-follower of docs/model.md section 3)
from the same initial state, over 30 cam revolutions sampled at 20 kHz, along a ladder of
tolerances; its error is measured against one truth and its time taken in this process,
interleaved with the others (for each tolerance, each tool once per round, 3 rounds, the
best time kept). The whole curve of every tool is reported, not a chosen rung.

- camdyn: ``camdyn.simulate(..., variables=["alpha"])`` (the whole call asked for the
  angle at the samples, as the peers are: checks, preparation, the Dataset) and its
  compiled core alone (``driver.integrate``); event location at every contact switch.
- SciPy ``solve_ivp``, LSODA and DOP853, with a plain Python right-hand side and with a
  numba-compiled one behind a thin Python wrapper; no events.
- numbalsoda, LSODA (and its DOP853), right-hand side a ``numba.cfunc``.
- CyRK ``nbsolve2_ivp`` (its C++ solver called from numba, the API its documentation
  recommends for a numba right-hand side), DOP853 (camdyn's scheme) and LSODA (CyRK's
  fastest method on these cases of RK45, DOP853, Tsit5, Vern7, Vern8 and LSODA),
  right-hand side a ``numba.cfunc``.

The peers' right-hand side (benchmarks/peer_models.py) is written independently of
camdyn's compiled model. None of the peers uses events: contact switches on the sign of
the penetration and Coulomb friction on the sign of the sliding velocity, and the
solvers step through the switches. Tolerances: rtol from 1e-4 to 1e-11 in half decades;
atol = rtol * 1e-3 times each state's scale (0.1 rad, 5 rad/s, the largest cam work
[J]) where a tool takes one per state (SciPy, CyRK), rtol * 1e-4 (the angle's) where it
takes one number (camdyn, numbalsoda). SciPy and CyRK get camdyn's largest step (1/12 of
the cam period, ``camdyn.simulation.limits.step_limits``); numbalsoda has no such option.

Truth: camdyn.testing.oracle.reference_simulate (SciPy DOP853 with events, restarted at
every switch), rtol 1e-13, atol 1e-15, cached in the temporary directory. Error: max
|alpha - alpha_true| / max |alpha_true| over the samples.

Setup (``make bench-peers`` does it): numbalsoda builds from source and needs a Fortran
compiler::

    apt-get install -y gfortran          # with sudo where not root
    python3 -m venv .venv-peers
    .venv-peers/bin/pip install -e . -r benchmarks/requirements-peers.txt
    .venv-peers/bin/python benchmarks/bench_peers.py [--quick]

Writes benchmarks/peers.json and docs/figures/work_precision.png, prints a summary and
writes it to bench_peers_summary.md in the temporary directory. ``--quick`` (3 rungs,
1 round, 5 revolutions) is a smoke check: its outputs all go to the temporary directory.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import tempfile
import time
from importlib import metadata
from pathlib import Path

import numpy as np
from peer_models import CALLS, cyrk_rhs, numba_rhs, numbalsoda_rhs, parameters, python_rhs
from scipy.integrate import solve_ivp

import camdyn
from camdyn.integrator import driver
from camdyn.simulation.limits import step_limits
from camdyn.simulation.runner import prepare
from camdyn.systems import registry as systems
from camdyn.testing.oracle import reference_simulate

HERE = Path(__file__).resolve().parent
CASES = {
    "ch4 sustained sliding contact": ("sundar2014-friction", {"cam.runout": "1.75 mm"}, 11.55),
    "ch3 impacts": ("sundar2014-impact", {"cam.runout": "3.5 mm"}, 16.0),
}
SAMPLE_RATE = 20e3  # [Hz]
RTOLS = tuple(float(f"{10 ** (-k / 2):.0e}") for k in range(8, 23))  # 1e-4, 3e-5, ..., 1e-11
QUICK_RTOLS = (1e-4, 1e-6, 1e-8)
STATE_SCALE = (0.1, 5.0)  # alpha [rad], alpha_dot [rad/s]
TARGETS = (1e-6, 1e-8)
TRUTH = {"method": "DOP853", "rtol": 1e-13, "atol": 1e-15}


class Case:
    """One benchmark case: system, initial state, sample times [s] and the truth."""

    def __init__(self, label, preset, overrides, speed, revolutions):
        self.label, self.revolutions = label, revolutions
        self.system = camdyn.load_system(preset, overrides).with_values(**{"motion.speed": speed})
        self.prep = prepare(self.system)
        self.period = 1.0 / speed  # [s]
        ds = camdyn.simulate(self.system, revolutions=revolutions, sample_rate=SAMPLE_RATE, rtol=1e-4, atol=1e-8)
        self.t = ds["time"].values.copy()
        self.duration = float(self.t[-1])
        self.y0 = self.prep.y0.copy()
        self.p = parameters(self.system, self.prep.theta0, self.prep.viscous_c)
        self.alpha_true, self.work_true = self._truth(preset)
        self.scale = float(np.max(np.abs(self.alpha_true)))
        self.atol_vector = np.array([*STATE_SCALE, max(float(np.max(np.abs(self.work_true))), 1e-6)]) * 1e-3

    def _truth(self, preset):
        """``(alpha [rad], W_cam [J])`` of the oracle at the samples, from the cache when it matches."""
        key = repr(self.system) + repr(TRUTH) + repr((self.prep.theta0, self.prep.y0.tolist(), self.prep.viscous_c))
        path = Path(tempfile.gettempdir()) / f"camdyn_peers_truth_{preset}_{self.revolutions}rev.npz"
        if path.exists():
            cached = np.load(path)
            if str(cached["key"]) == key and np.array_equal(cached["t"], self.t):
                return cached["alpha"], cached["work"]
        print(f"  computing the truth of {self.label!r} (oracle, DOP853 rtol 1e-13) ...", flush=True)
        start = time.perf_counter()
        _, y, _ = reference_simulate(self.system, self.prep.theta0, self.prep.y0, self.duration, self.t,
                                     self.prep.viscous_c, **TRUTH)
        print(f"  ... {time.perf_counter() - start:.0f} s", flush=True)
        np.savez(path, key=key, t=self.t, alpha=y[0], work=y[2])
        return y[0], y[2]

    def error(self, alpha):
        """Relative error [-]: max |alpha - alpha_true| / max |alpha_true|."""
        deviation = np.abs(np.asarray(alpha) - self.alpha_true)
        return math.inf if not np.all(np.isfinite(deviation)) else float(np.max(deviation) / self.scale)


def scalar_atol(rtol):
    """One absolute tolerance [rad, rad/s]: the angle's, ``rtol * 1e-3 * 0.1 rad``."""
    return rtol * 1e-3 * STATE_SCALE[0]


def run_camdyn(case, rtol):
    """``camdyn.simulate()`` asked for alpha only: alpha [rad] at the samples and the solver counters."""
    ds = camdyn.simulate(case.system, revolutions=case.revolutions, sample_rate=SAMPLE_RATE, rtol=rtol,
                         atol=scalar_atol(rtol), variables=["alpha"])
    names = ("accepted_steps", "rejected_steps", "rhs_calls")
    return ds["alpha"].values, {name: int(ds.attrs[f"solver_{name}"]) for name in names}


def run_camdyn_core(case, rtol):
    """camdyn's compiled core alone (``driver.integrate``, method chosen by the system)."""
    y, _, _, counters = driver.integrate(
        systems.CAM_FOLLOWER, case.prep.p, case.prep.y0.copy(), 0.0, case.duration, case.t, rtol,
        scalar_atol(rtol), step_limits(case.period)[0], 0, 50_000_000, 64 + 16 * case.revolutions, True,
        step_limits(case.period)[1])
    if counters[driver.COUNT_STATUS] != driver.STATUS_OK:
        raise RuntimeError(driver.STATUS_MESSAGES[int(counters[driver.COUNT_STATUS])])
    return y[:, 0], {name: int(counters[i]) for i, name in enumerate(driver.COUNTER_NAMES[:3])}


def scipy_tool(method, rhs):
    """A runner of ``solve_ivp(method)`` with the right-hand side ``rhs(p)`` builds."""
    def run(case, rtol):
        sol = solve_ivp(rhs(case.p), (0.0, case.duration), case.y0, method=method, t_eval=case.t, rtol=rtol,
                        atol=rtol * case.atol_vector, max_step=step_limits(case.period)[0])
        if sol.status != 0:
            raise RuntimeError(sol.message)
        return sol.y[0], {"rhs_calls": int(sol.nfev), "jacobians": int(sol.njev)}
    return run


def numbalsoda_tool(solver):
    """A runner of numbalsoda's ``lsoda`` or ``dop853``."""
    def run(case, rtol):
        data = case.p.copy()
        usol, success = solver(numbalsoda_rhs.address, case.y0.copy(), case.t, data=data, rtol=rtol,
                               atol=scalar_atol(rtol), mxstep=10_000_000)
        if not success:
            raise RuntimeError("numbalsoda reports a failure")
        return usol[:, 0], {"rhs_calls": int(data[CALLS])}
    return run


def cyrk_tool(method):
    """A runner of CyRK's ``nbsolve2_ivp`` (C++ CySolver, numba cfunc right-hand side)."""
    from CyRK import nbsolve2_ivp

    def run(case, rtol):
        sol = nbsolve2_ivp(cyrk_rhs.address, (0.0, case.duration), case.y0.copy(), method=method, t_eval=case.t,
                           args=case.p, rtol=rtol, atols=rtol * case.atol_vector, max_step=step_limits(case.period)[0])
        try:
            if not sol.success:
                raise RuntimeError(sol.message)
            return sol.y[0].copy(), {"accepted_steps": int(sol.steps_taken)}
        finally:
            sol.free()
    return run


def tools():
    """Name -> runner ``(case, rtol) -> (alpha [rad], counters)``, for the tools installed."""
    found = {"camdyn simulate()": run_camdyn, "camdyn core": run_camdyn_core}
    for method in ("LSODA", "DOP853"):
        found[f"SciPy {method}, Python RHS"] = scipy_tool(method, python_rhs)
        found[f"SciPy {method}, numba RHS"] = scipy_tool(method, numba_rhs)
    try:
        from numbalsoda import dop853, lsoda
        found["numbalsoda LSODA"] = numbalsoda_tool(lsoda)
        found["numbalsoda DOP853"] = numbalsoda_tool(dop853)
    except ImportError as exc:
        print(f"numbalsoda not available: {exc}", file=sys.stderr)
    try:
        found["CyRK DOP853"] = cyrk_tool("DOP853")
        found["CyRK LSODA"] = cyrk_tool("LSODA")
    except ImportError as exc:
        print(f"CyRK not available: {exc}", file=sys.stderr)
    return found


def measure(case, runners, rtols, rounds, budget):
    """Interleaved timing: per rung, each tool once per round; best time kept.

    A tool whose best time at a rung passes ``budget`` [s] is not run at tighter rungs.
    Returns name -> list of rows (rtol, ms_per_rev [ms], error [-], counters).
    """
    for run in runners.values():  # compile and warm up, untimed
        try:
            run(case, rtols[0])
        except RuntimeError:
            pass
    curves = {name: [] for name in runners}
    dropped = set()
    for rtol in rtols:
        seconds, rows = {}, {}
        for _ in range(rounds):
            for name, run in runners.items():
                if name in dropped or (name in rows and "failure" in rows[name]):
                    continue
                start = time.perf_counter()
                try:
                    alpha, counters = run(case, rtol)
                except RuntimeError as exc:
                    rows[name] = {"rtol": rtol, "failure": str(exc)}
                    continue
                seconds.setdefault(name, []).append(time.perf_counter() - start)
                if name not in rows:
                    rows[name] = {"rtol": rtol, "error": case.error(alpha), **counters}
        for name, row in rows.items():
            if name in seconds:
                row["ms_per_rev"] = 1e3 * min(seconds[name]) / case.revolutions
                row["round_seconds"] = seconds[name]
                if min(seconds[name]) > budget:
                    dropped.add(name)
            curves[name].append(row)
        shown = ", ".join(f"{n}: {r['ms_per_rev']:.3g} ms/rev {r['error']:.1e}" for n, r in rows.items()
                          if "ms_per_rev" in r)
        print(f"  rtol {rtol:.0e}: {shown}", flush=True)
    return curves


def envelope(rows):
    """``(error envelope [-], ms/rev [ms])`` of the rungs that ran: each rung's error replaced
    by the largest error at it or at any tighter rung, so that no lucky rung counts."""
    ok = [r for r in rows if "ms_per_rev" in r]
    errors = [r["error"] for r in ok]
    worst = [max(errors[i:]) for i in range(len(errors))]
    return worst, [r["ms_per_rev"] for r in ok]


def time_at(rows, target):
    """ms/rev [ms] at the error ``target`` [-], interpolated in log-log between the two rungs
    around it on the error envelope (or the cheapest rung at or below it); None if never reached."""
    errors, times = envelope(rows)
    found = [ms for e, ms in zip(errors, times) if e <= target]
    for i in range(len(errors) - 1):
        (e0, m0), (e1, m1) = (errors[i], times[i]), (errors[i + 1], times[i + 1])
        if e0 > target >= e1 > 0 and math.isfinite(e0):
            weight = math.log(target / e0) / math.log(e1 / e0)
            found.append(math.exp(math.log(m0) + weight * (math.log(m1) - math.log(m0))))
    return min(found) if found else None


def stagnation(rows):
    """Rungs [rtol] at which a tool's error does not fall below 0.9 of the looser rung's."""
    ok = [r for r in rows if "ms_per_rev" in r]
    return [b["rtol"] for a, b in zip(ok, ok[1:]) if b["error"] > 0.9 * a["error"]]


def summarize(results, revolutions):
    """Markdown: per case and error target, the fastest peer's time against camdyn's."""
    lines = [
        f"Work-precision, {revolutions} cam revolutions sampled at 20 kHz, one process, interleaved, best of "
        f"{results['settings']['rounds']}: each tool's time per revolution at an error target (max |alpha - "
        "alpha_true| / max |alpha_true| against a SciPy DOP853 truth at rtol 1e-13) is interpolated in log-log "
        "between the tolerance rungs around the target, on the worst error at that or any tighter rung. The peers "
        "step through contact and friction switches (no events); camdyn locates them. Speed-up: the fastest "
        "peer's time over camdyn's (below 1: the peer is faster); camdyn core is its compiled integrator alone "
        "(no Dataset, no derived channels).", "",
        "| case | error | fastest peer | peer [ms/rev] | camdyn simulate() [ms/rev] | speed-up "
        "| camdyn core [ms/rev] | speed-up (core) |",
        "|---|---|---|---|---|---|---|---|"]
    rows = []
    for label, case in results["cases"].items():
        curves = case["tools"]
        for target in TARGETS:
            peers = {n: time_at(rows_, target) for n, rows_ in curves.items() if not n.startswith("camdyn")}
            peers = {n: ms for n, ms in peers.items() if ms is not None}
            ours, core = time_at(curves["camdyn simulate()"], target), time_at(curves["camdyn core"], target)
            name = min(peers, key=peers.get) if peers else None
            row = {"case": label, "error": target, "fastest_peer": name, "peer_ms_per_rev": peers.get(name),
                   "camdyn_ms_per_rev": ours, "camdyn_core_ms_per_rev": core}
            rows.append(row)
            text = lambda v: "not reached" if v is None else f"{v:.3g}"
            ratio = lambda a, b: "-" if a is None or b is None else f"{a / b:.1f}x"
            lines.append(f"| {label} | {target:.0e} | {name or 'none reached it'} | {text(peers.get(name))} | "
                         f"{text(ours)} | {ratio(peers.get(name), ours)} | {text(core)} | "
                         f"{ratio(peers.get(name), core)} |")
    return "\n".join(lines) + "\n", rows


def notes(results):
    """Lines on failures, dropped rungs and errors that do not fall with the tolerance."""
    out = []
    for label, case in results["cases"].items():
        for name, rows in case["tools"].items():
            failed = [f"{r['rtol']:.0e} ({r['failure']})" for r in rows if "failure" in r]
            flat = stagnation(rows)
            ran = [r["rtol"] for r in rows]
            if failed:
                out.append(f"{label}, {name}: failed at rtol {', '.join(failed)}")
            if flat:
                out.append(f"{label}, {name}: error does not fall at rtol {', '.join(f'{r:.0e}' for r in flat)}")
            if len(ran) < len(results["settings"]["rtols"]):
                out.append(f"{label}, {name}: stopped after rtol {ran[-1]:.0e} (over the time budget)")
    return out


def plot(results, path):
    """Two panels, error against ms/rev, one line per tool; in camdyn's figure style and
    saved through its overlap check (tests/test_gallery_examples.py draws it from
    peers.json)."""
    import matplotlib.pyplot as plt

    from camdyn.plotting.style import figure_style, save_figure

    with figure_style():
        _draw(results, path, plt, save_figure)


def _draw(results, path, plt, save_figure):

    labels = list(results["cases"])
    fig, axes = plt.subplots(1, len(labels), figsize=(6.2 * len(labels), 5.2), layout="constrained")
    colours = plt.get_cmap("tab10").colors
    markers = "os^vD<>ph*"
    for ax, label in zip(np.atleast_1d(axes), labels):
        for i, (name, rows) in enumerate(results["cases"][label]["tools"].items()):
            ok = [r for r in rows if "ms_per_rev" in r]
            style = dict(color="black", lw=2.2) if name.startswith("camdyn") else dict(color=colours[i % 10], lw=1.3)
            ax.plot([r["error"] for r in ok], [r["ms_per_rev"] for r in ok], marker=markers[i % len(markers)],
                    ms=5, ls="--" if "core" in name or "Python" in name else "-", label=name, **style)
        ax.set(xscale="log", yscale="log", title=label, xlabel="error max|α − α_true| / max|α_true| [–]",
               ylabel="time per revolution [ms]")
        ax.grid(True, which="major", alpha=0.3)
    handles, names = np.atleast_1d(axes)[0].get_legend_handles_labels()
    fig.legend(handles, names, loc="outside lower center", ncols=4, frameon=False)
    fig.suptitle(f"Work-precision, {results['revolutions']} revolutions at 20 kHz (best of "
                 f"{results['settings']['rounds']}, interleaved)")
    path.parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, path)


def machine():
    """CPU, cores, OS and Python of this machine."""
    cpu = platform.processor() or platform.machine()
    try:
        cpu = next(line.split(":", 1)[1].strip() for line in Path("/proc/cpuinfo").read_text().splitlines()
                   if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    return {"cpu": cpu, "cores": os.cpu_count(), "os": platform.platform(), "python": platform.python_version()}


def versions():
    """Versions of camdyn and of every peer package found."""
    found = {}
    for name in ("camdyn", "numpy", "scipy", "numba", "llvmlite", "numbalsoda", "CyRK"):
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            found[name] = None
    return found


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="3 rungs, 1 round, 5 revolutions; outputs to the temp dir")
    parser.add_argument("--budget", type=float, default=60.0,
                        help="a tool whose best run passes this many seconds skips tighter rungs [s]")
    parser.add_argument("--redraw", action="store_true", help="only draw the figure again from peers.json")
    args = parser.parse_args()
    if args.redraw:
        plot(json.loads((HERE / "peers.json").read_text()), HERE.parent / "docs/figures/work_precision.png")
        return
    revolutions, rtols, rounds = (5, QUICK_RTOLS, 1) if args.quick else (30, RTOLS, 3)
    scratch = Path(tempfile.gettempdir())
    out_json = scratch / "peers-quick.json" if args.quick else HERE / "peers.json"
    out_figure = scratch / "work_precision-quick.png" if args.quick else HERE.parent / "docs/figures/work_precision.png"
    results = {"machine": machine(), "versions": versions(), "revolutions": revolutions,
               "settings": {"rtols": list(rtols), "rounds": rounds, "sample_rate_hz": SAMPLE_RATE,
                            "atol": "rtol * 1e-3 * (0.1 rad, 5 rad/s, max |W_cam| J), or rtol * 1e-4 as one number",
                            "truth": TRUTH, "budget_s": args.budget,
                            "events": "camdyn locates contact and friction switches; the peers step through them"},
               "cases": {}}
    runners = tools()
    for label, (preset, overrides, speed) in CASES.items():
        print(f"{label}:", flush=True)
        case = Case(label, preset, overrides, speed, revolutions)
        results["cases"][label] = {"preset": preset, "overrides": overrides, "speed_hz": speed,
                                   "samples": int(case.t.size), "alpha_scale_rad": case.scale,
                                   "atol_vector_per_rtol": (case.atol_vector).tolist(),
                                   "tools": measure(case, runners, rtols, rounds, args.budget)}
    summary, rows = summarize(results, revolutions)
    results["summary"], results["notes"] = rows, notes(results)
    out_json.write_text(json.dumps(results, indent=1))
    plot(results, out_figure)
    text = summary + "".join(f"\n- {line}" for line in results["notes"])
    (scratch / ("bench_peers_summary-quick.md" if args.quick else "bench_peers_summary.md")).write_text(text + "\n")
    print("\n" + text)
    print(f"\nwrote {out_json} and {out_figure}")


if __name__ == "__main__":
    main()
