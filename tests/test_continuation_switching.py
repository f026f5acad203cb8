"""Branch switching at a period doubling, against the rigid-impact oscillator's
period-2 two-impact orbit solved here in closed form (its free motion between impacts
written out, as in tests/test_continuation.py): the branch that the switch finds and
continues is that orbit at every point."""

import math

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq, fsolve

from camdyn.continuation import find_orbit, model_problem
from camdyn.continuation.branches import Bifurcation, continue_orbits
from camdyn.continuation.switching import doubled_orbit, switch_branch
from camdyn.errors import ParameterError
from camdyn.systems import registry as systems

W_NATURAL, ZETA, FORCE, RESTITUTION, WALL = 1.0, 0.05, 1.0, 0.8, 0.0


def _free(forcing, t_impact, x0, v0, s):
    """Free motion s [s] after leaving (x0 [m], v0 [m/s]) at t_impact [s]: the steady
    state x_p = X cos(W t - phi) plus the damped homogeneous solution."""
    w, z = W_NATURAL, ZETA
    amplitude = FORCE / math.hypot(w * w - forcing * forcing, 2 * z * w * forcing)
    phase = math.atan2(2 * z * w * forcing, w * w - forcing * forcing)
    wd = w * math.sqrt(1 - z * z)
    c1 = x0 - amplitude * math.cos(forcing * t_impact - phase)
    c2 = (v0 + amplitude * forcing * math.sin(forcing * t_impact - phase) + z * w * c1) / wd
    decay, cos, sin = math.exp(-z * w * s), math.cos(wd * s), math.sin(wd * s)
    t = t_impact + s
    x = amplitude * math.cos(forcing * t - phase) + decay * (c1 * cos + c2 * sin)
    v = -amplitude * forcing * math.sin(forcing * t - phase) + decay * (-z * w * (c1 * cos + c2 * sin)
                                                                         + wd * (c2 * cos - c1 * sin))
    return x, v


def _period_two(forcing, guess):
    """Impact times t1, t2 [s] and rebound velocities v1, v2 [m/s] of the two-impact orbit
    of period 2T: (t1, v1) -> (t2, -v2 / r) -> (t1 + 2T, -v1 / r)."""
    period = 2 * math.pi / forcing

    def residual(u):
        t1, v1, t2, v2 = u
        x, v = _free(forcing, t1, WALL, v1, t2 - t1)
        first = [x - WALL, v + v2 / RESTITUTION]
        x, v = _free(forcing, t2, WALL, v2, t1 + 2 * period - t2)
        return first + [x - WALL, v + v1 / RESTITUTION]
    solution = fsolve(residual, guess, xtol=1e-14)
    assert np.max(np.abs(residual(solution))) < 1e-12
    return solution


def _states_at_zero(forcing, solution):
    """The orbit's state at t = 0 (= 2T) [m, m/s], for both of its phases (shifted by T)."""
    t1, v1, t2, v2 = solution
    period = 2 * math.pi / forcing
    return [np.array(_free(forcing, t, WALL, v, 2 * period - t)) for t, v in ((t2, v2), (t1 + period, v1))]


HOMOGENEOUS = np.array([[0.0, 1.0], [-W_NATURAL ** 2, -2 * ZETA * W_NATURAL]])


def _saltation(forcing, t_impact, v):
    """The impact's saltation matrix at t_impact [s], rebound velocity v [m/s]:
    S = R + (f+ - R f-) n^T / (n^T f-) (Leine & Nijmeijer 2004, ch. 7), g = WALL - x."""
    v_minus = -v / RESTITUTION
    accel = FORCE * math.cos(forcing * t_impact) - W_NATURAL ** 2 * WALL
    f_minus = np.array([v_minus, accel - 2 * ZETA * W_NATURAL * v_minus])
    f_plus = np.array([v, accel - 2 * ZETA * W_NATURAL * v])
    reset, normal = np.diag([1.0, -RESTITUTION]), np.array([-1.0, 0.0])
    return reset + np.outer(f_plus - reset @ f_minus, normal) / (normal @ f_minus)


def _doubling_test(forcing, solution):
    """det(M + I) of the two-impact orbit's monodromy over 2T (zero where it doubles)."""
    t1, v1, t2, v2 = solution
    period = 2 * math.pi / forcing
    monodromy = (_saltation(forcing, t1, v1) @ expm(HOMOGENEOUS * (t1 + 2 * period - t2))
                 @ _saltation(forcing, t2, v2) @ expm(HOMOGENEOUS * (t2 - t1)))
    return float(np.linalg.det(monodromy + np.eye(2)))


def _rigid(forcing):
    return model_problem(systems.RIGID_IMPACT, [W_NATURAL, ZETA, FORCE, forcing, WALL, RESTITUTION],
                         [WALL - 1.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def period_one():
    """The period-1 branch of the rigid-impact oscillator from W = 2.3 over its period
    doubling (closed form W = 2.65888454668, tests/test_continuation.py)."""
    problem = _rigid(2.3)
    branch = continue_orbits(problem, find_orbit(problem), 2.75, step=0.02)
    doublings = [b for b in branch.bifurcations if b.kind == "period-doubling"]
    assert len(doublings) == 1
    return problem, doublings[0]


def test_switched_branch_is_the_closed_form_period_two_orbit(period_one):
    problem, doubling = period_one
    assert doubling.parameter == pytest.approx(2.65888454668, abs=1e-9)
    branch = switch_branch(problem, doubling, 2.75, step=0.01)
    orbits = branch.orbits
    assert len(orbits) >= 10 and orbits[-1].parameter == pytest.approx(2.75, abs=1e-12), branch.stopped
    first = orbits[0]
    assert first.periods == 2 and abs(first.parameter - doubling.parameter) < 1e-5   # O(amplitude^2) from it
    # the closed form followed along the branch from W = 2.68, where the two impacts differ
    solution = _period_two(2.68, [1.0, -0.2, 1.2 + 2 * math.pi / 2.68, -0.45])
    assert abs(solution[1] - solution[3]) > 0.01
    worst = 0.0
    for orbit in sorted((o for o in orbits if o.parameter >= 2.68), key=lambda o: o.parameter):
        solution = _period_two(orbit.parameter, solution)
        error = min(np.max(np.abs(orbit.state - state)) for state in _states_at_zero(orbit.parameter, solution))
        worst = max(worst, error)
        assert orbit.periods == 2 and orbit.impacts_per_period == 2
    assert worst < 1e-7, worst                                 # measured 1.0e-9
    # and down to the period doubling, where the two impacts merge
    solution = _period_two(2.68, [1.0, -0.2, 1.2 + 2 * math.pi / 2.68, -0.45])
    for orbit in sorted((o for o in orbits if o.parameter < 2.68), key=lambda o: -o.parameter):
        solution = _period_two(orbit.parameter, solution)
        error = min(np.max(np.abs(orbit.state - state)) for state in _states_at_zero(orbit.parameter, solution))
        assert error < 1e-7, (orbit.parameter, error)
    # supercritical: the period-2 orbit is stable past the doubling, where the period-1 orbit is not
    assert all(o.stable for o in orbits if o.parameter < 2.7)
    # the period-2 orbit doubles in turn where det(M + I) of its closed-form monodromy vanishes
    solutions, grid = [], np.linspace(2.68, 2.74, 31)
    solution = _period_two(2.68, [1.0, -0.2, 1.2 + 2 * math.pi / 2.68, -0.45])
    for forcing in grid:
        solution = _period_two(forcing, solution)
        solutions.append(solution)
    signs = np.sign([_doubling_test(w, u) for w, u in zip(grid, solutions)])
    i = int(np.flatnonzero(np.diff(signs))[0])
    expected = brentq(lambda w: _doubling_test(w, _period_two(w, solutions[i])), grid[i], grid[i + 1], xtol=1e-13)
    found = [b for b in branch.bifurcations if b.kind == "period-doubling"]
    assert len(found) == 1 and abs(found[0].parameter - expected) < 1e-9, (found, expected)   # measured 8e-12
    # and its own switch gives period-4 orbits
    quadruple = switch_branch(problem, found[0], 2.75, step=0.01, max_points=3)
    assert quadruple.orbits[0].periods == 4 and quadruple.orbits[0].impacts_per_period == 4


def test_doubled_orbit_refuses_a_point_that_is_not_a_period_doubling(period_one):
    problem, doubling = period_one
    plain = find_orbit(problem, value=2.4)
    with pytest.raises(ParameterError, match="not a period-doubling point"):
        doubled_orbit(problem, plain)
    with pytest.raises(ParameterError, match="period-doubling point"):
        switch_branch(problem, Bifurcation("fold", doubling.parameter, doubling.orbit), 2.75)
    with pytest.raises(ParameterError, match="amplitude"):
        doubled_orbit(problem, doubling.orbit, amplitude=0.0)


def test_switch_whose_newton_steps_stop_contracting_ends_at_its_third_step(period_one, monkeypatch):
    """Newton's method for the first period-2 orbit stops as soon as its steps stop
    contracting (from the third step on, one not shorter than 0.8 of the one before), after
    three variational runs, instead of running its 30 iterations: here the residual's
    plain run is offset by +-1e-4 m alternately, so that no iterate can converge."""
    from camdyn.continuation import switching
    from camdyn.errors import SimulationError
    problem, doubling = period_one
    calls = {"flow": 0, "shoot": 0}
    flow, shoot = switching.flow, switching.shoot

    def counted_flow(*args, **kwargs):
        calls["flow"] += 1
        return flow(*args, **kwargs)

    def offset_shoot(problem, x, value, periods=1):
        calls["shoot"] += 1                 # per iteration: value + h, value - h, then the residual's run
        end = shoot(problem, x, value, periods)
        if calls["shoot"] % 3 == 0:
            end = end + np.array([1e-4, 0.0]) * (-1) ** (calls["shoot"] // 3)
        return end

    monkeypatch.setattr(switching, "flow", counted_flow)
    monkeypatch.setattr(switching, "shoot", offset_shoot)
    with pytest.raises(SimulationError, match="diverged"):
        doubled_orbit(problem, doubling.orbit)
    assert calls["flow"] == 3, calls
