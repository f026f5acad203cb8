"""The Alzate / di Bernardo rig (the Siconos project's cam-follower example) three ways on
the same equations: camdyn's event-driven solution, the independent event-driven SciPy
solution of tests/test_translating_follower.py, and Siconos's own Moreau-Jean time
stepping. The Siconos numbers are read from tests/data/siconos_camfollower.json, written
by benchmarks/siconos_camfollower.py (``apt-get install python3-siconos``, then
``/usr/bin/python3 benchmarks/siconos_camfollower.py``); they come from outside camdyn and
are the expected values here.

Moreau-Jean time stepping is first order: an impact lands on the step grid, and in the
cam's frame the cam's acceleration, a force that jumps at the arcs' joints, is
integrated by the trapezoidal rule, with an error set by where each jump falls in its
step. Its errors are therefore first order in size but not steady in the step. The
tolerances below are Siconos's accuracy as measured on the ladder of steps (h, h/2,
h/4) the JSON holds: its scatter over the ladder and from revolution to revolution, and
the regimes are compared with the time stepping's scatter (NOISE) in the section.
"""

import json
import math
from pathlib import Path

import numpy as np
import pytest
from test_translating_follower import PHASE, _closed_form_liftoff, reference

from camdyn.simulation.translating import alzate_rig, simulate_translating

DATA = json.loads((Path(__file__).parent / "data" / "siconos_camfollower.json").read_text())
SPEEDS = (358, 660, 700)
LADDER = sorted(int(steps) for steps in DATA["speeds"]["358"])
#: the runs sample only the Poincare section, a few points per revolution, on purpose
pytestmark = pytest.mark.filterwarnings("ignore::camdyn.simulation.limits.LargeResultWarning")
#: a section repeats where it returns within this fraction of its RMS (the script's rule)
NOISE = 0.2


def omega(rpm):
    """Cam speed [rad/s] of ``rpm`` [rev/min]."""
    return rpm * 2.0 * math.pi / 60.0


def separates(rpm):
    """Does camdyn's follower, started on the cam at the end of the base dwell, leave it
    within a quarter revolution (past the nose arc)?"""
    period = 2.0 * math.pi / omega(rpm)
    ds = simulate_translating(alzate_rig(), omega(rpm) / (2 * math.pi), 0.25 * period, sample_rate=64 / period,
                              phase=PHASE)
    return bool((ds.event_kind.values == "separation").any())


def camdyn_liftoff(low=100.0, high=130.0, tolerance=1e-5):
    """camdyn's loss-of-contact speed [rpm], bisected on its event-driven runs."""
    assert not separates(low) and separates(high)
    while (high - low) / low > tolerance:
        middle = 0.5 * (low + high)
        low, high = (low, middle) if separates(middle) else (middle, high)
    return 0.5 * (low + high)


def long_run(rpm, transient, revolutions, rtol=1e-10):
    """camdyn from rest on the cam over ``transient + revolutions`` revolutions: the
    section (gap [m], relative velocity [m/s]) at the end of the base dwell every
    revolution after the transient, and the impacts after it faster than the JSON's
    velocity floor: (revolution, cam angle [rad] after the section, approach velocity)."""
    period = 2.0 * math.pi / omega(rpm)
    ds = simulate_translating(alzate_rig(), omega(rpm) / (2 * math.pi), (transient + revolutions) * period,
                              sample_rate=8 / period, phase=PHASE, rtol=rtol, atol=rtol / 100)
    gap, rate = ds.gap.values[::8], (ds.x_dot.values - ds.lift_rate.values)[::8]
    section = np.c_[gap, rate][transient:]
    t, v = ds.event_time.values, ds.event_velocity.values
    fast = (ds.event_kind.values == "impact") & (t >= transient * period) & (-v > DATA["velocity_floor_m_per_s"])
    turn = np.floor(t[fast] / period).astype(int)
    impacts = np.c_[turn - transient, omega(rpm) * t[fast] - 2.0 * math.pi * turn, v[fast]]
    return section, impacts


def lag_deviations(section, longest=24):
    """Largest change of the section over p = 1 .. longest revolutions, relative to its
    RMS, per coordinate (the script's definition)."""
    size = np.sqrt(np.mean(section ** 2, axis=0))
    return np.array([np.abs(section[p:] - section[:-p]).max(axis=0) / size for p in range(1, longest + 1)])


def period_of(deviations, noise=NOISE):
    """The least p whose lag deviations are within ``noise``, else None."""
    for p, deviation in enumerate(deviations, start=1):
        if deviation.max() <= noise:
            return p
    return None


@pytest.fixture(scope="module")
def camdyn_runs():
    run = DATA["speeds"]["358"][str(LADDER[0])]
    return {rpm: long_run(rpm, run["transient_revolutions"], run["revolutions"]) for rpm in SPEEDS}


def test_the_three_loss_of_contact_speeds_agree():
    """Siconos's lift-off (bisected on a step with no contact impulse) converges to
    camdyn's (bisected on its separation events) and the closed form as h falls."""
    closed = _closed_form_liftoff()[0] * 60.0 / (2.0 * math.pi)
    ours = camdyn_liftoff()
    assert ours == pytest.approx(closed, rel=1e-4)
    siconos = {int(steps): rpm for steps, rpm in DATA["liftoff_rpm"].items()}
    finest = siconos[max(siconos)]
    assert finest == pytest.approx(ours, rel=1e-3)
    errors = [abs(siconos[steps] - ours) for steps in sorted(siconos)]
    assert errors[-1] < errors[0]


def _nearest(times, t):
    """Index of the entry of ``times`` nearest to ``t``."""
    return int(np.argmin(np.abs(times - t)))


@pytest.mark.parametrize("rpm, revolutions", [(358, 2), (660, 4), (700, 4)])
def test_the_first_impacts_from_rest_agree_within_the_time_steppings_scatter(rpm, revolutions):
    """From rest on the cam: camdyn and the SciPy solution give the same events to 1e-8
    s. Siconos's impacts faster than 1 m/s (the chattering ones below are a few steps
    apart) at its finest step lie within its own scatter over the ladder of steps
    (largest minus smallest of the three) of camdyn's, in time and velocity. The scatter
    does not fall steadily with the step: in the cam's frame the cam's acceleration is a
    force on the follower that jumps by some 3 kN at the nose arc's ends, which the theta
    method integrates by the trapezoidal rule, with an error set by where each jump falls
    in its step."""
    w = omega(rpm)
    window = revolutions * (2.0 * math.pi / w)
    rtol = 1e-12 if rpm < 700 else 1e-11   # at 700 rpm rtol 1e-12 shrinks the step below time's resolution
    ds = simulate_translating(alzate_rig(), w / (2 * math.pi), window, sample_rate=64 / window, phase=PHASE, rtol=rtol,
                              atol=rtol / 100)
    real = ds.event_kind.values != "graze"
    events, _ = reference(w, window)
    assert list(ds.event_kind.values[real]) == [kind for _, kind in events if kind != "graze"]
    np.testing.assert_allclose(ds.event_time.values[real], [t for t, kind in events if kind != "graze"], atol=1e-8)
    fast = (ds.event_kind.values == "impact") & (ds.event_velocity.values < -1.0)
    times, velocities = ds.event_time.values[fast], ds.event_velocity.values[fast]
    assert times.size >= 4
    ladder = []
    for steps in LADDER:
        theirs = np.array(DATA["speeds"][str(rpm)][str(steps)]["first_impacts"])
        ladder.append(theirs[[_nearest(theirs[:, 0], t) for t in times]])
    ladder = np.array(ladder)   # step, impact, (time, velocity)
    scatter = np.ptp(ladder, axis=0)
    assert np.all(np.abs(ladder[-1, :, 0] - times) <= scatter[:, 0])
    assert np.all(np.abs(ladder[-1, :, 1] - velocities) <= scatter[:, 1])


def _separation(rpm, start, revolutions, kick=1e-9):
    """Distance in the section (gap / 0.1 m, relative velocity / 10 m/s) between camdyn's
    runs from ``start`` and from ``start`` with the velocity raised by ``kick`` [m/s],
    once per revolution."""
    period = 2.0 * math.pi / omega(rpm)
    runs = [simulate_translating(alzate_rig(), omega(rpm) / (2 * math.pi), revolutions * period, sample_rate=4 / period,
                                 phase=PHASE, initial_state=(start[0], start[1] + dv), rtol=1e-11, atol=1e-13)
            for dv in (0.0, kick)]
    gap = [run.gap.values[::4] for run in runs]
    rate = [(run.x_dot.values - run.lift_rate.values)[::4] for run in runs]
    return np.hypot((gap[1] - gap[0]) / 0.1, (rate[1] - rate[0]) / 10.0)


@pytest.mark.parametrize("rpm", SPEEDS)
def test_the_largest_lyapunov_exponent_is_positive_only_at_660_rpm(rpm, camdyn_runs):
    """Two camdyn runs from a point of the long run's section, 1e-9 m/s apart: at 660
    rpm their distance grows exponentially (measured: at about e^0.3 a revolution); at
    358 and 700 rpm it shrinks."""
    section, _ = camdyn_runs[rpm]
    start = section[0]   # the lift is 0 at the section's angle, the end of the base dwell: x = gap
    distance = _separation(rpm, start, 40)
    assert distance[0] == pytest.approx(1e-10)
    growing = (distance > 1e-8) & (distance < 1e-3)
    if rpm == 660:
        assert growing.sum() >= 5
        turns = np.flatnonzero(growing)
        exponent = np.polyfit(turns, np.log(distance[turns]), 1)[0]   # per revolution
        assert exponent > 0.1
        assert distance.max() > 1e4 * distance[0]
    else:
        assert distance[1:].max() < 1e-7
        assert distance[-1] < distance[1]


def _repeats(counts, period):
    """Do the impacts per revolution repeat after ``period`` revolutions?"""
    counts = np.asarray(counts)
    return bool(np.array_equal(counts[period:], counts[:-period]))


def _rotation(ours, theirs):
    """Is ``theirs`` ``ours`` started at another revolution?"""
    return any(np.array_equal(np.roll(ours, k), theirs) for k in range(len(ours)))


@pytest.mark.parametrize("rpm, period", [(358, 3), (660, None), (700, 1)])
def test_the_regimes_over_long_runs_agree(rpm, period, camdyn_runs):
    """Over the 100 revolutions after 200 of transient: camdyn's section repeats exactly
    (to 1e-6 of its size) with period 3 at 358 rpm and 1 at 700 rpm; Siconos's repeats
    within its scatter (NOISE) with the same period at every step, with the same impacts
    per revolution, from where it settles (at 358 rpm and 8192 steps per revolution its
    chaotic transient lasts 221 revolutions, camdyn's about 40). At 660 rpm neither
    repeats within 24 revolutions, at any step."""
    section, impacts = camdyn_runs[rpm]
    ours = lag_deviations(section)
    assert period_of(ours, 1e-6) == period
    for steps in LADDER:
        run = DATA["speeds"][str(rpm)][str(steps)]
        theirs = np.array(run["lag_deviations"])
        assert run["period_revolutions"] == period_of(theirs) == period, f"{steps} steps per revolution"
        if period is None:
            assert theirs.max(axis=1).min() > 2 * NOISE and ours.max(axis=1).min() > 2 * NOISE
            continue
        counts = np.bincount(impacts[:, 0].astype(int), minlength=len(section) - 1)[:len(section) - 1]
        settled = run["impacts_per_revolution"][run["settled_after_revolutions"]:]
        assert _repeats(counts, period) and _repeats(settled, period)
        assert _rotation(counts[:period], settled[:period])


def _orbit_velocities(period, section, impacts, run):
    """Siconos's impacts on its settled periodic orbit matched to camdyn's: each to
    camdyn's impact of the same revolution of the period (aligned on the section) nearest
    in cam angle. Returns, per impact of camdyn's orbit, the velocities [m/s] of the
    Siconos impacts matched to it."""
    settled = run["settled_after_revolutions"]
    theirs = np.array(run["section"])[settled:]
    scale = section.std(axis=0)
    shift = int(np.argmin([np.abs((theirs[0] - section[k]) / scale).max() for k in range(period)]))
    orbit = impacts[impacts[:, 0] < period]
    matched = [[] for _ in orbit]
    found = run["impacts"]
    for turn, angle, velocity in zip(found["revolution"], found["angle_rad"], found["velocity_m_per_s"]):
        if turn >= settled:
            same = np.flatnonzero(orbit[:, 0] == (turn - settled + shift) % period)
            matched[same[_nearest(orbit[same, 1], angle)]].append(velocity)
    return orbit, [np.array(v) for v in matched]


@pytest.mark.parametrize("rpm, period", [(358, 3), (700, 1)])
def test_the_impact_velocities_on_the_periodic_orbits_agree(rpm, period, camdyn_runs):
    """Every impact of camdyn's periodic orbit (8 per 3 revolutions at 358 rpm, 5 to 17
    m/s; 1 per revolution at 700 rpm, 91 m/s) is met once a period by Siconos, whose
    velocity there, averaged over the settled revolutions, lies within the time
    stepping's measured accuracy of camdyn's: the spread of that average over the three
    steps plus its largest excursion from it at the finest step. Its scatter from
    revolution to revolution falls as the step falls."""
    section, impacts = camdyn_runs[rpm]
    results = [_orbit_velocities(period, section, impacts, DATA["speeds"][str(rpm)][str(steps)]) for steps in LADDER]
    orbit = results[0][0]
    for slot in range(len(orbit)):
        velocities = [matched[slot] for _, matched in results]
        for steps, v in zip(LADDER, velocities):
            run = DATA["speeds"][str(rpm)][str(steps)]
            assert v.size >= (run["revolutions"] - run["settled_after_revolutions"]) // period - 1
        means = np.array([v.mean() for v in velocities])
        accuracy = np.ptp(means) + np.abs(velocities[-1] - means[-1]).max()
        assert abs(means[-1] - orbit[slot, 2]) <= accuracy
        assert velocities[-1].std() < velocities[0].std()
