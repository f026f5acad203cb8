"""Coverage of a whole range: restarts past where a branch ends, the period a restart reads
from its simulation, the gaps reported.

- The rigid-impact oscillator (closed forms in tests/test_continuation_switching.py):
  the period a restart reads is that of the closed-form orbit that is stable there, and
  the orbit it starts from is that orbit; a coverage whose first branch stops short is
  carried over the closed form's period doubling, which it locates, without a gap.
- The chapter 3 rig over 5-30 Hz in one command (``camdyn continue``): the branch from
  5 Hz ends in the chattering orbits near 6.9 Hz; the command reports the loss of
  contact there, the period doubling at 16.0161 Hz (where the brute-force diagram of
  tests/test_continuation_brute_force.py splits), and one gap, inside which a plain
  simulation settles on no period of up to 8 revolutions.
"""

import json
import math

import numpy as np
import pytest
from test_continuation_switching import _period_two, _rigid, _states_at_zero

from camdyn.continuation import continue_orbits, find_orbit
from camdyn.continuation.branches import Branch
from camdyn.continuation.coverage import MAX_PERIOD, cover_range, response_period
from camdyn.errors import ParameterError

#: The rigid-impact oscillator's period doubling, from its closed form [rad/s].
DOUBLING = 2.65888454668


def test_a_restart_reads_the_period_of_the_closed_form_orbit_stable_there():
    problem = _rigid(2.5)
    period, _ = response_period(problem, 2.5)
    assert period == 1                                  # below the doubling: period 1 is stable
    period, state = response_period(problem, 2.69)
    assert period == 2                                  # past it: the two-impact period-2 orbit
    orbit = find_orbit(problem, start=state, value=2.69, periods=2)
    solution = _period_two(2.68, [1.0, -0.2, 1.2 + 2 * math.pi / 2.68, -0.45])   # as the switching test
    solution = _period_two(2.69, solution)
    error = min(np.max(np.abs(orbit.state - s)) for s in _states_at_zero(2.69, solution))
    assert error < 1e-7 and orbit.stable, error


def test_a_branch_that_stops_short_is_carried_over_the_doubling_without_a_gap():
    problem = _rigid(2.3)
    short = continue_orbits(problem, find_orbit(problem), 2.45, step=0.02)   # ends at 2.45, not 2.75
    assert short.orbits[-1].parameter == pytest.approx(2.45)
    cover = cover_range(problem, short, 2.3, 2.75, step=0.02)
    assert cover.gaps == [] and "end of its range" in cover.stopped
    values = [o.parameter for b in cover.branches for o in b.orbits]
    assert min(values) == pytest.approx(2.3) and max(values) == pytest.approx(2.75)
    doublings = [d.parameter for b in cover.branches for d in b.bifurcations if d.kind == "period-doubling"]
    assert len(doublings) == 1 and abs(doublings[0] - DOUBLING) < 1e-8, doublings


def test_a_branch_that_used_its_budget_ends_the_coverage_with_a_gap_that_says_so():
    problem = _rigid(2.3)
    short = continue_orbits(problem, find_orbit(problem), 2.75, step=0.02, max_points=3)
    cover = cover_range(problem, short, 2.3, 2.75, max_points=3)
    assert len(cover.branches) == 1 and len(cover.gaps) == 1
    gap = cover.gaps[0]
    assert gap.start == pytest.approx(short.orbits[-1].parameter) and gap.stop == 2.75
    assert "budget of 3 points" in gap.reason


@pytest.mark.slow
def test_a_branch_winding_in_the_chattering_orbits_stalls_past_the_loss_of_contact():
    """The chapter 3 rig's branch from 6.5 Hz loses contact at 6.90709 Hz (the value
    tests/test_continuation_brute_force.py checks against the brute-force diagram), then
    winds within hundredths of a Hz: with the stall test it ends there, the loss of
    contact located; without it, it goes on winding."""
    import camdyn
    from camdyn.continuation.results import trace_branch

    rig = camdyn.load_system("sundar2014-impact")
    _, stalled = trace_branch(rig, "motion.speed", 6.5, 9.0, transient=30, stall=15)
    assert "stalled" in stalled.stopped and "Hz" in stalled.stopped
    losses = [b.parameter for b in stalled.bifurcations if b.kind == "contact-loss"]
    assert len(losses) == 1 and abs(losses[0] - 6.90709) < 1e-4
    recent = [o.parameter for o in stalled.orbits[-15:]]
    assert max(recent) - min(recent) < 2e-3 * 2.5
    _, plain = trace_branch(rig, "motion.speed", 6.5, 9.0, transient=30, max_points=len(stalled.orbits) + 10)
    assert len(plain.orbits) > len(stalled.orbits) and "stalled" not in plain.stopped


@pytest.mark.parametrize("arguments, words", [
    ({"start": 2.3, "stop": 2.3}, "two different"),
    ({"start": 2.3, "stop": math.nan}, "two different"),
    ({"start": 2.3, "stop": 2.75, "jump": -0.1}, "jump"),
    ({"start": 2.3, "stop": 2.75, "max_time": 0.0}, "max_time"),
])
def test_bad_settings_are_refused_before_any_work(arguments, words):
    problem = _rigid(2.3)
    with pytest.raises(ParameterError, match=words):
        cover_range(problem, Branch([]), **arguments)


@pytest.mark.slow
def test_the_chapter_3_rig_is_covered_from_5_to_30_hz_in_one_command(capsys):
    import camdyn
    from camdyn.cli.app import main

    assert main(["continue", "sundar2014-impact", "--set", "cam.runout=3.5 mm", "--parameter", "motion.speed",
                 "--from", "5Hz", "--to", "30Hz", "--json", "--quiet"]) == 0
    doc = json.loads(capsys.readouterr().out)
    summary, gaps = doc["summary"], doc["gaps"]
    covering = doc["branches"][:summary["covering_branch_count"]]
    values = [p["parameter"] for branch in covering for p in branch]
    assert min(values) == pytest.approx(5.0) and max(values) == pytest.approx(30.0)
    kinds = {(b["kind"], round(b["parameter"], 1)) for b in doc["bifurcations"]}
    assert ("contact-loss", 6.9) in kinds
    doubling = [b["parameter"] for b in doc["bifurcations"] if b["kind"] == "period-doubling"
                and 15.0 < b["parameter"] < 17.0]
    assert len(doubling) == 1 and abs(doubling[0] - 16.0161) < 1e-3, doubling
    # every part of the range is on a covering branch or in a gap
    assert summary["gap_count"] == len(gaps) >= 1
    for gap in gaps:
        assert gap["start"] < gap["stop"] and gap["reason"]
        inside = [v for v in values if gap["start"] + 1e-6 < v < gap["stop"] - 1e-6]
        assert not inside, (gap, inside)
    # inside the first gap a plain simulation settles on no period of up to 8 revolutions
    gap = gaps[0]
    assert 6.85 < gap["start"] < 7.0 and "stalled" in gap["reason"]
    rig = camdyn.load_system("sundar2014-impact", {"cam.runout": "3.5 mm"})
    middle = 0.5 * (gap["start"] + gap["stop"])
    revolutions = 300
    ds = camdyn.simulate(rig, speed=middle, revolutions=revolutions, sample_rate=8 * middle, variables=["alpha"])
    alpha = ds["alpha"].values[::8][-2 * MAX_PERIOD:]                       # once per revolution
    spread = np.ptp(alpha)
    assert all(np.max(np.abs(alpha[k:k + MAX_PERIOD] - alpha[:MAX_PERIOD])) > 1e-5 * spread
               for k in range(1, MAX_PERIOD + 1)), middle


@pytest.mark.parametrize("limit", ["0s", "-3min", "abc", "5 kg"])
def test_a_bad_time_limit_is_refused_in_one_line(limit, capsys):
    from camdyn.cli.app import main

    assert main(["continue", "sundar2014-friction", "--from", "11Hz", "--to", "12Hz", "--max-time", limit]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error:") and "--max-time" in err[0], err


@pytest.mark.parametrize("source", ["rocking-roller", "rocking-friction"])
def test_the_rocking_arm_on_a_profile_is_refused_with_the_reason(source, capsys):
    from camdyn.cli.app import main

    assert main(["continue", source, "--from", "10Hz", "--to", "10.1Hz"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no periodic problem" in err[0] and "camdyn simulate" in err[0], err
