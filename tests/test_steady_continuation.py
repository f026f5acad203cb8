"""Frequency responses by harmonic balance (camdyn.steady.continue_harmonic and
``camdyn continue --method harmonic-balance``) against independent references: a long
plain simulation's last revolution (numpy FFT) for the cam harmonics, shooting's
monodromy matrix for the stability, and shooting's continuation for the contact loss."""

import json
import math

import numpy as np
import pytest

import camdyn
from camdyn.continuation.branches import continue_orbits
from camdyn.continuation.orbits import find_orbit
from camdyn.continuation.problem import system_problem
from camdyn.continuation.spectra import cam_harmonics
from camdyn.steady import continue_harmonic
from camdyn.steady.tables import harmonic_record


@pytest.fixture(scope="module")
def rig():
    return camdyn.load_system("sundar2014-friction")                      # e/a = 0.1


@pytest.fixture(scope="module")
def curve(rig):
    problem = system_problem(rig.with_values(**{"motion.speed": 5.0}), "motion.speed")
    return problem, continue_harmonic(problem, 5.0, 17.0)


def _nearest(curve, value: float) -> int:
    return int(np.argmin(np.abs(np.asarray(curve.parameters) - value)))


def test_curve_covers_the_range_in_sustained_contact(curve):
    problem, branch = curve
    assert branch.parameters[0] == 5.0 and branch.parameters[-1] == pytest.approx(17.0, abs=1e-9)
    assert "end of its range" in branch.branch.stopped
    assert all(o.force_minimum > 0 for o in branch.branch.orbits)
    assert all(h.tail < 1e-8 for h in branch.harmonic_orbits)            # H doubled where needed
    assert np.all(np.diff(branch.parameters) > 0)


@pytest.mark.parametrize("speed", [7.0, 12.0, 16.5])
def test_alpha_ddot_harmonics_equal_a_long_simulation(rig, curve, speed):
    problem, branch = curve
    i = _nearest(branch, speed)
    value = branch.parameters[i]
    record = harmonic_record(problem, branch.branch.orbits[i], branch.harmonic_orbits[i])
    per_rev, revs = 256, 40
    ds = camdyn.simulate(rig.with_values(**{"motion.speed": value}), revolutions=revs, sample_rate=value * per_rev,
                         rtol=1e-11, atol=1e-13, variables=["alpha_ddot", "in_contact"])
    last = ds.alpha_ddot.values[(revs - 1) * per_rev:revs * per_rev]
    assert bool(ds.in_contact.values[-per_rev:].all())
    simulated = 2.0 * np.abs(np.fft.rfft(last))[1:5] / per_rev          # amplitudes of harmonics 1-4 [rad/s^2]
    balanced = np.asarray(record["harmonics"]["alpha_ddot"][:4])
    # each harmonic to 1e-6 of itself (measured at most 6.6e-7, the 4th at 7.2 Hz; 5e-11 of the 1st)
    assert np.all(np.abs(balanced - simulated) < 1e-6 * simulated), (balanced, simulated)


def test_hill_stability_agrees_with_the_monodromy_matrix(curve):
    problem, _ = curve
    # the 200-point curve of benchmarks/bench_steady_continuation.py, every point of it
    branch = continue_harmonic(problem, 5.0, 17.0, max_step=0.0165, max_points=400)
    assert len(branch.parameters) >= 200
    for orbit in branch.branch.orbits:
        shot = find_orbit(problem, start=orbit.state, value=orbit.parameter)
        assert shot.stable == orbit.stable
        # Floquet exponents' real parts ln|mu| / T agree to 5 % (measured at most 2.8 % over
        # the 206 points: Hill's matrix at the curve's H does not resolve the ~1 kHz contact
        # mode exactly)
        hill, monodromy = np.log(np.abs(orbit.multipliers)), np.log(np.abs(shot.multipliers))
        assert np.allclose(np.sort(hill), np.sort(monodromy), rtol=0.05), (orbit.parameter, hill, monodromy)


@pytest.mark.parametrize("runout, start, stop", [("1.75 mm", 17.8, 18.1), ("0.875 mm", 24.1, 24.45)])
def test_contact_loss_agrees_with_shooting(runout, start, stop):
    system = camdyn.load_system("sundar2014-friction", {"cam.runout": runout, "motion.speed": f"{start} Hz"})
    problem = system_problem(system, "motion.speed")
    branch = continue_harmonic(problem, start, stop)
    loss = [b for b in branch.branch.bifurcations if b.kind == "contact-loss"]
    assert len(loss) == 1 and "contact lost" in branch.branch.stopped
    assert branch.parameters[-1] == loss[0].parameter and abs(loss[0].orbit.force_minimum) < 1e-6
    shot = continue_orbits(problem, find_orbit(problem, start=branch.branch.orbits[0].state), stop, step=0.005,
                           max_step=0.01, max_points=40)
    expected = [b.parameter for b in shot.bifurcations if b.kind == "contact-loss"]
    assert len(expected) == 1
    # measured 1.6e-6 (e/a 0.1, 18.02379 Hz) and 1.7e-6 (e/a 0.05, 24.33295 Hz) relative
    assert abs(loss[0].parameter - expected[0]) < 1e-5 * expected[0], (loss[0].parameter, expected[0])


def test_cam_harmonics_of_a_known_signal():
    t = np.arange(64) / 64 * 2.0                                           # two forcing periods of 1 s
    values = 1.0 + 3.0 * np.cos(2 * math.pi * t) + 4.0 * np.sin(2 * math.pi * t) - 0.5 * np.sin(6 * math.pi * t) \
        + 0.25 * np.cos(math.pi * t)                                       # a subharmonic, not a cam harmonic
    assert np.allclose(cam_harmonics(values, 3, periods=2), [5.0, 0.0, 0.5], atol=1e-12)


def test_cli_frequency_response_json_has_shootings_schema_and_harmonics(capsys):
    from camdyn.cli.app import main
    assert main(["continue", "sundar2014-friction", "--method", "harmonic-balance", "--from", "11Hz", "--to",
                 "11.2Hz", "--json", "--quiet"]) == 0
    hb = json.loads(capsys.readouterr().out)
    assert main(["continue", "sundar2014-friction", "--from", "11Hz", "--to", "11.2Hz", "--json", "--quiet",
                 "--no-cover"]) == 0
    shot = json.loads(capsys.readouterr().out)
    assert hb["schema"] == shot["schema"] == "camdyn.continue/1"
    assert set(shot["summary"]) <= set(hb["summary"]) and hb["summary"]["method"] == "harmonic-balance"
    first, reference = hb["branches"][0][0], shot["branches"][0][0]
    assert set(reference) <= set(first) and first["parameter"] == reference["parameter"] == 11.0
    assert set(first["harmonics"]) == set(reference["harmonics"]) == {"alpha_ddot", "Fn", "Nx", "Ny"}
    assert len(first["harmonics"]["Fn"]) == first["harmonic_count"] and len(reference["harmonics"]["Fn"]) == 8
    # two methods, the same orbit: shooting's harmonics from its 512 samples per period
    for name in ("alpha_ddot", "Fn", "Nx", "Ny"):
        a, b = np.asarray(first["harmonics"][name][:4]), np.asarray(reference["harmonics"][name][:4])
        assert np.all(np.abs(a - b) < 1e-6 * np.max(b)), (name, a, b)


@pytest.mark.parametrize("args, words", [
    (["alzate", "--from", "700rpm", "--to", "710rpm"], "rocking cam-follower"),
    (["sundar2014-friction", "--from", "11Hz", "--to", "12Hz", "--period", "2"], "period-1"),
    (["sundar2014-friction", "--from", "11Hz", "--to", "12Hz", "--harmonics", "0"], "--harmonics"),
    (["sundar2014-friction", "--from", "19Hz", "--to", "20Hz"], "no orbit in sustained contact"),
])
def test_cli_harmonic_balance_refuses_in_one_line(args, words, capsys):
    from camdyn.cli.app import main
    assert main(["continue", *args, "--method", "harmonic-balance"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error:") and words in err[0], err
