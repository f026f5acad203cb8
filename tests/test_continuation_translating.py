"""Continuation of the translating follower's periodic orbits on the Alzate / di Bernardo rig
(preset ``alzate``), against values from outside the shooting code: long brute-force
runs of the simulator, Siconos's impact velocities (tests/data/siconos_camfollower.json),
a monodromy matrix built here from differences of perturbed simulations, the determinant
that Liouville's formula and the impact law give in closed form, and the regimes the
brute-force diagram shows on either side of a located bifurcation."""

import contextlib
import io
import json
import math
from pathlib import Path

import numpy as np
import pytest

from camdyn.cli.app import main
from camdyn.continuation.orbits import find_orbit
from camdyn.continuation.switching import switch_branch
from camdyn.continuation.translating import RPM, trace_translating, translating_dataset, translating_problem
from camdyn.errors import ParameterError
from camdyn.model.translating_follower import penalty_damping
from camdyn.simulation.translating import alzate_rig, simulate_translating

DATA = json.loads((Path(__file__).parent / "data" / "siconos_camfollower.json").read_text())
#: the runs sample only a few points per revolution, on purpose
pytestmark = pytest.mark.filterwarnings("ignore::camdyn.simulation.limits.LargeResultWarning")


@pytest.fixture(scope="module")
def rig():
    return alzate_rig()


@pytest.fixture(scope="module")
def orbit700(rig):
    return find_orbit(translating_problem(rig, (700.0 * RPM) / (2 * math.pi)), transient=100)


def _sections(rig, rpm, revolutions, per_revolution=8, initial_state=None):
    """The follower's state at cam angle 0 of every revolution of a plain run from the
    follower resting on the cam (or from ``initial_state``), and the run."""
    omega = rpm * RPM
    period = 2.0 * math.pi / omega
    ds = simulate_translating(rig, omega / (2 * math.pi), revolutions * period, sample_rate=per_revolution / period,
                              initial_state=initial_state)
    states = np.c_[ds["x"].values, ds["x_dot"].values][::per_revolution]
    return states, ds


def test_the_700_rpm_orbit_is_where_a_long_run_settles(rig, orbit700):
    """The period-1 orbit at 700 rpm (one impact per revolution) equals the state at cam
    angle 0 that a 300-revolution run from rest repeats, to 1e-6 relative."""
    states, _ = _sections(rig, 700.0, 300)
    last = states[-5:]
    assert np.ptp(last, axis=0).max() < 1e-8 * np.abs(last).max()          # the run has settled, period 1
    assert orbit700.impacts_per_period == 1 and orbit700.stable
    assert np.allclose(orbit700.state, last[-1], rtol=1e-6, atol=0.0)


def test_the_700_rpm_impact_velocity_agrees_with_siconos(rig, orbit700):
    """The orbit's impact velocity lies within Siconos's measured accuracy at 700 rpm of it:
    the spread of Siconos's average over its three steps plus its largest excursion from
    that average at the finest step (the measure of tests/test_siconos_benchmark.py)."""
    omega = 700.0 * RPM
    ds = simulate_translating(rig, omega / (2 * math.pi), 2.0 * math.pi / omega,
                              sample_rate=64 * omega / (2.0 * math.pi),
                              initial_state=orbit700.state)
    impacts = ds["event_velocity"].values[ds["event_kind"].values == "impact"]
    assert impacts.size == 1
    runs = [DATA["speeds"]["700"][steps] for steps in sorted(DATA["speeds"]["700"], key=int)]
    velocities = [np.array(run["impacts"]["velocity_m_per_s"][run["settled_after_revolutions"]:]) for run in runs]
    means = np.array([v.mean() for v in velocities])
    accuracy = np.ptp(means) + np.abs(velocities[-1] - means[-1]).max()
    assert abs(means[-1] - impacts[0]) <= accuracy
    assert accuracy < 0.01 * abs(impacts[0])                               # the comparison is not empty


def _compliant_rig():
    """The rig with the compliant law, its penalty matched to e = 0.8 (kc = 1e7 N/m)."""
    stiffness = 1e7
    return alzate_rig("compliant", stiffness, penalty_damping(0.8, stiffness, 1.221))


@pytest.mark.parametrize("law", ["rigid", "compliant"])
def test_the_monodromy_matches_differences_of_perturbed_simulations(rig, orbit700, law):
    """The saltation-corrected monodromy matrix equals central differences of one-revolution
    simulations from perturbed states (camdyn's simulator, automatic method, its own
    events), and its multipliers those of the differenced matrix, to 1e-5; for the rigid
    law (impact resets) and for the compliant one (a penalty switched on and off)."""
    if law == "compliant":
        rig = _compliant_rig()
        orbit700 = find_orbit(translating_problem(rig, (700.0 * RPM) / (2 * math.pi)), transient=100)
        assert orbit700.impacts_per_period == 1 and orbit700.stable
    omega = 700.0 * RPM
    period = 2.0 * math.pi / omega
    columns = []
    for j, h in enumerate((1e-6, 1e-5)):                                   # [m], [m/s]
        ends = []
        for sign in (1.0, -1.0):
            start = orbit700.state.copy()
            start[j] += sign * h
            ds = simulate_translating(rig, omega / (2 * math.pi), period, sample_rate=4.0 / period,
                                      initial_state=start, rtol=1e-12,
                                      atol=1e-14)
            ends.append(np.array([ds["x"].values[-1], ds["x_dot"].values[-1]]))
        columns.append((ends[0] - ends[1]) / (2.0 * h))
    differenced = np.column_stack(columns)
    assert np.allclose(orbit700.monodromy, differenced, rtol=1e-5, atol=1e-5 * np.abs(differenced).max())
    ours = np.sort_complex(orbit700.multipliers)
    theirs = np.sort_complex(np.linalg.eigvals(differenced))
    assert np.allclose(ours, theirs, rtol=0.0, atol=1e-5)


def test_the_multipliers_product_is_the_restitution_squared(rig, orbit700):
    """Without damping the flight conserves phase volume (Liouville) and an impact on the
    moving cam, ``x'+ = (1 + e) s_dot - e x'-``, multiplies it by ``e^2`` (its saltation
    matrix is lower triangular with diagonal ``(-e, -e)``): an orbit with one impact per
    revolution has ``mu1 mu2 = e^2 = 0.64``; here the pair is complex, ``|mu| = 0.8``."""
    product = np.prod(orbit700.multipliers)
    assert abs(product - rig.restitution ** 2) < 1e-8
    assert np.allclose(np.abs(orbit700.multipliers), rig.restitution, atol=1e-8)


def test_an_orbit_captured_by_the_cam_has_zero_multipliers(rig):
    """At 170 rpm, the follower leaves the cam, lands in an accumulation of some 70
    impacts and is captured into sustained contact until it leaves again: after the
    capture its state is the cam's whatever it was before, so the capture's and the
    lift-off's saltation matrices vanish and both multipliers are 0. One revolution of
    the simulator from two different starts (resting on the cam; 0.2 m above it, at
    rest) that both end in a capture lands on the orbit's state."""
    omega, phase = 170.0 * RPM, 2.9                                          # [rad/s], [rad]: in flight
    orbit = find_orbit(translating_problem(rig, omega / (2 * math.pi), phase=phase), transient=5)
    assert np.array_equal(orbit.multipliers, np.zeros(2)) and orbit.impacts_per_period > 50
    period = 2.0 * math.pi / omega
    for start in (None, (0.2, 0.0)):
        ds = simulate_translating(rig, omega / (2 * math.pi), period, sample_rate=8.0 / period, phase=phase,
                                  initial_state=start)
        assert (ds["event_kind"].values == "capture").sum() == 1
        end = np.array([ds["x"].values[-1], ds["x_dot"].values[-1]])
        assert np.allclose(end, orbit.state, rtol=1e-6, atol=0.0)


def _period(states, longest=4):
    """The smallest number of revolutions ``k <= longest`` after which the last states
    repeat (to 1e-6 of their size), or None."""
    tail = states[-4 * longest - 1:]
    size = np.abs(tail).max()
    return next((k for k in range(1, longest + 1) if np.abs(tail[k:] - tail[:-k]).max() < 1e-6 * size), None)


def test_a_located_period_doubling_lies_where_the_brute_force_regime_changes(rig):
    """Continued upward from 700 rpm, the period-1 orbit loses stability at a period
    doubling. Runs of 600 revolutions from rest settle on period 1 at 737 rpm and do not
    at 741 rpm (they wander, as the diagram does from 740 rpm), so the doubling lies
    between them; a run started on the period-2 orbit switched onto there stays on it with
    period 2, as its multipliers say it must."""
    problem, branch = trace_translating(rig, 700.0 * RPM / (2 * math.pi), 745.0 * RPM / (2 * math.pi), step=0.01,
                                        max_points=80)
    doublings = [b for b in branch.bifurcations if b.kind == "period-doubling"]
    assert len(doublings) == 1
    assert np.min(np.abs(doublings[0].orbit.multipliers + 1.0)) < 1e-4
    assert _period(_sections(rig, 737.0, 600, per_revolution=4)[0]) == 1
    assert _period(_sections(rig, 741.0, 600, per_revolution=4)[0]) is None
    assert 737.0 < doublings[0].parameter / RPM < 741.0
    doubled = switch_branch(problem, doublings[0], 745.0 * RPM, step=0.01, max_points=3)
    orbit = doubled.orbits[-1]
    assert orbit.periods == 2 and orbit.stable and orbit.parameter / RPM > doublings[0].parameter / RPM
    states, _ = _sections(rig, orbit.parameter / RPM, 300, per_revolution=4, initial_state=orbit.state)
    assert _period(states) == 2
    assert np.allclose(states[-1], orbit.state, rtol=1e-6, atol=0.0)             # an even revolution


def test_the_problem_refuses_bad_input(rig):
    with pytest.raises(ParameterError, match="speed"):
        translating_problem(rig, -1.0 / (2 * math.pi))
    with pytest.raises(ParameterError, match="initial_state"):
        translating_problem(rig, 70.0 / (2 * math.pi), initial_state=(0.0, 1.0, 2.0))
    with pytest.raises(ParameterError, match="TranslatingFollower"):
        translating_problem("alzate", 70.0 / (2 * math.pi))
    with pytest.raises(ParameterError, match="different"):
        trace_translating(rig, 70.0 / (2 * math.pi), 70.0 / (2 * math.pi))
    with pytest.raises(ParameterError, match="no orbit"):
        translating_dataset(translating_problem(rig, 70.0 / (2 * math.pi)), [])


def run(argv):
    """``camdyn ARGV``: its exit status, standard output and standard error."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main([str(a) for a in argv])
    return status, out.getvalue(), err.getvalue()


@pytest.mark.parametrize("arguments, message", [
    (["--parameter", "spring.stiffness", "--from", "690rpm", "--to", "700rpm"], "motion.speed only"),
    (["--from", "700rpm", "--to", "700rpm"], "two different positive"),
    (["--from", "-5rpm", "--to", "700rpm"], "two different positive"),
    (["--from", "690rpm", "--to", "700rpm", "--brute-force", "5"], "give --plot"),
    (["--from", "690rpm", "--to", "700rpm", "--period", "0"], "at least 1"),
    (["--from", "690rpm", "--to", "700rpm", "--set", "spring.stiffness=-3N/m"], "spring.stiffness"),
])
def test_the_cli_refuses_what_it_cannot_do_in_one_line(tmp_path, monkeypatch, arguments, message):
    monkeypatch.chdir(tmp_path)
    status, out, err = run(["continue", "alzate", *arguments])
    assert status == 2, (out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:") and message in lines[0], lines
    assert not any(tmp_path.iterdir())                                      # nothing was written


def test_the_cli_continues_the_alzate_rig(tmp_path):
    """``camdyn continue alzate`` from 690 to 750 rpm: the period-1 branch with its period
    doubling, the period-2 branch switched onto there, written and drawn."""
    out, plot = tmp_path / "branch.nc", tmp_path / "branch.png"
    status, text, err = run(["continue", "alzate", "--parameter", "motion.speed", "--from", "690rpm", "--to",
                             "750rpm", "--out", out, "--plot", plot, "--json"])
    assert status == 0, err
    doc = json.loads(text)
    assert doc["bifurcations"][0]["kind"] == "period-doubling" and doc["bifurcations"][0]["branch"] == 0
    assert doc["summary"]["branch_count"] == 2
    assert 735.0 < doc["bifurcations"][0]["speed_rpm"] < 742.0
    single, double = doc["branches"]
    assert all(o["periods"] == 1 and len(o["poincare"]) == 1 for o in single)
    assert all(o["periods"] == 2 and len(o["poincare"]) == 2 for o in double)
    assert out.stat().st_size > 0 and plot.stat().st_size > 0
