"""The rigid-impact linear oscillator (system 2 of the registry) against closed forms:
state resets at a wall located by the integrator's events, without any cam.

``x'' + 2 zeta w x' + w^2 x = A cos(W t)`` for ``x < sigma``; ``x'+ = -r x'-`` at the
wall. The expected values come from the free motion of the linear oscillator in closed
form, solved here independently of the integrator.
"""

import math

import numpy as np
import pytest
from scipy.optimize import fsolve

from camdyn.integrator import driver
from camdyn.systems import registry as systems

METHODS = [driver.METHOD_EXPLICIT, driver.METHOD_ROSENBROCK, driver.METHOD_DOP853]


def _run(p, y0, t_end, method=driver.METHOD_AUTO, rtol=1e-11):
    _, _, events, counters = driver.integrate(systems.RIGID_IMPACT, np.asarray(p, float), np.asarray(y0, float),
                                              0.0, t_end, np.array([0.0]), rtol, 1e-3 * rtol, 10.0, method,
                                              10 ** 7, 100_000, False, math.inf)
    assert counters[driver.COUNT_STATUS] == driver.STATUS_OK
    return events


#: event-log columns of the state at each impact (3 states, 1 guard)
POSITION = driver.event_columns(3, 1).index("state0")
VELOCITY = driver.event_columns(3, 1).index("state1")


@pytest.mark.parametrize("method", METHODS)
def test_free_bouncing_follows_the_restitution_law(method):
    # unforced, undamped, from rest at x0 = -1 against a wall at 0: impacts at
    # t_k = pi / 2 + (k - 1) pi with approach velocities r^(k-1) (w = 1)
    r = 0.8
    events = _run([1.0, 0.0, 0.0, 0.0, 0.0, r], [-1.0, 0.0, 0.0], 10.0, method)
    k = np.arange(events.shape[0])
    assert events.shape[0] == 3
    np.testing.assert_allclose(events[:, 0], math.pi / 2 + k * math.pi, rtol=0, atol=1e-8)
    np.testing.assert_allclose(events[:, VELOCITY], r ** k, rtol=1e-8)     # x' just before each impact
    np.testing.assert_allclose(events[:, POSITION], 0.0, atol=1e-9)        # at the wall


def _orbit_residual(unknowns, w, zeta, force, forcing, sigma, r):
    """Period-1 impacting orbit: leave the wall at phase t0 with x' = v (< 0) and come
    back to it one forcing period later with x' = -v / r. Free motion in closed form."""
    t0, v = unknowns
    period = 2 * math.pi / forcing
    amp = force / complex(w * w - forcing * forcing, 2 * zeta * w * forcing)   # x_p = Re(amp e^{iWt})

    def xp(t):
        z = amp * complex(math.cos(forcing * t), math.sin(forcing * t))
        return z.real, (1j * forcing * z).real

    wd = w * math.sqrt(1 - zeta * zeta)
    x0, v0 = xp(t0)
    c = sigma - x0
    d = (v - v0 + zeta * w * c) / wd
    decay = math.exp(-zeta * w * period)
    cs, sn = math.cos(wd * period), math.sin(wd * period)
    x1 = x0 + decay * (c * cs + d * sn)                 # x_p(t0 + T) = x_p(t0)
    v1 = v0 + decay * ((-zeta * w) * (c * cs + d * sn) + wd * (-c * sn + d * cs))
    return [x1 - sigma, v1 + v / r]


@pytest.mark.parametrize("forcing", [1.5, 2.0])
def test_period_one_orbit_matches_the_closed_form(forcing):
    w, zeta, force, sigma, r = 1.0, 0.05, 1.0, 0.0, 0.8
    period = 2 * math.pi / forcing
    events = _run([w, zeta, force, forcing, sigma, r], [-0.5, 0.0, 0.0], 300 * period)
    settled = events[events[:, 0] > 250 * period]
    assert settled.shape[0] == 50                       # one impact per forcing period
    phase = settled[-1, 0] % period
    approach = settled[-1, VELOCITY]
    t0, v = fsolve(_orbit_residual, [phase, -r * approach], args=(w, zeta, force, forcing, sigma, r), xtol=1e-12)
    assert np.max(np.abs(_orbit_residual([t0, v], w, zeta, force, forcing, sigma, r))) < 1e-12
    assert phase == pytest.approx(t0 % period, abs=1e-8)
    assert approach == pytest.approx(-v / r, rel=1e-8)


def test_wall_is_never_crossed_between_samples():
    # the gap to the wall stays >= 0 (to rounding) at every output sample
    p = np.array([1.0, 0.05, 1.0, 2.0, 0.0, 0.8])
    t_out = np.linspace(0.0, 60.0, 20001)
    y, _, events, counters = driver.integrate(systems.RIGID_IMPACT, p, np.array([-0.5, 0.0, 0.0]), 0.0, 60.0,
                                              t_out, 1e-9, 1e-12, 10.0, driver.METHOD_AUTO, 10 ** 7, 10_000,
                                              False, math.inf)
    assert counters[driver.COUNT_STATUS] == driver.STATUS_OK and events.shape[0] > 10
    assert y[:, 0].max() < 1e-9
