"""Continuation in the narrowest periodic windows of the chapter 3 impact rig (e/rc = 0.2)
against plain runs, the ends of the period-4 branch near 20.4 Hz, and the contact
branch's end at its loss of contact.

Each window's orbit is Newton-solved from the state of a plain run from rest after its
transient (as the brute-force diagram's runs are), at a speed where the diagram shows it:
period 3 at 8.9 Hz, period 8 at 19.3 Hz. Its Poincare points must be those of the same
plain run continued 1500 revolutions, and every bifurcation located on its branch must
lie between two speeds where plain runs started on the orbit settle on different motions
(the 0.1 Hz diagram is too coarse for windows 0.002 to 0.1 Hz wide: the brackets are
bisected here by runs of their own). The expected motions of those runs come from the
runs in the test, not from the continuation."""

import math

import numpy as np
import pytest

# forcing periods of the plain runs that decide a speed's motion: the slowest-decaying
# stable orbit at the bracketing speeds below has |mu| = 0.946 per 8 revolutions
# (19.3007 Hz, measured), 0.946^(1500/8) = 3e-5 of the start's distance (5e-3 rad/s
# there: 1.5e-7), below the comparison's 1e-6 rad; runs that did not settle are reported
# as no period
TRANSIENT = 1500
KEEP = 48


def _problem(speed):
    import camdyn
    from camdyn.continuation import system_problem
    system = camdyn.load_system("sundar2014-impact").with_values(**{"motion.speed": speed})
    return system_problem(system, "motion.speed")


def _settled(problem, start, speed, transient=TRANSIENT):
    """The period (forcing periods; 0 for none up to KEEP / 2) of the motion that a plain
    run from ``start`` [rad, rad/s] at ``speed`` [Hz] settles on, and its Poincare
    points alpha [rad], sorted."""
    from camdyn.continuation.orbits import shoot
    x = shoot(problem, np.asarray(start, float), speed, transient)
    points = [x]
    for _ in range(KEEP):
        points.append(shoot(problem, points[-1], speed, 1))
    alpha = np.array(points)[:, 0]
    for k in range(1, KEEP // 2 + 1):
        if np.max(np.abs(alpha[k:] - alpha[:-k])) < 1e-6:
            return k, np.sort(alpha[-k:])
    return 0, np.sort(alpha[-4:])


def _window(speed, periods, down, up, max_points=40, step=5e-4, max_step=2e-3):
    """The period-``periods`` orbit at ``speed`` [Hz] from a 400-revolution plain run from
    rest, and its branch continued down to ``down`` and up to ``up`` [Hz] (by default in
    steps short enough for a window 0.002 Hz wide: 0.0005 scaled, at most 0.002)."""
    from camdyn.continuation import continue_orbits, find_orbit
    from camdyn.continuation.orbits import transient_state
    problem = _problem(speed)
    start = transient_state(problem, 400)
    orbit = find_orbit(problem, start=start, periods=periods)
    branches = [continue_orbits(problem, orbit, stop, step=step, max_step=max_step, max_points=max_points)
                for stop in (down, up)]
    return problem, start, orbit, branches


def _located(branch, kind):
    return [b.parameter for b in branch.bifurcations if b.kind == kind]


def test_period_three_window_near_9_hz_from_its_grazing_to_its_doubling():
    """Period 3 (5 impacts per 3 revolutions) at 8.9 Hz: stable down to a grazing at
    8.81499 Hz (plain runs from its orbit: period 3 at 8.8155 Hz, irregular at 8.8145) and
    up to a period doubling at 8.91397 Hz (period 3 at 8.912 Hz, period 6 at 8.9145 Hz).
    The branch reaches the grazing and does not cross it: its corrector lands back on the
    5-impact side, and the points step to and fro within 1.4e-5 Hz of it (measured: no
    grazing reported in 100 points; within 300, at 8.814993 Hz)."""
    from camdyn.continuation.results import _sections
    problem, start, orbit, (down, up) = _window(8.9, 3, 8.7, 8.92, max_points=15, step=0.02, max_step=0.1)
    assert orbit.periods == 3 and orbit.impacts_per_period == 5 and orbit.stable
    period, seen = _settled(problem, start, 8.9)
    assert period == 3
    assert np.max(np.abs(np.sort(_sections(problem, orbit)) - seen)) < 1e-8   # measured 2.9e-11 rad
    lowest = min(o.parameter for o in down.orbits)
    assert 8.8145 < lowest < 8.8155 and all(o.stable and o.impacts_per_period == 5 for o in down.orbits)
    doublings = _located(up, "period-doubling")
    assert len(doublings) == 1 and 8.912 < doublings[0] < 8.9145, up.bifurcations
    assert _settled(problem, orbit.state, 8.8155)[0] == 3
    assert _settled(problem, orbit.state, 8.8145)[0] != 3
    assert _settled(problem, orbit.state, 8.912)[0] == 3
    assert _settled(problem, orbit.state, 8.9145)[0] == 6


def test_period_eight_window_at_19_3_hz_from_its_fold_to_its_doubling():
    """Period 8 (13 impacts per 8 revolutions) at 19.3 Hz, a window 0.0023 Hz wide: stable
    from a fold at 19.29845 Hz (plain runs from its orbit: irregular at 19.298 Hz, period 8
    at 19.2989) to a period doubling at 19.30079 Hz (period 8 at 19.3007, 16 at 19.3009)."""
    from camdyn.continuation.results import _sections
    problem, start, orbit, (down, up) = _window(19.3, 8, 19.2, 19.302)
    assert orbit.periods == 8 and orbit.impacts_per_period == 13 and orbit.stable
    period, seen = _settled(problem, start, 19.3)
    assert period == 8
    assert np.max(np.abs(np.sort(_sections(problem, orbit)) - seen)) < 1e-8   # measured 7.9e-12 rad
    folds, doublings = _located(down, "fold"), _located(up, "period-doubling")
    assert len(folds) == 1 and 19.298 < folds[0] < 19.2989, down.bifurcations
    assert len(doublings) == 1 and 19.3007 < doublings[0] < 19.3009, up.bifurcations
    # past the fold the branch comes back unstable (a multiplier above +1)
    assert any(not o.stable and np.max(o.multipliers.real) > 1.0 for o in down.orbits)
    assert _settled(problem, orbit.state, 19.298)[0] != 8
    assert _settled(problem, orbit.state, 19.2989)[0] == 8
    assert _settled(problem, orbit.state, 19.3007)[0] == 8
    assert _settled(problem, orbit.state, 19.3009)[0] == 16


def test_contact_branch_from_5_hz_reports_its_loss_of_contact():
    """The branch from 5 Hz (step 0.02) loses its contact (the smallest unclipped normal
    force reaches zero), then grazes (its first impact appears), where plain runs of 300
    revolutions started on its last orbit in contact first impact: they keep contact at
    6.907105 Hz and impact at 6.907125 Hz (measured here). A step that carried the orbit
    from contact straight onto an impacting orbit is refused (shorter steps pass the two
    one at a time): before, the loss was bisected across such a jump, at 6.907016 Hz from
    5 Hz and at 6.902899 Hz from 6.85 Hz with step 0.01, where plain runs keep contact."""
    import camdyn
    from camdyn.continuation.orbits import flow, shoot
    from camdyn.continuation.results import trace_branch
    problem, branch = trace_branch(camdyn.load_system("sundar2014-impact"), "motion.speed", 5.0, 30.0,
                                   transient=100, step=0.02, max_points=60)
    losses, grazings = _located(branch, "contact-loss"), _located(branch, "grazing")
    assert len(losses) == 1, branch.bifurcations
    first = min((g for g in grazings if g > losses[0]), default=math.nan)
    last = [o for o in branch.orbits if o.impacts_per_period == 0 and o.parameter < losses[0]][-1]

    def events(speed):                   # events of the 301st revolution from the last orbit in contact
        x = shoot(problem, last.state, speed, 300)
        return flow(problem, x, speed, 1).events

    assert events(losses[0]) == 0 and events(6.907105) == 0 and events(6.907125) > 0
    assert 6.907105 - 3e-5 < losses[0] < 6.907105 and 6.907105 - 1e-6 < first < 6.907125, (losses, first)


def test_period_four_branch_from_20_7_hz_ends_near_the_period_two_doubling():
    """The period-4 branch from 20.7 Hz (3 impacts per 4 revolutions) grazes at 20.57672 Hz
    (plain runs from its orbit at 20.5773 Hz: period 4 at 20.5768 Hz, period 16 at 20.5766),
    then, unstable with 4 impacts, doubles at 20.43622 Hz and comes near the period-2
    orbit's doubling at 20.41352 Hz, where it stepped to and fro between 20.41412 and
    20.41513 Hz for 200 points before the continuation ended such branches (measured); the
    period-8 branch switched at 20.43622 Hz fell back onto the period-4 orbit and crept
    along it. Both end now, with the same bifurcations located, within a few hundred
    points."""
    import camdyn
    from camdyn.continuation.orbits import shoot
    from camdyn.continuation.results import switch_doublings, trace_branch
    problem, branch = trace_branch(camdyn.load_system("sundar2014-impact"), "motion.speed", 20.7, 20.4, periods=4,
                                   transient=100, step=0.02, max_points=500)
    doubled = switch_doublings(problem, branch, 20.4, levels=1, max_points=500)
    assert "to and fro" in branch.stopped and len(branch.orbits) < 200, (branch.stopped, len(branch.orbits))
    assert 20.4135 < min(o.parameter for o in branch.orbits) < 20.4152
    grazings, doublings = _located(branch, "grazing"), _located(branch, "period-doubling")
    assert len(grazings) == 1 and 20.5766 < grazings[0] < 20.5768, branch.bifurcations
    assert len(doublings) == 1 and 20.4135 < doublings[0] < grazings[0], branch.bifurcations
    near = min(branch.orbits, key=lambda o: abs(o.parameter - 20.5773))
    assert near.stable and near.impacts_per_period == 3
    assert _settled(problem, near.state, 20.5768)[0] == 4
    assert _settled(problem, near.state, 20.5766)[0] == 16
    # the switched branch's last orbit repeats after 4 revolutions: it is the period-4 orbit
    assert len(doubled) == 1 and len(doubled[0].orbits) < 20, [len(b.orbits) for b in doubled]
    last = doubled[0].orbits[-1]
    assert last.periods == 8 and np.max(np.abs(shoot(problem, last.state, last.parameter, 4) - last.state)) < 1e-6


def test_period_five_branch_from_9_hz_ends_at_the_grazing_of_a_closest_approach():
    """The period-5 branch from 9.0 Hz (8 impacts per 5 revolutions) ends at 9.00712 Hz
    with its step below the minimum: between two of its contacts the follower comes back
    towards the cam without touching it, and that gap closes (6e-6 m at 9.0071 Hz), so
    that past it a ninth contact appears and no corrected orbit exists. The end is
    reported as a grazing at the secant zero of the gap. Plain runs of 200 revolutions
    from the last orbit bracket it: 8 impacts in every 5 revolutions at 9.0071215 Hz,
    a ninth in some at 9.0071225 Hz (measured here). The gap the orbit reports is the one
    a plain run sampled at 400 kHz from the orbit shows."""
    import camdyn
    from camdyn.continuation import continue_orbits, find_orbit
    from camdyn.continuation.orbits import transient_state
    problem = _problem(9.0)
    orbit = find_orbit(problem, start=transient_state(problem, 400), periods=5)
    assert orbit.periods == 5 and orbit.impacts_per_period == 8 and orbit.stable
    branch = continue_orbits(problem, orbit, 9.01, step=5e-4, max_step=2e-3, max_points=40)
    grazings = _located(branch, "grazing")
    assert "step fell below" in branch.stopped and len(grazings) == 1, (branch.stopped, branch.bifurcations)
    last = branch.orbits[-1]

    def impacts(speed, start, revolutions=200):     # impacts in each 5 revolutions of a plain run
        system = camdyn.load_system("sundar2014-impact").with_values(**{"motion.speed": speed})
        t = camdyn.simulate(system, revolutions=revolutions, initial_state=start, rtol=1e-11, atol=1e-14,
                            sample_rate=2000)["impact_time"].values * speed
        return np.bincount((t // 5).astype(int), minlength=revolutions // 5)[:revolutions // 5]

    assert np.all(impacts(9.0071215, last.state) == 8)
    assert np.any(impacts(9.0071225, last.state) == 9)
    assert 9.0071215 < grazings[0] < 9.0071225, grazings
    near = find_orbit(problem, start=last.state, value=9.0071, periods=5)
    system = camdyn.load_system("sundar2014-impact").with_values(**{"motion.speed": 9.0071})
    run = camdyn.simulate(system, revolutions=5, initial_state=near.state, rtol=1e-11, atol=1e-14,
                          sample_rate=400e3)
    delta, touching = run["penetration"].values, run["in_contact"].values > 0
    peaks = (delta[1:-1] > delta[:-2]) & (delta[1:-1] >= delta[2:]) & ~touching[1:-1] & (delta[1:-1] < 0)
    assert abs(near.flight_margin - (-np.max(delta[1:-1][peaks]))) < 1e-10   # 6.2536e-6 m, off by 2.6e-11


def test_period_three_branch_doubles_again_at_8_943_hz_and_grazes_at_8_9474_hz():
    """Past its doubling at 8.91397 Hz the period-3 branch from 8.9 Hz turns stable again at
    a second doubling, 8.94329 Hz, and ends at 8.947395 Hz, where the gap of a closest
    approach in flight closes (reported as a grazing). Plain runs from its stable orbit at
    8.945 Hz: at 8.9432 Hz the alternation of its Poincare points (period 6) stays at
    3.55e-4 rad from 1500 to 4500 revolutions; at 8.9434 Hz it decays (6.8e-6 to 7e-9 rad:
    period 3, whose multiplier is near -1 there, so that 1500 revolutions alone look like
    period 6). The orbit found at 8.947395 Hz keeps 5 impacts in every 3 revolutions of a
    201-revolution plain run, with a gap of 1.3e-8 m; none is found at 8.947396 Hz."""
    import camdyn
    from camdyn.continuation import continue_orbits, find_orbit
    from camdyn.continuation.orbits import shoot, transient_state
    from camdyn.errors import SimulationError
    problem = _problem(8.9)
    orbit = find_orbit(problem, start=transient_state(problem, 400), periods=3)
    branch = continue_orbits(problem, orbit, 8.96, step=5e-4, max_step=2e-3, max_points=80)
    doublings, grazings = _located(branch, "period-doubling"), _located(branch, "grazing")
    assert len(doublings) == 2 and 8.9432 < doublings[1] < 8.9434, branch.bifurcations
    assert len(grazings) == 1 and 8.947395 < grazings[0] < 8.947396, branch.bifurcations
    stable = min(branch.orbits, key=lambda o: abs(o.parameter - 8.945))
    assert stable.stable and stable.impacts_per_period == 5

    def alternation(speed, revolutions):          # |alpha(n + 3) - alpha(n)| after the revolutions [rad]
        x = shoot(problem, stable.state, speed, revolutions)
        return abs(shoot(problem, x, speed, 3)[0] - x[0])

    assert alternation(8.9432, 1500) > 1e-4 and alternation(8.9432, 4500) > 1e-4
    assert alternation(8.9434, 1500) > 1e-6 > 1e-7 > alternation(8.9434, 4500)
    last = find_orbit(problem, start=branch.orbits[-1].state, value=8.947395, periods=3)
    assert 0 < last.flight_margin < 2e-8
    system = camdyn.load_system("sundar2014-impact").with_values(**{"motion.speed": 8.947395})
    t = camdyn.simulate(system, revolutions=201, initial_state=last.state, rtol=1e-11, atol=1e-14,
                        sample_rate=2000)["impact_time"].values * 8.947395
    assert np.all(np.bincount((t // 3).astype(int), minlength=67)[:67] == 5)
    with pytest.raises(SimulationError):
        find_orbit(problem, start=last.state, value=8.947396, periods=3)
