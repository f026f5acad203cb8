"""Parameters fitted to a steady-state record through the harmonic-balance orbit
(camdyn.steady.record_fit.fit_record), on a record that camdyn did not make: the chapter 4
rig integrated by the independent SciPy model (camdyn.testing.oracle), its pivot
reactions written here by Newton-Euler in vector form."""

import math

import numpy as np
import pytest
import xarray as xr

import camdyn
from camdyn.continuation.problem import system_problem
from camdyn.errors import DataError, IdentificationError, ParameterError
from camdyn.identification.friction import estimate_friction
from camdyn.simulation.runner import prepare
from camdyn.steady import harmonic_balance
from camdyn.steady.record_fit import fit_record
from camdyn.testing.oracle import ReferenceModel, reference_simulate

MU = 0.3
PER_REV = 256


@pytest.fixture(scope="module")
def record():
    """Five revolutions of the chapter 4 rig (e/a = 0.1, 11.55 Hz, mu = 0.3) by the SciPy
    model: alpha_ddot, and Nx, Ny [N] from m a_G = N + F_contact + F_spring + m g."""
    system = camdyn.load_system("sundar2014-friction", {"friction.coefficient": MU})
    prep = prepare(system)
    # the start only: a state near the orbit, so that five revolutions are steady
    start = harmonic_balance(system_problem(system, "motion.speed"), "auto").samples[0]
    speed = system.motion.speed
    t = np.arange(5 * PER_REV) / (PER_REV * speed)
    _, y, info = reference_simulate(system, prep.theta0, start, t[-1], t, rtol=1e-10, atol=1e-12)
    assert info["events"] == 0                                   # sustained contact, one sliding direction
    model = ReferenceModel(system, prep.theta0)
    f, tilt = system.follower, system.spring.tilt
    nx, ny, acc = (np.empty(t.size) for _ in range(3))
    for j in range(t.size):
        alpha_dot = y[1, j]
        *_, vr, _, n, u = model.geometry(t[j], y[0, j], alpha_dot)
        alpha_ddot, fn, ff, fs, _ = model.forces(t[j], y[:, j], True, math.copysign(1.0, vr), 0.0)
        r_g = f.cg_distance * u
        # omega = -alpha_dot z: a_G = omega_dot x r_G + omega x (omega x r_G)
        a_g = -alpha_ddot * np.array([-r_g[1], r_g[0]]) - alpha_dot ** 2 * r_g
        reaction = (f.mass * a_g - (-fn * n + ff * u) - fs * np.array([math.sin(tilt), math.cos(tilt)])
                    - np.array([0.0, -f.mass * system.gravity]))
        nx[j], ny[j], acc[j] = reaction[0], reaction[1], alpha_ddot
    return xr.Dataset({"Nx": ("time", nx, {"units": "N"}), "Ny": ("time", ny, {"units": "N"}),
                       "alpha_ddot": ("time", acc, {"units": "rad/s^2"})},
                      coords={"time": ("time", t, {"units": "s"})}, attrs={"speed_hz": speed})


def _start(**values):
    return camdyn.load_system("sundar2014-friction", values)


def test_friction_from_an_independent_record(record):
    fit = fit_record(_start(**{"friction.coefficient": 0.1}), record)
    # noise-free: the two models agree to about 1e-9 of each harmonic (measured 1.5e-10 in mu)
    assert fit.values["friction.coefficient"] == pytest.approx(MU, rel=1e-6)
    assert fit.residual < 1e-7
    for channel in fit.channels:
        assert np.allclose(fit.predicted[channel], fit.measured[channel],
                           rtol=1e-6, atol=1e-6 * np.max(np.abs(fit.measured[channel])))
    assert fit.evaluations > 3 and fit.orbit.stable


def test_with_noise_it_beats_the_force_balance(record):
    rng = np.random.default_rng(7)
    noisy = record.copy()
    for name in ("Nx", "Ny", "alpha_ddot"):
        x = record[name].values
        noisy[name] = ("time", x + 0.01 * np.sqrt(np.mean(x ** 2)) * rng.standard_normal(x.size))
    fit = fit_record(_start(**{"friction.coefficient": 0.1}), noisy)
    balance = estimate_friction(_start(), noisy)
    # 1 % white noise on every channel, 5 revolutions: measured +4.7e-4 of mu (orbit, its
    # standard error 3.7e-4 of mu), +4.1e-3 (the thesis's force balance, 20 harmonics)
    error = abs(fit.values["friction.coefficient"] - MU)
    assert error < 3.0 * fit.standard_errors["friction.coefficient"]
    assert fit.standard_errors["friction.coefficient"] < 1e-3 * MU
    assert error < 0.2 * abs(balance.mu - MU)


def test_two_parameters_at_once(record):
    start = _start(**{"friction.coefficient": 0.1, "spring.stiffness": "2800 N/m"})
    fit = fit_record(start, record, keys=("friction.coefficient", "spring.stiffness"))
    assert fit.values["friction.coefficient"] == pytest.approx(MU, rel=1e-6)
    assert fit.values["spring.stiffness"] == pytest.approx(_start().spring.stiffness, rel=1e-6)   # 2954 N/m


def test_another_friction_makes_another_record_not_the_same_answer(record):
    # a deliberate mistake the fit must see: the record's Nx scaled as a friction change would
    wrong = record.copy()
    wrong["Nx"] = record["Nx"] * 1.05
    fit = fit_record(_start(), wrong)
    assert abs(fit.values["friction.coefficient"] - MU) > 1e-3
    assert fit.residual > 1e-3


@pytest.mark.parametrize("change, error, match", [
    ({"keys": ("friction.law",)}, ParameterError, "not a continuous parameter"),
    ({"keys": ("motion.speed",)}, ParameterError, "other than motion.speed"),
    ({"keys": ("friction.coefficient", "friction.coefficient")}, ParameterError, "distinct"),
    ({"harmonics": 0}, ParameterError, "harmonics"),
    ({"revolutions": 9}, IdentificationError, "whole cam revolutions"),
    ({"channels": ("Nz",)}, ParameterError, "channels"),
    ({"channels": ("Fn",)}, DataError, "no Fn channel"),
    ({"speed": "12 Hz"}, DataError, "its metadata"),
    ({"speed": "-3 Hz"}, ParameterError, "speed"),
    ({"bounds": ([0.5], [1.0])}, None, None),
])
def test_bad_settings_are_refused_before_any_work(record, change, error, match):
    if error is None:   # a start outside the bounds is moved inside: the fit ends on the bound
        fit = fit_record(_start(), record, **change)
        assert fit.values["friction.coefficient"] == pytest.approx(0.5)
        assert math.isnan(fit.standard_errors["friction.coefficient"])   # on its bound: none
        return
    with pytest.raises(error, match=match):
        fit_record(_start(), record, **change)


def test_a_file_name_is_refused_with_the_call_that_reads_it():
    with pytest.raises(ParameterError, match="read_measurement"):
        fit_record(_start(), "record.csv")


def test_command_line_fits_the_record_file(record, tmp_path, capsys):
    import json

    from camdyn.cli.app import main
    from camdyn.io.measurements import write_measurement

    path = write_measurement(record, tmp_path / "record.nc")
    assert main(["identify", "friction", "sundar2014-friction", str(path), "--set", "friction.coefficient=0.1",
                 "--method", "orbit", "--json"]) == 0
    document = json.loads(capsys.readouterr().out)
    assert document["schema"] == "camdyn.identify-orbit-fit/1"
    assert document["summary"]["values"]["friction.coefficient"] == pytest.approx(MU, rel=1e-6)
    assert document["units"]["Nx"] == "N" and document["summary"]["speed_hz"] == pytest.approx(11.55)
    assert main(["identify", "friction", "sundar2014-friction", str(path), "--fit", "friction.coefficient"]) == 2
    assert "--fit goes with --method orbit" in capsys.readouterr().err
    assert main(["identify", "friction", "sundar2014-friction", str(path), "--method", "guess"]) == 2


def test_more_harmonics_compared_than_the_orbit_needs(record):
    # K = 20 > the orbit's own H (8): the orbit is balanced at H = K so that its grid
    # resolves every harmonic compared
    fit = fit_record(_start(**{"friction.coefficient": 0.1}), record, harmonics=20)
    assert fit.orbit.harmonics >= 20 and len(fit.predicted["Nx"]) == 21
    assert fit.values["friction.coefficient"] == pytest.approx(MU, rel=1e-6)
