"""Periodic orbits and continuation on the mechanisms held at a prescribed cam speed (the
flexible pivot, two followers with ``drive.kind = "prescribed"``), against values from
outside the shooting code: the rigid pivot's orbit (the stiff bearing's limit), a
monodromy matrix built here by central differences of whole plain runs over one period,
plain runs of several periods from the found orbit, and the single follower's orbit
(two identical followers on a cam held at its speed do not feel each other)."""

import contextlib
import dataclasses
import io
import json
import math
from pathlib import Path

import numpy as np
import pytest

from camdyn.cli.app import main
from camdyn.continuation.branches import continue_orbits
from camdyn.continuation.mechanisms import mechanism_problem
from camdyn.continuation.orbits import find_orbit, flow
from camdyn.continuation.problem import system_problem
from camdyn.errors import ParameterError
from camdyn.integrator import driver
from camdyn.params.config import load_system
from camdyn.simulation.flexible_pivot import FlexiblePivotRig, chapter3_flexible_pivot
from camdyn.simulation.mechanisms import CamDrive
from camdyn.simulation.two_followers import TwoFollowerRig, drum_brake

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "mechanisms"
#: The chapter 4 friction rig (11.55 Hz), in sustained contact: a very stable orbit
FRICTION = "sundar2014-friction"


def plain_end(problem, x, value, periods=1, rtol=1e-12):
    """The unknowns after ``periods`` cam periods of a plain run (the model alone, no
    state-transition matrix) from the unknowns ``x`` at ``t = 0``."""
    p, period = problem.build(value)
    y0 = problem.full_state(x, value)
    t1 = periods * period
    y, _, _, counters = driver.integrate(problem.system_id, p, y0, 0.0, t1, np.array([t1]), rtol, rtol * 1e-2,
                                         period / 32.0, driver.METHOD_DOP853, 50_000_000, 100_000, True, math.inf)
    assert counters[driver.COUNT_STATUS] == 0
    return y[-1, :problem.unknowns]


def difference_monodromy(problem, orbit, steps):
    """The monodromy matrix by central differences of whole plain runs over one period,
    column ``j`` from the unknown ``j`` moved by ``+- steps[j]``."""
    u = problem.unknowns
    matrix = np.empty((u, u))
    for j in range(u):
        up, down = orbit.state.copy(), orbit.state.copy()
        up[j] += steps[j]
        down[j] -= steps[j]
        matrix[:, j] = (plain_end(problem, up, orbit.parameter) - plain_end(problem, down, orbit.parameter)) / (
            2.0 * steps[j])
    return matrix


def prescribed_pair():
    """The drum brake (two identical followers opposite each other, gravity off) on a cam
    held at 11.55 Hz."""
    rig = drum_brake()
    return TwoFollowerRig(rig.system, rig.second, rig.placement, CamDrive(2e-4, kind="prescribed"))


@pytest.fixture(scope="module")
def pair_problem():
    return mechanism_problem(prescribed_pair())


@pytest.fixture(scope="module")
def pair_orbit(pair_problem):
    return find_orbit(pair_problem, transient=30)


@pytest.fixture(scope="module")
def friction_rig():
    return load_system(FRICTION)


@pytest.fixture(scope="module")
def rigid_orbit(friction_rig):
    return find_orbit(system_problem(friction_rig), transient=50)


@pytest.fixture(scope="module")
def stiff_problem(friction_rig):
    """A bearing of 1e9 N/m (5 % damping): the rigid pivot's limit."""
    kp = 1e9
    damping = 2.0 * 0.05 * math.sqrt(kp * friction_rig.follower.mass)
    return mechanism_problem(FlexiblePivotRig(friction_rig, kp, damping))


@pytest.fixture(scope="module")
def stiff_orbit(stiff_problem, rigid_orbit):
    """Newton's method from the rigid pivot's orbit, the bearing at its static deflection."""
    return find_orbit(stiff_problem, start=np.r_[rigid_orbit.state, stiff_problem.template[2:6]])


def test_a_stiff_bearing_gives_the_rigid_pivots_orbit(rigid_orbit, stiff_orbit):
    """As the bearing stiffens the follower's orbit tends to the rigid pivot's (its
    deflection, about Fn / kp, goes to zero): at 1e9 N/m, alpha and alpha_dot at the
    section agree with the rigid pivot's orbit to 1e-5; the bearing's own multipliers
    (its modes at tens of kHz, damped over a cam period) are negligible and the
    follower's two approach the rigid pivot's: their modulus within 5 % (measured 0.7 %;
    both pairs below 1e-4 in modulus: the rig's orbit is strongly attracting)."""
    assert stiff_orbit.state.size == 6 and stiff_orbit.residual < 1e-9
    assert np.max(np.abs(stiff_orbit.state[:2] - rigid_orbit.state)) < 1e-5
    # the bearing's deflection [m] is its force over kp: well under 100 N / kp on this rig
    assert math.hypot(stiff_orbit.state[2], stiff_orbit.state[4]) < 100.0 / 1e9
    follower, bearing = stiff_orbit.multipliers[:2], stiff_orbit.multipliers[2:]
    assert np.max(np.abs(bearing)) < 1e-12
    assert np.max(np.abs(rigid_orbit.multipliers)) < 1e-4 and np.max(np.abs(follower)) < 1e-4
    assert abs(np.abs(follower[0]) - np.abs(rigid_orbit.multipliers[0])) < 0.05 * np.abs(rigid_orbit.multipliers[0])


def test_the_stiff_bearings_orbit_closes_over_several_periods(stiff_problem, stiff_orbit):
    """A plain run of 3 cam periods from the found orbit returns to it within the
    shooting's convergence test, 1e-9 (1 + |x|) in each unknown's SI unit."""
    end = plain_end(stiff_problem, stiff_orbit.state, stiff_orbit.parameter, periods=3, rtol=1e-11)
    assert np.max(np.abs(end - stiff_orbit.state) / (1.0 + np.abs(stiff_orbit.state))) < 1e-9


def test_each_of_two_identical_followers_rides_the_single_followers_orbit(pair_orbit):
    """On a cam held at its speed the followers do not feel each other: follower 1's
    orbit is the single follower's (``system_problem``), follower 2's the same orbit half
    a period later (it sits opposite, the cam turned by pi in its frame), both to 1e-6;
    the monodromy matrix has no coupling block, and follower 2's block has follower 1's
    multipliers (its own at phase 0 is follower 1's at phase T/2, which has the same
    eigenvalues) to 1e-5 (measured 1e-7, 2.2788e-5 in modulus; when follower 2's viscous
    contact damping was set at its own starting cam angle, 5 % below follower 1's, its
    pair was 3.8e-5)."""
    system = prescribed_pair().system
    single = system_problem(system)
    period = single.build(single.value)[1]
    first = find_orbit(single, transient=30)
    second = find_orbit(dataclasses.replace(single, t_start=0.5 * period), transient=30)
    assert np.max(np.abs(pair_orbit.state[:2] - first.state)) < 1e-6
    assert np.max(np.abs(pair_orbit.state[2:] - second.state)) < 1e-6
    assert np.all(pair_orbit.monodromy[:2, 2:] == 0.0) and np.all(pair_orbit.monodromy[2:, :2] == 0.0)
    ones, twos = (np.sort_complex(np.linalg.eigvals(block)) for block in (pair_orbit.monodromy[:2, :2],
                                                                            pair_orbit.monodromy[2:, 2:]))
    assert np.max(np.abs(twos - ones)) < 1e-5 * np.max(np.abs(ones))


def test_the_multipliers_are_those_of_a_difference_monodromy(pair_problem, pair_orbit):
    """The multipliers of the two followers' orbit against the eigenvalues of a monodromy
    matrix from central differences of whole plain runs (steps 1e-6 rad and 2e-5 rad/s):
    each to 2 % of its modulus (measured 0.2-0.4 %; the multipliers are of order 1e-5,
    the orbit is strongly attracting)."""
    matrix = difference_monodromy(pair_problem, pair_orbit, np.array([1e-6, 2e-5, 1e-6, 2e-5]))
    expected = np.linalg.eigvals(matrix)
    for mu in pair_orbit.multipliers:
        assert np.min(np.abs(expected - mu)) < 0.02 * abs(mu)


def test_the_impacting_pivots_multipliers_are_those_of_a_difference_monodromy():
    """The chapter 3 impact rig on its flexible bearing (``flexible_pivot.toml``, 16 Hz):
    a period-1 orbit with one impact per revolution, unstable past a period doubling
    (leading multiplier about -1.15, the rigid pivot's -0.99). Its two leading
    multipliers against the eigenvalues of a difference monodromy (plain runs at
    ``rtol = 1e-12``, steps 1e-6 rad, 1e-5 rad/s, 1e-9 m, 1e-6 m/s; -1.148071 and
    -0.266403, within 4e-6 of those at ten times smaller steps or ``rtol = 1e-13``):

    - from a variational run at ``rtol = 1e-9``, to 3e-5 of their modulus (measured
      1.0e-5 and 8e-6; the run at ``1e-10`` gives 1.5e-5 and 1.2e-5). With the flexible
      pivot's former Jacobian by plain central differences of the right-hand side, these
      runs converged to 2.4e-4 away (-1.147799 at ``1e-10``);
    - the orbit's own, from the run at the problem's matrix tolerance (``1e-7``), to 1e-3:
      at that tolerance they move by a few 1e-4 from run to run (measured 4.9e-4).

    And a plain run of 4 periods returns to the orbit."""
    problem = mechanism_problem(chapter3_flexible_pivot())
    orbit = find_orbit(problem, transient=20)
    assert orbit.impacts_per_period == 1 and not orbit.stable
    matrix = difference_monodromy(problem, orbit, 1e-6 * np.array([1.0, 10.0, 1e-3, 1.0, 1e-3, 1.0]))
    expected = np.linalg.eigvals(matrix)
    expected = expected[np.argsort(-np.abs(expected))][:2]
    assert expected[0].real < -1.0
    tight = flow(dataclasses.replace(problem, matrix_rtol=1e-9, matrix_atol=1e-11), orbit.state, orbit.parameter)
    found = np.linalg.eigvals(tight.matrix)
    found = found[np.argsort(-np.abs(found))][:2]
    assert np.max(np.abs(found - expected) / np.abs(expected)) < 3e-5
    assert np.max(np.abs(orbit.multipliers[:2] - expected) / np.abs(expected)) < 1e-3
    end = plain_end(problem, orbit.state, orbit.parameter, periods=4)
    assert np.max(np.abs(end - orbit.state) / (1.0 + np.abs(orbit.state))) < 1e-9


def test_the_pairs_orbit_closes_over_several_periods(pair_problem, pair_orbit):
    """A plain run of 5 cam periods from the found orbit returns to it to 1e-9."""
    end = plain_end(pair_problem, pair_orbit.state, pair_orbit.parameter, periods=5)
    assert np.max(np.abs(end - pair_orbit.state) / (1.0 + np.abs(pair_orbit.state))) < 1e-9


def test_a_short_continuation_in_the_cam_speed(pair_problem, pair_orbit):
    """From 11.55 Hz towards 11.75 Hz, three orbits: each closes under a plain run of 2
    periods at its own speed, and the speed moves on."""
    branch = continue_orbits(pair_problem, pair_orbit, 11.75, step=0.01, max_step=0.05, max_points=3)
    assert len(branch.orbits) == 3 and np.all(np.diff([o.parameter for o in branch.orbits]) > 0.0)
    for orbit in branch.orbits:
        end = plain_end(pair_problem, orbit.state, orbit.parameter, periods=2)
        assert np.max(np.abs(end - orbit.state) / (1.0 + np.abs(orbit.state))) < 1e-8


def test_the_problem_refuses_what_it_does_not_take():
    rig = drum_brake()
    with pytest.raises(ParameterError, match="sets only where the driven cam starts"):
        mechanism_problem(rig, "motion.speed")                              # a torque-driven shaft: a state
    with pytest.raises(ParameterError, match="got System"):
        mechanism_problem(load_system(FRICTION))
    with pytest.raises(ParameterError, match="unknown parameter"):
        mechanism_problem(prescribed_pair(), "cam.nonsense")
    with pytest.raises(ParameterError, match="constant speed"):
        mechanism_problem(prescribed_pair(), "motion.frequency")


def run(argv):
    """``camdyn ARGV``: its exit status, standard output and standard error."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main([str(a) for a in argv])
    return status, out.getvalue(), err.getvalue()


@pytest.mark.parametrize("source, arguments, message", [
    ("drum_brake.toml", ["--parameter", "motion.speed"], "sets only where the driven cam starts"),
    ("driven_cam.toml", ["--parameter", "motion.speed"], "sets only where the driven cam starts"),
    ("driven_cam.toml", ["--parameter", "drive.torque"], "does not enter a 'motor' drive"),
    ("two_followers_prescribed.toml", ["--parameter", "drive.torque"], "a key of a cam under its drive"),
    ("two_followers_prescribed.toml", ["--parameter", "pivot.stiffness"], "flexible pivot only"),
    ("two_followers_prescribed.toml", ["--brute-force", "5"], "not offered for a mechanism"),
    ("flexible_pivot.toml", ["--set", "pivot.stiffness=-1N/m"], "pivot.stiffness"),
])
def test_the_cli_refuses_in_one_line(tmp_path, monkeypatch, source, arguments, message):
    monkeypatch.chdir(tmp_path)
    status, out, err = run(["continue", EXAMPLES / source, "--from", "11.55Hz", "--to", "11.6Hz", *arguments])
    assert status == 2, (out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:") and message in lines[0], lines
    assert not any(tmp_path.iterdir())


def test_the_cli_continues_two_followers(tmp_path):
    out = tmp_path / "branch.nc"
    status, text, err = run(["continue", EXAMPLES / "two_followers_prescribed.toml", "--from", "11.55Hz", "--to",
                             "11.6Hz", "--max-points", "3", "--step", "0.002", "--transient", "5", "--out", out,
                             "--json"])
    assert status == 0, err
    doc = json.loads(text)
    assert doc["summary"]["units"] == "Hz" and doc["summary"]["points"] >= 2
    first = doc["branches"][0][0]
    assert len(first["state"]) == 4 and len(first["multipliers"]) == 4 and first["stable"]
    assert out.stat().st_size > 0


def test_newton_from_past_the_doubling_gives_up_at_once(tmp_path, monkeypatch):
    """The flexible pivot at 16 Hz, past its period doubling (15.895 Hz): 50 cam periods
    of transient end on the period-2 attractor, and Newton's method for the period-1
    orbit from there wanders: its third iterate put the follower 4.7 mm into the cam,
    whose variational run took 1.1 million steps for a sixteenth of a period (the command
    ran for more than 12 minutes). Newton's method stops where a variational run needs 20 times the
    first one's steps: the command fails in one line (measured 10 s), and a shorter
    transient, still near the unstable period-1 orbit, finds it."""
    monkeypatch.chdir(tmp_path)
    status, out, err = run(["continue", EXAMPLES / "flexible_pivot.toml", "--from", "16Hz", "--to", "15.7Hz",
                            "--json"])
    lines = err.strip().splitlines()
    assert status == 1 and out == "" and len(lines) == 1, (out, err)
    assert lines[0].startswith("error: no period-1 orbit found") and "left the start's neighbourhood" in lines[0]


def test_the_cli_shows_its_progress_and_announces_a_long_run(tmp_path, monkeypatch):
    """On a terminal the continuation shows what it does (the parameter's value, the
    orbits found, the time) and, where the point budget at the first orbit's cost
    exceeds the limit (set to 0 s here), says how long it may take."""
    from rich.console import Console

    from camdyn.cli import continuation as command

    screen = io.StringIO()
    monkeypatch.setattr(command, "err_console", Console(file=screen, force_terminal=True, width=160))
    monkeypatch.setattr(command, "LONG_RUN", 0.0)
    status, text, err = run(["continue", EXAMPLES / "two_followers_prescribed.toml", "--from", "11.55Hz", "--to",
                             "11.6Hz", "--max-points", "3", "--step", "0.002", "--transient", "5"])
    assert status == 0, err
    shown = screen.getvalue()
    assert "motion.speed = 11.5" in shown and "3 orbits" in shown, shown
    assert "note: the first orbit took" in shown and "--max-points" in shown, shown
