"""The compiled core against the independent SciPy model, and energy bookkeeping."""

import math

import numpy as np
import pytest

import camdyn
from camdyn.simulation.runner import prepare
from camdyn.testing.oracle import reference_simulate


def compare_with_reference(system, revolutions, speed, fs=20e3):
    system = system.with_values(**{"motion.speed": speed})
    prep = prepare(system)
    ds = camdyn.simulate(system, revolutions=revolutions, sample_rate=fs, rtol=1e-11, atol=1e-13)
    t = ds.time.values
    # The viscous coefficient (eq 2.24) is given to the oracle: these runs bounce, which
    # amplifies the ~1e-8 by which the two implementations' coefficients differ (finite
    # differences) beyond the tolerances below; test_oracle_laws.py compares the coefficients.
    _, ref, info = reference_simulate(system, prep.theta0, prep.y0, t[-1], t, prep.viscous_c,
                                      method="DOP853", rtol=1e-12, atol=1e-14)
    return ds, ref, info


def test_sliding_contact_agrees_with_scipy(friction_rig):
    ds, ref, _ = compare_with_reference(friction_rig, 2, 11.55)
    scale = np.max(np.abs(ref[0]))
    # 1e-6 relative; both runs are far tighter than that
    np.testing.assert_allclose(ds.alpha.values, ref[0], rtol=0, atol=1e-6 * scale)
    np.testing.assert_allclose(ds.alpha_dot.values, ref[1], rtol=0, atol=1e-6 * np.max(np.abs(ref[1])))


def test_impacts_agree_with_scipy(impact_rig):
    # chapter 3 rig at e/rc = 0.2 and 16 Hz: one impact per revolution
    ds, ref, info = compare_with_reference(impact_rig, 4, 16.0)
    assert ds.sizes["impact"] >= 3
    assert info["events"] >= 2 * ds.sizes["impact"]
    scale = np.max(np.abs(ref[0]))
    np.testing.assert_allclose(ds.alpha.values, ref[0], rtol=0, atol=1e-6 * scale)


def test_energy_is_conserved_without_damping_or_friction(impact_rig):
    # undamped, frictionless: T + V_spring + V_gravity + V_contact - W_cam is constant.
    # The potentials are written here from docs/model.md, independently of the core.
    s = impact_rig.with_values(**{"contact.damping": "none", "friction.law": "none"})
    ds = camdyn.simulate(s, speed=16.0, revolutions=3, sample_rate=50e3, rtol=1e-11, atol=1e-13)
    assert ds.sizes["impact"] >= 2
    f, sp = s.follower, s.spring
    a, ad = ds.alpha.values, ds.alpha_dot.values
    kinetic = 0.5 * f.inertia * ad ** 2
    # spring moment M = -Fs dx with Fs = ks (Ls - dy + dx tan a + 0.5 wb sec a): its potential
    v_spring = sp.stiffness * sp.attachment_x * (
        (sp.free_length - sp.ground_depth) * a - sp.attachment_x * np.log(np.cos(a))
        + 0.5 * f.width * np.log(1 / np.cos(a) + np.tan(a)))
    v_gravity = -f.mass * s.gravity * f.cg_distance * np.sin(a)
    rho_e = 1 / (1 / s.cam.semi_major + 1 / f.pin_radius)
    estar = 1 / (2 * (1 - 0.3 ** 2) / 210e9)
    k = 4 / 3 * estar * math.sqrt(rho_e)
    delta = np.clip(ds.penetration.values, 0, None)
    v_contact = 0.4 * k * delta ** 2.5
    total = kinetic + v_spring + v_gravity + v_contact - ds.cam_work.values
    swing = np.ptp(kinetic)
    assert np.ptp(total) < 1e-6 * swing, np.ptp(total) / swing


def test_elliptic_cam_agrees_with_scipy(friction_rig):
    # table 4.7's elliptic cams: b/a = 0.8, e/a = 0.1, 8.33 Hz
    s = friction_rig.with_values(**{"cam.semi_minor": 0.8 * friction_rig.cam.semi_major})
    ds, ref, _ = compare_with_reference(s, 1.5, 8.33)
    scale = np.max(np.abs(ref[0]))
    np.testing.assert_allclose(ds.alpha.values, ref[0], rtol=0, atol=1e-6 * scale)


@pytest.mark.parametrize("kind", ["line", "point"])
def test_contact_on_bar_face_centre_pivot_agrees_with_scipy(standin_rig, kind):
    # chapter 2 layout: pivot at the centre of gravity, contact on the bar face: line
    # contact, or the pinless point contact of eq 2.34 (the cam's curvature alone)
    s = standin_rig.with_values(**{"contact.kind": kind})
    ds, ref, _ = compare_with_reference(s, 0.1, 2.5)  # 40 ms: the 5 kHz contact mode is costly for SciPy
    scale = np.max(np.abs(ref[0]))
    np.testing.assert_allclose(ds.alpha.values, ref[0], rtol=0, atol=1e-6 * scale)


def test_oscillating_cam_agrees_with_scipy(friction_rig):
    # tanh friction (Coulomb friction through reversals of the sliding velocity is checked
    # in test_oracle_laws.py)
    s = friction_rig.with_values(**{"motion.kind": "oscillating", "motion.amplitude": 0.6,
                                    "motion.frequency": 3.0, "friction.law": "tanh"})
    prep = prepare(s)
    ds = camdyn.simulate(s, revolutions=0.12, sample_rate=20e3, rtol=1e-11, atol=1e-13)
    t = ds.time.values
    _, ref, _ = reference_simulate(s, prep.theta0, prep.y0, t[-1], t, prep.viscous_c, method="DOP853",
                                   rtol=1e-12, atol=1e-14)
    scale = np.max(np.abs(ref[0]))
    np.testing.assert_allclose(ds.alpha.values, ref[0], rtol=0, atol=1e-6 * scale)
    # the cam angle follows Theta0 + 0.5 Theta_p sin(omega_c t)
    np.testing.assert_allclose(ds.cam_angle.values, prep.theta0 + 0.3 * np.sin(2 * np.pi * 3.0 * t), atol=1e-12)
