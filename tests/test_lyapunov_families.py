"""Lyapunov exponents of every family with a periodic problem
(camdyn.continuation.lyapunov, ``camdyn lyapunov``), against closed forms:

- the forced linear oscillator: both exponents are -zeta w (the real part of
  -zeta w +- i w sqrt(1 - zeta^2));
- the rigid-impact oscillator's stable one-impact orbit (closed form in
  tests/test_continuation.py): both exponents are ln|mu| / T of its closed-form monodromy
  (a complex pair);
- a strongly attracting mechanism (two followers at a prescribed 10 Hz, contracting by
  e^-12 per period): the two-trajectory estimate, renormalised within the period, equals
  the Floquet exponent of the orbit Newton's method finds, where one renormalisation per
  period left the gap in the integration error (-98 against -123 1/s).

Each estimate must lie within its stated uncertainty of the exact value: twice its
standard error plus the start's allowance ln(10) / (N T) (camdyn.analysis.chaos).
"""

import json
import math

import numpy as np
import pytest
from test_continuation import _closed_form_multipliers, _impact_orbit, _rigid

from camdyn.analysis.chaos import START_ALLOWANCE
from camdyn.cli.problems import source_problem
from camdyn.continuation import find_orbit, model_problem
from camdyn.continuation.lyapunov import orbit_lyapunov, orbit_spectrum
from camdyn.errors import ParameterError
from camdyn.systems import registry as systems

PERIODS = 200


def _within(estimate: float, error: float, exact: float, period: float) -> bool:
    return abs(estimate - exact) <= 2.0 * error + START_ALLOWANCE / (PERIODS * period)


def test_the_linear_oscillators_exponents_are_minus_zeta_w():
    w, zeta, forcing = 2.0, 0.05, 1.3
    problem = model_problem(systems.OSCILLATOR, [w, zeta, 0.7, forcing, 0.0], [0.0, 0.0, 0.0])
    period = 2 * math.pi / forcing
    two = orbit_lyapunov(problem, revolutions=PERIODS, transient=20)
    assert two.speed == pytest.approx(1.0 / period, rel=1e-14)
    assert _within(two.exponent, two.error, -zeta * w, period), (two.exponent, two.error)
    spectrum = orbit_spectrum(problem, revolutions=PERIODS, transient=20)
    for value, error in zip(spectrum.exponents, spectrum.errors):
        assert _within(value, error, -zeta * w, period), (value, error)
    assert spectrum.total == pytest.approx(-2 * zeta * w, abs=1e-6)   # the trace: exact every period


def test_the_rigid_impact_orbits_exponents_are_its_closed_form_multipliers():
    forcing = 2.5
    period = 2 * math.pi / forcing
    t_impact, v = _impact_orbit(forcing, 0.0, [1.1, -0.5])
    exact = np.log(np.abs(_closed_form_multipliers(forcing, 0.0, t_impact, v))) / period
    assert exact[0] == pytest.approx(exact[1], rel=1e-12)       # a complex pair
    problem = _rigid(forcing)
    two = orbit_lyapunov(problem, revolutions=PERIODS, transient=50)
    assert _within(two.exponent, two.error, exact[0], period), (two.exponent, two.error, exact)
    spectrum = orbit_spectrum(problem, revolutions=PERIODS, transient=50)
    assert spectrum.events >= PERIODS                           # one impact per period, saltation applied
    for value, error in zip(spectrum.exponents, spectrum.errors):
        assert _within(value, error, exact[0], period), (value, error, exact)


def test_a_strongly_attracting_mechanism_is_measured_below_its_integration_error():
    problem = source_problem("two-followers-prescribed", None, "10 Hz")
    floquet = np.log(np.abs(find_orbit(problem, transient=100).multipliers)).max() * 10.0   # 1 / T = 10 Hz
    two = orbit_lyapunov(problem, revolutions=60, transient=30)
    assert abs(two.exponent - floquet) <= 2.0 * two.error + START_ALLOWANCE / (60 / 10.0), (two.exponent, floquet)
    assert floquet < -100.0                                     # e^-12 per period


def test_a_cam_under_its_drive_and_the_rocking_arm_are_refused_with_the_reason():
    with pytest.raises(ParameterError, match="sets its own speed"):
        orbit_lyapunov(source_problem("driven-cam"), revolutions=10, transient=1)
    with pytest.raises(ParameterError, match="no periodic problem"):
        source_problem("rocking-roller")


@pytest.mark.parametrize("source, words", [("driven-cam", "sets its own speed"),
                                           ("rocking-roller", "no periodic problem")])
def test_the_command_refuses_them_in_one_line(source, words, capsys):
    from camdyn.cli.app import main

    assert main(["lyapunov", source, "--speed", "10Hz", "--revolutions", "10", "--transient", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error:") and words in err[0], err


@pytest.mark.parametrize("source, spectrum", [("alzate", True), ("flexible-pivot", True),
                                              ("two-followers-prescribed", False),   # 2.4 s per period
                                              ("examples/models/valve_train.py:VALVE_TRAIN", True)])
def test_the_command_takes_every_family_at_a_prescribed_speed(source, spectrum, capsys):
    from pathlib import Path

    from camdyn.cli.app import main

    if source.startswith("examples"):
        source = str(Path(__file__).resolve().parents[1] / source)
    assert main(["lyapunov", source, "--speed", "10Hz", "--revolutions", "20", "--transient", "10", "--json"]
                + (["--spectrum"] if spectrum else [])) == 0
    summary = json.loads(capsys.readouterr().out)["summary"]
    assert summary["speed_hz"] == pytest.approx(10.0, rel=1e-12) and math.isfinite(summary["exponent_per_s"])
    if spectrum:
        assert len(summary["spectrum_per_s"]) >= 2 and summary["spectrum_per_s"][0] >= summary["spectrum_per_s"][-1]
