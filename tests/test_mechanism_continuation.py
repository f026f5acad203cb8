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
from camdyn.continuation.orbits import find_orbit
from camdyn.continuation.problem import system_problem
from camdyn.errors import ParameterError
from camdyn.integrator import driver
from camdyn.params.config import load_system
from camdyn.simulation.flexible_pivot import FlexiblePivotRig
from camdyn.simulation.mechanisms import CamDrive
from camdyn.simulation.two_followers import TwoFollowerRig, drum_brake
from camdyn.systems import registry as systems

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "mechanisms"
#: The chapter 3 impact rig at 14 Hz: one impact-free orbit in contact
SPEED = 14.0


def plain_end(problem, x, value, periods=1, rtol=1e-12):
    """The unknowns after ``periods`` cam periods of a plain run (the model alone, no
    state-transition matrix) from the unknowns ``x`` at ``t = 0``."""
    p, period = problem.build(value)
    y0 = problem.full_state(x, value)
    t1 = periods * period
    y, _, _, counters = driver.integrate(problem.system_id, p, y0, 0.0, t1, np.array([t1]), rtol, rtol * 1e-2,
                                         period / 32.0, driver.METHOD_DOP853, 50_000_000, 100_000, True)
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


@pytest.fixture(scope="module")
def impact_rig():
    return load_system("sundar2014-impact").with_values(**{"motion.speed": SPEED})


@pytest.fixture(scope="module")
def rigid_orbit(impact_rig):
    return find_orbit(system_problem(impact_rig), transient=60)


@pytest.fixture(scope="module")
def pivot_problem(impact_rig):
    """A soft bearing with little damping: its multipliers are of order one."""
    kp = 2e7
    return mechanism_problem(FlexiblePivotRig(impact_rig, kp, 2.0 * 0.002 * math.sqrt(kp * impact_rig.follower.mass)))


@pytest.fixture(scope="module")
def pivot_orbit(pivot_problem):
    return find_orbit(pivot_problem, transient=60)
