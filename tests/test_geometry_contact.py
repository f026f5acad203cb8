"""Geometry (support function) and contact laws against independent calculations."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import camdyn
from camdyn.model import layout as L
from camdyn.model.contact import (
    equivalent_radius,
    hertz_line_coefficient,
    hertz_point_coefficient,
    hunt_crossley_beta,
)
from camdyn.model.dynamics import evaluate
from camdyn.model.geometry import (
    cam_acceleration,
    cam_angle,
    contact_kinematics,
    contact_point,
    contact_point_rate,
    contact_rates_trig,
)


def brute_force(alpha, theta, a, b, e, ex, ey, h, n=200001):
    """Closest ellipse point to the follower surface by sampling the boundary."""
    phi = np.linspace(0, 2 * np.pi, n)
    e1 = np.array([math.cos(theta), math.sin(theta)])
    e2 = np.array([-math.sin(theta), math.cos(theta)])
    g = np.array([ex, ey]) - e * e1
    x = g[:, None] + np.outer(e1, a * np.cos(phi)) + np.outer(e2, b * np.sin(phi))
    nrm = np.array([math.sin(alpha), math.cos(alpha)])
    proj = nrm @ x
    i = np.argmin(proj)
    u = np.array([math.cos(alpha), -math.sin(alpha)])
    return h - proj[i], u @ x[:, i]


@settings(max_examples=40, deadline=None)
@given(alpha=st.floats(-0.3, 0.3), theta=st.floats(0, 2 * math.pi), ratio=st.floats(0.6, 1.0),
       e_frac=st.floats(0.0, 0.5))
def test_support_function_matches_brute_force(alpha, theta, ratio, e_frac):
    a, b = 0.0175, 0.0175 * ratio
    p = np.zeros(L.SIZE)
    p[L.SEMI_A], p[L.SEMI_B], p[L.RUNOUT] = a, b, e_frac * b
    p[L.PIVOT_X], p[L.PIVOT_Y], p[L.OFFSET] = 0.086, 0.024, 0.01275
    delta, chi, *_ = contact_point(alpha, theta, p)
    d_ref, chi_ref = brute_force(alpha, theta, a, b, p[L.RUNOUT], 0.086, 0.024, 0.01275)
    # sampling 2e5 points resolves the minimum to a * (pi/1e5)^2 / 2 < 1e-11 m in delta
    assert delta == pytest.approx(d_ref, abs=1e-10)
    assert chi == pytest.approx(chi_ref, abs=2e-6)


@settings(max_examples=25, deadline=None)
@given(alpha=st.floats(0.0, 0.15), alpha_dot=st.floats(-5, 5), t=st.floats(0, 0.1), ratio=st.floats(0.7, 1.0))
def test_rates_match_finite_differences(alpha, alpha_dot, t, ratio):
    s = camdyn.load_system("sundar2014-friction", {"cam.semi_minor": f"{17.5 * ratio} mm"})
    p = L.pack(s, initial_angle=0.3)
    h = 1e-7

    def state(tt):
        th, thd = cam_angle(tt, p)
        return alpha + alpha_dot * (tt - t), th, thd

    a0, th0, thd0 = state(t)
    delta, delta_dot, chi, rho, vr, *_ = contact_kinematics(a0, alpha_dot, th0, thd0, p)
    dp = contact_point(*state(t + h)[:2], p)
    dm = contact_point(*state(t - h)[:2], p)
    # envelope theorem: delta_dot = -alpha_dot chi - n . v_cam
    assert delta_dot == pytest.approx((dp[0] - dm[0]) / (2 * h), rel=1e-6, abs=1e-10)
    chi_dot = contact_point_rate(a0, alpha_dot, th0, thd0, p)
    assert chi_dot == pytest.approx((dp[1] - dm[1]) / (2 * h), rel=1e-5, abs=1e-8)


@settings(max_examples=30, deadline=None)
@given(alpha=st.floats(0.0, 0.15), alpha_dot=st.floats(-5, 5), alpha_ddot=st.floats(-3e3, 3e3),
       t=st.floats(0, 0.1), ratio=st.floats(0.7, 1.0), oscillating=st.booleans())
def test_guard_rates_match_finite_differences(alpha, alpha_dot, alpha_ddot, t, ratio, oscillating):
    """The event core's exact guard rates (sliding velocity and penetration rate) against
    central differences of contact_kinematics along alpha(t) = a0 + a1 t + a2 t^2 / 2."""
    extra = {"motion.kind": "oscillating", "motion.amplitude": "40 deg", "motion.frequency": "7 Hz"} \
        if oscillating else {}
    s = camdyn.load_system("sundar2014-friction", {"cam.semi_minor": f"{17.5 * ratio} mm", **extra})
    p = L.pack(s, initial_angle=0.3)
    h = 1e-6

    def kinematics(tt):
        d = tt - t
        th, thd = cam_angle(tt, p)
        return contact_kinematics(alpha + alpha_dot * d + 0.5 * alpha_ddot * d * d, alpha_dot + alpha_ddot * d,
                                  th, thd, p)

    th0, thd0 = cam_angle(t, p)
    thdd0 = cam_acceleration(t, p)
    assert thdd0 == pytest.approx((cam_angle(t + h, p)[1] - cam_angle(t - h, p)[1]) / (2 * h), rel=1e-6, abs=1e-6)
    delta, vr, delta_dot, vr_dot, delta_ddot = contact_rates_trig(
        math.cos(alpha), math.sin(alpha), math.cos(th0), math.sin(th0), alpha_dot, alpha_ddot, thd0, thdd0, p)
    k0, kp, km = kinematics(t), kinematics(t + h), kinematics(t - h)
    assert (delta, vr, delta_dot) == pytest.approx((k0[0], k0[4], k0[1]), rel=1e-12, abs=1e-15)
    assert vr_dot == pytest.approx((kp[4] - km[4]) / (2 * h), rel=1e-5, abs=1e-6)
    assert delta_ddot == pytest.approx((kp[1] - km[1]) / (2 * h), rel=1e-5, abs=1e-6)
    unknown = contact_rates_trig(math.cos(alpha), math.sin(alpha), math.cos(th0), math.sin(th0), alpha_dot,
                                 math.nan, thd0, thdd0, p)
    assert math.isnan(unknown[3]) and math.isnan(unknown[4]) and unknown[:3] == (delta, vr, delta_dot)


def test_curvature_of_circle_and_ellipse():
    s = camdyn.load_system("sundar2014-friction", {"cam.semi_minor": "12 mm"})
    p = L.pack(s)
    a, b = 0.0175, 0.012
    radii = [contact_point(0.05, th, p)[2] for th in np.linspace(0, 2 * np.pi, 50)]
    # curvature radius of an ellipse lies between b^2/a and a^2/b
    assert min(radii) == pytest.approx(b * b / a, rel=1e-3)
    assert max(radii) == pytest.approx(a * a / b, rel=1e-3)


def test_hertz_numbers_of_the_thesis(impact_rig):
    # thesis 3.8.3: k = 8.0 GN/m^1.5 for the chapter 3 crossed cylinders (210 GPa, nu 0.3)
    estar = L.effective_modulus(impact_rig)
    k = hertz_point_coefficient(estar, equivalent_radius(0.0175, 0.0032))
    assert round(k / 1e9, 1) == 8.0
    # and the Hunt-Crossley equivalent of gamma = 0.758 s/m is 9.1 GN s/m^2.5
    assert round(hunt_crossley_beta(0.758, k) / 1e9, 1) == 9.1
    # thesis 2.6: line contact 1.6 mm long, steel at 200 GPa: 138 MN/m
    estar200 = 1.0 / (2 * (1 - 0.09) / 200e9)
    assert round(hertz_line_coefficient(estar200, 1.6e-3) / 1e6) == 138


@settings(max_examples=60, deadline=None)
@given(alpha=st.floats(0.05, 0.12), alpha_dot=st.floats(-20, 20), t=st.floats(0, 0.2),
       law=st.sampled_from(["coulomb", "tanh"]), mu=st.floats(0.0, 0.8), slip=st.sampled_from([-1.0, 1.0]))
def test_friction_never_exceeds_mu_times_normal_force(alpha, alpha_dot, t, law, mu, slip):
    s = camdyn.load_system("sundar2014-friction", {"friction.law": law, "friction.coefficient": str(mu)})
    p = L.pack(s, viscous_c=50.0, initial_angle=0.0)
    mode = np.array([1.0, slip, 0.0, 0.01, 0.0])
    res = evaluate(t, alpha, alpha_dot, mode, p)
    fn, ff = res[1], res[2]
    assert abs(ff) <= mu * abs(fn) * (1 + 1e-12)
