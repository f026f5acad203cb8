"""The integrator's failure paths: each stop of the driver (step limit, step-size underflow,
non-finite state) is forced by settings that must cause it, and reaches the user as a
SimulationError that names its reason.

The fourth stop, events accumulating at one instant, is not forced here: no preset
configuration found reaches it (Coulomb sticking on a frozen cam chatters in pairs of
slip reversals at one instant, spaced by microseconds, which the limit rightly lets pass).
"""

import math
import re

import numpy as np
import pytest

import camdyn
from camdyn.errors import SimulationError
from camdyn.integrator import driver
from camdyn.simulation.runner import prepare
from camdyn.systems import registry as systems

UNDERFLOW = "step size fell below the resolution of time"
MAX_STEPS = "maximum number of steps was reached"
NOT_FINITE = "state became infinite or NaN"


def _stop_time(message):
    return float(re.search(r"near t = (\S+) s", message).group(1))


def test_step_limit(impact_rig):
    # 2 revolutions at 16 Hz take some 2000 accepted steps at the default tolerances
    # (solver_accepted_steps of a completed run); 50 cannot reach the end
    with pytest.raises(SimulationError, match=MAX_STEPS) as info:
        camdyn.simulate(impact_rig, revolutions=2, max_steps=50)
    assert 0 < _stop_time(str(info.value)) < 2 / 16.0


def test_step_size_underflow(impact_rig):
    # the follower set spinning at 1e20 rad/s turns once in 6e-20 s, far below the
    # resolution of time near t = 0 (4e-16 s): no step is short enough to follow it
    angle = prepare(impact_rig).equilibrium.angle
    with pytest.raises(SimulationError, match=UNDERFLOW) as info:
        camdyn.simulate(impact_rig, revolutions=1, initial_state=(angle, 1e20))
    assert _stop_time(str(info.value)) < 1e-4


@pytest.mark.parametrize("method", [driver.METHOD_DOP853, driver.METHOD_EXPLICIT, driver.METHOD_ROSENBROCK])
def test_state_overflow_is_reported_as_not_finite_at_the_right_time(method):
    """Negative damping (zeta = -100, w = 1 rad/s) makes y'' - 200 y' + y = 0 grow as
    exp(lambda1 t), lambda1 = 100 + sqrt(9999). From y = 1 at rest,
    y' = (exp(lambda1 t) - exp(lambda2 t)) / (lambda2 - lambda1) (lambda1 lambda2 = 1), whose
    magnitude passes the largest double at t_v = (ln(DBL_MAX) + ln(lambda1 - lambda2)) /
    lambda1 = 3.5755 s. The run must stop there with the non-finite status (it used to
    be reported as a step-size underflow), having followed the closed form up to it.
    Both are outside values: the closed form, and the range of double precision."""
    lam1 = 100.0 + math.sqrt(9999.0)
    lam2 = 1.0 / lam1
    t_v = (math.log(np.finfo(float).max) + math.log(lam1 - lam2)) / lam1
    p = np.array([1.0, -100.0, 0.0, 0.0, 0.0])
    t_out = np.arange(0.0, 4.0, 1e-3)
    y, _, _, counters = driver.integrate(systems.OSCILLATOR, p, np.array([1.0, 0.0, 0.0]), 0.0, 4.0, t_out,
                                         1e-8, 1e-10, 1.0, method, 10 ** 6, 10, False, math.inf)
    assert counters[driver.COUNT_STATUS] == driver.STATUS_NOT_FINITE
    assert NOT_FINITE in driver.STATUS_MESSAGES[driver.STATUS_NOT_FINITE]
    last = t_out[np.isfinite(y[:, 1])][-1]
    # it stops as the state nears the largest double: the intermediate sums of a step
    # overflow a little earlier than the state itself (stage combinations of f = 200 y',
    # DOP853's dense-output coefficients, RODAS4's 1 / (gamma h) in its linear solve); the
    # last finite output measured 8 (Dormand-Prince), 11.5 (DOP853) and 15.5 (RODAS4)
    # e-folds before t_v. Within 20 e-folds (0.1 s) is required: a stop for another
    # reason (the step-size limit, a bad norm) would come at any time
    assert t_v - 20 / lam1 < last < t_v
    # up to there the run follows the closed form (rtol 1e-8 per step, 700 e-folds: 1e-5)
    i = np.searchsorted(t_out, 3.0)
    y_exact = (lam1 * np.exp(lam2 * t_out[i]) - lam2 * np.exp(lam1 * t_out[i])) / (lam1 - lam2)
    assert y[i, 0] == pytest.approx(y_exact, rel=1e-5)
