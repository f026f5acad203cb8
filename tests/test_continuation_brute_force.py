"""Continuation against the brute-force bifurcation diagram of the chapter 3 impact rig
(e/rc = 0.2) from 14.1 to 16.9 Hz: a sweep (the `camdyn bifurcation` machinery, its
stroboscopic Poincare points once per cam revolution after a transient) computed here,
and the branches found by continuation with a switch at the period doubling.

Where the diagram is periodic, the stable orbit found by continuation at that speed has
the diagram's Poincare points; the period doubling lies between the diagram's last
period-1 speed and its first period-2 speed; the unstable period-1 orbit past the
doubling is one the brute force does not see."""

import numpy as np
import pytest

SPEEDS = np.round(np.arange(14.1, 17.0, 0.4), 10)     # Hz; none within 0.08 Hz of the doubling


@pytest.fixture(scope="module")
def diagram_and_branches(tmp_path_factory):
    import camdyn
    from camdyn.continuation.results import switch_doublings, trace_branch
    from camdyn.sweeps import run_sweep, spec_from_dict
    # tolerances of the shooting runs, so that the Poincare points carry no integration error
    # above 1e-8 rad; 100 revolutions of transient: the slowest-decaying stable orbit here has
    # |mu| = 0.83 (15.7 Hz), 0.83^100 = 1e-8
    table = {"system": {"source": "sundar2014-impact", "set": {}},
             "vary": [{"key": "motion.speed", "values": [float(v) for v in SPEEDS]}],
             "run": {"revolutions": 150, "discard": 100, "rtol": 1e-10, "atol": 1e-12},
             "metrics": {"names": ["poincare", "regime"]},
             "output": {"path": str(tmp_path_factory.mktemp("sweep") / "diagram.nc")}}
    diagram = run_sweep(spec_from_dict(table, name="diagram"), workers=0, progress=False).load()
    system = camdyn.load_system("sundar2014-impact")
    problem, branch = trace_branch(system, "motion.speed", 14.1, 16.9, transient=100, step=0.02, max_points=200)
    doubled = switch_doublings(problem, branch, 16.9, levels=1)
    return diagram, problem, branch, doubled


def _orbit_at(problem, branch, speed):
    """The branch's orbit at ``speed`` [Hz], by Newton's method from its nearest point."""
    from camdyn.continuation import find_orbit
    nearest = min(branch.orbits, key=lambda o: abs(o.parameter - speed))
    return find_orbit(problem, start=nearest.state, value=speed, periods=nearest.periods)


def _section(problem, orbit):
    """alpha [rad] at each cam revolution of ``orbit``, sorted."""
    from camdyn.continuation.orbits import shoot
    x, points = orbit.state, [orbit.state[0]]
    for _ in range(orbit.periods - 1):
        x = shoot(problem, x, orbit.parameter, 1)
        points.append(x[0])
    return np.sort(points)


def test_stable_branches_have_the_diagrams_poincare_points(diagram_and_branches):
    diagram, problem, branch, doubled = diagram_and_branches
    assert len(doubled) == 1 and doubled[0].orbits[0].periods == 2
    worst, compared = 0.0, 0
    for i, speed in enumerate(SPEEDS):
        period = int(diagram["period"].values[i])
        assert int(diagram["regime"].values[i]) == 2 and period in (1, 2)   # periodic impacts throughout
        orbit = _orbit_at(problem, branch if period == 1 else doubled[0], speed)
        assert orbit.stable and orbit.periods == period
        seen = np.sort(diagram["poincare_alpha"].values[i, -period:])
        worst = max(worst, float(np.max(np.abs(_section(problem, orbit) - seen))))
        compared += 1
    assert compared == SPEEDS.size and worst < 1e-8, worst       # measured 5.8e-10 rad (target 1e-6)


def test_period_doubling_lies_where_the_diagram_doubles_and_the_unstable_orbit_is_unseen(diagram_and_branches):
    diagram, problem, branch, _ = diagram_and_branches
    doublings = [b.parameter for b in branch.bifurcations if b.kind == "period-doubling"]
    assert len(doublings) == 1, [(b.kind, b.parameter) for b in branch.bifurcations]
    periods = diagram["period"].values
    last_single = SPEEDS[periods == 1].max()
    first_double = SPEEDS[periods == 2].min()
    assert last_single < doublings[0] < first_double, (last_single, doublings[0], first_double)
    # past the doubling the period-1 orbit is unstable, and the diagram's points lie off it
    for i in np.flatnonzero(SPEEDS > doublings[0]):
        orbit = _orbit_at(problem, branch, SPEEDS[i])
        assert not orbit.stable and orbit.periods == 1
        assert np.min(np.abs(diagram["poincare_alpha"].values[i, -2:] - orbit.state[0])) > 1e-3


def test_continue_cli_switches_at_the_doubling(capsys):
    import json

    from camdyn.cli.app import main
    assert main(["continue", "sundar2014-impact", "--from", "15.8Hz", "--to", "16.3Hz", "--transient", "100",
                 "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["summary"]["branch_count"] == 2
    assert [(b["kind"], b["branch"]) for b in doc["bifurcations"]] == [("period-doubling", 0)]
    assert abs(doc["bifurcations"][0]["parameter"] - 16.0161) < 1e-3          # as the brute-force test finds it
    single, double = doc["branches"]
    assert all(p["periods"] == 1 and len(p["poincare"]) == 1 for p in single)
    assert all(p["periods"] == 2 and len(p["poincare"]) == 2 for p in double)
    assert double[-1]["parameter"] == pytest.approx(16.3, abs=1e-9) and double[-1]["stable"]
    # the two Poincare points of the period-2 orbit split apart past the doubling
    assert abs(double[-1]["poincare"][0] - double[-1]["poincare"][1]) > 1e-3


def test_contact_loss_lies_where_the_diagram_starts_to_impact(tmp_path):
    import camdyn
    from camdyn.continuation.results import trace_branch
    from camdyn.sweeps import run_sweep, spec_from_dict
    speeds = [6.8, 6.85, 6.95, 7.0]
    table = {"system": {"source": "sundar2014-impact", "set": {}},
             "vary": [{"key": "motion.speed", "values": speeds}],
             "run": {"revolutions": 60, "discard": 40}, "metrics": {"names": ["regime", "impacts"]},
             "output": {"path": str(tmp_path / "diagram.nc")}}
    diagram = run_sweep(spec_from_dict(table, name="diagram"), workers=0, progress=False).load()
    kept = diagram["regime"].values == 0                          # contact kept, no impacts
    assert kept.tolist() == [True, True, False, False], diagram["regime"].values
    assert np.all(diagram["impacts_per_revolution"].values[~kept] > 1)
    # a short first step: with 0.02 the corrector can jump across the opening contact onto an
    # unstable impacting orbit (docs/continuation.md, limits)
    _, branch = trace_branch(camdyn.load_system("sundar2014-impact"), "motion.speed", 6.8, 7.0, transient=100,
                             step=0.005)
    assert branch.orbits[0].impacts_per_period == 0 and branch.orbits[0].stable
    loss = [b.parameter for b in branch.bifurcations if b.kind == "contact-loss"]
    # the contact branch's smallest force reaches zero (6.9071 Hz) between the diagram's last
    # speed in contact and its first with impacts
    assert len(loss) == 1 and 6.85 < loss[0] < 6.95, (loss, branch.stopped)
