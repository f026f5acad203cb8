"""Accuracy through events: the global error follows the tolerance through impacts, and
no crossing is missed (grazing dips, two sign changes within one step, chattering).

Truths come from outside the compiled core: closed forms for the linear oscillator
(system 1 of the registry), and the SciPy reference model of :mod:`camdyn.testing.oracle`
(a separate implementation of the equations, restarted at every contact switch) for the
cam-follower.
"""

import math

import numpy as np
import pytest

import camdyn
from camdyn.integrator import driver
from camdyn.simulation.runner import prepare
from camdyn.systems import registry as systems
from camdyn.testing.oracle import reference_simulate

METHODS = [driver.METHOD_EXPLICIT, driver.METHOD_ROSENBROCK, driver.METHOD_DOP853]


def _impact_rig(speed):
    return camdyn.load_system("sundar2014-impact", {"cam.runout": "3.5 mm"}).with_values(**{"motion.speed": speed})


@pytest.mark.slow
def test_impact_rig_global_error_follows_the_tolerance():
    # 30 revolutions of the chapter 3 rig with one impact per revolution: the error in
    # alpha, relative to its amplitude, is at most 10 rtol and falls at every decade of
    # rtol from 1e-5 to 1e-10 (atol = 1e-3 rtol [rad, rad/s], so that it never binds).
    # Before each event's state came from a step taken to it (it came from the
    # interpolant of a step straddling the separation, where the Hertz force
    # |delta|^1.5 is not smooth), this ladder gave 50, 75, 261, 9712, 4085, 51 x rtol.
    speed, revolutions, rate = 16.0, 30, 20e3
    system = _impact_rig(speed)
    prep = prepare(system)
    t = np.arange(int(revolutions / speed * rate) + 1) / rate
    _, truth, info = reference_simulate(system, prep.theta0, prep.y0, t[-1], t, prep.viscous_c,
                                        method="DOP853", rtol=1e-13, atol=1e-15)
    assert sum(kind == "onset" for _, kind in info["log"]) == revolutions
    amplitude = np.max(np.abs(truth[0]))
    errors = []
    for rtol in (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10):
        alpha = camdyn.simulate(system, revolutions=revolutions, sample_rate=rate, rtol=rtol,
                                atol=1e-3 * rtol)["alpha"].values
        n = min(alpha.size, t.size)
        errors.append(np.max(np.abs(alpha[:n] - truth[0, :n])) / amplitude)
    ratios = np.array(errors) / np.array([1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10])
    assert np.all(ratios <= 10.0), ratios
    assert np.all(np.diff(errors) < 0.0), errors


def _oscillator_dip(epsilon, method, rtol=1e-9):
    """y'' + w^2 y = A from rest at y = c (2 + epsilon), c = A / w^2: y = c + c (1 + epsilon)
    cos(w t), whose minimum -c epsilon at w t = pi dips below zero for epsilon > 0."""
    w, force = 1.0, 1.0
    c = force / w ** 2
    p = np.array([w, 0.0, force, 0.0, 0.0])
    y0 = np.array([c * (2.0 + epsilon), 0.0, 0.0])
    _, _, events, counters = driver.integrate(systems.OSCILLATOR, p, y0, 0.0, 4.0, np.array([0.0]), rtol,
                                              1e-3 * rtol, 10.0, method, 10 ** 6, 100, False, math.inf)
    half_gap = math.acos(1.0 / (1.0 + epsilon)) / w if epsilon > 0 else 0.0
    return events, counters, (math.pi / w - half_gap, math.pi / w + half_gap)


@pytest.mark.parametrize("method", METHODS)
def test_grazing_dip_gives_both_crossings(method):
    # a dip of 1e-6 below the guard lasts 2.8e-3 s, inside one step of about 0.1-1 s
    events, counters, (t_down, t_up) = _oscillator_dip(1e-6, method)
    assert events.shape[0] == 2, events
    assert list(events[:, 2]) == [-1.0, 1.0]          # the guard's new sign after each
    # near a graze the crossing time is ill-conditioned (dt = dy / y', y' ~ 1.4e-3):
    # 1e-6 s is 4e-4 of the dip's length
    np.testing.assert_allclose(events[:, 0], [t_down, t_up], rtol=0, atol=1e-6)
    assert counters[driver.COUNT_STATUS] == driver.STATUS_OK


@pytest.mark.parametrize("method", METHODS)
def test_near_graze_above_the_guard_gives_no_event(method):
    events, counters, _ = _oscillator_dip(-1e-6, method)
    assert events.shape[0] == 0, events
    assert counters[driver.COUNT_STATUS] == driver.STATUS_OK


@pytest.mark.parametrize("method", METHODS)
def test_two_sign_changes_within_one_long_step(method):
    # y = 1e-3 cos t - 0.05 sin t crosses zero at t1 = atan(0.02) and again at t1 + pi;
    # at rtol 1e-6 on this slow oscillator the steps are longer than pi - 2 t1
    p = np.array([1.0, 0.0, 0.0, 0.0, 0.0])
    y0 = np.array([1e-3, -0.05, 0.0])
    _, _, events, _ = driver.integrate(systems.OSCILLATOR, p, y0, 0.0, 4.0, np.array([0.0]), 1e-6, 1e-9, 10.0,
                                       method, 10 ** 6, 100, False, math.inf)
    t1 = math.atan2(1e-3, 0.05)
    assert events.shape[0] == 2, events
    np.testing.assert_allclose(events[:, 0], [t1, t1 + math.pi], rtol=0, atol=1e-5)


def test_a_dip_inside_a_long_step_is_found_by_the_scan():
    # y = c + c (1 + eps) cos t dips 1e-6 c below zero for 2 acos(1 / (1 + eps)) = 2.8e-3 s
    # around t = pi. DOP853 at rtol 1e-7 takes steps of about 0.3 s, over which the cubic
    # through a step's ends misses the dip (its error, about c h^4 / 384 = 2e-5 c, lifts
    # it over the dip): without a scan no event is logged. Scanned every 0.05 s (the
    # cubic's error there 1.6e-8 c) both crossings are found, at the closed form's
    # times: near a graze the crossing time is ill-conditioned, an error dy in y moving
    # it by dy / y' with y' = c sqrt(2 eps) = 1.4e-3 c /s there, so that the run's error
    # of about 2e-8 c at rtol 1e-7 allows 1.5e-5 s.
    epsilon, rtol, c = 1e-6, 1e-7, 1.0
    p = np.array([1.0, 0.0, c, 0.0, 0.0])
    y0 = np.array([c * (2.0 + epsilon), 0.0, 0.0])
    runs = {scan: driver.integrate(systems.OSCILLATOR, p, y0, 0.0, 4.0, np.array([0.0]), rtol, 1e-3 * rtol, 10.0,
                                   driver.METHOD_DOP853, 10 ** 6, 100, False, scan) for scan in (math.inf, 0.05)}
    plain, scanned = runs[math.inf], runs[0.05]
    assert plain[3][driver.COUNT_ACCEPTED] < 4.0 / 0.25    # steps longer than 0.25 s on average
    assert plain[2].shape[0] == 0, plain[2]
    events = scanned[2]
    assert events.shape[0] == 2, events
    assert list(events[:, 2]) == [-1.0, 1.0]
    half_gap = math.acos(1.0 / (1.0 + epsilon))
    np.testing.assert_allclose(events[:, 0], [math.pi - half_gap, math.pi + half_gap], rtol=0, atol=1.5e-5)


@pytest.mark.slow
def test_chattering_sequence_matches_the_reference():
    # at 7.5 Hz the follower bounces four times per revolution; every impact of the
    # reference model (steps capped at 20 us, so that none is skipped) is found, in order
    speed, revolutions = 7.5, 4
    system = _impact_rig(speed)
    prep = prepare(system)
    t = np.linspace(0.0, revolutions / speed, 201)
    _, _, info = reference_simulate(system, prep.theta0, prep.y0, t[-1], t, prep.viscous_c, method="DOP853",
                                    rtol=1e-12, atol=1e-14, max_step=2e-5)
    onsets = np.array([time for time, kind in info["log"] if kind == "onset"])
    found = camdyn.simulate(system, revolutions=revolutions, sample_rate=1e3, rtol=1e-10,
                            atol=1e-13)["impact_time"].values
    assert onsets.size >= 4 * revolutions - 1
    assert found.size == onsets.size
    np.testing.assert_allclose(found, onsets, rtol=0, atol=1e-7)


def test_a_run_with_more_events_than_the_log_holds_logs_them_all():
    # 3 revolutions of the chapter 4 rig from rest: 124 events (54 impacts, their peaks
    # of penetration, the separations) against the first log's room of 64 + 16 per
    # revolution, 112. The run is taken again with room for all: every impact is in the
    # result, as many as the SciPy reference model counts (before, 12 events were
    # dropped and 4 of the 41 impacts in these 3 revolutions were missing).
    system = camdyn.load_system("sundar2014-friction", {"cam.runout": "1.75 mm"}).with_values(
        **{"motion.speed": 11.55})
    prep = prepare(system)
    ds = camdyn.simulate(system, revolutions=3)
    assert ds.attrs["solver_events"] > 64 + 16 * 3 and ds.attrs["solver_events_dropped"] == 0
    _, _, info = reference_simulate(system, prep.theta0, prep.y0, 3 / 11.55, np.array([3 / 11.55]),
                                    prep.viscous_c, method="DOP853", rtol=1e-10, atol=1e-12)
    onsets = [t for t, kind in info["log"] if kind == "onset"]
    assert ds["impact_time"].size == len(onsets) == 41
    np.testing.assert_allclose(ds["impact_time"].values, onsets, atol=1e-6)
