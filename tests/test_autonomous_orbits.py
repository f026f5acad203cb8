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
                                         50_000_000, 100_000, True)
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
    u = orbit.state.size
    matrix = np.empty((u, u))
    for j in range(u):
        step = 1e-6 * max(abs(orbit.state[j]), 1.0)
        ends = []
        for sign in (1.0, -1.0):
            x = orbit.state.copy()
            x[j] += sign * step
            _, y = next_section(systems.DRIVEN_CAM, p, time_state(x, base, 2, drive), 2, theta0 + 2.0 * math.pi)
            ends.append(periodic(y, 2, drive))
        matrix[:, j] = (ends[0] - ends[1]) / (2.0 * step)
    reference = np.linalg.eigvals(matrix)
    reference = reference[np.argsort(-np.abs(reference), kind="stable")]
    error = np.max(np.abs(np.sort_complex(reference) - np.sort_complex(orbit.multipliers)))
    assert error < 1e-5
    assert orbit.stable == bool(np.all(np.abs(reference) < 1.0))


def test_a_pi_controller_holds_the_mean_speed_at_its_set_point(driven):
    """Under a PI controller with an integral gain the integral is periodic only if the
    mean speed is the set point: the period is ``2 pi / omega_ref`` (closed form), to
    1e-10 relative."""
    drive, problem, orbit = driven
    if drive.kind != "controller":
        pytest.skip("the closed form is the controller's")
    assert problem.unknowns == 4
    assert abs(orbit.period - 2.0 * math.pi / drive.target_speed) < 1e-10 * orbit.period


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
