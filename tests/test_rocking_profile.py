"""The rocking follower on a cam given by a profile table (camdyn.model.rocking_profile).

Expected values come from outside the table path: the closed-form circle of the ellipse
path (a different code path: support function of the ellipse, not a segment table), and
for a non-circular cam the plain-SciPy oracle (camdyn.testing.oracle) with its geometry
replaced here by a brute-force search over points of the cam's curve, built from the
profile's support function ``h = r_base + s`` in this file.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import camdyn
from camdyn.errors import GeometryError, ParameterError
from camdyn.integrator import driver
from camdyn.model import geometry
from camdyn.model import layout as L
from camdyn.model.profiles import Profile, eccentric_circle, rise_return_profile, tabulated_profile
from camdyn.simulation.runner import impact_table, prepare, simulate
from camdyn.systems import registry
from camdyn.testing import oracle

#: Tabulated circle: samples per revolution of the periodic spline. Measured on the ch3 and
#: ch4 rigs (3 revolutions at rtol 1e-11), the largest relative error of alpha_dot against
#: the closed-form circle falls from 9e-5 (ch4: 256 samples) to 9e-6 (512) and 8e-8
#: (1024), then stays at the integration's own level, about 1e-8 (2048: 2.4e-8 ch3,
#: 1.2e-8 ch4; the closed form itself moves by 1.2e-8 from rtol 1e-11 to 1e-12).
CIRCLE_SAMPLES = 2048


def _rig(name):
    return camdyn.load_system(name)


def _with_profile(system, profile):
    return dataclasses.replace(system, profile=profile)


def _circle_table(system, samples):
    """The system's eccentric circle as a tabulated lift ``e (1 + cos theta)``, sampled."""
    r, e = system.cam.semi_major, system.cam.runout
    theta = 2.0 * math.pi * np.arange(samples) / samples
    return tabulated_profile(e * (1.0 + np.cos(theta)), r - e)


def _run(system, viscous_c, revolutions=3.0, rtol=1e-11):
    """States ``(alpha, alpha_dot)`` sampled at 20 kHz and the number of impacts of a run
    of ``system`` with the law-A coefficient ``viscous_c`` [N s/m] imposed.

    Law A's ``c = 2 zeta omega_n I_P / chi*^2`` takes ``omega_n`` from a central
    difference of the static moment, whose rounding (the penetration is a difference of
    lengths 1e5 times larger) differs between the closed form and a table by 1.4e-8
    relative (measured on ch4); the light damping of the ch4 rig's 41 impacts in 3
    revolutions turns that into 2e-6 in alpha_dot. Both paths are run with the closed
    form's ``c`` so that the comparison sees the geometry alone."""
    prep = prepare(system)
    prep.p[L.VISCOUS_C] = viscous_c
    period = system.motion.period
    duration = revolutions * period
    t = np.minimum(np.arange(int(duration * 20e3) + 1) / 20e3, duration)
    y, _, events, counters = driver.integrate(registry.CAM_FOLLOWER, prep.p, prep.y0, 0.0, duration, t, rtol,
                                              rtol * 1e-2, period / 32.0, driver.METHOD_AUTO, 50_000_000, 1000,
                                              True, math.inf)
    assert counters[driver.COUNT_STATUS] == driver.STATUS_OK
    return y[:, :2], impact_table(events)["time"].size


def _relative_error(run, reference):
    """Largest differences of alpha [rad] and alpha_dot [rad/s], each relative to the
    reference's largest magnitude."""
    return np.max(np.abs(run - reference), axis=0) / np.max(np.abs(reference), axis=0)


# --- (a) the circle as a profile against the closed-form circle -----------------------


@pytest.fixture(scope="module", params=["sundar2014-impact", "sundar2014-friction"])
def circle_runs(request):
    """The rig, its closed form's law-A coefficient, its closed-form run (3 revolutions at
    rtol 1e-11) and how far that run moves at rtol 1e-12 (the integration's own error)."""
    system = _rig(request.param)
    c = prepare(system).viscous_c
    reference, impacts = _run(system, c)
    tighter, _ = _run(system, c, rtol=1e-12)
    return system, c, reference, impacts, _relative_error(tighter, reference)


def test_arc_table_circle_matches_closed_form(circle_runs):
    """eccentric_circle is exact (a circular-arc row): only rounding separates the paths.
    Measured: alpha 5e-12 (ch3), 2e-11 (ch4); alpha_dot 5e-10 (ch3), 7e-9 (ch4, where
    the closed form itself moves by 1.2e-8 between rtol 1e-11 and 1e-12)."""
    system, c, reference, impacts, own = circle_runs
    run, count = _run(_with_profile(system, eccentric_circle(system.cam.semi_major, system.cam.runout)), c)
    assert count == impacts
    error = _relative_error(run, reference)
    assert error[0] < 1e-9
    assert error[1] < 1e-9 + own[1]


def test_tabulated_circle_matches_closed_form(circle_runs):
    """A periodic cubic spline through CIRCLE_SAMPLES samples of the circle's lift: the
    state to 1e-7 relative."""
    system, c, reference, impacts, _ = circle_runs
    run, count = _run(_with_profile(system, _circle_table(system, CIRCLE_SAMPLES)), c)
    assert count == impacts
    assert np.all(_relative_error(run, reference) < 1e-7)


# --- (b) geometry of the table path against the closed form ---------------------------


_CH3 = _rig("sundar2014-impact")
_P_ELLIPSE = L.pack(_CH3)
_P_TABLE = L.pack(_with_profile(_CH3, eccentric_circle(_CH3.cam.semi_major, _CH3.cam.runout)))


@settings(max_examples=200, deadline=None)
@given(alpha=st.floats(-0.6, 0.6), theta=st.floats(-20.0, 20.0), alpha_dot=st.floats(-50.0, 50.0),
       theta_dot=st.floats(-300.0, 300.0), alpha_ddot=st.floats(-1e4, 1e4), theta_ddot=st.floats(-1e3, 1e3))
def test_circle_table_geometry_matches_closed_form(alpha, theta, alpha_dot, theta_dot, alpha_ddot, theta_ddot):
    """Penetration, moment arm, curvature, contact point, guards and their rates: the
    exact circle table against the ellipse path with a = b, to 1e-12 of their scale."""
    length = _CH3.cam.semi_major
    closed = np.array(geometry.contact_point(alpha, theta, _P_ELLIPSE))
    table = np.array(geometry.contact_point(alpha, theta, _P_TABLE))
    np.testing.assert_allclose(table, closed, rtol=0.0, atol=1e-12 * length)
    trig = (math.cos(alpha), math.sin(alpha), math.cos(theta), math.sin(theta))
    closed = np.array(geometry.contact_rates_trig(*trig, alpha_dot, alpha_ddot, theta_dot, theta_ddot, _P_ELLIPSE))
    table = np.array(geometry.contact_rates_trig(*trig, alpha_dot, alpha_ddot, theta_dot, theta_ddot, _P_TABLE))
    scale = np.array([length, 1.0, 1.0, 1.0, 1.0]) * np.max(np.abs(closed[1:]) + length)
    np.testing.assert_array_less(np.abs(table - closed), 1e-12 * scale)
    closed = geometry.contact_point_rate(alpha, alpha_dot, theta, theta_dot, _P_ELLIPSE)
    table = geometry.contact_point_rate(alpha, alpha_dot, theta, theta_dot, _P_TABLE)
    assert abs(table - closed) <= 1e-12 * (abs(closed) + length * (abs(alpha_dot) + abs(theta_dot)))


def test_circle_zero_states_match_closed_form():
    """Both 0-state conventions of a circle given as a profile are the closed form's."""
    for name in ("sundar2014-impact", "sundar2014-friction"):
        system = _rig(name)
        table = _with_profile(system, eccentric_circle(system.cam.semi_major, system.cam.runout))
        np.testing.assert_allclose(geometry.zero_state(table), geometry.zero_state(system), rtol=0, atol=1e-14)


# --- (c) a cycloidal rise-dwell-return cam against the SciPy oracle --------------------


RISE = 2.0 * math.pi / 3.0       # span of the rise and of the return [rad]
DWELL = math.pi / 3.0            # span of each dwell [rad]


def _cycloidal_cam(base_radius=15.75e-3, lift=3.5e-3):
    """Rise 120 deg, dwell 60 deg, return 120 deg, dwell 60 deg, cycloidal."""
    return rise_return_profile([("cycloidal", RISE, lift), ("dwell", DWELL, 0.0), ("cycloidal", RISE, -lift),
                                ("dwell", DWELL, 0.0)], base_radius)


def _cycloidal_lift(theta, lift=3.5e-3):
    """The same cam's lift ``s`` [m] and its derivatives ``s'``, ``s''`` written again
    here: ``s = L (u - sin(2 pi u) / (2 pi))`` over the rise (Norton 2009), mirrored
    over the return."""
    theta = np.mod(theta, 2.0 * math.pi)
    rising = theta < RISE
    returning = (theta >= RISE + DWELL) & (theta < 2.0 * RISE + DWELL)
    u = np.where(rising, theta / RISE, np.where(returning, (theta - RISE - DWELL) / RISE, 0.0))
    w = 2.0 * math.pi * u
    sign = np.where(rising, 1.0, np.where(returning, -1.0, 0.0))
    top = np.where(returning | ((theta >= RISE) & (theta < RISE + DWELL)), lift, 0.0)
    s = top + sign * lift * (u - np.sin(w) / (2.0 * math.pi))
    s1 = sign * lift / RISE * (1.0 - np.cos(w))
    s2 = sign * lift * 2.0 * math.pi / RISE ** 2 * np.sin(w)
    return s, s1, s2


class _CurveCam:
    """The cycloidal cam's curve in its own frame, from its support function ``h = r_base
    + s``: the profile's point at angle theta is ``h (cos, sin) + h' (-sin, cos)``
    (Rothbart 2004), mirrored (x -> -x) into the rocking cam's frame, where the
    profile's angle runs the other way (camdyn.model.rocking_profile)."""

    def __init__(self, base_radius=15.75e-3, samples=4096):
        self.base_radius = base_radius
        self.grid = np.linspace(0.0, 2.0 * math.pi, samples, endpoint=False)
        self.step = self.grid[1]
        self.points = self.point(self.grid)

    def point(self, theta):
        s, s1, _ = _cycloidal_lift(theta)
        h = self.base_radius + s
        c, n = np.cos(theta), np.sin(theta)
        return np.stack([-(h * c - s1 * n), h * n + s1 * c], axis=-1)

    def curvature_radius(self, theta):
        """``h + h''`` [m] (Rothbart 2004)."""
        s, _, s2 = _cycloidal_lift(np.array([theta]))
        return self.base_radius + float(s[0] + s2[0])

    def closest(self, direction):
        """Profile angle [rad] of the cam point furthest along ``-direction`` (in the cam's
        frame): brute force over the samples and over finer samples around the best one
        (33 per level, 2 levels: to 1e-5 rad), then Newton's method on the stationarity
        ``direction . dX/dtheta = 0``, with ``dX/dtheta = (h + h'') (-sin, cos)`` mirrored
        (the derivative of :meth:`point`), to rounding."""
        k = int(np.argmin(self.points @ direction))
        low, high = self.grid[k] - self.step, self.grid[k] + self.step
        for _ in range(2):
            trial = np.linspace(low, high, 33)
            j = int(np.argmin(self.point(trial) @ direction))
            width = (high - low) / 32.0
            low, high = trial[j] - width, trial[j] + width
        theta = 0.5 * (low + high)
        for _ in range(3):   # direction . (sin, cos) = 0, the mirrored tangent (-sin, cos)
            theta -= ((direction[0] * math.sin(theta) + direction[1] * math.cos(theta))
                      / (direction[0] * math.cos(theta) - direction[1] * math.sin(theta)))
        return theta


def _profile_oracle():
    """The oracle's model with its ellipse replaced by the brute-force cycloidal cam."""
    curve = _CurveCam()

    class ProfileModel(oracle.ReferenceModel):
        def geometry_at(self, th, thd, alpha, alpha_dot):
            rotation = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
            n = np.array([math.sin(alpha), math.cos(alpha)])
            u = np.array([math.cos(alpha), -math.sin(alpha)])
            angle = curve.closest(rotation.T @ n)
            x = self.E + rotation @ curve.point(np.array([angle]))[0]
            delta = self.h - n @ x
            chi = u @ x
            r = x - self.E
            v_cam = thd * np.array([-r[1], r[0]])
            delta_dot = -alpha_dot * chi - n @ v_cam
            xb = chi * u + self.h * n
            v_fol = -alpha_dot * np.array([-xb[1], xb[0]])
            return delta, delta_dot, chi, curve.curvature_radius(angle), (v_cam - v_fol) @ u, v_cam, n, u

    return ProfileModel


def test_cycloidal_geometry_matches_brute_force():
    """Penetration, moment arm and curvature of a non-circular cam at random angles."""
    profile = _cycloidal_cam()
    system = _with_profile(_rig("sundar2014-friction"), profile)
    p = L.pack(system)
    model = _profile_oracle()(system, 0.0, 0.0)
    rng = np.random.default_rng(7)
    for alpha, theta in zip(rng.uniform(-0.2, 0.3, 40), rng.uniform(0.0, 2.0 * math.pi, 40)):
        delta, chi, rho, _, _ = geometry.contact_point(alpha, theta, p)
        expected = model.geometry_at(theta, 0.0, alpha, 0.0)
        assert abs(delta - expected[0]) < 1e-12
        assert abs(chi - expected[2]) < 1e-9
        assert abs(rho - expected[3]) < 1e-9


def test_cycloidal_cam_run_matches_oracle(monkeypatch):
    """40 ms in sustained contact on the cycloidal cam at 6 Hz, from the middle of the
    return (where ``s'' = 0``; the follower starts at its static equilibrium there with
    the velocity of rigid contact, ``alpha_dot = Theta_dot h' / chi`` from ``delta_dot =
    0``): the compiled table path (rtol 1e-11) against the oracle with the brute-force
    geometry (rtol 1e-10), to the 1e-6 asked (measured: 1e-11 in alpha, 2e-9 in
    alpha_dot over 15 ms)."""
    middle = RISE + DWELL + 0.5 * RISE                  # profile angle of the return's middle [rad]
    rig = _with_profile(_rig("sundar2014-friction"), _cycloidal_cam())
    alpha_guess = prepare(rig.with_values(**{"motion.speed": 6.0})).equilibrium.angle
    system = rig.with_values(**{"motion.speed": 6.0, "motion.initial_angle": middle + 0.5 * math.pi - alpha_guess})
    prep = prepare(system)
    eq = prep.equilibrium
    slope = _cycloidal_lift(np.array([eq.angle + eq.cam_angle - 0.5 * math.pi]))[1][0]
    start = (eq.angle, system.motion.angular_speed * slope / eq.moment_arm)
    duration = 0.04
    t = np.linspace(0.0, duration, 61)
    run = simulate(system, duration=duration, sample_rate=60 / duration, rtol=1e-11, atol=1e-13,
                   initial_state=start, variables=["alpha", "alpha_dot", "in_contact"])
    assert run.in_contact.values.all()
    monkeypatch.setattr(oracle, "ReferenceModel", _profile_oracle())
    _, truth, info = oracle.reference_simulate(system, prep.theta0, start, duration, t, prep.viscous_c,
                                               rtol=1e-10, atol=1e-13)
    assert all(kind == "reversal" for _, kind in info["log"])
    for j, name in enumerate(("alpha", "alpha_dot")):
        error = np.max(np.abs(run[name].values - truth[j])) / np.max(np.abs(truth[j]))
        assert error < 1e-6, (name, error)


# --- (d) refusals ---------------------------------------------------------------------


@pytest.mark.parametrize("follower", ["roller", "knife"])
def test_roller_or_knife_profile_refused(follower):
    radius = 2e-3 if follower == "roller" else 0.0
    profile = eccentric_circle(17.5e-3, 1.75e-3, follower=follower, roller_radius=radius)
    with pytest.raises(ParameterError, match="flat face"):
        _with_profile(_rig("sundar2014-friction"), profile)


def test_not_a_profile_refused():
    with pytest.raises(ParameterError, match="cam profile"):
        _with_profile(_rig("sundar2014-friction"), np.zeros(9))


def test_profile_that_cannot_reach_the_follower_refused():
    """A cam far too small for the rig's pivot distance: refused before any run."""
    system = _with_profile(_rig("sundar2014-friction"), eccentric_circle(5e-3, 1e-3))
    with pytest.raises(GeometryError, match="cannot reach"):
        simulate(system, revolutions=1)


def test_non_convex_profile_refused():
    """A table built by hand, bypassing the constructors' check, is checked by prepare."""
    table = _cycloidal_cam().table            # r_base + s + s'' = -0.8 mm at 3/4 of the rise
    system = _with_profile(_rig("sundar2014-friction"), Profile(table, 1e-3, "flat"))
    with pytest.raises(GeometryError, match="not convex"):
        simulate(system, revolutions=1)


def test_equal_profiles_make_equal_systems():
    """Systems are cached by value: two equal profiles, built apart, give equal systems."""
    rig = _rig("sundar2014-friction")
    first = _with_profile(rig, _cycloidal_cam())
    second = _with_profile(rig, _cycloidal_cam())
    assert first == second and hash(first) == hash(second)
    assert first != _with_profile(rig, _cycloidal_cam(lift=3e-3))
