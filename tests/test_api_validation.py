"""Input checked before work: the Python API raises camdyn's own exceptions,
with a message that says what was expected, for values of the wrong kind, limits that
would hang or exhaust memory, and values outside their meaning; the command line
refuses the same with exit status 2 and one line ``error: ...``. Each check runs before
any compiled work: where the old code would start the work (and hang), the work is
replaced by a failure, so the test fails instead of hanging."""

import math
import re
from pathlib import Path

import numpy as np
import pytest

import camdyn
from camdyn.errors import ParameterError, UnitError


def _no_work(*_args, **_kwargs):
    raise AssertionError("the work started: the input was not checked before it")


@pytest.fixture
def no_simulation(monkeypatch):
    """``simulate`` fails if it gets as far as preparing the system."""
    from camdyn.simulation import runner

    monkeypatch.setattr(runner, "prepare", _no_work)


# -- 1. foreign exceptions from the Python API -------------------------------------------


def test_static_equilibrium_takes_a_preset_name(impact_rig):
    by_name = camdyn.static_equilibrium("sundar2014-impact")
    assert by_name == camdyn.static_equilibrium(impact_rig)
    assert camdyn.natural_frequency("sundar2014-impact") == camdyn.natural_frequency(impact_rig)


@pytest.mark.parametrize("function", ["static_equilibrium", "natural_frequency"])
def test_equilibrium_refuses_what_is_not_a_system(function):
    with pytest.raises(ParameterError, match=r"expected a System \(from camdyn.load_system\).*got NoneType"):
        getattr(camdyn, function)(None)


def test_estimate_friction_refuses_a_file_name(friction_rig):
    from camdyn.identification.friction import estimate_friction

    with pytest.raises(ParameterError, match=r"expected a record .*got str 'meas.csv'.*read_measurement"):
        estimate_friction(friction_rig, "meas.csv")


@pytest.fixture(scope="module")
def friction_record():
    from camdyn.records.synthesis import synthesize

    return synthesize(camdyn.load_system("sundar2014-friction"), 11.55, revolutions=10, sample_rate=9460.0,
                      settle=5)


def test_estimate_friction_reads_a_speed_with_its_unit(friction_rig, friction_record):
    from camdyn.identification.friction import estimate_friction

    as_text = estimate_friction(friction_rig, friction_record, speed="11.55 Hz")
    as_number = estimate_friction(friction_rig, friction_record, speed=11.55)
    assert as_text.mu == as_number.mu and as_text.speed_hz == 11.55
    assert estimate_friction(friction_rig, friction_record, speed="693 rpm").mu == pytest.approx(as_number.mu)
    with pytest.raises(UnitError, match="not a rotational speed"):
        estimate_friction(friction_rig, friction_record, speed="11.55 kg")
    with pytest.raises(ParameterError, match="positive, finite cam speed"):
        estimate_friction(friction_rig, friction_record, speed="0 Hz")


def test_trace_branch_reads_values_with_their_units(impact_rig):
    from camdyn.continuation.results import parameter_value, trace_branch

    assert parameter_value("motion.speed", "5 Hz") == 5.0
    assert parameter_value("motion.speed", "600 rpm") == pytest.approx(10.0)
    assert parameter_value("cam.runout", "1.2 mm") == pytest.approx(1.2e-3)
    # read, then refused before any work: the same value twice is no range
    with pytest.raises(ParameterError, match="two different finite values, got 5.0 and 5.0"):
        trace_branch(impact_rig, "motion.speed", "5 Hz", "300 rpm")
    with pytest.raises(UnitError, match="motion.speed"):
        trace_branch(impact_rig, "motion.speed", "5 kg", "30 Hz")
    with pytest.raises(ParameterError, match="start must be a number"):
        trace_branch(impact_rig, "motion.speed", None, 30.0)


def test_half_power_damping_refuses_empty_spectra():
    from camdyn.identification.modal import half_power_damping

    with pytest.raises(ParameterError, match=r"1-D arrays of the same length.*shapes \(0,\) and \(0,\)"):
        half_power_damping([], [])
    with pytest.raises(ParameterError, match=r"shapes \(5,\) and \(4,\)"):
        half_power_damping(np.arange(5.0), np.ones(4))


def test_read_measurement_refuses_what_is_not_a_path():
    from camdyn.io.measurements import read_measurement

    with pytest.raises(ParameterError, match="expects the record's file name.*got NoneType"):
        read_measurement(None)


def test_run_sweep_refuses_what_is_not_a_spec():
    from camdyn.sweeps.execution import run_sweep

    with pytest.raises(ParameterError, match=r"expected a SweepSpec .*got str 'not a spec'.*load_spec"):
        run_sweep("not a spec")


# -- 2. step limits and tolerances that would hang ---------------------------------------


@pytest.mark.parametrize("max_step", [float("nan"), float("inf"), 0.0, -1e-3, "1 ms"])
def test_simulate_refuses_a_meaningless_max_step(impact_rig, no_simulation, max_step):
    with pytest.raises(ParameterError, match="max_step must be a"):
        camdyn.simulate(impact_rig, speed=16, revolutions=2, max_step=max_step)


@pytest.mark.parametrize("max_steps", [2 ** 70, 0, -5, 1e6, True, float("nan")])
def test_simulate_refuses_a_meaningless_max_steps(impact_rig, no_simulation, max_steps):
    with pytest.raises(ParameterError, match="max_steps must be a whole number from 1 to 1e"):
        camdyn.simulate(impact_rig, speed=16, revolutions=2, max_steps=max_steps)


def test_simulate_refuses_a_step_too_short_for_its_budget(impact_rig, no_simulation):
    with pytest.raises(ParameterError, match=r"needs at least 1\.25e\+08 steps .*more than max_steps = 1000"):
        camdyn.simulate(impact_rig, speed=16, revolutions=2, max_step=1e-9, max_steps=1000)


def test_mechanisms_refuse_a_nan_max_step(impact_rig, monkeypatch):
    from camdyn.integrator import driver
    from camdyn.simulation.flexible_pivot import simulate_flexible_pivot

    monkeypatch.setattr(driver, "integrate", _no_work)
    with pytest.raises(ParameterError, match="max_step must be a positive, finite number of seconds, got nan"):
        simulate_flexible_pivot(impact_rig.with_values(**{"motion.speed": 16.0}), 1e9, 50.0, revolutions=1,
                                max_step=float("nan"))


# -- 2b. sweep and map tolerances ----------------------------------------------------------


def _sweep(tmp_path, run=None, vary=None):
    return {"system": {"source": "sundar2014-impact"},
            "vary": [vary or {"key": "motion.speed", "start": "10 Hz", "stop": "20 Hz", "num": 3}],
            "run": run or {}, "output": {"path": str(tmp_path / "s.nc")}}


@pytest.mark.parametrize("run, words", [
    ({"rtol": 1e-300}, r"rtol = 1e-300 is outside the sensible range 1e-14 to 0.01"),
    ({"atol": 1e-300}, r"atol = 1e-300 is outside the sensible range 1e-16 to 0.001 rad"),
    ({"atol": 10.0}, r"atol = 10.0 is outside the sensible range 1e-16 to 0.001 rad"),
])
def test_sweep_spec_refuses_tolerances_simulate_refuses(tmp_path, run, words):
    from camdyn.sweeps.spec import spec_from_dict

    with pytest.raises(ParameterError, match="sweep spec: \\[run\\] " + words):
        spec_from_dict(_sweep(tmp_path, run))


def test_map_command_refuses_tolerances_simulate_refuses(tmp_path, capsys):
    status, err = _cli(capsys, "map", "sundar2014-impact", "--x", "cam.runout=1mm:2mm:3", "--y",
                       "speed=60rpm:200rpm:3", "--atol", "10", "--out", tmp_path / "m.nc")
    assert status == 2 and "atol = 10.0 is outside the sensible range 1e-16 to 0.001 rad" in err


@pytest.mark.parametrize("vary, words", [
    ({"key": "motion.speed", "start": "8 Hz", "stop": "8 Hz", "num": 4}, "gives the value 8 Hz 4 times"),
    ({"key": "motion.speed", "values": ["8 Hz", "10 Hz", "480 rpm"]}, "gives the value 8 Hz 2 times"),
    ({"key": "cam.runout", "values": ["3 mm", "3.5 mm", "3 mm"]}, "gives the value 0.003 m 2 times"),
])
def test_sweep_spec_refuses_a_value_given_twice(tmp_path, vary, words):
    from camdyn.sweeps.spec import spec_from_dict

    with pytest.raises(ParameterError, match=re.escape(f"sweep spec: [[vary]] #1 ({vary['key']}) {words}")):
        spec_from_dict(_sweep(tmp_path, vary=vary))


def test_sweep_spec_says_when_its_values_run_backwards(tmp_path, capsys):
    from camdyn.sweeps.spec import spec_from_dict

    vary = {"key": "motion.speed", "start": "20 Hz", "stop": "10 Hz", "num": 3}
    with pytest.warns(UserWarning, match=re.escape("(motion.speed) values decrease (from 20 to 10 Hz)")):
        spec = spec_from_dict(_sweep(tmp_path, vary=vary))
    assert spec.vary[0].values == (20.0, 15.0, 10.0)          # run in the order given
    with pytest.warns(UserWarning, match="values do not increase steadily"):
        spec_from_dict(_sweep(tmp_path, vary={"key": "motion.speed", "values": ["10 Hz", "20 Hz", "15 Hz"]}))
    status, err = _cli(capsys, "map", "sundar2014-impact", "--x", "cam.runout=2mm:2mm:3", "--out", tmp_path / "m.nc")
    _one_error_line(status, err, "(cam.runout) gives the value 0.002 m 3 times")
    assert not (tmp_path / "m.nc").exists()


# -- 3. sizes refused before anything is allocated -----------------------------------------


@pytest.fixture
def counted_prepare(monkeypatch):
    """``prepare`` of the runner, failing from its 100th call: checking a spec must not
    prepare one system per value."""
    from camdyn.simulation import runner

    real, calls = runner.prepare, []

    def prepare(system):
        calls.append(1)
        if len(calls) > 100:
            raise AssertionError("the spec's check prepares a system per value")
        return real(system)

    monkeypatch.setattr(runner, "prepare", prepare)
    return calls


@pytest.mark.parametrize("num", [10 ** 8, 10 ** 6])
def test_sweep_spec_refuses_too_many_values_at_once(tmp_path, counted_prepare, num):
    from camdyn.sweeps.spec import spec_from_dict

    vary = {"key": "motion.speed", "start": "10 Hz", "stop": "20 Hz", "num": num}
    with pytest.raises(ParameterError, match=re.escape(f"num = {num} implies {num:.3g} values (about ") +
                       ".*the limit is 1e\\+05 values"):
        spec_from_dict(_sweep(tmp_path, vary=vary))
    assert not counted_prepare


def test_sweep_spec_checks_a_bounded_number_of_values(tmp_path, counted_prepare):
    from camdyn.sweeps.spec import spec_from_dict

    vary = {"key": "motion.speed", "start": "10 Hz", "stop": "20 Hz", "num": 2000}
    spec = spec_from_dict(_sweep(tmp_path, vary=vary))
    from camdyn.sweeps.spec import CHECKED_VALUES

    assert spec.points == 2000 and len(counted_prepare) == CHECKED_VALUES


def test_sweep_spec_refuses_huge_samples_per_revolution(tmp_path):
    from camdyn.sweeps.spec import spec_from_dict

    with pytest.raises(ParameterError, match=r"samples_per_revolution = 1000000000000 .*implies 4\.8e\+14 samples"
                                             r".*the limit is 1e\+09 samples"):
        spec_from_dict(_sweep(tmp_path, {"samples_per_revolution": 10 ** 12}))


def test_check_request_names_the_size_and_the_limit():
    from camdyn.simulation import limits

    with pytest.raises(ParameterError, match=r"the grid implies 2e\+06 points \(about 16 MB\); the limit is 1e\+06"):
        limits.check_request("the grid", 2e6, 8, limit=1e6, unit="points")
    with pytest.raises(ParameterError, match=r"implies 1e\+15 samples of 8 B, about 8e\+03 TB, but only .* free"):
        limits.check_request("a record", 1e15, 8, unit="samples")
    with pytest.raises(ParameterError, match="not a size"):
        limits.check_request("a record", math.nan, 8)
    assert limits.check_request("a record", 1000, 8) == 1000


def _cli(capsys, *argv):
    """Run the command line in this process: (status, standard error)."""
    from camdyn.cli.app import main

    capsys.readouterr()
    status = main([str(a) for a in argv])
    return status, capsys.readouterr().err


def _one_error_line(status, err, *words):
    lines = [line for line in err.splitlines() if line.strip()]
    assert status == 2, err
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    for word in words:
        assert word in lines[0], lines[0]


@pytest.mark.parametrize("argv, words", [
    (["--duration", "1e9"], ["an impulse test of 1e+09 s at 20000 Hz implies 2e+13 samples", "memory are free"]),
    (["--sample-rate", "1THz"], ["an impulse test of 1 s at 1e+12 Hz implies 1e+12 samples", "memory are free"]),
    (["--noise", "1e300"], ["noise must be a fraction of each channel's rms from 0 to 10", "1e+300"]),
    (["--noise", "-1"], ["noise must be a fraction of each channel's rms from 0 to 10", "-1.0"]),
])
def test_synthesize_impulse_refuses_before_allocating(tmp_path, capsys, argv, words):
    out = tmp_path / "imp.csv"
    _one_error_line(*_cli(capsys, "synthesize-impulse", *argv, "--out", out), *words)
    assert not out.exists()


def test_design_refuses_a_huge_grid_before_making_it(tmp_path, capsys):
    status, err = _cli(capsys, "design", "sundar2014-friction", "--ratios", "0.05:0.5:10000000", "--speeds",
                       "5Hz:30Hz:100000", "--json")
    _one_error_line(status, err, "the design grid implies 1e+07 points", "the limit is 1e+05 points")
    status, err = _cli(capsys, "design", "sundar2014-friction", "--ratios", "0.05:0.5:1000", "--speeds",
                       "5Hz:30Hz:1000", "--json")
    _one_error_line(status, err, "the design grid implies 1e+06 points", "the limit is 1e+05 points")


def test_identify_impact_damping_refuses_a_huge_or_negative_bootstrap(tmp_path, capsys):
    record = tmp_path / "r.csv"     # never read: the option is refused first
    status, err = _cli(capsys, "identify", "impact-damping", "sundar2014-impact", record, "--bootstrap",
                       "100000000")
    _one_error_line(status, err, "bootstrap = 100000000 implies 1e+08 replicates", "the limit is 1e+04")
    status, err = _cli(capsys, "identify", "impact-damping", "sundar2014-impact", record, "--bootstrap", "-3")
    _one_error_line(status, err, "bootstrap must be a whole number of replicates >= 0", "-3")


def test_identify_impact_damping_refuses_a_record_given_twice(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    status, err = _cli(capsys, "identify", "impact-damping", "sundar2014-impact", "r.csv", tmp_path / "r.csv")
    _one_error_line(status, err, f"the record {tmp_path / 'r.csv'} is given twice (as r.csv before)")


def test_impact_damping_api_refuses_the_same_record_twice(impact_rig):
    from camdyn.identification.impact_damping import estimate_impact_damping
    from camdyn.records.schema import make_record

    rec = make_record(np.arange(100) / 1e3, {"alpha_ddot": np.zeros(100)}, speed_hz=16.0)
    with pytest.raises(ParameterError, match="record #2 is the same record as an earlier one"):
        estimate_impact_damping(impact_rig, [rec, rec], bootstrap=0)
    with pytest.raises(ParameterError, match=r"expected a record \(#1\).*got str 'r.csv'"):
        estimate_impact_damping(impact_rig, ["r.csv"], bootstrap=0)


def test_lyapunov_refuses_a_billion_revolutions(capsys):
    status, err = _cli(capsys, "lyapunov", "sundar2014-impact", "--speed", "16Hz", "--revolutions", "1000000000")
    _one_error_line(status, err, "a Lyapunov spectrum of 200 + 1000000000 periods implies 1e+09 periods",
                    "the limit is 1e+06 periods")


def test_lyapunov_spectrum_api_refuses_a_billion_revolutions(impact_rig, no_simulation):
    from camdyn.analysis.lyapunov import lyapunov_spectrum

    with pytest.raises(ParameterError, match="the limit is 1e\\+06 periods"):
        lyapunov_spectrum(impact_rig, speed=16.0, revolutions=10 ** 9)


# -- 4. values accepted without a word ------------------------------------------------------


def test_simulate_warns_about_less_than_a_revolution(capsys):
    status, err = _cli(capsys, "simulate", "sundar2014-impact", "--speed", "16Hz", "--revolutions", "0.5", "--json")
    assert status == 0 and "warning: --revolutions 0.5 is less than one cam revolution" in err
    status, err = _cli(capsys, "simulate", "sundar2014-impact", "--revolutions", "0")
    _one_error_line(status, err, "--revolutions must be a positive, finite number of cam revolutions, got 0.0")


def test_an_unphysical_friction_coefficient_is_warned_about():
    with pytest.warns(UserWarning, match=r"friction.coefficient = 1e\+06 is outside any physical range"):
        camdyn.load_system("sundar2014-friction", {"friction.coefficient": "1e6"})


@pytest.mark.parametrize("noise, seed, words", [
    (1e300, 0, "noise must be a fraction of each channel's rms from 0 to 10"),
    (-1.0, 0, "noise must be a fraction of each channel's rms from 0 to 10"),
    (0.01, -1, "the noise seed must be a whole number >= 0"),
    (0.01, 1.5, "the noise seed must be a whole number >= 0"),
])
def test_synthesize_refuses_meaningless_noise_and_seed(friction_rig, no_simulation, noise, seed, words):
    from camdyn.records.synthesis import synthesize

    with pytest.raises(ParameterError, match=words):
        synthesize(friction_rig, 11.55, revolutions=3, noise=noise, seed=seed)


def test_a_seed_is_any_whole_number_from_zero(no_simulation):
    from camdyn.identification.modal import synthesize_impulse_test

    with pytest.raises(ParameterError, match="the noise seed must be a whole number >= 0"):
        synthesize_impulse_test(duration=0.01, noise=0.01, seed=-1)
    a = synthesize_impulse_test(duration=0.01, noise=0.01, seed=12345678901234567890123)
    b = synthesize_impulse_test(duration=0.01, noise=0.01, seed=12345678901234567890123)
    assert np.array_equal(a["force"].values, b["force"].values)


@pytest.mark.parametrize("argv, words", [
    (["--harmonic-margin", "-1"], ["harmonic_margin must be a positive, finite ratio, got -1.0"]),
    (["--speeds", "30Hz:5Hz:6"], ["the design speeds must increase", "30 Hz ... 5 Hz"]),
])
def test_design_refuses_meaningless_options(tmp_path, capsys, argv, words):
    grid = {"--ratios": "0.1,0.3", "--speeds": "8Hz:20Hz:3", **dict(zip(argv[::2], argv[1::2]))}
    status, err = _cli(capsys, "design", "sundar2014-friction", *[x for kv in grid.items() for x in kv], "--json")
    _one_error_line(status, err, *words)


def test_design_map_api_refuses_reversed_speeds_before_work(friction_rig, monkeypatch):
    from camdyn.tribology import design

    monkeypatch.setattr(design, "_point", _no_work)
    with pytest.raises(ParameterError, match="the design speeds must increase"):
        design.design_map(friction_rig, "runout", [0.1], [30.0, 20.0, 10.0])
    with pytest.raises(ParameterError, match="contact_margin must be a non-negative, finite ratio"):
        design.design_map(friction_rig, "runout", [0.1], [10.0], contact_margin=math.nan)


def test_more_workers_than_cores_are_capped_with_a_warning():
    from camdyn.sweeps.execution import check_workers, default_workers

    with pytest.warns(UserWarning, match=f"workers = 100000 is more than the {default_workers()} cores"):
        assert check_workers(100000) == default_workers()
    assert check_workers(100000, dask="local") == 100000
    with pytest.raises(ParameterError, match="workers must be a whole number >= 0, got -1"):
        check_workers(-1)
    with pytest.raises(ParameterError, match="workers must be a whole number >= 0, got '4'"):
        check_workers("4")


def test_more_threads_than_cores_are_capped_with_a_warning(monkeypatch):
    from camdyn.sweeps import execution

    monkeypatch.setattr(execution, "default_workers", lambda: 4)
    with pytest.warns(UserWarning, match="threads = 1000 per worker on 1 process.* the 4 cores .*; using 4"):
        assert execution.check_threads(1000, 0) == 4                   # inline: this process
    with pytest.warns(UserWarning, match="threads = 3 per worker on 2 process.*; using 2"):
        assert execution.check_threads(3, 2) == 2
    with pytest.warns(UserWarning, match="using 1"):
        assert execution.check_threads(2, 4) == 1
    assert execution.check_threads(2, 2) == 2 and execution.check_threads(8, 4, dask="local") == 8
    for bad in (0, -1, 1.5, "2", True):
        with pytest.raises(ParameterError, match="threads must be a whole number >= 1"):
            execution.check_threads(bad, 1)


# -- 5. TOML nested without bound ------------------------------------------------------------


@pytest.mark.parametrize("text", ["a = " + "[" * 5000 + "]" * 5000 + "\n",
                                  "a = " + "{b = " * 2000 + "1" + "}" * 2000 + "\n",
                                  "[" + ".".join(["t"] * 200) + "]\nx = 1\n"])
def test_deep_toml_is_refused_with_the_limit(tmp_path, capsys, text):
    from camdyn.params.config import MAX_TOML_DEPTH, load_system

    path = tmp_path / "deep.toml"
    path.write_text(text)
    with pytest.raises(ParameterError, match=f"deep.toml: TOML nested deeper than {MAX_TOML_DEPTH} levels"):
        load_system(path)
    status, err = _cli(capsys, "simulate", path)
    _one_error_line(status, err, f"TOML nested deeper than {MAX_TOML_DEPTH} levels")


def test_a_toml_file_too_long_is_refused_without_reading_it_whole(tmp_path, capsys, monkeypatch):
    from camdyn.params.config import MAX_TOML_CHARS, load_system
    from camdyn.sweeps.spec import load_spec

    path = tmp_path / "long.toml"
    path.write_text("# " + "x" * MAX_TOML_CHARS + "\n")

    def whole(self, *args, **kwargs):
        raise AssertionError(f"{self} read whole")

    monkeypatch.setattr(Path, "read_text", whole)       # a file of gigabytes would be in memory
    words = f"more than {MAX_TOML_CHARS} characters of TOML"
    with pytest.raises(ParameterError, match=f"long.toml: {words}"):
        load_system(path)
    with pytest.raises(ParameterError, match=f"sweep spec long.toml: {words}"):
        load_spec(path)
    status, err = _cli(capsys, "simulate", path)
    _one_error_line(status, err, words)


def test_deep_sweep_spec_is_refused_with_the_limit(tmp_path):
    from camdyn.sweeps.spec import load_spec

    path = tmp_path / "deep.toml"
    path.write_text("a = " + "[" * 5000 + "]" * 5000 + "\n")
    with pytest.raises(ParameterError, match="sweep spec deep.toml: TOML nested deeper than 32 levels"):
        load_spec(path)


# -- 6. messages that say what happened -----------------------------------------------------


def test_too_many_impacts_are_counted_in_the_message():
    from camdyn.errors import IdentificationError
    from camdyn.identification.impact_events import _periodic_contacts

    rate, speed = 10e3, 1.0
    t = np.arange(int(2 * rate)) / rate            # two revolutions
    acc = np.random.default_rng(0).normal(0.0, 1.0, t.size)
    for at in (0.3, 0.9, 1.5):                     # three impacts
        acc[int(at * rate):int(at * rate) + 20] += 1000.0
    with pytest.raises(IdentificationError, match=r"found 3 impacts in 2 revolutions, 1\.50 impacts per revolution; "
                                                  r"the estimator needs exactly one impact per revolution, because"):
        _periodic_contacts(t, acc, speed, 1, 0)


def test_tribology_refuses_a_cam_at_rest_before_work(capsys, friction_rig, monkeypatch):
    from camdyn.tribology import film

    monkeypatch.setattr(film, "inverse_kinematics", _no_work)
    with pytest.raises(ParameterError, match="the contact conditions need a turning cam"):
        film.contact_conditions(friction_rig, 0.0)
    status, err = _cli(capsys, "tribology", "sundar2014-friction", "--speed", "0Hz")
    _one_error_line(status, err, "the contact conditions need a turning cam", "got 0.0")
    assert "All-NaN" not in err


def test_mechanism_sweep_spec_checks_a_bounded_number_of_values(tmp_path, monkeypatch):
    from pathlib import Path

    from camdyn.sweeps import mechanism_spec
    from camdyn.sweeps.spec import spec_from_dict

    real, calls = mechanism_spec.check_mechanism, []

    def check(mechanism):
        calls.append(1)
        if len(calls) > 100:
            raise AssertionError("the spec's check builds a mechanism per value")
        return real(mechanism)

    monkeypatch.setattr(mechanism_spec, "check_mechanism", check)
    source = str(Path(__file__).parent.parent / "examples" / "mechanisms" / "flexible_pivot.toml")
    spec = spec_from_dict({"system": {"source": source},
                           "vary": [{"key": "pivot.stiffness", "start": "2e7 N/m", "stop": "5e7 N/m", "num": 1000}],
                           "output": {"path": str(tmp_path / "m.nc")}})
    from camdyn.sweeps.spec import CHECKED_VALUES

    assert spec.points == 1000 and len(calls) == 1 + CHECKED_VALUES     # the base mechanism, then the values


@pytest.mark.parametrize("path, words", [
    ("examples/profiles/rocking_roller.toml", "the rocking follower ([follower] kind = 'rocking')"),
    ("examples/mechanisms/flexible_pivot.toml", "a mechanism's configuration"),
])
def test_another_familys_configuration_is_named_not_taken_for_a_typo(path, words):
    """A configuration of another family given to an entry of the thesis's rocking
    follower says what it is, not "unknown parameter 'follower.kind'; did you mean ..."."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    with pytest.raises(ParameterError, match="not the rocking flat-faced follower") as caught:
        camdyn.load_system(str(root / path))
    assert words in str(caught.value) and "did you mean" not in str(caught.value)


def test_a_record_named_txt_is_written_as_csv_text_and_says_so(tmp_path, capsys):
    # .txt is read as CSV (camdyn.io.measurements), so it may name a record; the command
    # says which format it wrote, and a suffix of no record format is refused
    from camdyn.cli.app import main
    from camdyn.io.measurements import read_measurement

    out = tmp_path / "y11.txt"
    capsys.readouterr()
    assert main(["synthesize-impulse", "--duration", "0.05", "--out", str(out)]) == 0
    said = capsys.readouterr().out
    assert said.startswith(f"wrote {out} (") and ") as CSV text: modes at" in said, said
    assert out.read_text().lstrip().startswith(("#", "time"))          # text, not HDF5 or UFF
    assert set(read_measurement(out).data_vars) >= {"force", "acceleration"}
    refused = tmp_path / "y11.dat"
    _one_error_line(*_cli(capsys, "synthesize-impulse", "--duration", "0.05", "--out", refused),
                    "a record is .csv (or .txt, written as CSV text)")
    assert not refused.exists()
