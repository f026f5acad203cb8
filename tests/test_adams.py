"""The driver's Adams method (``METHOD_ADAMS``: Adams-Moulton in Nordsieck form, functional
iteration, started from a DOP853 step) against closed-form solutions.

System 1 of :mod:`camdyn.systems.registry` is the forced linear oscillator
y'' + 2 zeta w y' + w^2 y = A cos(W t), whose exact solution comes from the matrix
exponential of the autonomous 4-state system (y, y', cos W t, sin W t).
"""

import math

import numpy as np
import pytest
from test_integrator import AMP, W0, WF, ZETA, exact  # the forced oscillator's closed form

from camdyn.integrator import driver
from camdyn.integrator import nordsieck as nd
from camdyn.systems import registry as systems


def test_start_history_is_the_extension_about_the_step_end():
    # the Nordsieck array built from a DOP853 step's extension is that polynomial's Taylor
    # expansion about the step's end: sum_j z_j (tau - 1)^j gives the extension back
    rng = np.random.default_rng(7)
    coefficients, y0 = rng.normal(size=(7, 3)), rng.normal(size=3)

    def extension(tau):   # the nested form of camdyn.integrator.steppers.dense, written out
        s = 1.0 - tau
        c = coefficients
        return y0 + ((((((c[6] * tau + c[5]) * s + c[4]) * tau + c[3]) * s + c[2]) * tau + c[1]) * s + c[0]) * tau

    history = np.zeros((nd.ROWS, 3))
    nd.adams_start(history, coefficients, extension(1.0), 2.0, 0.01, 1e-6, 1e-9, 2, np.empty(3))
    for tau in (0.0, 0.25, 0.6, 1.0):
        taylor = sum(history[nd.Z + j] * (tau - 1.0) ** j for j in range(8))
        np.testing.assert_allclose(taylor, extension(tau), rtol=0, atol=1e-13)
    assert history[nd.ORDER, 0] == nd.START_ORDER and history[nd.TIME, 0] == 2.0


def test_error_falls_with_the_tolerance():
    p = np.array([W0, ZETA, AMP, WF, 0.0])
    t_out = np.linspace(0.0, 5.0, 101)   # dense output: most samples fall inside steps
    ref = np.array([exact(t, 1.0, 0.0)[0] for t in t_out])
    errors = []
    for rtol in (1e-5, 1e-7, 1e-9, 1e-11):
        y, _, _, counters = driver.integrate(systems.OSCILLATOR, p, np.array([1.0, 0.0, 0.0]), 0.0, 5.0,
                                             t_out, rtol, rtol * 1e-2, 1.0, driver.METHOD_ADAMS, 10 ** 6, 100,
                                             False, math.inf)
        assert counters[driver.COUNT_STATUS] == 0
        errors.append(np.max(np.abs(y[:, 0] - ref)))
    assert all(b < a / 10 for a, b in zip(errors, errors[1:])), errors
    assert errors[-1] < 1e-8, errors


def test_events_are_located_exactly():
    # undamped free oscillator y = cos(w t): zero crossings at (k + 1/2) pi / w, located on
    # the Nordsieck polynomial of the step (each event restarts the history)
    w = 7.0
    p = np.array([w, 0.0, 0.0, 0.0, 0.0])
    _, _, events, counters = driver.integrate(systems.OSCILLATOR, p, np.array([1.0, 0.0, 0.0]), 0.0, 10.0,
                                              np.array([0.0]), 1e-11, 1e-13, 1.0, driver.METHOD_ADAMS, 10 ** 6,
                                              100, False, math.inf)
    expected = (np.arange(events.shape[0]) + 0.5) * math.pi / w
    assert counters[driver.COUNT_STATUS] == 0
    assert events.shape[0] == int(10.0 * w / math.pi + 0.5)
    np.testing.assert_allclose(events[:, 0], expected, rtol=0, atol=1e-9)


@pytest.fixture(scope="module")
def impact_rig():
    """The chapter 3 rig (impacts), its prepared run and the SciPy oracle over one revolution."""
    import camdyn
    from camdyn.simulation.runner import prepare
    from camdyn.testing.oracle import reference_simulate
    s = camdyn.load_system("sundar2014-impact", {"cam.runout": "3.5 mm"}).with_values(**{"motion.speed": 16.0})
    prep = prepare(s)
    t_out = np.linspace(0.0, 1.0 / 16.0, 201)
    _, truth, info = reference_simulate(s, prep.theta0, prep.y0, t_out[-1], t_out, prep.viscous_c, rtol=1e-11,
                                        atol=1e-13)
    return prep, t_out, truth


@pytest.mark.parametrize("method", [driver.METHOD_ADAMS, driver.METHOD_MULTISTEP])
@pytest.mark.parametrize("rtol", [1e-6, 1e-9])
def test_cam_run_against_the_oracle(impact_rig, rtol, method):
    # every impact located, the angle within a modest multiple of the tolerance of SciPy's
    # DOP853 run of the reference model (restarted at each switch); the same with Adams and
    # BDF switched automatically
    prep, t_out, truth = impact_rig
    y, _, events, counters = driver.integrate(systems.CAM_FOLLOWER, prep.p, prep.y0.copy(), 0.0, t_out[-1], t_out,
                                              rtol, rtol * 1e-4, t_out[-1] / 32, method, 10 ** 7, 100, False, math.inf)
    assert counters[driver.COUNT_STATUS] == 0
    assert events.shape[0] > 0
    error = np.max(np.abs(y[:, 0] - truth[0])) / np.max(np.abs(truth[0]))
    assert error < 1e3 * rtol, error
