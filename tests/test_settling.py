"""The warning that a run has not settled (camdyn.simulation.settling): closed-form
signals whose period and decay are known, then the chapter 4 rig at 17 Hz, which from
rest still bounces after 12 revolutions (37 impacts) and has settled after 40."""

import math
import warnings

import numpy as np
import pytest

from camdyn.simulation.settling import REPEAT_TOLERANCE, TransientWarning, check_settled, repeat

PERIOD = 0.1                                  # s
TIMES = np.arange(0.0, 30 * PERIOD, PERIOD / 400)


def test_a_periodic_signal_repeats_after_its_own_period():
    assert repeat(TIMES, np.sin(2 * math.pi * TIMES / PERIOD), PERIOD)[0] == 1
    # a subharmonic of half the forcing frequency repeats after two periods, not one
    k, _ = repeat(TIMES, np.sin(math.pi * TIMES / PERIOD) + np.sin(2 * math.pi * TIMES / PERIOD), PERIOD)
    assert k == 2
    # and one of a third after three
    assert repeat(TIMES, np.cos(2 * math.pi * TIMES / (3 * PERIOD)), PERIOD)[0] == 3


@pytest.mark.parametrize("tau, settled", [(1.0, False), (0.25, True)])
def test_a_decaying_transient_is_settled_once_it_has_decayed_below_the_tolerance(tau, settled):
    """x = sin(2 pi t / T) + exp(-t / tau) over 30 periods (3 s): at its start t1 = end - T
    the last period differs most from the one before, by exp(-t1 / tau) (exp(T / tau) - 1),
    over the range of the two periods: 2.9e-3 for tau = 1 s (not settled), 2.3e-6 for
    tau = 0.25 s."""
    x = np.sin(2 * math.pi * TIMES / PERIOD) + np.exp(-TIMES / tau)
    end = TIMES[-1]
    first = TIMES[TIMES >= end - PERIOD][0]
    expected = math.exp(-first / tau) * (math.exp(PERIOD / tau) - 1) / np.ptp(x[TIMES >= end - 2 * PERIOD])
    k, difference = repeat(TIMES, x, PERIOD)
    assert difference == pytest.approx(expected, rel=0.02) if k is None or k == 1 else False
    assert (k == 1) == settled and (expected < REPEAT_TOLERANCE) == settled


def test_noise_repeats_within_no_period_and_warns():
    noise = np.random.default_rng(7).normal(size=TIMES.size)
    assert repeat(TIMES, noise, PERIOD)[0] is None
    with pytest.warns(TransientWarning, match="has not settled"):
        check_settled(TIMES, noise, PERIOD, "alpha")


def test_short_runs_and_a_cam_at_rest_are_not_judged():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        short = TIMES < 8.9 * PERIOD             # shorter than 9 periods: a period 8 could not show
        check_settled(TIMES[short], np.random.default_rng(1).normal(size=short.sum()), PERIOD, "alpha")
        check_settled(TIMES, np.ones(TIMES.size), math.inf, "alpha")


def test_simulate_warns_of_a_run_that_still_bounces_and_not_of_a_settled_one():
    import camdyn

    rig = camdyn.load_system("sundar2014-friction")                     # e/a = 0.1
    with pytest.warns(TransientWarning, match="find_orbit"):
        ds = camdyn.simulate(rig, speed=17.0, revolutions=12, variables=["alpha", "impact"])
    assert ds.sizes["impact"] > 0
    with warnings.catch_warnings():
        warnings.simplefilter("error", TransientWarning)
        camdyn.simulate(rig, speed=17.0, revolutions=40, variables=["alpha"])
