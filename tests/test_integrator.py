"""The compiled integrator against closed-form solutions (no cams involved).

System 1 of :mod:`camdyn.systems.registry` is the forced linear oscillator
y'' + 2 zeta w y' + w^2 y = A cos(W t), whose exact solution comes from the matrix
exponential of the autonomous 4-state system (y, y', cos W t, sin W t).
"""

import math

import numpy as np
import pytest
from scipy.linalg import expm

from camdyn.integrator import driver
from camdyn.integrator.steppers import dormand_prince_step, rosenbrock_step
from camdyn.systems import registry as systems

W0, ZETA, AMP, WF = 3.0, 0.1, 1.0, 2.0


def exact(t, y0, v0):
    a = np.array([[0, 1, 0, 0], [-W0 ** 2, -2 * ZETA * W0, AMP, 0], [0, 0, 0, -WF], [0, 0, WF, 0]], float)
    return (expm(a * t) @ np.array([y0, v0, 1.0, 0.0]))[:2]


def fixed_step_error(stepper, n):
    p = np.array([W0, ZETA, AMP, WF, 0.0])
    mode = np.zeros(5)
    y = np.array([1.0, 0.0, 0.0])
    f = np.empty(3)
    f1 = np.empty(3)
    y1 = np.empty(3)
    err = np.empty(3)
    h = 1.0 / n
    t = 0.0
    systems.rhs(systems.OSCILLATOR, t, y, mode, p, f)
    for _ in range(n):
        if stepper == "dp":
            dormand_prince_step(systems.OSCILLATOR, t, y, f, h, mode, p, np.empty((6, 3)), y1, f1, err)
        else:
            rosenbrock_step(systems.OSCILLATOR, t, y, f, h, mode, p, np.empty((6, 3)), np.empty((6, 3)),
                            np.empty((3, 3)), np.empty(3, dtype=np.int64), y1, err)
            systems.rhs(systems.OSCILLATOR, t + h, y1, mode, p, f1)
        y[:] = y1
        f[:] = f1
        t += h
    return abs(y[0] - exact(1.0, 1.0, 0.0)[0])


@pytest.mark.parametrize("stepper, order", [("dp", 5), ("rosenbrock", 4)])
def test_order_of_convergence(stepper, order):
    # halving the step divides the global error by 2^order; a mistyped coefficient
    # in either tableau drops the observed order by at least one
    errors = [fixed_step_error(stepper, n) for n in (8, 16, 32, 64)]
    observed = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert observed[-1] == pytest.approx(order, abs=0.35), observed


@pytest.mark.parametrize("method", [driver.METHOD_EXPLICIT, driver.METHOD_ROSENBROCK])
def test_adaptive_error_scales_with_tolerance(method):
    p = np.array([W0, ZETA, AMP, WF, 0.0])
    t_out = np.linspace(0.0, 5.0, 51)
    ref = np.array([exact(t, 1.0, 0.0)[0] for t in t_out])
    errs = []
    for rtol in (1e-6, 1e-9):
        y, _, _, counters = driver.integrate(systems.OSCILLATOR, p, np.array([1.0, 0.0, 0.0]), 0.0, 5.0,
                                             t_out, rtol, rtol * 1e-2, 1.0, method, 10 ** 6, 100, False, math.inf)
        assert counters[driver.COUNT_STATUS] == 0
        errs.append(np.max(np.abs(y[:, 0] - ref)))
    # global error stays within a modest multiple of the tolerance and falls with it
    assert errs[0] < 50 * 1e-6
    assert errs[1] < 50 * 1e-9
    assert errs[1] < errs[0] / 100


METHODS = [driver.METHOD_EXPLICIT, driver.METHOD_DOP853, driver.METHOD_ROSENBROCK]


@pytest.mark.parametrize("method", METHODS)
def test_events_are_located_exactly(method):
    # undamped free oscillator y = cos(w t): zero crossings at (k + 1/2) pi / w, located on
    # each method's own continuous extension (DOP853's 7th-order one in every cam run)
    w = 7.0
    p = np.array([w, 0.0, 0.0, 0.0, 0.0])
    _, _, events, counters = driver.integrate(systems.OSCILLATOR, p, np.array([1.0, 0.0, 0.0]), 0.0, 10.0,
                                              np.array([0.0]), 1e-11, 1e-13, 1.0, method, 10 ** 6, 100, False, math.inf)
    expected = (np.arange(events.shape[0]) + 0.5) * math.pi / w
    assert events.shape[0] == int(10.0 * w / math.pi + 0.5)
    np.testing.assert_allclose(events[:, 0], expected, rtol=0, atol=1e-9)


@pytest.mark.parametrize("method", METHODS)
def test_crossing_inside_a_long_step_is_located(method):
    # a crossing shortly after the start of a step that may be 10 s long
    w = 1.0
    p = np.array([w, 0.0, 0.0, 0.0, 0.0])
    y0 = np.array([1e-3, -0.05, 0.0])  # crosses zero near t = 0.02, returns near t = pi - 0.02
    t_out = np.array([0.0])
    _, _, events, _ = driver.integrate(systems.OSCILLATOR, p, y0, 0.0, 0.5, t_out, 1e-10, 1e-12, 10.0,
                                       method, 10 ** 6, 100, False, math.inf)
    exact_t = math.atan2(1e-3, 0.05)  # y = 1e-3 cos t - 0.05 sin t = 0
    assert events.shape[0] == 1
    assert events[0, 0] == pytest.approx(exact_t, abs=1e-10)


def test_dense_output_is_fourth_order():
    # the continuous extension of Dormand-Prince is (at least) 4th order: its local error
    # inside one step falls by at least 2^5 when the step is halved (a cubic Hermite
    # interpolant would only give 2^4); on this linear problem it does better still
    from camdyn.integrator.steppers import dense
    p = np.array([W0, ZETA, AMP, WF, 0.0])
    mode = np.zeros(5)
    errs = []
    for h in (0.8, 0.4, 0.2):
        y = np.array([1.0, 0.0, 0.0])
        f = np.empty(3)
        systems.rhs(systems.OSCILLATOR, 0.0, y, mode, p, f)
        work, y1, f1, err, out = np.empty((6, 3)), np.empty(3), np.empty(3), np.empty(3), np.empty(3)
        dormand_prince_step(systems.OSCILLATOR, 0.0, y, f, h, mode, p, work, y1, f1, err)
        worst = 0.0
        for theta in np.linspace(0.05, 0.95, 19):
            dense(theta, h, y, f, y1, f1, work, 0, out)
            worst = max(worst, abs(out[0] - exact(theta * h, 1.0, 0.0)[0]))
        errs.append(worst)
        dense(1.0, h, y, f, y1, f1, work, 0, out)
        assert out[0] == pytest.approx(y1[0], rel=1e-13, abs=1e-14)
    ratios = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert ratios.min() > 4.6, ratios
