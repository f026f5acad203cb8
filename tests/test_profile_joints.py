"""Events at the joints of a cam profile (guard 2 of the translating follower): no step
straddles a joint, where the lift's second derivative jumps, and a follower in rigid
sustained contact separates exactly at a joint beyond which the cam would pull.

Expected values come from outside the model: the one-revolution map restarted at cam
angle 0 each revolution (the bifurcation diagram's runs, checked against continuous runs
in tests/test_poincare.py), the rig's joint angle and contact force written again here
from its arcs (tests/test_translating_follower.py), and a SciPy solution of a compliant
follower on a simple harmonic cam written here segment by segment between the joints.
"""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from test_translating_follower import PHASE, _reference_state, reference
from test_translating_follower import contact_force as rig_force

from camdyn.analysis.poincare import poincare_section
from camdyn.integrator import driver
from camdyn.model import translating_follower as model
from camdyn.model.profiles import eccentric_circle, rise_return_profile, tabulated_profile
from camdyn.simulation.translating import TranslatingFollower, alzate_rig, simulate_translating
from camdyn.systems import registry as systems

pytestmark = pytest.mark.filterwarnings("ignore::camdyn.simulation.limits.LargeResultWarning")
#: the rig's joint of flank and nose [rad]: the flank arc ends where the nose arc begins,
#: pi/2 (base dwell) + BETA2 (the flank's span) of tests/test_translating_follower.py
FLANK_END = math.pi / 2 + 1.050328174371336
REVOLUTIONS = 20


def omega(rpm):
    """Cam speed [rad/s] of ``rpm`` [rev/min]."""
    return rpm * 2.0 * math.pi / 60.0


@pytest.fixture(scope="module")
def rig():
    return alzate_rig()


@pytest.mark.parametrize("rpm", [130.0, 160.0, 190.0])
def test_a_continuous_rigid_run_completes_and_follows_the_restarted_map(rig, rpm):
    """Speeds at which one continuous run used to stop (the follower separating at the
    joint of flank and nose, then grazing until the step collapsed): 20 revolutions
    complete, and the state at cam angle 0 of each revolution is the one-revolution
    map's, restarted at cam angle 0 each revolution at the same tolerance. At these
    speeds (complete chattering) every revolution ends in a capture, which wipes out
    the runs' differences; where the follower is not captured every revolution the two
    drift apart as the motion stretches them (below)."""
    w = omega(rpm)
    period = 2.0 * math.pi / w
    ds = simulate_translating(rig, w / (2 * math.pi), REVOLUTIONS * period, sample_rate=16 / period)
    assert ds.attrs["status"] == "completed"
    section = poincare_section(rig, [rpm / 60], transient=0, revolutions=REVOLUTIONS)   # [Hz]
    assert np.all(section.rtol.values == 1e-10)   # no revolution needed a fallback tolerance
    kinds = ds.event_kind.values
    assert np.count_nonzero(kinds == "separation") >= REVOLUTIONS and np.count_nonzero(kinds == "impact") >= 100
    np.testing.assert_allclose(section.x.values[0], ds.x.values[16::16], rtol=0, atol=1e-10)
    np.testing.assert_allclose(section.x_dot.values[0], ds.x_dot.values[16::16], rtol=0, atol=1e-10 * w)


@pytest.mark.parametrize("rpm", [210.0, 250.0])
def test_a_continuous_rigid_run_completes_where_captures_are_rare(rig, rpm):
    """Incomplete chattering (captures every few revolutions): 20 revolutions complete
    at rtol 1e-10, and the state at cam angle 0 agrees with the restarted map's to
    1e-5 m (the differences of the step sequences, stretched by the motion: measured
    2e-7 m at 210 rpm)."""
    w = omega(rpm)
    period = 2.0 * math.pi / w
    ds = simulate_translating(rig, w / (2 * math.pi), REVOLUTIONS * period, sample_rate=16 / period)
    assert ds.attrs["status"] == "completed"
    section = poincare_section(rig, [rpm / 60], transient=0, revolutions=REVOLUTIONS)   # [Hz]
    np.testing.assert_allclose(section.x.values[0], ds.x.values[16::16], rtol=0, atol=1e-5)


def test_the_follower_separates_exactly_at_the_joint(rig):
    """At 130 rpm the contact force jumps below zero where the flank meets the nose: the
    rig's force written from its arcs is positive just before the joint and negative just
    after it, and the follower's first separation of each revolution lies on the joint
    to 1e-12 rad (its second, in the nose arc, is where the force falls to zero)."""
    w = omega(130.0)
    assert np.abs(rig.profile.joints - FLANK_END).min() < 1e-12   # the preset's cam angle is the rig's
    joint_time = (FLANK_END - PHASE) / w   # the rig's force is written at the phase PHASE
    assert rig_force(joint_time - 1e-9, w) > 0.0 > rig_force(joint_time + 1e-9, w)
    period = 2.0 * math.pi / w
    ds = simulate_translating(rig, w / (2 * math.pi), 10 * period, sample_rate=8 / period)
    angles = (w * ds.event_time.values[ds.event_kind.values == "separation"]) % (2.0 * math.pi)
    at_joint = angles[np.abs(angles - FLANK_END) < 1e-3]
    assert at_joint.size == 10
    np.testing.assert_allclose(at_joint, FLANK_END, rtol=0, atol=1e-12)
    later = angles[np.abs(angles - FLANK_END) >= 1e-3]   # the force (from the arcs) vanishes there
    assert np.abs([rig_force((a - PHASE) / w, w) for a in later]).max() < 1e-6 * rig_force(0.0, w)


# --- a compliant follower held on a simple harmonic cam: the SciPy solution by segments

LIFT, SPANS = 0.01, (2.0 * math.pi / 3.0, math.pi / 3.0, 2.0 * math.pi / 3.0, math.pi / 3.0)
MASS, SPRING, PRELOAD, CONTACT = 0.5, 300.0, 20.0, 1e5
SPEED = 40.0    # [rad/s]


def harmonic_lift(theta):
    """Lift [m] and its rate in the cam angle [m/rad] of the simple harmonic rise (span
    beta, lift L: ``s = L/2 (1 - cos(pi u / beta))``, Norton 2009), dwell, return, dwell."""
    a = theta % (2.0 * math.pi)
    rise, top, fall, _ = SPANS
    if a < rise:
        return 0.5 * LIFT * (1.0 - math.cos(math.pi * a / rise)), 0.5 * LIFT * math.pi / rise * math.sin(
            math.pi * a / rise)
    if a < rise + top:
        return LIFT, 0.0
    if a < rise + top + fall:
        u = a - rise - top
        return 0.5 * LIFT * (1.0 + math.cos(math.pi * u / fall)), -0.5 * LIFT * math.pi / fall * math.sin(
            math.pi * u / fall)
    return 0.0, 0.0


def scipy_solution(damping, times):
    """The compliant follower ``m x'' = -F0 - k x + kc (s - x) + cc (s_dot - x')`` by
    solve_ivp, restarted at every joint of the cam."""
    def field(t, y):
        s, s1 = harmonic_lift(SPEED * t)
        return [y[1], (-PRELOAD - SPRING * y[0] + CONTACT * (s - y[0]) + damping * (SPEED * s1 - y[1])) / MASS]
    joints = np.cumsum((0.0,) + SPANS) / SPEED
    joints[-1] = max(joints[-1], times[-1])
    y = np.array([-PRELOAD / CONTACT, 0.0])   # pressed into the base circle
    out = np.full((times.size, 2), np.nan)
    for start, end in zip(joints[:-1], joints[1:]):
        inside = (times >= start) & (times <= end)
        sol = solve_ivp(field, (start, end), y, method="DOP853", rtol=1e-13, atol=1e-16, dense_output=True)
        out[inside] = sol.sol(times[inside]).T
        y = sol.y[:, -1]
    return out


def harmonic_follower():
    """The compliant follower on the simple harmonic cam, and its dashpot [N s/m]."""
    profile = rise_return_profile([("harmonic", SPANS[0], LIFT), ("dwell", SPANS[1], 0.0),
                                   ("harmonic", SPANS[2], -LIFT), ("dwell", SPANS[3], 0.0)], 0.05)
    damping = model.penalty_damping(0.3, CONTACT, MASS)
    return TranslatingFollower(profile, MASS, SPRING, PRELOAD, contact="compliant", contact_stiffness=CONTACT,
                               contact_damping=damping), damping


def test_sustained_contact_converges_with_the_tolerance_across_joints():
    """One revolution in contact (the penalty never lets go: its force stays above 10 N):
    the error against the segment-by-segment SciPy solution falls at every rung of rtol
    from 1e-6 to 1e-11 (measured 7.1e-11 m down to 8.4e-15 m), and a run at rtol 1e-12
    completes within 1e-13 m of it."""
    follower, damping = harmonic_follower()
    period = 2.0 * math.pi / SPEED
    times = np.linspace(0.0, period, 257)
    expected = scipy_solution(damping, times)
    errors = []
    for rtol in (1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12):
        ds = simulate_translating(follower, SPEED / (2 * math.pi), period, sample_rate=256 / period,
                                  initial_state=(-PRELOAD / CONTACT, 0.0), rtol=rtol, atol=rtol * 1e-3)
        assert ds.attrs["status"] == "completed" and ds.event_kind.size == 0
        errors.append(np.abs(ds.x.values - expected[:, 0]).max())
    assert all(later < earlier for earlier, later in zip(errors[:-2], errors[1:-1])), errors
    assert errors[-1] < 1e-13, errors   # measured 2.2e-15 m at rtol 1e-12


def test_rigid_sustained_contact_at_rtol_1e_13_completes_and_matches_the_reference():
    """The rig at 130 rpm, whose sustained contact crosses the arcs' joints, at rtol
    1e-13 (where the step used to shrink below the resolution of time there): it
    completes, with the events of the independent event-driven SciPy solution of
    tests/test_translating_follower.py, within 1e-8 s, and its position within 1e-7 m."""
    w = omega(130.0)
    ds = simulate_translating(alzate_rig(), w / (2 * math.pi), 0.35, sample_rate=2000, phase=PHASE, rtol=1e-13,
                              atol=1e-15)
    assert ds.attrs["status"] == "completed"
    events, pieces = reference(w, 0.35)
    events = [(t, k) for t, k in events if k != "graze"]
    real = ds.event_kind.values != "graze"
    assert list(ds.event_kind.values[real]) == [k for _, k in events]
    assert [k for _, k in events].count("capture") >= 2
    np.testing.assert_allclose(ds.event_time.values[real], [t for t, _ in events], rtol=0, atol=1e-8)
    expected = np.array([_reference_state(pieces, t, w) for t in ds.time.values])
    np.testing.assert_allclose(ds.x.values, expected[:, 0], rtol=0, atol=1e-7)


@pytest.mark.parametrize("profile", [eccentric_circle(0.04, 0.01),
                                     tabulated_profile(0.01 * (1.0 - np.cos(np.linspace(0, 2 * math.pi, 64,
                                                                                        endpoint=False))), 0.05)],
                         ids=["one arc", "spline"])
def test_profiles_without_joints_have_no_joint_guard(profile):
    """A one-segment profile and a spline: the joint guard is never active, so they log
    no joint event and the runs are those of the model without it."""
    follower = TranslatingFollower(profile, 0.5, 300.0, 5.0, restitution=0.5)
    p = follower.pack(60.0)
    assert not model.has_joints(p)
    mode = np.zeros(model.MODE_SIZE)
    model.initial_mode(0.0, np.zeros(2), p, mode)
    assert systems.expected_sign(systems.TRANSLATING_FOLLOWER, model.JOINT, mode, p) == 0.0
    t_out = np.linspace(0.0, 1.0, 11)
    _, _, events, counters = driver.integrate(systems.TRANSLATING_FOLLOWER, p, np.zeros(2), 0.0, 1.0, t_out, 1e-10,
                                              1e-12, 0.01, driver.METHOD_AUTO, 100_000, 1000, True, math.inf)
    assert counters[driver.COUNT_STATUS] == driver.STATUS_OK and events.shape[0] > 0
    assert not np.any(events[:, driver.EVENT_GUARD] == model.JOINT)
