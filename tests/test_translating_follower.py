"""The translating follower (system 4) on the Alzate / di Bernardo rig of the Siconos
cam-follower example: against an event-driven SciPy solution written here (free flight by
solve_ivp, impacts by Newton's law, sustained contact until the contact force vanishes),
the lift-off speed against its closed form, the compliant contact's rigid limit, the
variational system, and refusals."""

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, minimize_scalar

from camdyn.errors import ParameterError
from camdyn.integrator import driver
from camdyn.model import translating_follower as model
from camdyn.simulation.translating import TranslatingFollower, alzate_rig, liftoff_speed, simulate_translating
from camdyn.systems import registry as systems

# the rig as the Siconos example's FollowerPlugin gives it (cam angle folded onto [0, pi])
MASS, STIFFNESS, RESTITUTION, RELAXED = 1.221, 1430.8, 0.8, 0.30
BASE, K1, RHO1, K2, RHO3 = 0.40, 0.45, 0.85, 0.40393320723821, 0.15
TOP = K2 + RHO3
BETA2, BETA3 = 1.050328174371336, 1.22173047639603
PHASE = math.pi / 2


def _ray(phi, d, rho):
    """Distance r from the axis to a circle (centre at distance d on phi = 0, radius rho)
    along the ray at phi, and r', r'' from the implicit derivative of r^2 - 2 d r cos(phi)
    + d^2 = rho^2."""
    b = d * math.cos(phi)
    r = b + math.sqrt(b * b - d * d + rho * rho)
    den = r - b
    r1 = -d * r * math.sin(phi) / den
    r2 = (-2.0 * d * r1 * math.sin(phi) - d * r * math.cos(phi) - r1 * r1) / den
    return r, r1, r2


def rig_lift(theta):
    """The rig's cam: distance h from the axis [m] and its derivatives in the cam angle."""
    beta = theta % (2 * math.pi)
    sign = 1.0
    if beta > math.pi:
        beta, sign = 2 * math.pi - beta, -1.0
    if beta <= math.pi / 2:
        h, h1, h2 = BASE, 0.0, 0.0
    elif beta <= math.pi / 2 + BETA2:
        h, h1, h2 = _ray(beta + math.pi / 2, K1, RHO1)
    elif beta <= math.pi / 2 + BETA3:
        h, h1, h2 = _ray(beta + math.pi / 9 - math.pi, K2, RHO3)
    else:
        h, h1, h2 = TOP, 0.0, 0.0
    return h, sign * h1, h2


def contact_force(t, w):
    """The force the cam needs to hold the follower [N]: m h_ddot + k (h - 0.30)."""
    h, _, h2 = rig_lift(PHASE + w * t)
    return MASS * w * w * h2 + STIFFNESS * (h - RELAXED)


def reference(w, t_end, capture=1e-6):
    """Event-driven solution: (events [(time, kind)], dense pieces [(t0, t1, sol or None)])."""
    def flight(t, y):
        return [y[1], -STIFFNESS * (y[0] + BASE - RELAXED) / MASS]

    def gap(t, y):
        return y[0] + BASE - rig_lift(PHASE + w * t)[0]
    gap.terminal, gap.direction = True, -1
    # solve_ivp sees an event only as a sign change between step ends: a bounce shorter
    # than a step is missed. Its steps are kept below half the shortest flight the last
    # rebound allows, 2 v / a, with a bound a on the relative acceleration of follower and cam.
    angles = np.linspace(0.0, 2 * math.pi, 20001)
    a = STIFFNESS * (TOP - RELAXED) / MASS + w * w * max(abs(rig_lift(b)[2]) for b in angles)
    rebound = math.inf
    t, events, pieces = 0.0, [], []
    h, h1, _ = rig_lift(PHASE)
    y = np.array([h - BASE, w * h1])
    contact = contact_force(0.0, w) > 0
    while t < t_end:
        if contact:   # on the cam until its force changes sign (scanned, then bracketed)
            grid = np.arange(t, t_end, 2e-5)[1:]
            negative = [u for u in grid if contact_force(u, w) < 0.0]
            if not negative:
                pieces.append((t, t_end, None))
                break
            right = negative[0]
            left = max(t, right - 2e-5)
            t_sep = brentq(lambda u: contact_force(u, w), left, right, xtol=1e-15, rtol=1e-15)
            pieces.append((t, t_sep, None))
            t = t_sep
            h, h1, _ = rig_lift(PHASE + w * t)
            y = np.array([h - BASE, w * h1])
            events.append((t, "separation"))
            contact, rebound = False, math.inf
            continue
        step = min(2 * math.pi / w / 64, max(rebound / a, 1e-10))
        sol = solve_ivp(flight, (t, t_end), y, method="DOP853", rtol=1e-12, atol=1e-14, events=gap,
                        dense_output=True, max_step=step)
        pieces.append((t, sol.t[-1], sol.sol))
        t, y = sol.t[-1], sol.y[:, -1].copy()
        if sol.status != 1:
            break
        h, h1, _ = rig_lift(PHASE + w * t)
        approach = y[1] - w * h1
        if -approach > capture:
            y[1] = w * h1 - RESTITUTION * approach
            rebound = -RESTITUTION * approach
            events.append((t, "impact"))
        else:
            y = np.array([h - BASE, w * h1])
            contact = contact_force(t, w) > 0
            events.append((t, "capture" if contact else "graze"))
            rebound = math.inf
    return events, pieces


def _reference_state(pieces, t, w):
    for t0, t1, sol in pieces:
        if t0 <= t <= t1:
            if sol is None:
                h, h1, _ = rig_lift(PHASE + w * t)
                return np.array([h - BASE, w * h1])
            return sol(t)
    return np.full(2, np.nan)


@pytest.mark.parametrize("rpm, duration, least", [(358, 1.0, {"impact": 20}),
                                                   (130, 0.35, {"impact": 100, "capture": 2, "separation": 2})])
def test_the_rig_matches_an_independent_event_driven_solution(rpm, duration, least):
    """At 358 rpm over 1 s: 28 events, 13 of them a chattering sequence that the top dwell's
    end cuts short. The orbit stretches errors by about 1e5 over the second: the compiled
    run at rtol 1e-12 lies 2.2e-7 m from one at rtol 1e-13 near t = 0.9 s (measured), so
    it runs at rtol 1e-13. At 130 rpm the follower leaves the nose, chatters back (about
    60 impacts) and is captured into sustained contact, twice; its sustained contact
    crosses the joints of the arcs, where rtol 1e-13 shrinks the step below the
    resolution of time, so it runs at rtol 1e-12."""
    w = rpm * 2 * math.pi / 60
    rtol = 1e-13 if rpm == 358 else 1e-12
    ds = simulate_translating(alzate_rig(), w / (2 * math.pi), duration, sample_rate=2000, phase=PHASE, rtol=rtol,
                              atol=rtol / 100)
    events, pieces = reference(w, duration)
    events = [(t, k) for t, k in events if k != "graze"]
    kinds = [k for _, k in events]
    # grazes (touches at rounding-level speed just after a separation, which change
    # nothing) are the compiled locator's alone
    real = ds.event_kind.values != "graze"
    assert list(ds.event_kind.values[real]) == kinds
    for kind, count in least.items():   # the run is rich in events, not a trivial one
        assert kinds.count(kind) >= count
    np.testing.assert_allclose(ds.event_time.values[real], [t for t, _ in events], rtol=0, atol=1e-8)
    assert np.abs(ds.event_velocity.values[~real]).max(initial=0.0) < 1e-9
    expected = np.array([_reference_state(pieces, t, w) for t in ds.time.values])
    np.testing.assert_allclose(ds.x.values, expected[:, 0], rtol=0, atol=1e-7)
    np.testing.assert_allclose(ds.x_dot.values, expected[:, 1], rtol=0, atol=1e-7 * w)
    assert ds.in_contact.values.any() == ("capture" in kinds or kinds[0] != "impact")


def _closed_form_liftoff():
    """min over the decelerating arcs of sqrt(k (h - 0.30) / (-m h'')) [rad/s]."""
    def squared(beta):
        h, _, h2 = rig_lift(beta)
        return STIFFNESS * (h - RELAXED) / (-MASS * h2) if h2 < 0 else math.inf
    # h'' < 0 only on the nose arc (the flank arc accelerates the follower: h'' > 0)
    nose = (math.pi / 2 + BETA2, math.pi / 2 + BETA3)
    best = minimize_scalar(squared, bounds=nose, method="bounded", options={"xatol": 1e-12})
    return math.sqrt(min(best.fun, squared(nose[0] + 1e-13))), nose


def test_the_rig_leaves_the_cam_at_its_closed_form_liftoff_speed():
    w_lift, nose = _closed_form_liftoff()
    assert w_lift * 60 / (2 * math.pi) == pytest.approx(115.0, abs=0.5)   # 114.98 rpm
    rig = alzate_rig()
    assert liftoff_speed(rig) == pytest.approx(w_lift, rel=1e-6)
    revolution = 2 * math.pi / w_lift
    below = simulate_translating(rig, (0.995 * w_lift) / (2 * math.pi), 3 * revolution, sample_rate=500 / revolution,
                                 phase=PHASE)
    assert below.event_time.size == 0 and below.in_contact.values.all()
    above = simulate_translating(rig, (1.005 * w_lift) / (2 * math.pi), 1.2 * revolution,
                                 sample_rate=500 / revolution, phase=PHASE)
    assert above.event_kind.values[0] == "separation"
    angle = (PHASE + 1.005 * w_lift * above.event_time.values[0]) % (2 * math.pi)
    # it leaves the cam at the start of the nose arc, where the closed form has its minimum
    assert nose[0] - 1e-9 <= angle <= nose[0] + 0.02


def _compliant_times(stiffness, w, t_end):
    rig = alzate_rig("compliant", stiffness, model.penalty_damping(RESTITUTION, stiffness, MASS))
    ds = simulate_translating(rig, w / (2 * math.pi), t_end, sample_rate=2000, phase=PHASE, rtol=1e-11, atol=1e-13)
    return ds.event_time.values[ds.event_kind.values == "contact onset"]


def test_the_compliant_contact_converges_to_the_rigid_impacts():
    """Kelvin-Voigt contact with the dashpot matched to e = 0.8: the times of the first
    three landings after lift-off approach the rigid solution's as the contact stiffens.
    A contact lasts pi sqrt(m / kc), so the error is expected to fall as kc^(-1/2): by a
    factor 10 over two decades of kc. (The compliant run starts with a contact onset at
    t = 0, the follower resting on the rising cam.)"""
    w, t_end = 358 * 2 * math.pi / 60, 0.2
    rigid = simulate_translating(alzate_rig(), w / (2 * math.pi), t_end, sample_rate=2000, phase=PHASE, rtol=1e-11,
                                 atol=1e-13)
    impacts = rigid.event_time.values[rigid.event_kind.values == "impact"][:3]
    errors = []
    for stiffness in (1e6, 1e7, 1e8):
        onsets = _compliant_times(stiffness, w, t_end)
        assert onsets.size >= impacts.size + 1
        errors.append(np.abs(onsets[1:impacts.size + 1] - impacts).max())
    assert errors[0] > errors[1] > errors[2]
    slopes = np.diff(np.log10(errors))   # per decade of kc
    np.testing.assert_allclose(slopes, -0.5, atol=0.1)


def test_the_variational_system_of_the_compliant_follower_matches_finite_differences():
    w = 358 * 2 * math.pi / 60
    rig = alzate_rig("compliant", 1e6, model.penalty_damping(RESTITUTION, 1e6, MASS))
    p = rig.pack(w, PHASE)
    y0 = np.array([0.02, 0.0])
    t_end, t_out = 0.08, np.array([0.08])

    def run(system, y):
        out, _, events, counters = driver.integrate(system, p, y, 0.0, t_end, t_out, 1e-12, 1e-14, 1e-3,
                                                    driver.METHOD_AUTO, 10 ** 6, 1000, False, math.inf)
        assert counters[driver.COUNT_STATUS] == driver.STATUS_OK
        return out[-1], events
    big = run(systems.VARIATIONAL + systems.TRANSLATING_FOLLOWER, np.r_[y0, 1.0, 0.0, 0.0, 1.0])[0]
    _, events = run(systems.TRANSLATING_FOLLOWER, y0)
    assert events.shape[0] >= 2   # it lands and leaves: the saltation matrix is exercised
    phi = big[2:].reshape(2, 2)
    steps = (1e-5, 1e-4)
    fd = np.column_stack([(run(systems.TRANSLATING_FOLLOWER, y0 + steps[j] * np.eye(2)[j])[0]
                           - run(systems.TRANSLATING_FOLLOWER, y0 - steps[j] * np.eye(2)[j])[0]) / (2 * steps[j])
                          for j in range(2)])
    np.testing.assert_allclose(phi, fd, rtol=1e-4, atol=1e-6)


@pytest.mark.parametrize("change, match", [
    ({"mass": 0.0}, "mass"),
    ({"stiffness": -1.0}, "stiffness"),
    ({"restitution": 1.5}, "restitution"),
    ({"contact": "soft"}, "contact"),
    ({"contact": "compliant"}, "contact_stiffness"),
    ({"damping": math.nan}, "damping"),
])
def test_bad_parameters_are_refused(change, match):
    rig = alzate_rig()
    values = {name: getattr(rig, name) for name in ("profile", "mass", "stiffness", "preload", "damping", "contact",
                                                     "restitution")}
    values.update(change)
    with pytest.raises(ParameterError, match=match):
        TranslatingFollower(**values)


def test_bad_runs_are_refused_before_any_work():
    rig = alzate_rig()
    for kwargs, match in (({"speed": -1.0, "duration": 1.0}, "speed"), ({"speed": 10.0, "duration": 0.0}, "duration"),
                          ({"speed": 10.0, "duration": 1.0, "initial_state": (0.0,)}, "initial_state"),
                          ({"speed": 10.0, "duration": 1.0, "max_step": -1.0}, "max_step"),
                          ({"speed": 10.0, "duration": 1.0, "max_step": math.nan}, "max_step"),
                          ({"speed": 10.0, "duration": 1.0, "max_events": 0}, "max_events")):
        with pytest.raises(ParameterError, match=match):
            simulate_translating(rig, **kwargs)


def test_with_damping_the_liftoff_speed_brackets_the_first_separation():
    """The damper's force c omega s' enters the contact force: lift-off is the smallest
    root of a quadratic in omega. Simulations 0.5 % either side of it stay on the cam and
    leave it."""
    rig = dataclasses.replace(alzate_rig(), damping=5.0)
    w_lift = liftoff_speed(rig)
    assert w_lift < liftoff_speed(alzate_rig())   # the damper pulls back on the rise's end
    revolution = 2 * math.pi / w_lift
    below = simulate_translating(rig, (0.995 * w_lift) / (2 * math.pi), 3 * revolution, sample_rate=500 / revolution,
                                 phase=PHASE)
    assert below.event_time.size == 0 and below.in_contact.values.all()
    above = simulate_translating(rig, (1.005 * w_lift) / (2 * math.pi), 1.2 * revolution,
                                 sample_rate=500 / revolution, phase=PHASE)
    assert above.event_kind.values[0] == "separation"
