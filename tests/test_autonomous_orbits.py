"""Periodic orbits and continuation of the autonomous mechanisms (the driven cam, two
followers on a driven shaft), found in the cam angle, against values from outside that
code: plain runs of the time-domain models (:data:`camdyn.systems.registry.DRIVEN_CAM`,
``TWO_FOLLOWERS``) located on the section ``Theta = Theta_0`` here by Newton's method on
each run's end time, the Poincare map's Jacobian by central differences of such runs,
the set point of a PI controller (the closed form of its mean speed), and the orbit of
the cam held at its speed (the limit of a huge shaft inertia)."""

import contextlib
import dataclasses
import io
import json
import math
from pathlib import Path

import numpy as np
import pytest

from camdyn.cli.app import main
from camdyn.continuation.mechanisms import mechanism_problem, trace_mechanism
from camdyn.continuation.orbits import find_orbit
from camdyn.continuation.problem import system_problem
from camdyn.continuation.results import switch_doublings, trace_branch
from camdyn.errors import ParameterError, SimulationError
from camdyn.integrator import driver
from camdyn.io.mechanism_config import load_mechanism, mechanism_rig
from camdyn.params.config import load_system
from camdyn.simulation.mechanisms import CamDrive, DrivenCamRig
from camdyn.simulation.runner import prepare
from camdyn.simulation.two_followers import TwoFollowerRig, drum_brake, pack_two_followers
from camdyn.systems import registry as systems

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "mechanisms" / "driven_cam.toml"
#: The chapter 4 friction rig (11.55 Hz), in sustained contact
FRICTION = "sundar2014-friction"
SPEED = 2.0 * math.pi * 11.55                                   # [rad/s]
#: Three drives of the rig's cam (3e-4 kg m^2): a torque against a viscous bearing, a PI
#: controller at 11.55 Hz, and the DC motor of the example mechanism file.
DRIVES = {
    "constant": CamDrive(3e-4, "constant", torque=0.05, bearing_viscous=5e-4),
    "controller": CamDrive(3e-4, "controller", proportional=0.01, integral=0.1, target_speed=SPEED),
    "motor": CamDrive(3e-4, "motor", stall_torque=1.0, free_speed=2.0 * math.pi * 13.86),
}


def time_run(system_id, p, y0, duration, rtol=1e-12):
    """The time-domain state after ``duration`` [s] of a plain run from ``y0`` at t = 0."""
    y, _, _, counters = driver.integrate(system_id, p.copy(), np.asarray(y0, float), 0.0, duration,
                                         np.array([duration]), rtol, rtol * 1e-2, 1e-3, driver.METHOD_DOP853,
                                         50_000_000, 100_000, True, math.inf)
    assert counters[driver.COUNT_STATUS] == 0
    return y[-1]


def next_section(system_id, p, y0, slot, target):
    """``(time [s], state)`` where the cam angle ``y[slot]`` of a plain run from ``y0``
    reaches ``target`` [rad]: Newton's method on the run's end time (each iterate a whole
    run from ``y0``), the angle's rate the speed ``y[slot + 1]``."""
    duration = (target - y0[slot]) / y0[slot + 1]
    for _ in range(30):
        y = time_run(system_id, p, y0, duration)
        miss = target - y[slot]
        if abs(miss) < 1e-13 * abs(target) + 1e-14:
            return duration, y
        duration += miss / y[slot + 1]
    raise AssertionError("the section was not reached")


def driven_p(system, drive):
    """The time-domain driven cam's parameter vector (as ``simulate_driven_cam`` packs it)."""
    return np.r_[prepare(system).p, drive.slots()]


def periodic(y, slot, drive):
    """The time-domain state's periodic components: everything before the cam angle, its
    speed, and the controller's integral where it enters the torque."""
    parts = [y[:slot], y[slot + 1:slot + 2]]
    if drive.kind == "controller" and drive.integral != 0.0:
        parts.append(y[slot + 2:slot + 3])
    return np.concatenate(parts)


def time_state(x, template_y, slot, drive):
    """A time-domain state with the periodic components ``x`` (:func:`periodic`), the rest
    from ``template_y``."""
    y = template_y.copy()
    y[:slot] = x[:slot]
    y[slot + 1] = x[slot]
    if x.size > slot + 1:
        y[slot + 2] = x[slot + 1]
    return y


def difference_map(system_id, p, state, base, slot, drive, target):
    """The return map's Jacobian at the periodic components ``state`` by central
    differences of plain time-domain runs (the rest of the state from ``base``) to the
    crossing of ``target`` [rad], steps 1e-6 of each component's size (at least 1e-6)."""
    matrix = np.empty((state.size, state.size))
    for j in range(state.size):
        step = 1e-6 * max(abs(state[j]), 1.0)
        ends = []
        for sign in (1.0, -1.0):
            x = state.copy()
            x[j] += sign * step
            _, y = next_section(system_id, p, time_state(x, base, slot, drive), slot, target)
            ends.append(periodic(y, slot, drive))
        matrix[:, j] = (ends[0] - ends[1]) / (2.0 * step)
    return matrix


@pytest.fixture(scope="module")
def rig_system():
    return load_system(FRICTION)


@pytest.fixture(scope="module", params=sorted(DRIVES))
def driven(request, rig_system):
    """``(drive, problem, orbit)`` of the rig's cam under each drive."""
    drive = DRIVES[request.param]
    problem = mechanism_problem(DrivenCamRig(rig_system, drive))
    return drive, problem, find_orbit(problem, transient=30)


def test_a_plain_run_from_rest_settles_onto_the_orbit(rig_system, driven):
    """A plain run of the time-domain driven cam from the static equilibrium (the cam at
    its starting angle and speed): after 120 turns (the slowest orbit here, the constant
    torque's, contracts by 0.8 per turn) its next three points on the section
    ``Theta = Theta_0 + 2 pi j`` equal the orbit's state to 1e-8 (relative to
    ``1 + |x|``), and the time between them is the orbit's period to 1e-10 relative."""
    drive, problem, orbit = driven
    p = driven_p(rig_system, drive)
    prep = prepare(rig_system)
    theta0 = prep.theta0
    y = np.array([prep.equilibrium.angle, 0.0, theta0, rig_system.motion.angular_speed, 0.0, 0.0, 0.0, 0.0])
    _, y = next_section(systems.DRIVEN_CAM, p, y, 2, theta0 + 120 * 2.0 * math.pi)
    for turn in range(121, 124):
        elapsed, y = next_section(systems.DRIVEN_CAM, p, y, 2, theta0 + turn * 2.0 * math.pi)
        x = periodic(y, 2, drive)
        assert np.max(np.abs(x - orbit.state) / (1.0 + np.abs(orbit.state))) < 1e-8
        assert abs(elapsed - orbit.period) < 1e-10 * orbit.period


def test_the_multipliers_are_those_of_a_difference_poincare_map(rig_system, driven):
    """The orbit's multipliers against the eigenvalues of the Poincare map's Jacobian by
    central differences of plain time-domain runs from the orbit's state on the section
    to their next crossing of it (steps 1e-6 of each unknown's size, at least 1e-6):
    within 1e-5 (measured 2.3e-6 under the constant torque, whose multipliers are 0.80
    and a pair of 1.5e-7; 4.3e-7 under the controller, 0.24 and 4.1e-5 in modulus;
    1.2e-6 under the motor, 0.059 and 1.8e-4). The trivial multiplier 1, along the
    flow, is not among them: the section removes it."""
    drive, problem, orbit = driven
    p = driven_p(rig_system, drive)
    theta0 = problem.t_start
    base = np.array([0.0, 0.0, theta0, 0.0, 0.0, 0.0, 0.0, 0.0])
    matrix = difference_map(systems.DRIVEN_CAM, p, orbit.state, base, 2, drive, theta0 + 2.0 * math.pi)
    reference = np.linalg.eigvals(matrix)
    reference = reference[np.argsort(-np.abs(reference), kind="stable")]
    error = np.max(np.abs(np.sort_complex(reference) - np.sort_complex(orbit.multipliers)))
    assert error < 1e-5
    assert orbit.stable == bool(np.all(np.abs(reference) < 1.0))


def test_the_multipliers_through_impacts_under_a_restitution_law():
    """The chapter 3 impact rig (one impact per turn) under the Hunt-Crossley damping law
    (restitution 0.8, whose force depends on the approach velocity carried from each
    contact's onset: the variational system carries its derivatives), its cam on a motor:
    the multipliers (a pair of modulus 0.82 and 0.106) against a difference return map
    from plain time-domain runs, within 2e-5 (measured 7.6e-6; the impact's saltation is
    in them)."""
    system = load_system("sundar2014-impact").with_values(
        **{"motion.speed": 15.0, "contact.damping": "hunt-crossley", "contact.restitution": 0.8})
    drive = CamDrive(3e-4, "motor", stall_torque=1.0, free_speed=2.0 * math.pi * 15.5)
    problem = mechanism_problem(DrivenCamRig(system, drive))
    orbit = find_orbit(problem, transient=50)
    assert orbit.impacts_per_period == 1
    p, theta0 = driven_p(system, drive), problem.t_start
    base = np.array([0.0, 0.0, theta0, 0.0, 0.0, 0.0, 0.0, 0.0])
    matrix = difference_map(systems.DRIVEN_CAM, p, orbit.state, base, 2, drive, theta0 + 2.0 * math.pi)
    reference = np.sort_complex(np.linalg.eigvals(matrix))
    assert np.max(np.abs(reference - np.sort_complex(orbit.multipliers))) < 2e-5


def test_a_pi_controller_holds_the_mean_speed_at_its_set_point(rig_system):
    """Under a PI controller with an integral gain the integral is periodic only if the
    mean speed is the set point: the integral is an unknown, and the period is
    ``2 pi / omega_ref`` (closed form) to 1e-10 relative, at two set points."""
    for target in (SPEED, 0.9 * SPEED):
        drive = dataclasses.replace(DRIVES["controller"], target_speed=target)
        problem = mechanism_problem(DrivenCamRig(rig_system, drive))
        orbit = find_orbit(problem, transient=30)
        assert problem.unknowns == 4
        assert abs(orbit.period - 2.0 * math.pi / target) < 1e-10 * orbit.period


@pytest.fixture(scope="module")
def held_orbit(rig_system):
    """The cam-follower's orbit with the cam held at 11.55 Hz, and the torque [N m] that
    holds it on average: the drive's work over one period of a plain run of the driven cam
    with its speed prescribed, over the angle turned, 2 pi."""
    orbit = find_orbit(system_problem(rig_system), transient=30)
    prep = prepare(rig_system)
    y0 = np.array([*orbit.state, prep.theta0, SPEED, 0.0, 0.0, 0.0, 0.0])
    end = time_run(systems.DRIVEN_CAM, np.r_[prep.p, CamDrive(1.0, "prescribed").slots()], y0, 2.0 * math.pi / SPEED)
    return orbit, end[5] / (2.0 * math.pi)


def test_a_huge_shaft_inertia_gives_the_orbit_of_the_cam_held_at_its_speed(rig_system, held_orbit):
    """A motor whose line passes through the held cam's speed (11.55 Hz) and mean torque
    (its free speed 11.56 Hz): as the shaft's inertia ``J`` grows the cam's speed
    fluctuation (about the contact torque's over ``J`` omega) vanishes and the orbit tends
    to the held cam's. At ``J = 10 kg m^2`` alpha and alpha_dot on the section equal the
    held cam's to 1e-6 relative (measured 1.0e-7) and the period is ``1 / 11.55 Hz`` to
    1e-9 relative (3.9e-11); from ``J = 1`` to 10 the difference falls tenfold (1/J,
    within 20 %). The speed's multiplier is the rigid shaft's on the motor line,
    ``exp(-(T_stall / omega_free) T / J)``, to 1e-3 of its distance from 1 (measured 5e-5:
    the load's own dependence on the speed is weak), and the follower's are the held
    cam's to 1e-4 of their modulus. (At ``J = 100`` the speed's multiplier, 0.99964,
    leaves Newton's method a residual noise of 4e-8 in the period: larger inertias gain
    nothing at these tolerances.)"""
    held, torque = held_orbit
    free = 2.0 * math.pi * 11.56
    stall = torque / (1.0 - SPEED / free)
    differences = []
    for inertia in (1.0, 10.0):
        drive = CamDrive(inertia, "motor", stall_torque=stall, free_speed=free)
        orbit = find_orbit(mechanism_problem(DrivenCamRig(rig_system, drive)), transient=30)
        differences.append(np.max(np.abs(orbit.state[:2] - held.state) / np.abs(held.state)))
    assert differences[1] < 1e-6
    assert 8.0 < differences[0] / differences[1] < 12.0
    period = 2.0 * math.pi / SPEED
    assert abs(orbit.period - period) < 1e-9 * period
    rigid = math.exp(-stall / free * period / 10.0)
    assert abs(orbit.multipliers[0] - rigid) < 1e-3 * (1.0 - rigid)
    follower = np.sort(np.abs(orbit.multipliers[1:]))
    assert np.max(np.abs(follower - np.sort(np.abs(held.multipliers)))) < 1e-4 * np.max(follower)


def test_a_light_shaft_delays_the_period_doubling_and_the_doubled_branch_is_found():
    """The chapter 3 impact rig (one impact per turn) with its cam on a DC motor (stall
    1 N m), continued in the motor's free speed: its period doubling is located (the
    orbit there has a multiplier -1 to 1e-3) at a mean cam speed 0.16 Hz above the held
    cam's (16.016 Hz, continued in the cam speed: measured 16.176 against 16.016 Hz with
    3e-4 kg m^2), and within 0.01 Hz of it with 1e-2 kg m^2 (measured 16.022): the
    shaft's fluctuation delays the doubling, as ``1 / J``. The period-2 branch born there
    (1e-2 kg m^2)
    is found: its first orbit closes under a plain time-domain run of two turns to 1e-8
    and not of one (its two points on the section 1e-3 apart at least, relative)."""
    system = load_system("sundar2014-impact").with_values(**{"motion.speed": 15.0})
    _, held = trace_branch(system, "motion.speed", 15.8, 16.3, step=0.01, max_points=20)
    held_hz = [b.parameter for b in held.bifurcations if b.kind == "period-doubling"]
    assert len(held_hz) == 1
    located = {}
    for inertia in (3e-4, 1e-2):
        drive = CamDrive(inertia, "motor", stall_torque=1.0, free_speed=2.0 * math.pi * 15.5)
        problem, branch = trace_mechanism(DrivenCamRig(system, drive), "drive.free_speed", 2.0 * math.pi * 16.3,
                                          2.0 * math.pi * 17.0, step=0.01, max_points=20, transient=50)
        doublings = [b for b in branch.bifurcations if b.kind == "period-doubling"]
        assert len(doublings) == 1 and np.min(np.abs(doublings[0].orbit.multipliers + 1.0)) < 1e-3
        located[inertia] = 1.0 / doublings[0].orbit.period
    assert 0.1 < located[3e-4] - held_hz[0] < 0.25 and abs(located[1e-2] - held_hz[0]) < 0.01
    extra = switch_doublings(problem, branch, 2.0 * math.pi * 17.0, max_points=2)
    assert len(extra) == 1
    first = extra[0].orbits[0]
    assert first.periods == 2
    theta0 = problem.t_start
    moved = dataclasses.replace(drive, free_speed=first.parameter)
    p = driven_p(system, moved)
    y0 = time_state(first.state, np.array([0.0, 0.0, theta0, 0.0, 0.0, 0.0, 0.0, 0.0]), 2, moved)
    _, once = next_section(systems.DRIVEN_CAM, p, y0, 2, theta0 + 2.0 * math.pi)
    elapsed, twice = next_section(systems.DRIVEN_CAM, p, y0, 2, theta0 + 4.0 * math.pi)
    scale = 1.0 + np.abs(first.state)
    assert np.max(np.abs(periodic(twice, 2, moved) - first.state) / scale) < 1e-8
    assert abs(elapsed - first.period) < 1e-10 * first.period
    assert np.max(np.abs(periodic(once, 2, moved) - first.state) / scale) > 1e-3


def pair_rig(drive):
    """The drum brake (two identical followers opposite each other, gravity off) under
    ``drive``."""
    rig = drum_brake()
    return TwoFollowerRig(rig.system, rig.second, rig.placement, drive)


@pytest.fixture(scope="module")
def pair_orbit():
    """The drum brake's cam on the example's DC motor (its shaft 2e-4 kg m^2)."""
    rig = pair_rig(dataclasses.replace(DRIVES["motor"], shaft_inertia=2e-4))
    problem = mechanism_problem(rig)
    return rig, problem, find_orbit(problem, transient=30)


def test_two_followers_on_a_motor_settle_onto_their_orbit(pair_orbit):
    """Two followers on a motor-driven shaft: five unknowns (each follower's angle and
    rate, the shaft's speed). A plain time-domain run from the orbit's state, perturbed by
    1e-4 rad/s in follower 1's rate, crosses the section 20 turns later on the orbit's
    state to 1e-8 (its multipliers are at most 0.012), the last turn taking the orbit's
    period to 1e-10 relative; and the multipliers are those of the Poincare map's
    Jacobian by central differences of plain runs, to 1e-5."""
    rig, problem, orbit = pair_orbit
    assert problem.unknowns == 5 and orbit.stable
    p, y0 = pack_two_followers(rig.system, rig.second, rig.placement, rig.drive)
    theta0 = y0[4]
    x = orbit.state.copy()
    x[1] += 1e-4
    y = time_state(x, y0, 4, rig.drive)
    _, y = next_section(systems.TWO_FOLLOWERS, p, y, 4, theta0 + 19 * 2.0 * math.pi)
    elapsed, y = next_section(systems.TWO_FOLLOWERS, p, y, 4, theta0 + 20 * 2.0 * math.pi)
    assert np.max(np.abs(periodic(y, 4, rig.drive) - orbit.state) / (1.0 + np.abs(orbit.state))) < 1e-8
    assert abs(elapsed - orbit.period) < 1e-10 * orbit.period
    matrix = difference_map(systems.TWO_FOLLOWERS, p, orbit.state, y0, 4, rig.drive, theta0 + 2.0 * math.pi)
    reference = np.sort_complex(np.linalg.eigvals(matrix))
    assert np.max(np.abs(reference - np.sort_complex(orbit.multipliers))) < 1e-5


def test_a_short_continuation_in_the_motors_free_speed():
    """The example's motor (``driven_cam.toml``) from a free speed of 13.86 Hz towards
    14.5 Hz: four orbits, the cam's mean speed rising with the motor's; each closes under a
    plain time-domain run from its state to the next section, to 1e-9, in its period to
    1e-10 relative."""
    rig = mechanism_rig(load_mechanism(EXAMPLE))
    problem, branch = trace_mechanism(rig, "drive.free_speed", 2.0 * math.pi * 13.86, 2.0 * math.pi * 14.5,
                                      step=0.01, max_points=4, transient=30)
    assert problem.unit == "rad/s" and len(branch.orbits) == 4
    assert np.all(np.diff([o.parameter for o in branch.orbits]) > 0.0)
    assert np.all(np.diff([o.period for o in branch.orbits]) < 0.0)
    theta0 = problem.t_start
    for orbit in branch.orbits:
        drive = dataclasses.replace(rig.drive, free_speed=orbit.parameter)
        y0 = time_state(orbit.state, np.array([0.0, 0.0, theta0, 0.0, 0.0, 0.0, 0.0, 0.0]), 2, drive)
        elapsed, y = next_section(systems.DRIVEN_CAM, driven_p(rig.system, drive), y0, 2, theta0 + 2.0 * math.pi)
        assert np.max(np.abs(periodic(y, 2, drive) - orbit.state) / (1.0 + np.abs(orbit.state))) < 1e-9
        assert abs(elapsed - orbit.period) < 1e-10 * orbit.period


def test_bad_input_is_refused_before_any_work(rig_system, monkeypatch):
    """Each refused with a ParameterError that says why, no run made."""
    def no_run(*args, **kwargs):
        raise AssertionError("a run was made")

    monkeypatch.setattr(driver, "integrate", no_run)
    motor = DrivenCamRig(rig_system, DRIVES["motor"])
    cases = [
        (DrivenCamRig(rig_system, CamDrive(3e-4, "prescribed")), None, "fixed period"),
        (DrivenCamRig(rig_system, CamDrive(3e-4, "constant", torque=0.0, bearing_viscous=1e-3)), None,
         "no steady state"),
        (DrivenCamRig(rig_system.with_values(**{"motion.direction": -1}), DRIVES["motor"]), None, "turning forward"),
        (motor, "motion.speed", "sets only where the driven cam starts"),
        (motor, "drive.torque", "does not enter a 'motor' drive"),
        (motor, "drive.kind", "not a continuous drive key"),
        (motor, "cam.nonsense", "unknown parameter"),
    ]
    for rig, key, message in cases:
        with pytest.raises(ParameterError, match=message):
            mechanism_problem(rig, key)
    controller = DrivenCamRig(rig_system, DRIVES["controller"])
    with pytest.raises(ParameterError, match="must keep its sign"):
        trace_mechanism(controller, "drive.integral", 0.1, -0.1)
    with pytest.raises(ParameterError, match="drive.stall_torque > 0"):
        trace_mechanism(motor, "drive.stall_torque", 1.0, -1.0)
    with pytest.raises(ParameterError, match="static_friction is for two followers"):
        mechanism_problem(motor, static_friction=0.5)


@pytest.mark.parametrize("torque, bearing", [(0.001, 0.0), (0.05, 0.0)])
def test_a_drive_without_a_steady_state_fails_in_one_clear_error(rig_system, torque, bearing):
    """A constant torque below the load (the cam slows down and stops: the cam angle is
    no longer a variable) or with no loss that grows with the speed (the cam speeds up
    without bound): no orbit, and a SimulationError that says what a steady state needs."""
    rig = DrivenCamRig(rig_system, CamDrive(3e-4, "constant", torque=torque, bearing_viscous=bearing))
    with pytest.raises(SimulationError, match="periodic orbit only where its speed settles"):
        trace_mechanism(rig, "drive.torque", torque, 1.1 * torque, max_points=3, transient=30)


def run(argv):
    """``camdyn ARGV``: its exit status, standard output and standard error."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main([str(a) for a in argv])
    return status, out.getvalue(), err.getvalue()


def test_the_cli_continues_the_driven_cam(tmp_path):
    """``camdyn continue driven_cam.toml`` continues in the motor's free speed (the drive
    key that sets the speed) given in Hz: the JSON's parameter is in rad/s (2 pi 13.86),
    its period the orbit's own, the time a plain time-domain run from its state takes to
    turn once (to 1e-10 relative), not the starting speed's."""
    out = tmp_path / "branch.nc"
    status, text, err = run(["continue", EXAMPLE, "--from", "13.86Hz", "--to", "14Hz", "--max-points", "3",
                             "--transient", "30", "--out", out, "--json"])
    assert status == 0, err
    doc = json.loads(text)
    assert doc["summary"]["parameter"] == "drive.free_speed" and doc["summary"]["units"] == "rad/s"
    first = doc["branches"][0][0]
    assert abs(first["parameter"] - 2.0 * math.pi * 13.86) < 1e-12 * first["parameter"]
    rig = mechanism_rig(load_mechanism(EXAMPLE))
    theta0 = prepare(rig.system).theta0
    y0 = time_state(np.array(first["state"]), np.array([0.0, 0.0, theta0, 0.0, 0.0, 0.0, 0.0, 0.0]), 2, rig.drive)
    elapsed, _ = next_section(systems.DRIVEN_CAM, driven_p(rig.system, rig.drive), y0, 2, theta0 + 2.0 * math.pi)
    assert abs(first["period"] - elapsed) < 1e-10 * elapsed
    assert abs(first["period"] - 1.0 / 11.55) > 1e-3 / 11.55
    assert len(first["state"]) == 3 and first["stable"] and out.stat().st_size > 0
