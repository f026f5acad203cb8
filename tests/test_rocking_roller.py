"""The rocking roller and knife-edge followers on a cam profile
(:mod:`camdyn.model.rocking_roller`, :mod:`camdyn.simulation.rocking_roller`), against
values computed here from outside the code:

- on an eccentric circle cam the roller's centre lies on the circle of radius ``R + r``
  about the cam's moving centre: the arm angle is a circle-circle intersection, written
  here in closed form with its derivatives by implicit differentiation;
- an event-driven SciPy solution in the arm angle itself (its own geometry, Newton's law
  on the normal velocity at the roller) against the compiled run;
- a long arm tends to the translating roller follower, the error falling like 1/L;
- refusals before any work.
"""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, minimize_scalar

from camdyn.errors import GeometryError, ParameterError
from camdyn.model.profiles import eccentric_circle, pressure_angle, rise_return_profile
from camdyn.model.rocking_roller import RockingGeometry, contact_configuration
from camdyn.simulation.rocking_roller import (
    RockingFollower,
    rocking_liftoff_speed,
    rocking_table,
    simulate_rocking,
)
from camdyn.simulation.translating import TranslatingFollower, simulate_translating

RADIUS, RUNOUT, ROLLER, ARM = 0.025, 0.005, 0.008, 0.06
PIVOT = (-0.06, 0.03)
INERTIA, STIFFNESS, PRELOAD = 2e-4, 0.5, 0.05


def closed_form(theta, pivot=PIVOT, arm=ARM, radius=RADIUS + ROLLER, runout=RUNOUT, sigma=1):
    """``(psi, psi', psi'', pressure angle)`` [rad, rad/rad, rad/rad^2, rad] of the arm on
    the eccentric circle turned by ``theta`` (counter-clockwise; its centre at ``R(theta)
    (0, runout)``). The roller centre C = P + arm e(psi) is at ``radius`` from the centre
    O: with D = O - P, ``F = e(psi).D - k = 0``, ``k = (arm^2 + |D|^2 - radius^2) / (2
    arm)``, so ``psi = atan2(D) +- acos(k / |D|)``, the sign where turning the arm by
    ``sigma`` moves C away from O."""
    c, s = math.cos(theta), math.sin(theta)
    centre = np.array([-runout * s, runout * c])
    d = centre - np.asarray(pivot)
    d1 = np.array([-runout * c, -runout * s])
    d2 = np.array([runout * s, -runout * c])
    dist = math.hypot(*d)
    k = (arm * arm + dist * dist - radius * radius) / (2 * arm)
    k1 = d @ d1 / arm
    k2 = (d1 @ d1 + d @ d2) / arm
    for sign in (1, -1):
        psi = math.atan2(d[1], d[0]) + sign * math.acos(k / dist)
        e, e1 = np.array([math.cos(psi), math.sin(psi)]), np.array([-math.sin(psi), math.cos(psi)])
        normal = (np.asarray(pivot) + arm * e - centre) / radius
        motion = sigma * e1
        if motion @ normal > 0:
            break
    f_psi, f_theta = e1 @ d, e @ d1 - k1
    psi1 = -f_theta / f_psi
    psi2 = -(-(e @ d) * psi1 ** 2 + 2 * (e1 @ d1) * psi1 + (e @ d2 - k2)) / f_psi
    phi = math.atan2(motion[0] * normal[1] - motion[1] * normal[0], motion @ normal)
    return psi, psi1, psi2, phi


def closed_third(theta, h=1e-3, **kw):
    """psi''' by the five-point central difference of the closed form's psi'' (error
    h^4 psi^(5) / 30, about 1e-13 here)."""
    v = [closed_form(theta + d, **kw)[2] for d in (-2 * h, -h, h, 2 * h)]
    return (v[0] - 8 * v[1] + 8 * v[2] - v[3]) / (12 * h)


def circle_geometry(face="roller", pivot=PIVOT, arm=ARM, roller=ROLLER, sigma=1):
    profile = eccentric_circle(RADIUS, RUNOUT, follower=face, roller_radius=roller if face == "roller" else 0.0)
    return RockingGeometry(profile, pivot[0], pivot[1], arm, roller, sigma)


CASES = {   # name: (face of the profile, pivot, roller, lift sense)
    "roller profile": ("roller", PIVOT, ROLLER, 1),
    "flat profile, roller": ("flat", PIVOT, ROLLER, 1),
    "flat profile, knife edge": ("flat", PIVOT, 0.0, 1),
    "pivot on the right, lifted clockwise": ("roller", (0.05, 0.045), ROLLER, -1),
}


@pytest.mark.parametrize("case", CASES)
def test_the_contact_angle_on_an_eccentric_circle_matches_the_circle_intersection(case):
    """psi_c, its three derivatives and the pressure angle at 40 random cam angles to
    1e-10 (measured: 1e-15 for psi and its first two derivatives and the pressure angle,
    8e-14 for psi''', the difference quotient's own error). The profile made for a flat
    face reaches psi''' through a difference quotient of s''' (five points, step 1e-3
    rad)."""
    face, pivot, roller, sigma = CASES[case]
    geometry = circle_geometry(face, pivot, roller=roller, sigma=sigma)
    theta = np.random.default_rng(7).uniform(0.0, 2 * math.pi, 40)
    config = contact_configuration(geometry, theta)
    kw = {"pivot": pivot, "radius": RADIUS + roller, "sigma": sigma}
    expected = np.array([closed_form(t, **kw) for t in theta]).T
    wrapped = (config.psi[0] - expected[0] + math.pi) % (2 * math.pi) - math.pi
    assert np.abs(wrapped).max() < 1e-12
    np.testing.assert_allclose(config.psi[1], expected[1], rtol=0, atol=1e-10)
    np.testing.assert_allclose(config.psi[2], expected[2], rtol=0, atol=1e-10)
    np.testing.assert_allclose(config.psi[3], [closed_third(t, **kw) for t in theta], rtol=0, atol=1e-10)
    np.testing.assert_allclose(config.pressure_angle, expected[3], rtol=0, atol=1e-10)
    assert np.abs(config.psi[1]).max() > 0.05 and np.abs(config.pressure_angle).max() > 0.1   # not trivial


CYCLOIDAL = [("cycloidal", 2 * math.pi / 3, 0.008), ("dwell", math.pi / 3, 0.0),
             ("cycloidal", 2 * math.pi / 3, -0.008), ("dwell", math.pi / 3, 0.0)]


def _cycloidal(u):
    """The cycloidal rise-dwell-return lift [m] written again here."""
    u = u % (2 * math.pi)
    beta = 2 * math.pi / 3
    if u < beta:
        x = u / beta
        return 0.008 * (x - math.sin(2 * math.pi * x) / (2 * math.pi))
    if u < math.pi:
        return 0.008
    if u < math.pi + beta:
        x = (u - math.pi) / beta
        return 0.008 * (1 - x + math.sin(2 * math.pi * x) / (2 * math.pi))
    return 0.0


@pytest.mark.parametrize("face", ["roller", "flat"])
def test_on_a_cycloidal_cam_the_roller_touches_the_cam_and_the_derivatives_match_differences(face):
    """A cycloidal rise-dwell-return cam (base 30 mm, lift 8 mm), the roller of 8 mm on
    an arm of 70 mm. The roller centre C, taken to the cam's frame, against the cam built
    here: for the roller profile it lies on the pitch curve, ``|C| = r_base + r_r +
    s(u)`` at its own polar angle (``u = pi/2 - atan2``); for the flat-face profile its
    distance to the cam, ``max_u (C . n(u) - h(u))`` over the support lines of the convex
    cam (``h = r_base + s``, ``n = (sin u, cos u)``), is the roller radius; both to 1e-12
    m. The derivatives against five-point differences of psi_c itself (step 1e-3 rad):
    1e-9 (measured 3e-13, 4e-13, 2e-12 on the roller profile; 8e-13, 2e-12, 7e-11 on
    the flat-face one, whose psi''' takes a difference quotient of s''')."""
    roller = 0.008
    profile = rise_return_profile(CYCLOIDAL, 0.03, follower=face, roller_radius=roller if face == "roller" else 0.0)
    geometry = RockingGeometry(profile, -0.07, 0.04, 0.07, roller, 1)
    theta = np.random.default_rng(5).uniform(0.0, 2 * math.pi, 12)
    config = contact_configuration(geometry, theta)
    for t, centre in zip(theta, config.centre.T):
        x, y = math.cos(t) * centre[0] + math.sin(t) * centre[1], -math.sin(t) * centre[0] + math.cos(t) * centre[1]
        if face == "roller":
            assert abs(math.hypot(x, y) - (0.03 + roller + _cycloidal(math.pi / 2 - math.atan2(y, x)))) < 1e-12
        else:
            def distance(u):
                return x * math.sin(u) + y * math.cos(u) - 0.03 - _cycloidal(u)
            grid = np.linspace(0, 2 * math.pi, 7201)
            best = grid[int(np.argmax([distance(u) for u in grid]))]
            u = minimize_scalar(lambda v: -distance(v), bounds=(best - 1e-3, best + 1e-3), method="bounded",
                                options={"xatol": 1e-12}).x
            assert abs(distance(u) - roller) < 1e-12
    h = 1e-3
    shifted = [contact_configuration(geometry, theta + d, reference=0.0).psi for d in (-2 * h, -h, h, 2 * h)]
    for k in range(3):
        difference = (shifted[0][k] - 8 * shifted[1][k] + 8 * shifted[2][k] - shifted[3][k]) / (12 * h)
        np.testing.assert_allclose(config.psi[k + 1], difference, rtol=0, atol=1e-9)
    assert np.abs(config.psi[1]).max() > 0.05


def test_the_lift_table_interpolates_the_exact_contact_angle():
    """The spline table of 8192 samples against the exact contact angle between its
    samples: s within 1e-14 rad, s' within 1e-11, s'' within 1e-7 (measured 6e-16,
    1e-12, 8e-9); its s''' is constant per interval, within 1e-3 (measured 6e-5)."""
    geometry = circle_geometry()
    table = rocking_table(geometry, 8192)
    theta = np.random.default_rng(3).uniform(0.0, 2 * math.pi, 200)
    exact = contact_configuration(geometry, theta, reference=table.rest_angle).psi.copy()
    exact[0] -= table.rest_angle
    spline = np.array(table.profile.lift(theta))
    for k, tolerance in enumerate((1e-14, 1e-11, 1e-7, 1e-3)):
        assert np.abs(spline[k] - exact[k]).max() < tolerance
    # the rest angle is the least contact angle, where psi_c' = 0
    lowest = brentq(lambda t: closed_form(t)[1], 2.0, 4.5, xtol=1e-15)
    assert abs(table.rest_angle - closed_form(lowest)[0]) < 1e-14


def _normal_rates(theta, psi, psi_dot, w):
    """Normal velocity [m/s] of the roller centre relative to the cam point under it, and
    ``L e'(psi) . N`` [m], on the eccentric circle (its own geometry)."""
    c, s = math.cos(theta), math.sin(theta)
    centre = np.array([-RUNOUT * s, RUNOUT * c])
    e, e1 = np.array([math.cos(psi), math.sin(psi)]), np.array([-math.sin(psi), math.cos(psi)])
    roller = np.asarray(PIVOT) + ARM * e
    normal = (roller - centre) / (RADIUS + ROLLER)
    cam_velocity = w * np.array([-roller[1], roller[0]])   # omega z x C, the cam turning about O
    return (ARM * psi_dot * e1 - cam_velocity) @ normal, ARM * (e1 @ normal)


def reference(w, t_end, rest, restitution, capture=1e-6):
    """Event-driven SciPy solution in the arm angle psi: I psi'' = -M0 - k (psi - psi0)
    in flight; at a landing Newton's law on the normal velocity, v_n+ = -e v_n-; held on
    the cam while its moment I w^2 psi_c'' + M0 + k (psi_c - psi0) is positive."""
    def flight(t, y):
        return [y[1], (-PRELOAD - STIFFNESS * (y[0] - rest)) / INERTIA]

    def gap(t, y):
        return y[0] - closed_form(w * t)[0]
    gap.terminal, gap.direction = True, -1

    def moment(t):
        psi, _, psi2, _ = closed_form(w * t)
        return INERTIA * w * w * psi2 + PRELOAD + STIFFNESS * (psi - rest)

    # solve_ivp sees an event only as a sign change between step ends: its steps are kept
    # below half the shortest bounce the last rebound allows, 2 v / a, with a bound a on
    # the relative angular acceleration of arm and contact angle
    a = (PRELOAD + STIFFNESS * 0.5) / INERTIA + w * w * max(abs(closed_form(b)[2]) for b in np.linspace(0, 7, 700))
    t, events, pieces, rebound = 0.0, [], [], math.inf
    psi, psi1, _, _ = closed_form(0.0)
    y = np.array([psi, w * psi1])
    contact = moment(0.0) > 0
    while t < t_end:
        if contact:
            grid = np.arange(t, t_end, 2e-5)[1:]
            negative = [u for u in grid if moment(u) < 0.0]
            if not negative:
                pieces.append((t, t_end, None))
                break
            t_sep = brentq(moment, max(t, negative[0] - 2e-5), negative[0], xtol=1e-15, rtol=1e-15)
            pieces.append((t, t_sep, None))
            t = t_sep
            psi, psi1, _, _ = closed_form(w * t)
            y = np.array([psi, w * psi1])
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
        normal_velocity, lever = _normal_rates(w * t, y[0], y[1], w)
        psi, psi1, _, _ = closed_form(w * t)
        if -(y[1] - w * psi1) > capture:
            y[1] -= (1 + restitution) * normal_velocity / lever   # v_n+ = -e v_n-
            rebound = -restitution * normal_velocity / lever
            events.append((t, "impact"))
        else:
            y = np.array([psi, w * psi1])
            contact = moment(t) > 0
            events.append((t, "capture" if contact else "graze"))
            rebound = math.inf
    return events, pieces


def test_a_run_with_impacts_matches_an_independent_event_driven_solution():
    """Three revolutions at 1.15 times the lift-off speed with e = 0.5: the arm leaves
    the cam, lands, chatters and is captured again, each revolution. The compiled run
    (the angle-coordinate model on the spline table) against the reference: the same
    events (48 impacts, 3 captures, 3 separations), every time within 1e-8 s (measured
    3e-10 s) and the arm angle within 1e-8 rad (measured 1e-12 rad). The capture
    velocity is 1e-4 rad/s: at 1e-6 rad/s the last bounces of an accumulation rise some
    5e-16 rad, a few units in the last place of psi, where neither solution resolves them
    (they disagreed there on whether one more impact came, 1e-10 s apart)."""
    geometry = circle_geometry()
    follower = RockingFollower(geometry, INERTIA, STIFFNESS, PRELOAD, restitution=0.5, capture_velocity=1e-4)
    w = 1.15 * rocking_liftoff_speed(follower)
    duration = 3 * 2 * math.pi / w
    ds = simulate_rocking(follower, w / (2 * math.pi), duration, sample_rate=4000, rtol=1e-12, atol=1e-14)
    rest = ds.attrs["rest_angle_rad"]
    events, pieces = reference(w, duration, rest, 0.5, capture=1e-4)
    events = [(t, k) for t, k in events if k != "graze"]
    real = ds.event_kind.values != "graze"
    kinds = [k for _, k in events]
    assert list(ds.event_kind.values[real]) == kinds
    assert kinds.count("impact") > 30 and kinds.count("capture") >= 2 and kinds.count("separation") >= 2
    np.testing.assert_allclose(ds.event_time.values[real], [t for t, _ in events], rtol=0, atol=1e-8)
    for t, psi in zip(ds.time.values, ds.psi.values):
        for t0, t1, sol in pieces:
            if t0 <= t <= t1:
                expected = closed_form(w * t)[0] if sol is None else sol(t)[0]
                assert abs(psi - expected) < 1e-8
                break


def test_a_long_arm_tends_to_the_translating_roller_follower():
    """The pivot at distance L to the left of the roller, the arm horizontal: as L grows
    the roller moves along a vertical line, as the translating in-line roller does. The
    roller centre's rise L (sin psi_c - sin psi_0) against the translating lift s; for a
    held arm (I = m L^2, k_t = k L^2, M0 = F0 L) its moment over L against the translating
    follower's force along its line, and its normal force against that force over the
    cosine of the translating follower's pressure angle: all three errors fall like 1/L
    (ratio 10 +- 20 % per decade; measured at L = 0.3, 3, 30 m: 2.6e-6, 2.6e-7, 2.6e-8 m;
    2.1e-3, 2.1e-4, 2.3e-5 N; 1.0e-2, 9.8e-4, 9.8e-5 N of about 6 N)."""
    profile = eccentric_circle(RADIUS, RUNOUT, follower="roller", roller_radius=ROLLER)
    theta = np.linspace(0.0, 2 * math.pi, 90, endpoint=False)
    lift = profile.lift(theta)[0]
    mass, stiffness, preload, w = 0.1, 200.0, 5.0, 40.0
    translating = simulate_translating(TranslatingFollower(profile, mass, stiffness, preload), w / (2 * math.pi),
                                       2 * math.pi / w,
                                       sample_rate=2000)
    normal = translating.contact_force.values / np.cos(pressure_angle(profile, w * translating.time.values))
    kinematic, moment, force = [], [], []
    for arm in (0.3, 3.0, 30.0):
        geometry = RockingGeometry(profile, -arm, RADIUS + ROLLER, arm, ROLLER, 1)
        psi = contact_configuration(geometry, theta, reference=0.0).psi[0]
        table = rocking_table(geometry, 4096)
        rise = arm * (np.sin(psi) - math.sin(table.rest_angle))
        kinematic.append(np.abs(rise - lift).max())
        rocking = RockingFollower(geometry, mass * arm ** 2, stiffness * arm ** 2, preload * arm, samples=4096)
        ds = simulate_rocking(rocking, w / (2 * math.pi), 2 * math.pi / w, sample_rate=2000)
        assert ds.in_contact.values.all() and translating.in_contact.values.all()
        moment.append(np.abs(ds.contact_moment.values / arm - translating.contact_force.values).max())
        force.append(np.abs(ds.contact_force.values - normal).max())
    for errors in (kinematic, moment, force):
        ratios = np.array(errors[:-1]) / np.array(errors[1:])
        assert np.all((ratios > 8.0) & (ratios < 12.0)), errors


def _bad_geometry(**change):
    values = {"profile": eccentric_circle(RADIUS, RUNOUT, follower="roller", roller_radius=ROLLER),
              "pivot_x": PIVOT[0], "pivot_y": PIVOT[1], "arm_length": ARM, "roller_radius": ROLLER,
              "lift_direction": 1}
    values.update(change)
    return RockingGeometry(**values)


@pytest.mark.parametrize("change, error, match", [
    ({"arm_length": 0.0}, ParameterError, "arm length"),
    ({"arm_length": math.nan}, ParameterError, "arm_length"),
    ({"roller_radius": -0.001}, ParameterError, "roller radius"),
    ({"roller_radius": 0.004}, ParameterError, "same radius"),
    ({"lift_direction": 0}, ParameterError, "lift_direction"),
    ({"profile": "circle"}, ParameterError, "Profile"),
    ({"pivot_x": 0.01, "pivot_y": 0.0}, GeometryError, "pivot"),
    ({"profile": rise_return_profile([("cycloidal", 0.8, 0.02), ("dwell", 2 * math.pi - 1.6, 0.0),
                                      ("cycloidal", 0.8, -0.02)], 0.02, follower="knife"),
      "roller_radius": 0.0}, GeometryError, "not convex"),
])
def test_bad_geometries_are_refused_when_built(change, error, match):
    with pytest.raises(error, match=match):
        _bad_geometry(**change)


def test_an_arm_that_cannot_reach_or_would_lock_is_refused_before_any_run():
    too_short = _bad_geometry(pivot_x=-0.2, arm_length=0.05)
    with pytest.raises(GeometryError, match="cannot reach"):
        rocking_table(too_short, 1024)
    # the arm's circle nearly tangent to the pitch circle at 180 deg (pivot 0.105 m from
    # the circle's centre, 0.0722 + 0.033 = 0.1052 m): the pressure angle reaches 82 deg
    locking = _bad_geometry(pivot_x=0.0, pivot_y=0.1, arm_length=0.0722)
    with pytest.raises(GeometryError, match="pressure angle"):
        rocking_table(locking, 1024)


@pytest.mark.parametrize("change, match", [({"inertia": 0.0}, "inertia"), ({"stiffness": -1.0}, "stiffness"),
                                           ({"restitution": 1.5}, "restitution"), ({"samples": 10}, "samples"),
                                           ({"preload": math.inf}, "preload")])
def test_bad_followers_and_runs_are_refused(change, match):
    values = {"geometry": circle_geometry(), "inertia": INERTIA, "stiffness": STIFFNESS, "preload": PRELOAD}
    values.update(change)
    with pytest.raises(ParameterError, match=match):
        RockingFollower(**values)


def test_bad_runs_are_refused():
    follower = RockingFollower(circle_geometry(), INERTIA, STIFFNESS, PRELOAD, samples=1024)
    with pytest.raises(ParameterError, match="initial_state"):
        simulate_rocking(follower, 10.0 / (2 * math.pi), 0.1, initial_state=(0.1,))
    with pytest.raises(ParameterError, match="speed"):
        simulate_rocking(follower, -1.0 / (2 * math.pi), 0.1)
    with pytest.raises(ParameterError, match="RockingFollower"):
        simulate_rocking(circle_geometry(), 10.0 / (2 * math.pi), 0.1)
    built = rocking_table.cache_info().misses
    for kwargs in ({"speed": math.nan, "duration": 0.1}, {"speed": 10.0, "duration": -1.0},
                   {"speed": 10.0, "duration": 0.1, "initial_state": (0.1, 0.0, 0.0)}):
        with pytest.raises(ParameterError):
            simulate_rocking(RockingFollower(circle_geometry(), INERTIA, STIFFNESS, PRELOAD, samples=999), **kwargs)
    assert rocking_table.cache_info().misses == built   # refused before any table was built
