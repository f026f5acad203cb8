"""A model written outside the package (examples/models/valve_train.py) through the model
protocol: its own compiled driver, checked against an independent SciPy solution of its
equations written here, cached across processes, and refused clearly when ill-formed."""

from __future__ import annotations

import importlib.util
import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numba
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import camdyn
from camdyn.errors import ParameterError, UnitError
from camdyn.systems.protocol import Model, adapter_source

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "models" / "valve_train.py"


@pytest.fixture(scope="module")
def cache():
    """camdyn's cache folder of generated drivers (the default one, or $CAMDYN_CACHE_DIR),
    shared with the gallery's valve-train example so that the docs build loads the driver
    this module compiles."""
    from camdyn.integrator.instances import cache_root

    return cache_root().parent


@pytest.fixture(scope="module")
def valve(cache):
    sys.path.insert(0, str(EXAMPLE.parent))
    try:
        spec = importlib.util.spec_from_file_location("valve_train", EXAMPLE)
        module = importlib.util.module_from_spec(spec)
        sys.modules["valve_train"] = module
        spec.loader.exec_module(module)
        yield module
    finally:
        sys.path.remove(str(EXAMPLE.parent))


# --- the valve train again, in plain Python and SciPy (independent of the example's code)

def _lift(t, q):
    """Cam lift [m] and its rate [m/s]: h sin^4(pi phi / beta) on the window."""
    omega = 2 * math.pi * q["speed"]
    phi = (omega * t) % (2 * math.pi) - q["cam.opening_angle"]
    if not 0.0 < phi < q["cam.window"]:
        return 0.0, 0.0
    x = math.pi * phi / q["cam.window"]
    return q["cam.lift"] * math.sin(x) ** 4, q["cam.lift"] * 4 * math.sin(x) ** 3 * math.cos(x) * math.pi / q[
        "cam.window"] * omega


def _scipy_valve_train(q, y0, t_eval):
    """Integrate mode by mode with terminal, directional events at the two penetrations."""
    def field(cam, seat):
        def f(t, y):
            s, sd = _lift(t, q)
            fc = max(0.0, q["contact.stiffness"] * (s - q["lash"] - y[0])
                     * (1 + q["contact.damping"] * (sd - y[1]))) if cam else 0.0
            fs = max(0.0, q["seat.stiffness"] * -y[0] * (1 - q["seat.damping"] * y[1])) if seat else 0.0
            f2 = q["spring.preload"] + q["spring.retainer_stiffness"] * (y[0] - y[2]) + q["spring.damping"] * (
                y[1] - y[3])
            f1 = q["spring.preload"] + q["spring.head_stiffness"] * y[2] + q["spring.damping"] * y[3]
            return [y[1], (fc + fs - f2) / q["valve.mass"], y[3], (f2 - f1) / q["spring.mass"]]
        return f

    def cam_gap(t, y):
        return _lift(t, q)[0] - q["lash"] - y[0]

    def seat_gap(t, y):
        return -y[0]

    cam = cam_gap(0.0, y0) > 0
    seat = y0[0] < 0
    t, y = 0.0, np.array(y0, float)
    out = np.full((len(t_eval), 4), np.nan)
    events = 0
    while t < t_eval[-1]:
        cam_gap.terminal = seat_gap.terminal = True
        cam_gap.direction = -1.0 if cam else 1.0
        seat_gap.direction = -1.0 if seat else 1.0
        sol = solve_ivp(field(cam, seat), (t, t_eval[-1]), y, method="DOP853", rtol=1e-12, atol=1e-16,
                        events=[cam_gap, seat_gap], dense_output=True, max_step=1e-4)
        inside = (t_eval >= t) & (t_eval <= sol.t[-1])
        if inside.any():
            out[inside] = sol.sol(t_eval[inside]).T
        if sol.status != 1:
            break
        which = 0 if sol.t_events[0].size else 1
        t, y = sol.t_events[which][0], sol.y_events[which][0]
        if which == 0:
            cam = not cam
        else:
            seat = not seat
        events += 1
    return out, events


def test_valve_train_agrees_with_scipy(valve):
    bound = valve.VALVE_TRAIN.bind({"speed": "2400 rpm"})   # 40 Hz
    ds = camdyn.simulate(bound, revolutions=2, sample_rate=4000.0, rtol=1e-11, atol=1e-14)
    q = dict(zip(bound.model.parameter_names, bound.values))
    assert q["speed"] == pytest.approx(40.0)
    reference, events = _scipy_valve_train(q, bound.initial_state(), ds["time"].values)
    amplitude = np.max(np.abs(reference[:, 0]))
    error = np.max(np.abs(ds["x_v"].values - reference[:, 0])) / amplitude
    # measured: 3.3e-12 of the lift with 36 events (the valve bounces on its seat 7 times
    # after each landing) in both solutions
    assert error < 1e-7
    assert ds.sizes["event"] == events
    assert ds["x_v"].attrs["units"] == "m" and ds["cam_force"].attrs["units"] == "N"
    # a deliberate mistake must show: the SciPy model with a 1 % softer seat is far off
    wrong = dict(q, **{"seat.stiffness": 0.99 * q["seat.stiffness"]})
    other, _ = _scipy_valve_train(wrong, bound.initial_state(), ds["time"].values)
    assert np.max(np.abs(ds["x_v"].values - other[:, 0])) / amplitude > 1e-4   # measured 2.2e-4


def test_second_process_loads_the_driver_without_compiling(valve, cache):
    camdyn.simulate(valve.VALVE_TRAIN.bind(), revolutions=1)   # compiled (or loaded) here
    script = textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {str(EXAMPLE.parent)!r})
        import camdyn, valve_train
        from camdyn.simulation.models import model_driver
        ds = camdyn.simulate(valve_train.VALVE_TRAIN.bind(), revolutions=1)
        stats = model_driver(valve_train.VALVE_TRAIN).integrate.stats
        print(sum(stats.cache_hits.values()), sum(stats.cache_misses.values()))
    """)
    env = dict(os.environ, CAMDYN_CACHE_DIR=str(cache))   # the folder this process used
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=600)
    assert run.returncode == 0, run.stderr
    hits, misses = map(int, run.stdout.split()[-2:])
    assert (hits, misses) == (1, 0)


def test_parameters_with_units_and_refusals(valve):
    model = valve.VALVE_TRAIN
    bound = model.bind({"lash": "0.3 mm", "spring.preload": 300})
    assert bound["lash"] == pytest.approx(3e-4)
    assert bound["spring.preload"] == 300.0
    with pytest.raises(ParameterError, match="has no parameter 'lashes'"):
        model.bind({"lashes": 1e-4})
    with pytest.raises(UnitError):
        model.bind({"lash": "3 kg"})
    with pytest.raises(ParameterError, match="must be finite"):
        model.bind({"lash": float("nan")})
    with pytest.raises(ParameterError, match="initial_state must be 4 finite numbers"):
        camdyn.simulate(bound, revolutions=1, initial_state=[0.0, 0.0])
    with pytest.raises(ParameterError, match="max_step"):
        camdyn.simulate(bound, revolutions=1, max_step=float("nan"))
    with pytest.raises(ParameterError, match="max_steps"):
        camdyn.simulate(bound, revolutions=1, max_steps=2 ** 70)


@numba.njit
def _rhs(t, y, mode, p, dydt):   # pragma: no cover - only its description is checked
    dydt[0] = 0.0


def test_ill_formed_models_are_refused():
    good = {"rhs": _rhs, "guards": _rhs, "expected_sign": _rhs, "transition": _rhs, "initial_mode": _rhs}
    with pytest.raises(ParameterError, match=r"functions missing \['initial_mode'\]"):
        Model("m", ["x"], [], [], ["m"], {k: v for k, v in good.items() if k != "initial_mode"})
    with pytest.raises(ParameterError, match="must be compiled with @numba.njit"):
        Model("m", ["x"], [], [], ["m"], dict(good, rhs=lambda t, y, mode, p, dydt: None))
    with pytest.raises(ParameterError, match="speed parameter 'f'"):
        Model("m", ["x"], [("k", "N/m")], [], ["m"], good, speed="f")
    with pytest.raises(ParameterError, match="repeat the names"):
        Model("m", ["x", "x"], [], [], ["m"], good)

    @numba.njit
    def local(t, y, mode, p, dydt):   # pragma: no cover
        dydt[0] = 0.0

    with pytest.raises(ParameterError, match="top level of a module"):
        Model("m", ["x"], [], [], ["m"], dict(good, rhs=local))


def test_adapter_calls_the_models_functions(valve):
    source = adapter_source(valve.VALVE_TRAIN)
    assert "from valve_train import rhs as _rhs" in source
    assert "def state_size(system):\n    return 4" in source
    assert "def guard_count(system):\n    return 2" in source


def test_valve_train_jacobian_against_differences(valve):
    bound = valve.VALVE_TRAIN.bind()
    p = bound.p
    rng = np.random.default_rng(7)
    n = 4
    for mode in ([1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [0.0, 0.0]):
        mode = np.array(mode)
        for _ in range(5):
            t = rng.uniform(0.0, 1.0 / 40.0)
            y = np.array([rng.uniform(-2e-5, 8e-3), rng.uniform(-0.5, 0.5), rng.uniform(-1e-3, 4e-3),
                          rng.uniform(-0.5, 0.5)])
            f0 = np.empty(n)
            valve.rhs(t, y, mode, p, f0)
            jac = np.empty((n, n))
            valve.jacobian(t, y, f0, mode, p, jac)
            typical = (1e-3, 0.1, 1e-3, 0.1)   # m, m/s: steps well above the rounding of f
            for j in range(n):
                h = 1e-5 * max(abs(y[j]), typical[j])
                fp, fm = np.empty(n), np.empty(n)
                valve.rhs(t, y + h * np.eye(n)[j], mode, p, fp)
                valve.rhs(t, y - h * np.eye(n)[j], mode, p, fm)
                column = (fp - fm) / (2 * h)
                assert np.allclose(jac[:, j], column, rtol=1e-6, atol=1e-6 * np.abs(column).max() + 1e-9), (mode, j)


def test_valve_train_periodic_orbit_against_scipy(valve):
    from camdyn.continuation import bound_problem, continue_orbits, find_orbit

    bound = valve.VALVE_TRAIN.bind({"speed": 30.0})
    problem = bound_problem(bound, rtol=1e-10, atol=1e-13)
    orbit = find_orbit(problem, transient=30)
    q = dict(zip(bound.model.parameter_names, bound.values))
    period = 1.0 / 30.0
    # periodicity checked by the independent SciPy model: one period from the orbit's state
    end, _ = _scipy_valve_train(q, orbit.state, np.array([0.0, period]))
    scale = orbit.extent   # the largest magnitude of each state component over the orbit
    assert np.all(np.abs(end[-1] - orbit.state) <= 1e-6 * scale + 1e-12)
    # the monodromy matrix against central differences of the SciPy flow
    monodromy = np.empty((4, 4))
    for j in range(4):
        h = 1e-6 * scale[j]
        plus, _ = _scipy_valve_train(q, orbit.state + h * np.eye(4)[j], np.array([0.0, period]))
        minus, _ = _scipy_valve_train(q, orbit.state - h * np.eye(4)[j], np.array([0.0, period]))
        monodromy[:, j] = (plus[-1] - minus[-1]) / (2 * h)
    expected = np.sort(np.abs(np.linalg.eigvals(monodromy)))[::-1]
    got = np.sort(np.abs(orbit.multipliers))[::-1]
    assert np.allclose(got, expected, rtol=1e-3, atol=1e-4)
    # and a short branch in the speed
    branch = continue_orbits(problem, orbit, 31.0, step=0.01, max_step=0.05, max_points=40)
    assert branch.orbits[-1].parameter == pytest.approx(31.0)


def test_valve_train_sweep_on_the_sweep_engine(valve, tmp_path):
    """The sweep engine over the user's model, its points run by two worker processes
    that load the model from its file: at 2 Hz the valve's peak lift is the quasi-static
    balance of contact and spring, a closed form; at 40 Hz the events, the section and the
    peak lift are those of the independent SciPy solution."""
    from camdyn.sweeps import run_sweep, spec_from_dict

    spec = spec_from_dict({
        "system": {"source": f"{EXAMPLE.name}:VALVE_TRAIN"},   # relative to the spec's folder
        "vary": [{"key": "speed", "values": ["120 rpm", "40 Hz"]}],
        "run": {"revolutions": 3, "discard": 1, "samples_per_revolution": 2048, "rtol": 1e-11, "atol": 1e-14,
                "chunk": 1},
        "output": {"path": str(tmp_path / "valve.nc")}}, base_dir=EXAMPLE.parent)
    ds = run_sweep(spec, workers=2, progress=False)
    assert list(ds["speed"].values) == [2.0, 40.0] and ds["speed"].attrs["units"] == "Hz"
    assert ds["max_x_v"].attrs["units"] == "m" and ds["events_seat"].attrs["units"] == "1/rev"
    q = dict(zip(valve.VALVE_TRAIN.parameter_names, valve.VALVE_TRAIN.bind().values))
    # 2 Hz: k_c (h - lash - x) = P + K x, K the two spring halves in series; the valve's
    # and coil's inertia at the peak (m 4 h (pi / beta)^2 omega^2 / k_c) moves it 0.14 um
    k_series = 1.0 / (1.0 / q["spring.head_stiffness"] + 1.0 / q["spring.retainer_stiffness"])
    x_peak = (q["cam.lift"] - q["lash"] - q["spring.preload"] / q["contact.stiffness"]) / (
        1.0 + k_series / q["contact.stiffness"])
    assert abs(float(ds["max_x_v"].sel(speed=2.0)) - x_peak) < 0.5e-6
    assert int(ds["period"].sel(speed=2.0)) == 1
    # 40 Hz against SciPy over the kept revolutions 1..3 (periods of 25 ms)
    period = 1.0 / 40.0
    times = np.linspace(period, 3 * period, 2 * 2048 + 1)
    bound = valve.VALVE_TRAIN.bind({"speed": 40.0})
    q40 = dict(q, speed=40.0)
    reference, events = _scipy_valve_train(q40, bound.initial_state(), np.r_[0.0, times])
    reference = reference[1:]
    _, discarded = _scipy_valve_train(q40, bound.initial_state(), np.array([0.0, period]))
    np.testing.assert_allclose(ds["poincare_x_v"].sel(speed=40.0).values, reference[[0, 2048], 0],
                               rtol=0, atol=1e-7 * q["cam.lift"])
    assert float(ds["max_x_v"].sel(speed=40.0)) == pytest.approx(reference[:-1, 0].max(), abs=1e-7 * q["cam.lift"])
    per_revolution = float(ds["events_seat"].sel(speed=40.0) + ds["events_cam_contact"].sel(speed=40.0))
    assert per_revolution * 2 == events - discarded   # SciPy's crossings of both gaps in the kept window
    assert float(ds["events_seat"].sel(speed=40.0)) > 2   # the valve bounces on its seat
    # the same spec again resumes from its checkpoints: nothing recomputed, the same numbers
    again = run_sweep(spec, workers=1, progress=False)
    assert again.equals(ds)


def test_a_model_sweep_refuses_unknown_keys_and_files(valve, tmp_path):
    from camdyn.sweeps import spec_from_dict

    base = {"system": {"source": f"{EXAMPLE}:VALVE_TRAIN"}, "output": {"path": str(tmp_path / "x.nc")}}
    with pytest.raises(ParameterError, match="did you mean spring.preload"):
        spec_from_dict(dict(base, vary=[{"key": "spring.preloads", "values": [200, 300]}]))
    with pytest.raises(ParameterError, match="speed.*must be positive"):
        spec_from_dict(dict(base, vary=[{"key": "speed", "values": [-5, 30]}]))
    with pytest.raises(ParameterError, match="no model 'VALVE'"):
        spec_from_dict(dict(base, system={"source": f"{EXAMPLE}:VALVE"}, vary=[{"key": "lash", "values": [1e-4]}]))
    with pytest.raises(ParameterError, match="does not exist"):
        spec_from_dict(dict(base, system={"source": str(tmp_path / "none.py")}, vary=[{"key": "lash",
                                                                                       "values": [1e-4]}]))
    with pytest.raises(ParameterError, match="unknown metric"):
        spec_from_dict(dict(base, vary=[{"key": "lash", "values": [1e-4]}], metrics={"names": ["regime"]}))


def _cli(*argv):
    import contextlib
    import io

    from camdyn.cli.app import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main([str(a) for a in argv])
    return status, out.getvalue(), err.getvalue()


def test_the_command_line_simulates_the_model_file(valve, tmp_path):
    """``camdyn simulate FILE.py:NAME``: the summary's speed, revolutions and events are
    those of the independent SciPy solution over the same two revolutions."""
    import json

    status, out, err = _cli("simulate", f"{EXAMPLE}:VALVE_TRAIN", "--speed", "2400rpm", "--revolutions", "2",
                            "--rtol", "1e-11", "--json", "--plot", tmp_path / "vt.png")
    assert status == 0, err
    summary = json.loads(out)["summary"]
    assert summary["speed_hz"] == pytest.approx(40.0, rel=1e-15) and summary["revolutions"] == pytest.approx(2.0)
    bound = valve.VALVE_TRAIN.bind({"speed": 40.0})
    q = dict(zip(bound.model.parameter_names, bound.values))
    _, events = _scipy_valve_train(q, bound.initial_state(), np.array([0.0, 2 / 40.0]))
    assert sum(summary["events_per_revolution"].values()) * 2 == pytest.approx(events)
    assert summary["ranges"]["x_v"]["unit"] == "m" and (tmp_path / "vt.png").stat().st_size > 0
    # bad input: one line, exit 2, nothing written
    for argv, words in (((f"{EXAMPLE}:VALVE", ), "no model 'VALVE'"),
                        ((f"{EXAMPLE}:VALVE_TRAIN", "--set", "lashes=1mm"), "no parameter 'lashes'"),
                        ((str(tmp_path / "none.py"), ), "does not exist")):
        status, out, err = _cli("simulate", *argv, "--revolutions", "1")
        assert status == 2 and words in err and len(err.strip().splitlines()) == 1, err


def test_the_command_line_continues_the_model_file(valve):
    """``camdyn continue FILE.py:NAME``: each orbit of the branch closes on itself under
    the independent SciPy model."""
    import json

    status, out, err = _cli("continue", f"{EXAMPLE}:VALVE_TRAIN", "--from", "30Hz", "--to", "1830rpm",
                            "--transient", "30", "--json", "--quiet")
    assert status == 0, err
    document = json.loads(out)
    assert document["summary"]["parameter"] == "speed" and document["summary"]["units"] == "Hz"
    orbits = document["branches"][0]
    assert orbits[-1]["parameter"] == pytest.approx(30.5)
    q = dict(zip(valve.VALVE_TRAIN.parameter_names, valve.VALVE_TRAIN.bind().values))
    for orbit in (orbits[0], orbits[-1]):
        state = np.array(orbit["state"])
        end, _ = _scipy_valve_train(dict(q, speed=orbit["parameter"]), state, np.array([0.0, orbit["period"]]))
        scale = np.array([q["cam.lift"], 1.0, q["cam.lift"], 1.0])   # m, m/s
        assert np.all(np.abs(end[-1] - state) <= 1e-6 * scale)
    status, _, err = _cli("continue", f"{EXAMPLE}:VALVE_TRAIN", "--parameter", "lashes", "--from", "1mm", "--to",
                          "2mm")
    assert status == 2 and "no parameter 'lashes'" in err and len(err.strip().splitlines()) == 1


def test_the_spectrum_of_the_model_files_cam_lift_is_its_fourier_series(valve):
    """``camdyn spectrum FILE.py:NAME``: the cam harmonics of the lift channel are the
    Fourier coefficients of the closed-form lift h sin^4(pi phi / beta), integrated here."""
    import json

    status, out, err = _cli("spectrum", f"{EXAMPLE}:VALVE_TRAIN", "--speed", "40Hz", "--revolutions", "6",
                            "--window", "4", "--variable", "cam_lift", "--harmonics", "4", "--json")
    assert status == 0, err
    document = json.loads(out)
    summary = document["summary"]
    q = dict(zip(valve.VALVE_TRAIN.parameter_names, valve.VALVE_TRAIN.bind().values))
    t = np.linspace(0.0, 1 / 40.0, 200_001)[:-1]
    lift = np.array([_lift(x, dict(q, speed=40.0))[0] for x in t[::20]])   # 10^4 points of one period
    coefficients = np.abs(np.fft.rfft(lift)) * 2 / lift.size
    got = [h["amplitude"] for h in document["harmonics"]]
    np.testing.assert_allclose(got, coefficients[1:5], rtol=1e-9)   # measured 3e-12
    assert summary["units"] == "m"
