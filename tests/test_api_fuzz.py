"""Fuzzing the public Python API: whatever the arguments, a call returns or raises one of
camdyn's own exceptions (:class:`camdyn.errors.CamdynError`), never a foreign one
(``AttributeError``, ``TypeError``, ``IndexError``, numpy's or pint's), and never runs
past its time limit.

One Hypothesis property draws a public function and its arguments: mostly values of the
wrong kind, out of range, non-finite, misspelt or of another family (refused before any
work), and a small share of valid short calls on the warm compiled cache. Where a valid
call would start long work (a branch's continuation, a sweep, a Lyapunov run, an impact
identification), that work is replaced by a stand-in that stops it at once: the call
counts as accepted. The examples are derandomized, so every run tries the same calls;
the outcomes are counted per function and printed (``pytest -s``).
"""

from __future__ import annotations

import math
import os
import signal
import time
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import camdyn
from camdyn.errors import CamdynError

#: Generated calls in all [-]; the property stops at this many examples.
#: ``CAMDYN_FUZZ_CALLS=N`` tries N random calls instead (not derandomized): the longer runs
#: outside CI that docs/reliability.md reports.
CALLS = int(os.environ.get("CAMDYN_FUZZ_CALLS", 1100))
DERANDOMIZE = "CAMDYN_FUZZ_CALLS" not in os.environ
#: Longest a single call may take [s] (a short simulation on the warm cache takes well
#: under a second; 2 shared cores can be slow).
CALL_LIMIT = 20.0
#: A call still running after this long is stopped by an alarm and counted as a hang [s].
HANG_LIMIT = 60

PRESET = "sundar2014-impact"
NAN, INF = float("nan"), float("inf")

#: Values of every wrong kind: None, booleans, integers too large for C, non-finite and
#: extreme floats, text (empty, misspelt, with the wrong unit, a decimal comma), bytes,
#: containers, complex numbers, numpy scalars and arrays, paths that do not exist.
ODD = [None, True, False, 0, -1, 1, 3, 2 ** 70, -(2 ** 70), 0.0, -0.0, 1e-300, 1e300, NAN, INF, -INF, 3.5,
       "", "fast", "16 Hz", "3.5 mm", "nan Hz", "1e400 Hz", "-5 Hz", "0 Hz", "1 kg", "3,5 mm", "16", "16 Hz Hz",
       b"16 Hz", [], [1.0, 2.0], (1.0, 2.0), {}, {"a": 1}, object(), 1j, np.float64(NAN), np.int64(3),
       np.array([]), np.array([1.0, NAN]), np.ones((2, 2)), Path("no/such/file.toml"), "no/such/file.csv",
       "sundar2014-impakt", PRESET, "x" * 5000]

odd = st.sampled_from(ODD)


def either(valid: list, share: int = 1):
    """``valid`` values ``share`` times in 10 draws, else :data:`ODD` ones (Hypothesis
    has no weights: the choice is a sampled digit)."""
    return st.integers(0, 9).flatmap(lambda d: st.sampled_from(valid) if d < share else odd)


def optional_kwargs(draw, options: dict) -> dict:
    """A random subset of ``options`` (name -> strategy), each drawn."""
    names = draw(st.lists(st.sampled_from(sorted(options)), unique=True, max_size=len(options)))
    return {name: draw(options[name]) for name in names}


class Accepted(Exception):
    """Raised by a stand-in for long work: the inputs passed every check before it."""


def _accepted(*_args, **_kwargs):
    raise Accepted


# --- the calls: each draws (name, function, args, kwargs) --------------------------------------------


def _simulate(draw, ctx):
    system = draw(either([ctx["rig"], PRESET, "sundar2014-friction"], 5))
    speed = draw(either([None, 16.0, "12 Hz", "693 rpm"], 6))
    revolutions = draw(either([0.5, 1.0, 2.0], 6))
    kwargs = optional_kwargs(draw, {
        "sample_rate": either([2e3, 20e3], 5), "rtol": either([1e-6, 1e-8], 5), "atol": either([1e-8, 1e-10], 5),
        "duration": either([0.02, 0.1], 3), "method": either(["auto", "dop853", "explicit", "rosenbrock"], 5),
        "initial_state": either([(0.0, 0.0)], 2), "max_step": either([None, 1e-3], 5),
        "max_steps": either([10 ** 6], 5), "variables": either([None, ["alpha"], ["Nx", "impact"]], 5)})
    return "simulate", camdyn.simulate, (system, speed, revolutions), kwargs


def _load_system(draw, ctx):
    source = draw(either([PRESET, "sundar2014-friction", "alzate2007-standin"], 4))
    overrides = draw(either([None, {}, {"cam.runout": "3.5 mm"}, {"cam.runnout": "1 mm"},
                             {"cam.runout": draw(odd)}, {"motion.speed": draw(odd)}, {"x": 1}, {1: "3.5 mm"}],
                            6))
    return "load_system", camdyn.load_system, (source, overrides), {}


def _equilibrium(draw, ctx):
    system = draw(either([ctx["rig"], PRESET], 3))
    if draw(st.booleans()):
        return "natural_frequency", camdyn.natural_frequency, (system,), {}
    theta0 = draw(either([None, 0.0, 0.5], 5))
    return "static_equilibrium", camdyn.static_equilibrium, (system, theta0), {}


def _units(draw, ctx):
    from camdyn.params.units import angular_speed, parse_quantity, parse_speed

    text = draw(st.one_of(odd, st.text(max_size=20),
                          st.sampled_from(["17.5 mm", "693 rpm", "72.6 rad/s", "2 ** 1000 m", "(1", "1/0 mm",
                                           "0x10 mm", "1 degC", "µm", "1e309 mm", "-0 mm", "3.5mm"])))
    which = draw(st.sampled_from(["parse_quantity", "parse_speed", "angular_speed"]))
    if which == "parse_quantity":
        unit = draw(either(["m", "N*s/m**2.5", "", "Hz"], 7))
        return which, parse_quantity, (text, unit), {}
    return which, parse_speed if which == "parse_speed" else angular_speed, (text,), {}


def _read_measurement(draw, ctx):
    from camdyn.io.measurements import read_measurement

    path = draw(either([ctx["record_path"], ctx["folder"], ctx["folder"] / "missing.csv", str(ctx["record_path"]),
                        ctx["folder"] / "empty.csv"], 5))
    return "read_measurement", read_measurement, (path,), {}


def _half_power(draw, ctx):
    from camdyn.identification.modal import half_power_damping

    f = np.linspace(0.0, 200.0, 401)
    h = 1.0 / (1.0 - (f / 100.0) ** 2 + 0.04j * f / 100.0)
    frequency = draw(either([f, f[:2], list(f), f[::-1]], 5))
    response = draw(either([h, h[:2], np.abs(h), h * NAN], 5))
    kwargs = optional_kwargs(draw, {"band": either([None, (50.0, 150.0), (150.0, 50.0), (0.0, 1e9)], 4)})
    return "half_power_damping", half_power_damping, (frequency, response), kwargs


def _estimate_friction(draw, ctx):
    from camdyn.identification.friction import estimate_friction

    system = draw(either([ctx["friction_rig"], "sundar2014-friction"], 6))
    record = draw(either([ctx["friction_record"], ctx["friction_record"].drop_vars("Nx"), xr.Dataset(),
                          ctx["record_path"]], 6))
    kwargs = optional_kwargs(draw, {"speed": either([None, 11.55, "11.55 Hz"], 4), "harmonics": either([20, 5], 4),
                                    "enforce": either([True, False], 4)})
    return "estimate_friction", estimate_friction, (system, record), kwargs


def _trace_branch(draw, ctx):
    from camdyn.continuation.results import trace_branch

    system = draw(either([ctx["rig"], PRESET], 6))
    key = draw(either(["motion.speed", "cam.runout", "contact.stiffness", "cam.runnout"], 6))
    start, stop = draw(either([5.0, "5 Hz", "1.2 mm"], 5)), draw(either([30.0, "30 Hz", "2 mm"], 5))
    kwargs = optional_kwargs(draw, {name: either(valid, 5) for name, valid in (
        ("periods", [1, 2]), ("step", [0.02]), ("max_points", [200]), ("transient", [50]), ("rtol", [1e-10]),
        ("segments", [1, 3]))})
    return "trace_branch", trace_branch, (system, key, start, stop), kwargs


SPEC = {"system": {"source": PRESET, "set": {"cam.runout": "3.5 mm"}},
        "vary": [{"key": "motion.speed", "start": "8 Hz", "stop": "25 Hz", "num": 4}],
        "run": {"revolutions": 20, "discard": 10, "chunk": 2},
        "metrics": {"names": ["poincare", "impacts"]}, "output": {"path": "fuzz.nc"}}


def _spec_dict(draw):
    """The valid spec with one table, entry or value replaced by an odd one."""
    spec = {table: (dict(value) if isinstance(value, dict) else [dict(v) for v in value])
            for table, value in SPEC.items()}
    table = draw(st.sampled_from(sorted(spec) + ["extra"]))
    if table == "vary":
        entry = dict(spec["vary"][0])
        entry[draw(st.sampled_from(["key", "start", "stop", "num", "values", "scale"]))] = draw(odd)
        spec["vary"] = draw(st.sampled_from([[entry], [], [entry, entry], entry]))
    elif table in spec and draw(st.booleans()):
        inner = dict(spec[table])
        inner[draw(st.sampled_from(sorted(inner) + ["bogus"]))] = draw(odd)
        spec[table] = inner
    else:
        spec[table] = draw(odd)
    return spec


def _sweeps(draw, ctx):
    from camdyn.sweeps import run_sweep, spec_from_dict

    if draw(st.booleans()):
        spec = _spec_dict(draw) if draw(st.integers(0, 9)) else draw(odd)
        return "spec_from_dict", spec_from_dict, (spec,), {"base_dir": ctx["folder"]}
    spec = draw(either([ctx["spec"]], 6))
    kwargs = optional_kwargs(draw, {"workers": either([0, 1], 5), "dask": either([None, "tcp://:"], 5),
                                    "threads": either([1], 5), "progress": st.just(False),
                                    "restart": either([True, False], 5)})
    kwargs.setdefault("progress", False)
    return "run_sweep", run_sweep, (spec,), kwargs


def _lyapunov(draw, ctx):
    from camdyn.analysis.chaos import lyapunov_exponent
    from camdyn.analysis.lyapunov import lyapunov_spectrum

    system = draw(either([ctx["rig"]], 7))
    kwargs = optional_kwargs(draw, {"speed": either([None, 16.0, "18 Hz"], 5), "revolutions": either([10, 400], 5),
                                    "transient": either([0, 20], 5), "rtol": either([1e-8], 5),
                                    "atol": either([1e-10], 5)})
    if draw(st.booleans()):
        return "lyapunov_spectrum", lyapunov_spectrum, (system,), kwargs
    kwargs.update(optional_kwargs(draw, {"separation": either([1e-7], 5)}))
    return "lyapunov_exponent", lyapunov_exponent, (system,), kwargs


def _impact_damping(draw, ctx):
    from camdyn.identification.impact_damping import estimate_impact_damping

    system = draw(either([ctx["rig"], PRESET], 7))
    records = draw(either([ctx["friction_record"], [ctx["friction_record"]], [], xr.Dataset()], 6))
    kwargs = optional_kwargs(draw, {name: either(valid, 5) for name, valid in (
        ("speed", [None, 15.0]), ("runout", [None, 3.5e-3]), ("exponent", [None, 1.5, 0.0]),
        ("residue", [None, "lambda1", "combined"]), ("bootstrap", [0, 64]), ("seed", [0, None]),
        ("min_impacts", [5]))})
    return "estimate_impact_damping", estimate_impact_damping, (system, records), kwargs


def _synthesize(draw, ctx):
    from camdyn.records.synthesis import synthesize

    system = draw(either([ctx["rig"]], 6))
    kwargs = optional_kwargs(draw, {"speed": either([None, 16.0, "16 Hz"], 5), "revolutions": either([1.0, 2.0], 6),
                                    "sample_rate": either([5e3], 5), "noise": either([0.0, 0.01], 5),
                                    "settle": either([0.0, 1.0], 6), "seed": either([0, 12345678901234567890123], 5),
                                    "channels": either([("Nx",), ("Nx", "alpha_ddot")], 5)})
    kwargs.setdefault("settle", 1.0)
    kwargs.setdefault("revolutions", 1.0)
    return "synthesize", synthesize, (system,), kwargs


def _kinematics(draw, ctx):
    from camdyn.analysis.kinematics import inverse_kinematics
    from camdyn.analysis.linear import linearize

    system = draw(either([ctx["rig"], PRESET], 6))
    speed = draw(either([None, 16.0, "16 Hz"], 5))
    if draw(st.booleans()):
        return "linearize", linearize, (system, speed), {}
    kwargs = optional_kwargs(draw, {"points": either([256, 1024], 5)})
    return "inverse_kinematics", inverse_kinematics, (system, speed), kwargs


def _impulse_test(draw, ctx):
    from camdyn.identification.modal import synthesize_impulse_test

    kwargs = optional_kwargs(draw, {name: either(valid, 4) for name, valid in (
        ("masses", [(0.21, 0.05)]), ("stiffnesses", [(8.0e6, 6.0e6)]), ("damping_ratios", [(0.02, 0.02)]),
        ("duration", [0.05]), ("sample_rate", [20e3]), ("pulse", [2e-4]), ("force_peak", [100.0]),
        ("noise", [0.0, 0.01]), ("seed", [0, None]))})
    kwargs.setdefault("duration", 0.05)
    return "synthesize_impulse_test", synthesize_impulse_test, (), kwargs


def _harmonics(draw, ctx):
    from camdyn.analysis.harmonics import amplitude_spectrum, harmonic_amplitudes

    ds = draw(either([ctx["run"], ctx["run"].isel(time=slice(0, 3)), xr.Dataset()], 6))
    variable = draw(either(["alpha_ddot", "Nx", "nothing"], 6))
    if draw(st.booleans()):
        kwargs = optional_kwargs(draw, {"orders": either([(1, 2), (1,)], 5), "revolutions": either([1, 2], 5)})
        return "harmonic_amplitudes", harmonic_amplitudes, (ds, variable), kwargs
    kwargs = optional_kwargs(draw, {"revolutions": either([None, 1], 5)})
    return "amplitude_spectrum", amplitude_spectrum, (ds, variable), kwargs


CALLERS = [_simulate, _load_system, _equilibrium, _units, _read_measurement, _half_power, _estimate_friction,
           _trace_branch, _sweeps, _lyapunov, _impact_damping, _synthesize, _kinematics, _impulse_test, _harmonics]


# --- the property ---------------------------------------------------------------------------------------


class Hang(Exception):
    pass


def _alarm(_signum, _frame):
    raise Hang


@pytest.fixture(scope="module")
def context(tmp_path_factory, impact_rig, friction_rig):
    from camdyn.io.measurements import write_measurement
    from camdyn.records.synthesis import synthesize
    from camdyn.sweeps import spec_from_dict

    folder = tmp_path_factory.mktemp("fuzz")
    record = synthesize(friction_rig, 11.55, revolutions=6, sample_rate=5e3, settle=2)
    path = write_measurement(record, folder / "record.csv")
    (folder / "empty.csv").write_text("")
    spec = spec_from_dict(dict(SPEC, output={"path": str(folder / "fuzz.nc")}), base_dir=folder)
    run = camdyn.simulate(impact_rig, 16.0, 3.0, sample_rate=5e3)
    return {"rig": impact_rig, "friction_rig": friction_rig, "friction_record": record, "record_path": path,
            "folder": folder, "spec": spec, "run": run}


@pytest.fixture
def stand_ins(monkeypatch):
    """Long work replaced by :func:`_accepted`."""
    from camdyn.analysis import chaos, lyapunov
    from camdyn.continuation import results
    from camdyn.identification import impact_damping
    from camdyn.sweeps import execution

    monkeypatch.setattr(results, "find_orbit", _accepted)
    monkeypatch.setattr(execution, "_compute_missing", _accepted)
    monkeypatch.setattr(chaos, "_benettin", _accepted)
    monkeypatch.setattr(lyapunov, "model_spectrum", _accepted)
    monkeypatch.setattr(impact_damping, "ImpactProblem", _accepted)


@pytest.mark.filterwarnings("ignore::UserWarning")   # the warnings of odd but valid calls
def test_public_api_returns_or_raises_a_camdyn_error(context, stand_ins, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    outcomes: dict[str, Counter] = {}
    foreign: dict[tuple, str] = {}     # (function, exception, message) -> the first call
    slow: list[str] = []

    @settings(max_examples=CALLS, deadline=None, derandomize=DERANDOMIZE, database=None,
              suppress_health_check=list(HealthCheck))
    @given(st.data())
    def one_call(data):
        caller = data.draw(st.sampled_from(CALLERS))
        name, function, args, kwargs = caller(data.draw, context)
        previous = signal.signal(signal.SIGALRM, _alarm)
        signal.alarm(HANG_LIMIT)
        start = time.perf_counter()
        try:
            function(*args, **kwargs)
            outcome = "returned"
        except Accepted:
            outcome = "accepted, long work not started"
        except CamdynError as exc:
            outcome = type(exc).__name__
        except (Hang, KeyboardInterrupt):
            outcome = "hang"
        except Exception as exc:      # noqa: BLE001 - what the test looks for
            outcome = "foreign"
            foreign.setdefault((name, type(exc).__name__, str(exc)[:60]), f"{name}{_show(args, kwargs)}: {exc}"[:300])
        finally:
            signal.alarm(0)
            signal.signal(signal.SIGALRM, previous)
        elapsed = time.perf_counter() - start
        if elapsed > CALL_LIMIT or outcome == "hang":
            slow.append(f"{name}{_show(args, kwargs)}: {elapsed:.1f} s")
        outcomes.setdefault(name, Counter())[outcome] += 1

    one_call()
    total = sum(sum(c.values()) for c in outcomes.values())
    for name in sorted(outcomes):
        print(f"{name:26s} {sum(outcomes[name].values()):5d}  {dict(outcomes[name])}")
    print(f"{'total':26s} {total:5d}")
    assert not foreign, "\n".join(f"{kind[1]}: {call}" for kind, call in sorted(foreign.items()))
    assert not slow, "\n".join(slow)
    assert total >= 1000
    assert len(outcomes) >= 20


def _show(args, kwargs) -> str:
    shown = [f"{a!r:.40}" for a in args] + [f"{k}={v!r:.40}" for k, v in kwargs.items()]
    return "(" + ", ".join(shown) + ")"


def test_values_the_fuzz_draws_are_of_every_kind():
    kinds = {type(v).__name__ for v in ODD}
    assert {"NoneType", "bool", "int", "float", "str", "bytes", "list", "tuple", "dict", "complex",
            "ndarray", "PosixPath"} <= kinds
    assert any(isinstance(v, float) and math.isnan(v) for v in ODD)
