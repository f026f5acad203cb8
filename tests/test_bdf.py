"""The BDF family of the Nordsieck multistep methods and the automatic Adams/BDF switching
(``METHOD_MULTISTEP``) against closed-form solutions.

The non-stiff problem is the forced oscillator of test_integrator (its closed form is
imported). The stiff one is the same oscillator overdamped, ``w = 100`` rad/s and
``zeta = 50``: its eigenvalues are about -1 and -1e4 [1/s], and with the forcing
``A = w^2`` at 1 rad/s it follows ``cos t`` closely after a transient of about 1e-4 s;
its closed form is the matrix exponential of the autonomous system, written here.
"""

import math

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq
from test_integrator import AMP, W0, WF, ZETA, exact  # the forced oscillator's closed form

from camdyn.integrator import driver
from camdyn.integrator import multistep as ms
from camdyn.integrator import nordsieck as nd
from camdyn.systems import registry as systems

STIFF_W, STIFF_ZETA, STIFF_AMP, STIFF_WF = 100.0, 50.0, 1e4, 1.0
STIFF_P = np.array([STIFF_W, STIFF_ZETA, STIFF_AMP, STIFF_WF, 0.0])


def oscillator_matrix(w, zeta, amp, wf):
    """The autonomous linear system of (y, y', cos W t, sin W t)."""
    return np.array([[0, 1, 0, 0], [-w ** 2, -2 * zeta * w, amp, 0], [0, 0, 0, -wf], [0, 0, wf, 0]], float)


def stiff_exact(t):
    return (expm(oscillator_matrix(STIFF_W, STIFF_ZETA, STIFF_AMP, STIFF_WF) * t) @ np.array([1.0, 0, 1, 0]))[0]


def run(p, t_end, t_out, rtol, method, max_events=1000):
    y, _, events, counters = driver.integrate(systems.OSCILLATOR, p, np.array([1.0, 0.0, 0.0]), 0.0, t_end, t_out,
                                              rtol, rtol * 1e-2, 1.0, method, 10 ** 7, max_events, False, math.inf)
    assert counters[driver.COUNT_STATUS] == driver.STATUS_OK
    return y, events, dict(zip(driver.COUNTER_NAMES, counters))


def test_bdf_coefficients_are_those_of_the_backward_differences():
    # l_0 = 1 / (1 + 1/2 + ... + 1/q); order 1 is backward Euler, as Adams' order 1; order 2's
    # l = (2/3, 1, 1/3) (Byrne and Hindmarsh 1975, table of BDF coefficients)
    for q in range(1, nd.BDF_MAX_ORDER + 1):
        assert nd.EL[nd.BDF, q, 0] == pytest.approx(1.0 / sum(1.0 / i for i in range(1, q + 1)), rel=1e-14)
        assert nd.EL[nd.BDF, q, 1] == 1.0
    np.testing.assert_allclose(nd.EL[nd.BDF, 2, :3], [2 / 3, 1, 1 / 3], rtol=1e-14)
    np.testing.assert_allclose(nd.EL[nd.BDF, 1], nd.EL[nd.ADAMS, 1], rtol=1e-14)
    assert nd.CURRENT[nd.BDF, 1] == pytest.approx(nd.CURRENT[nd.ADAMS, 1], rel=1e-14)


def test_spectral_radius_estimate():
    # Gelfand's ||J^64||^(1/64) bounds the spectral radius from above (any induced norm
    # does) and, for these matrices, lies within 25 % of it; the oscillator's weighted
    # norm itself is 300 times its spectral radius at y = (1, 0)
    rng = np.random.default_rng(3)
    y = np.array([1.0, 0.0, 0.0])
    matrices = [rng.normal(size=(3, 3)) * 10.0 ** rng.uniform(-2, 4) for _ in range(20)]
    matrices += [np.array([[0, 1, 0], [-w ** 2, -2 * z * w, 0], [1, 0, 0]], float)
                 for w, z in ((3.0, 0.1), (100.0, 50.0), (6000.0, 0.02))]
    for jac in matrices:
        rho = np.max(np.abs(np.linalg.eigvals(jac)))
        estimate = ms.spectral_radius(jac, y, 1e-6, 1e-8, 3)
        assert rho * (1 - 1e-9) <= estimate <= 1.25 * rho, (jac, rho, estimate)
    weights = 1e-8 + 1e-6 * np.abs(y[:2])
    oscillator = matrices[-3][:2, :2]
    weighted_norm = np.max(np.abs(oscillator) @ weights / weights)
    assert weighted_norm > 300 * np.max(np.abs(np.linalg.eigvals(oscillator)))


def fixed_step_error(q, n):
    """Largest global error at t = 0.1, 0.2, .. 1 s of BDF of order ``q`` at the fixed step
    1/n from the exact Nordsieck array (the Taylor coefficients of the closed form),
    Newton's matrix exact (at a single time the error's leading term may pass near zero)."""
    m = oscillator_matrix(W0, ZETA, AMP, WF)
    x0 = np.array([1.0, 0.0, 1.0, 0.0])
    h = 1.0 / n
    hist = np.zeros((ms.history_rows(3), 3))
    for j in range(q + 1):   # z_j = h^j y^(j) / j!; the quadrature's j-th derivative is y's (j-1)-th
        derivative = np.linalg.matrix_power(m, j) @ x0
        previous = np.linalg.matrix_power(m, j - 1) @ x0 if j > 0 else np.zeros(4)
        hist[nd.Z + j] = np.array([derivative[0], derivative[1], previous[0]]) * h ** j / math.factorial(j)
    hist[nd.FAMILY, 0], hist[nd.ORDER, 0], hist[nd.TIME, 0], hist[nd.STEP, 0] = nd.BDF, q, 0.0, h
    hist[nd.WAIT, 0] = 1e9
    hist[nd.MATRIX_AGE, 0] = hist[nd.JACOBIAN_AGE, 0] = np.inf
    p = np.array([W0, ZETA, AMP, WF, 0.0])
    y1, f1, work = np.empty(3), np.empty(3), np.empty(3)
    matrix, pivots = np.empty((3, 3)), np.empty(3, dtype=np.int64)
    t = 0.0
    error = 0.0
    for k in range(n):
        y, f = hist[nd.Z].copy(), hist[nd.Z + 1] / h
        # tolerances of 1: every step passes the error test, and Newton stops after its
        # first update, which is exact for this linear problem
        e, _, _, _ = ms.multistep_step(systems.OSCILLATOR, t, y, f, h, np.ones(5), p, hist, y1, f1, work, matrix,
                                       pivots, 1.0, 1.0, False)
        assert e <= 1.0
        hist[nd.NEXT_ORDER, 0] = q
        nd.adams_accept(hist, t + h, h)
        t += h
        if (k + 1) % (n // 10) == 0:
            error = max(error, abs(hist[nd.Z, 0] - exact(t, 1.0, 0.0)[0]))
    return error


@pytest.mark.parametrize("q", [1, 2, 3, 4, 5])
def test_order_of_convergence(q):
    errors = [fixed_step_error(q, n) for n in (40, 80, 160)]
    observed = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert observed[-1] == pytest.approx(q, abs=0.3), (errors, observed)


@pytest.fixture(scope="module")
def stiff_runs():
    """The stiff oscillator over 10 s at rtol 1e-6 by the switching method, Adams and DOP853."""
    t_out = np.linspace(0.0, 10.0, 201)
    truth = np.array([stiff_exact(t) for t in t_out])
    runs = {m: run(STIFF_P, 10.0, t_out, 1e-6, m) for m in
            (driver.METHOD_MULTISTEP, driver.METHOD_ADAMS, driver.METHOD_DOP853)}
    return truth, runs


def test_stiff_problem_takes_bdf_and_far_fewer_steps(stiff_runs):
    truth, runs = stiff_runs
    y, _, switching = runs[driver.METHOD_MULTISTEP]
    assert np.max(np.abs(y[:, 0] - truth)) < 2e-5
    # mostly BDF, with far fewer steps and right-hand sides than either explicit-type method
    assert switching["bdf_steps"] > 0.6 * switching["accepted_steps"], switching
    for method in (driver.METHOD_ADAMS, driver.METHOD_DOP853):
        other = runs[method][2]
        assert other["bdf_steps"] == 0 and other["jacobians"] == 0
        assert 10 * switching["accepted_steps"] < other["accepted_steps"], (switching, other)
        assert 10 * switching["rhs_calls"] < other["rhs_calls"], (switching, other)


def test_work_counters(stiff_runs):
    _, runs = stiff_runs
    switching = runs[driver.METHOD_MULTISTEP][2]
    # every accepted step is a BDF step or an explicit-type one (Adams, DOP853 starts); a
    # step retaken to end at an event (at most one per event) moves to the rejected ones
    # but stays counted by its method
    by_method = switching["bdf_steps"] + switching["explicit_steps"]
    assert switching["accepted_steps"] <= by_method <= switching["accepted_steps"] + switching["events"]
    assert switching["rosenbrock_steps"] == 0
    # the Newton matrix is reused: a Jacobian per tens of steps, not per step
    assert 0 < switching["jacobians"] < switching["bdf_steps"] / 10, switching
    # the BDF steps take about one right-hand side each (Newton's rate kept across steps)
    assert switching["rhs_calls"] < 2 * switching["accepted_steps"] + 12 * switching["events"] + 100, switching


def test_error_falls_with_the_tolerance():
    t_out = np.linspace(0.0, 10.0, 101)
    truth = np.array([stiff_exact(t) for t in t_out])
    errors = []
    for rtol in (1e-5, 1e-7, 1e-9):
        y, _, counters = run(STIFF_P, 10.0, t_out, rtol, driver.METHOD_MULTISTEP)
        assert counters["bdf_steps"] > 0.5 * counters["accepted_steps"]
        errors.append(np.max(np.abs(y[:, 0] - truth)))
    assert all(b < a / 10 for a, b in zip(errors, errors[1:])), errors
    assert errors[-1] < 1e-7, errors


def test_switches_back_to_adams_on_a_non_stiff_problem():
    # a BDF history on the non-stiff oscillator (|lambda| = 3 1/s): at the first test the
    # Adams step, free of its stability bound, is the longer, and the family changes
    p = np.array([W0, ZETA, AMP, WF, 0.0])
    y = np.array([1.0, 0.0, 0.0])
    f = np.empty(3)
    systems.rhs(systems.OSCILLATOR, 0.0, y, np.ones(5), p, f)
    hist = np.zeros((ms.history_rows(3), 3))
    hist[nd.Z], hist[nd.Z + 1] = y, 1e-3 * f
    hist[nd.FAMILY, 0], hist[nd.ORDER, 0], hist[nd.TIME, 0], hist[nd.STEP, 0], hist[nd.WAIT, 0] = nd.BDF, 1, 0, 1e-3, 2
    hist[nd.MATRIX_AGE, 0] = hist[nd.JACOBIAN_AGE, 0] = np.inf
    y1, f1, work = np.empty(3), np.empty(3), np.empty(3)
    matrix, pivots = np.empty((3, 3)), np.empty(3, dtype=np.int64)
    t, h, families = 0.0, 1e-3, []
    while t < 5.0 and len(families) < 200:
        y = hist[nd.Z].copy()
        e, order, _, _ = ms.multistep_step(systems.OSCILLATOR, t, y, f, h, np.ones(5), p, hist, y1, f1, work,
                                           matrix, pivots, 1e-6, 1e-8, True)
        if e > 1.0:
            h *= max(0.2, 0.9 * e ** (-1.0 / order))
            continue
        families.append(int(hist[nd.FAMILY, 0]))
        f = f1.copy()
        t, h = t + h, nd.adams_accept(hist, t + h, h)
    assert families[0] == nd.BDF
    switch = families.index(nd.ADAMS)
    assert switch <= ms.SWITCH_STEPS + 1 and set(families[switch:]) == {nd.ADAMS}, families
    assert abs(hist[nd.Z, 0] - exact(t, 1.0, 0.0)[0]) < 1e-4


def test_events_are_located_exactly():
    # the stiff oscillator's zero crossings, from its closed form, located on the BDF
    # steps' Nordsieck polynomials (each event restarts the history from a DOP853 step)
    _, events, counters = run(STIFF_P, 10.0, np.array([0.0]), 1e-11, driver.METHOD_MULTISTEP)
    grid = np.linspace(1e-3, 10.0, 2001)
    values = np.array([stiff_exact(t) for t in grid])
    expected = [brentq(stiff_exact, a, b, xtol=1e-14) for a, b, va, vb in
                zip(grid, grid[1:], values, values[1:]) if va * vb < 0]
    assert counters["bdf_steps"] > 0.5 * counters["accepted_steps"]
    assert events.shape[0] == len(expected) == 3
    np.testing.assert_allclose(events[:, 0], expected, rtol=0, atol=1e-9)


def test_events_of_a_non_stiff_run_are_located_exactly():
    # undamped free oscillator y = cos(w t), as test_adams: the switching method stays Adams
    w = 7.0
    p = np.array([w, 0.0, 0.0, 0.0, 0.0])
    _, events, counters = run(p, 10.0, np.array([0.0]), 1e-11, driver.METHOD_MULTISTEP, 100)
    expected = (np.arange(events.shape[0]) + 0.5) * math.pi / w
    assert counters["bdf_steps"] == 0
    assert events.shape[0] == int(10.0 * w / math.pi + 0.5)
    np.testing.assert_allclose(events[:, 0], expected, rtol=0, atol=1e-9)
