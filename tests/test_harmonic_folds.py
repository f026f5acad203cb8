"""Folds of a frequency response by harmonic balance, on a model written outside the package
(examples/models/duffing.py, a hardening Duffing oscillator, eq. D1): the one-harmonic
folds against their closed form, the converged folds and the branch's stability against
monodromy matrices integrated by SciPy in this file, and the convergence test that a
symmetric nonlinearity's zero even harmonics must not fool."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from camdyn.continuation.problem import bound_problem
from camdyn.steady import continue_harmonic, harmonic_balance
from camdyn.systems.model_files import load_model

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "models" / "duffing.py"
# the example's defaults, in the nondimensional form x'' + 2 zeta x' + x + g x^3 = F cos(W tau)
# (tau = w0 t; with w0 = 2 pi rad/s, W equals the forcing frequency in Hz)
W0, ZETA, G, F = 2.0 * math.pi, 0.05, 1.0, 0.1


@pytest.fixture(scope="module")
def problem():
    return bound_problem(load_model(f"{EXAMPLE}:DUFFING").bind({}))


def one_harmonic_folds() -> list[float]:
    """The folds of the one-harmonic amplitude equation r [(1 - W^2 + 3/4 g r)^2 + (2 zeta
    W)^2] = F^2, r = A^2: the frequencies W where that cubic in r has a double root (its
    discriminant vanishes)."""
    def discriminant(w):
        a, b = (0.75 * G) ** 2, 1.5 * G * (1 - w * w)
        c, d = (1 - w * w) ** 2 + (2 * ZETA * w) ** 2, -F * F
        return 18 * a * b * c * d - 4 * b ** 3 * d + b * b * c * c - 4 * a * c ** 3 - 27 * a * a * d * d
    grid = np.linspace(1.0, 1.4, 4001)
    values = discriminant(grid)
    return sorted(brentq(discriminant, grid[i], grid[i + 1], xtol=1e-15, rtol=1e-15)
                  for i in np.nonzero(np.diff(np.sign(values)))[0])


def monodromy(state, frequency):
    """The state after one forcing period from ``state`` and the monodromy matrix, by SciPy
    on eq. D1 (dimensional) and its variational equation."""
    w0, gamma, force = W0, G * W0 ** 2, F * W0 ** 2

    def rates(t, y):
        x, v = y[0], y[1]
        jac = np.array([[0.0, 1.0], [-w0 ** 2 - 3.0 * gamma * x ** 2, -2.0 * ZETA * w0]])
        acc = force * math.cos(2 * math.pi * frequency * t) - 2 * ZETA * w0 * v - w0 ** 2 * x - gamma * x ** 3
        return np.concatenate([[v, acc], (jac @ y[2:].reshape(2, 2)).ravel()])

    run = solve_ivp(rates, (0.0, 1.0 / frequency), np.concatenate([state, np.eye(2).ravel()]), method="DOP853",
                    rtol=1e-12, atol=1e-12)
    return run.y[:2, -1], run.y[2:, -1].reshape(2, 2)


def test_one_harmonic_folds_are_those_of_the_closed_form(problem):
    # with one harmonic, harmonic balance is the amplitude equation exactly (the cubic's
    # third harmonic cannot alias onto the first on 10 grid times)
    curve = continue_harmonic(problem, 1.1, 1.3, harmonics=1, max_step=0.5, max_points=4000)
    folds = sorted(b.parameter for b in curve.branch.bifurcations if b.kind == "fold")
    assert len(folds) == 2
    np.testing.assert_allclose(folds, one_harmonic_folds(), rtol=1e-10)


def test_converged_folds_have_a_unit_multiplier_and_an_unstable_branch_between(problem):
    curve = continue_harmonic(problem, 1.1, 1.3, max_step=0.5, max_points=4000)
    branch = curve.branch
    assert branch.stopped.endswith("end of its range")
    folds = [b for b in branch.bifurcations if b.kind == "fold"]
    assert len(folds) == 2
    upper, lower = folds                                        # met in this order along the branch
    assert upper.parameter > lower.parameter
    # the third harmonic moves the folds (the closed form's are those of one harmonic)
    assert abs(upper.parameter - one_harmonic_folds()[1]) > 1e-3
    for fold in folds:
        end, matrix = monodromy(fold.orbit.state, fold.parameter)
        np.testing.assert_allclose(end, fold.orbit.state, atol=1e-9)          # a periodic orbit
        assert np.min(np.abs(np.linalg.eigvals(matrix) - 1.0)) < 1e-6          # a unit multiplier
    parameters = np.array(curve.parameters)
    turn_up = int(np.argmax(np.diff(parameters) < 0))                       # the branch turns back
    turn_down = turn_up + int(np.argmax(np.diff(parameters[turn_up:]) > 0))  # and forward again
    assert parameters[turn_up] == pytest.approx(upper.parameter, abs=1e-3)
    assert parameters[turn_down] == pytest.approx(lower.parameter, abs=1e-3)
    # a point ten steps before the upper fold has no unit multiplier: the check above can fail
    before = branch.orbits[turn_up - 10]
    assert np.min(np.abs(np.linalg.eigvals(monodromy(before.state, before.parameter)[1]) - 1.0)) > 1e-2
    # stable outside the folds, unstable between them (the middle branch), as SciPy's matrices say
    for index, unstable in ((turn_up // 2, False), ((turn_up + turn_down) // 2, True),
                            ((turn_down + parameters.size) // 2, False)):
        orbit = branch.orbits[index]
        scipy_unstable = bool(np.max(np.abs(np.linalg.eigvals(monodromy(orbit.state, orbit.parameter)[1]))) > 1.0)
        assert orbit.stable is (not unstable) and scipy_unstable is unstable


def test_the_convergence_test_is_not_fooled_by_zero_even_harmonics(problem):
    # D1's cubic makes every even harmonic zero: at H = 2 the top harmonic alone is zero
    # although the third is not; "auto" goes on until the top two are below the tolerance
    orbit = harmonic_balance(problem, value=1.2)
    assert orbit.harmonics >= 8
    amplitudes = np.hypot(orbit.coefficients[0, 1::2], orbit.coefficients[0, 2::2])
    assert amplitudes[1] < 1e-12 * amplitudes[0]                             # no second harmonic
    assert amplitudes[2] > 1e-3 * amplitudes[0]                              # a third harmonic
