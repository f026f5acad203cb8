"""Multiple shooting for periodic orbits, against closed forms of the rigid-impact
oscillator ``x'' + 2 zeta w x' + w^2 x = A cos(W t)``, ``x'+ = -r x'-`` at the wall ``x =
sigma``: its one-impact period-1 orbits are solved here from the free motion between
impacts written out (steady state plus damped homogeneous solution), their monodromy is
the impact's saltation matrix times the free flow's exponential. Checked: a stable orbit
and its multipliers with 1, 2 and 4 segments (and a segment boundary on the impact); an
unstable orbit shot over five forcing periods (its multiplier there about 4e6), which
single shooting misses from a perturbed start and multiple shooting finds; 1 segment
being single shooting itself."""

import math

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq, fsolve

# the rigid-impact oscillator's closed form, from the single-shooting tests
from test_continuation import FORCE, HOMOGENEOUS, RESTITUTION, W_NATURAL, ZETA, _free, _impact_orbit, _saltation

from camdyn.continuation import continue_orbits, find_orbit, model_problem
from camdyn.continuation.multiple import continuity, cyclic_jacobian, monodromy, newton_step
from camdyn.errors import ParameterError, SimulationError
from camdyn.systems import registry as systems


class ImpactOrbit:
    """The closed-form one-impact period-1 orbit: it leaves the wall ``sigma`` [m] with
    the rebound velocity ``v`` [m/s] at ``t_impact`` [s] and returns one period later with
    ``-v / r``."""

    def __init__(self, forcing, sigma, t_impact, v):
        self.forcing, self.sigma, self.v = forcing, sigma, v
        self.period = 2 * math.pi / forcing
        self.t_impact = t_impact % self.period
        flight = [self.state(self.t_impact + s)[0] for s in np.linspace(0.01, self.period - 0.01, 400)]
        assert max(flight) < sigma                       # a true orbit: in flight between impacts

    def state(self, t):
        """(x [m], x' [m/s]) at the time t [s]."""
        return np.array(_free(self.forcing, self.t_impact, self.sigma, self.v, (t - self.t_impact) % self.period))

    def monodromy(self):
        """Saltation of the impact times the free flow over one period, at the impact."""
        return _saltation(self.forcing, self.sigma, self.t_impact, self.v) @ expm(HOMOGENEOUS * self.period)

    def multipliers(self, periods=1):
        values = np.linalg.eigvals(np.linalg.matrix_power(self.monodromy(), periods))
        return values[np.argsort(-np.abs(values))]


def _solve(forcing, sigma, guess):
    """The orbit with the given forcing W [rad/s] and wall sigma [m], from a guess of
    (t_impact, v)."""
    return ImpactOrbit(forcing, sigma, *_impact_orbit(forcing, sigma, guess))


def _unstable(v):
    """The unstable one-impact orbit with rebound velocity v [m/s] on the wall at 1.5 m
    (the side of the branch born at grazing, before its fold): W(v) solved for."""
    sigma = 1.5

    def residual(u):
        x, velocity = _free(u[1], u[0], sigma, v, 2 * math.pi / u[1])
        return [x - sigma, velocity + v / RESTITUTION]
    (t_impact, forcing) = fsolve(residual, (11.0, 0.53), xtol=1e-14)
    assert np.max(np.abs(residual((t_impact, forcing)))) < 1e-12
    return ImpactOrbit(forcing, sigma, t_impact, v)


def _problem(orbit, t_start=0.0):
    return model_problem(systems.RIGID_IMPACT, [W_NATURAL, ZETA, FORCE, orbit.forcing, orbit.sigma, RESTITUTION],
                         [orbit.sigma - 1.0, 0.0, 0.0], t_start=t_start)


@pytest.fixture(scope="module")
def stable():
    return _solve(2.5, 0.0, [1.1, -0.5])


@pytest.mark.parametrize("segments", [1, 2, 4])
def test_stable_orbit_and_multipliers_match_the_closed_form(stable, segments):
    orbit = find_orbit(_problem(stable), segments=segments)           # from a 50-period transient
    np.testing.assert_allclose(orbit.state, stable.state(0.0), rtol=0, atol=1e-11)       # measured 4e-14
    np.testing.assert_allclose(orbit.multipliers, stable.multipliers(), rtol=0, atol=1e-11)
    assert orbit.stable and orbit.impacts_per_period == 1 and orbit.period == pytest.approx(stable.period, 1e-15)
    if segments > 1:
        times = np.arange(segments) * stable.period / segments
        np.testing.assert_allclose(orbit.segment_states, [stable.state(t) for t in times], rtol=0, atol=1e-11)
        # the orbit's samples join the segments' runs, 256 / m + 1 each sharing their ends:
        # 257 evenly spaced over the period, where the closed form gives the smallest gap
        # to the wall, refined by the parabola through the smallest sample and its neighbours
        gaps = np.array([stable.sigma - stable.state(t)[0] for t in np.linspace(0.0, stable.period, 257)])
        i = int(np.argmin(gaps))
        left, middle, right = gaps[i - 1:i + 2]
        expected = middle - (right - left) ** 2 / (8 * (left - 2 * middle + right))
        assert orbit.guard_minimum == pytest.approx(expected, abs=1e-11)
        assert orbit.extent[0] == pytest.approx(max(abs(stable.state(t)[0]) for t in
                                                    np.linspace(0, stable.period, 2001)), abs=1e-4)


def test_one_segment_is_single_shooting_bit_for_bit(stable):
    problem = _problem(stable)
    start = stable.state(0.0) + [0.01, -0.02]
    single, one = find_orbit(problem, start=start), find_orbit(problem, start=start, segments=1)
    assert single.iterations == one.iterations > 0
    assert np.array_equal(single.state, one.state) and np.array_equal(single.monodromy, one.monodromy)
    assert single.residual == one.residual and one.segment_states is None


def test_a_segment_boundary_on_the_impact(stable):
    # t_start half a period before the impact: the boundary between the two segments is
    # the impact's instant. From the closed form carried to the boundary by a plain run
    # (which stops there with the impact not yet applied) the residual is already below the
    # tolerance; the second segment's variational run starts on the wall, moving into it,
    # and applies the impact and its saltation at once: the product of the segments'
    # matrices is the closed-form monodromy, and the impact is counted once
    problem = _problem(stable, t_start=stable.t_impact - stable.period / 2)
    orbit = find_orbit(problem, start=stable.state(problem.t_start), segments=2)   # carried to the boundary
    assert orbit.iterations == 0 and orbit.impacts_per_period == 1
    np.testing.assert_allclose(orbit.multipliers, stable.multipliers(), rtol=0, atol=1e-12)   # measured 2e-14
    # a boundary 1e-3 T after the impact: Newton's method from 0.01 off the orbit
    problem = _problem(stable, t_start=stable.t_impact + 1e-3 * stable.period - stable.period / 2)
    orbit = find_orbit(problem, start=stable.state(problem.t_start) + [0.01, 0.01], segments=2)
    np.testing.assert_allclose(orbit.state, stable.state(problem.t_start), rtol=0, atol=1e-10)   # measured 6e-12
    np.testing.assert_allclose(orbit.multipliers, stable.multipliers(), rtol=0, atol=1e-10)
    assert orbit.impacts_per_period == 1


@pytest.mark.parametrize("phase, offset", [(0.25, [0.0, 0.005]), (0.4, [0.001, 0.0])])
def test_strongly_unstable_orbit_single_shooting_fails_multiple_shooting_finds(phase, offset):
    # The unstable one-impact orbit (|mu| = 20.9 per period) sought over five forcing
    # periods, as a period-5 orbit would be: over 5 T its multiplier is 20.9^5 = 4.0e6.
    # The phase of the first boundary is `phase` periods after an impact; ten segments,
    # two per period, all boundaries in flight.
    orbit = _unstable(-0.02)
    periods, segments = 5, 10
    mu = orbit.multipliers(periods)
    assert abs(orbit.multipliers()[0]) == pytest.approx(20.916, abs=1e-3) and abs(mu[0]) > 4e6
    problem = _problem(orbit, t_start=orbit.t_impact + phase * orbit.period)
    offset = np.array(offset)                                               # [m, m/s]
    # single shooting from the orbit's state plus the offset: a Newton iterate lands
    # beyond the wall, where the run cannot start
    with pytest.raises(SimulationError, match="step size fell below"):
        find_orbit(problem, start=orbit.state(problem.t_start) + offset, periods=periods)
    # multiple shooting from every segment's state plus the same offset finds the orbit
    times = problem.t_start + np.arange(segments) * periods * orbit.period / segments
    found = find_orbit(problem, start=[orbit.state(t) + offset for t in times], periods=periods, segments=segments)
    np.testing.assert_allclose(found.segment_states, [orbit.state(t) for t in times], rtol=0, atol=1e-10)  # 2e-11
    assert found.impacts_per_period == periods and not found.stable
    # the large multiplier to 1e-7 relatively (measured 2e-8, 1e-9); the small one,
    # mu_2^5 = 1.1e-10, is below the plain product's rounding (|M| eps = 1e-9): not checked
    assert abs(found.multipliers[0] / mu[0] - 1) < 1e-7


def test_multiple_shooting_keeps_the_large_multiplier_accurate():
    # From a start on the orbit, over 5 periods: single shooting converges, but its
    # monodromy carries the integration error times 4e6; the product of ten segments'
    # matrices does not
    orbit = _unstable(-0.02)
    problem = _problem(orbit, t_start=orbit.t_impact + orbit.period / 4)      # boundaries in flight
    expected = orbit.multipliers(5)[0]
    single = find_orbit(problem, start=orbit.state(problem.t_start), periods=5)
    times = problem.t_start + np.arange(10) * orbit.period / 2
    multiple = find_orbit(problem, start=[orbit.state(t) for t in times], periods=5, segments=10)
    single_error = abs(single.multipliers[0] / expected - 1)
    multiple_error = abs(multiple.multipliers[0] / expected - 1)
    # measured: single 6.9e-6 (after 15 Newton iterations on a residual whose noise the
    # multiplier amplifies), multiple 8.9e-9 (0 iterations); the bound is the integration
    # tolerance (1e-10) times the segments' amplification, with margin
    assert multiple_error < 1e-7 and multiple_error < single_error / 100, (single_error, multiple_error)


def test_cyclic_jacobian_solves_a_linear_periodic_map_in_one_step():
    # x -> A_i x + b_i on three segments: the fixed point of the composed map, by hand
    rng = np.random.default_rng(3)
    matrices = rng.normal(size=(3, 2, 2)) * 3.0
    shifts = rng.normal(size=(3, 2))
    composed, offset = np.eye(2), np.zeros(2)
    for a, b in zip(matrices, shifts):
        composed, offset = a @ composed, a @ offset + b
    fixed = np.linalg.solve(np.eye(2) - composed, offset)
    states = rng.normal(size=(3, 2))
    ends = np.einsum("ijk,ik->ij", matrices, states) + shifts
    states = states + newton_step(cyclic_jacobian(matrices), continuity(ends, states))
    np.testing.assert_allclose(states[0], fixed, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(monodromy(matrices), composed, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(continuity(np.einsum("ijk,ik->ij", matrices, states) + shifts, states), 0.0,
                               atol=1e-12)


def test_multiple_shooting_refuses_bad_input(stable):
    problem = _problem(stable)
    for segments in (0, 1.5, True):
        with pytest.raises(ParameterError, match="segments must be a positive integer"):
            find_orbit(problem, segments=segments)
    with pytest.raises(ParameterError, match="rows"):
        find_orbit(problem, start=np.zeros((3, 2)), segments=2)
    with pytest.raises(ParameterError, match="finite"):
        find_orbit(problem, start=[[0.0, math.nan], [0.0, 0.0]], segments=2)
    with pytest.raises(SimulationError, match="2 shooting segments: Newton's method did not converge"):
        find_orbit(problem, start=[[-0.5, 0.3], [-0.2, 0.1]], segments=2, max_iterations=1)


def test_continuation_with_segments_locates_the_period_doubling_of_the_closed_form():
    # the branch of single shooting's test (tests/test_continuation.py), continued with
    # three segments from W = 2.3 to 3 rad/s; det(M + I) of the closed-form one-impact
    # orbit vanishes where a multiplier is -1
    def doubling(forcing):
        values = _solve(forcing, 0.0, [1.1, -0.3]).multipliers()
        return float(np.real(np.prod(values + 1.0)))
    expected = brentq(doubling, 2.6, 2.7, xtol=1e-14)
    problem = _problem(_solve(2.3, 0.0, [1.1, -0.5]))
    start = find_orbit(problem, segments=3)
    branch = continue_orbits(problem, start, 3.0, step=0.02)
    assert [b.kind for b in branch.bifurcations] == ["period-doubling"]
    assert abs(branch.bifurcations[0].parameter - expected) < 1e-9, (branch.bifurcations[0].parameter, expected)
    assert "end of its range" in branch.stopped and len(branch.orbits) > 20
    for orbit in branch.orbits[1::4]:                 # every segment's state on the closed form
        closed = _solve(orbit.parameter, 0.0, [1.1, -0.4])
        times = np.arange(3) * closed.period / 3
        np.testing.assert_allclose(orbit.segment_states, [closed.state(t) for t in times], rtol=0, atol=1e-9)


def test_continue_cli_with_segments_ends_on_the_single_shooting_orbit(capsys):
    # the chapter 4 rig (e/a = 0.05) from 11.55 to 12 Hz with two segments: the branch's
    # last orbit, at 12 Hz, is the one single shooting finds there on its own
    import json

    import camdyn
    from camdyn.cli.app import main
    from camdyn.continuation import system_problem

    assert main(["continue", "sundar2014-friction", "--set", "cam.runout=0.875mm", "--from", "11.55Hz", "--to",
                 "12Hz", "--segments", "2", "--doublings", "0", "--json", "--quiet"]) == 0
    last = json.loads(capsys.readouterr().out)["branches"][0][-1]
    assert last["parameter"] == pytest.approx(12.0, abs=1e-12)
    system = camdyn.load_system("sundar2014-friction").with_values(**{"cam.runout": 0.875e-3, "motion.speed": 12.0})
    single = find_orbit(system_problem(system, "motion.speed"), transient=1)
    np.testing.assert_allclose(last["state"], single.state, rtol=0, atol=1e-9)              # measured 9e-12
    multipliers = np.array([complex(*pair) for pair in last["multipliers"]])
    np.testing.assert_allclose(multipliers, single.multipliers, rtol=0, atol=1e-9)         # measured 6e-11


@pytest.mark.parametrize("source, args, words", [
    ("sundar2014-friction", ["--segments", "0"], "--segments"),
    ("alzate", ["--segments", "2"], "single shooting"),
])
def test_continue_cli_refuses_bad_segments_in_one_line(source, args, words, capsys):
    from camdyn.cli.app import main
    assert main(["continue", source, "--from", "11Hz", "--to", "12Hz", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error:") and words in err[0], err
