"""The thesis's tables (docs/model.md section 5) and closed-form limits of the simulation."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

import camdyn
from camdyn.analysis.harmonics import harmonic_amplitudes, steady_window
from camdyn.cli.demo import TABLE_4_5
from camdyn.simulation.runner import prepare
from camdyn.testing.oracle import ReferenceModel

#: Thesis table 4.6 (e/a = 0.1): speed [Hz] -> first harmonic of alpha_ddot [rad/s^2].
TABLE_4_6 = {2: 3.24, 5: 20.26, 8: 51.77, 11: 97.9, 14: 158.5, 17: 233.8, 21: 356.7}


def first_two_harmonics(system, ratio, speed):
    s = system.with_values(**{"cam.runout": ratio * system.cam.semi_major})
    revs = max(12, int(0.15 * speed) + 12)  # contact transients die in ~0.1 s
    ds = camdyn.simulate(s, speed=speed, revolutions=revs, sample_rate=max(20e3, 400 * speed))
    # the start from rest may bounce once; the steady window is what the tables describe
    return harmonic_amplitudes(ds, "alpha_ddot", (1, 2), revolutions=8), steady_window(ds, 8)


def kinematic_harmonics(system, ratio, speed, n=512):
    """Rigid-contact (inverse kinematics) limit: solve delta(alpha, Theta) = 0 with the
    independent parametric geometry of camdyn.testing.oracle, then differentiate spectrally."""
    s = system.with_values(**{"cam.runout": ratio * system.cam.semi_major, "motion.speed": speed})
    model = ReferenceModel(s, theta0=0.0)
    omega = 2 * math.pi * speed
    t = np.arange(n) / (n * speed)
    alpha = np.array([brentq(lambda a: model.geometry(tt, a, 0.0)[0], -0.5, 0.5, xtol=1e-15) for tt in t])
    c = np.fft.rfft(alpha) / n
    k = np.arange(c.size)
    acc = -(k * omega) ** 2 * 2 * np.abs(c)
    return np.abs(acc[1]), np.abs(acc[2])


@pytest.mark.parametrize("ratio", [0.05, 0.30])
def test_compliant_contact_tends_to_rigid_kinematics(friction_rig, ratio):
    # closed-form limit: far below the ~1 kHz contact resonance the follower follows
    # the rigid-contact cam lift; the difference scales as (f / f_n)^2 ~ 1e-4
    (h1, h2), _ = first_two_harmonics(friction_rig, ratio, 11.55)
    k1, k2 = kinematic_harmonics(friction_rig, ratio, 11.55)
    assert h1 == pytest.approx(k1, rel=2e-3)
    assert h2 == pytest.approx(k2, rel=5e-3)


@pytest.mark.parametrize("ratio", sorted(TABLE_4_5))
def test_table_4_5_second_harmonic_within_20_percent(friction_rig, ratio):
    (h1, h2), ds = first_two_harmonics(friction_rig, ratio, 11.55)
    assert int(ds.in_contact.min()) == 1
    assert h2 == pytest.approx(TABLE_4_5[ratio][1], rel=0.20)


@pytest.mark.xfail(strict=True, reason="camdyn is +4.5 % on table 4.5's first harmonic (the target was 3 %); "
                                       "see docs/thesis-comparison.md")
def test_table_4_5_first_harmonic_within_3_percent(friction_rig):
    # camdyn is +4.5 % on every row (docs/thesis-comparison.md): the thesis's two tables
    # disagree with each other by 2.7 % at the same operating point (next test), and
    # camdyn equals the rigid-contact kinematics of docs/model.md's geometry to 0.2 %
    # (test_compliant_contact_tends_to_rigid_kinematics). Strict: if a defensible
    # reading of the geometry closes the gap, this starts passing and must be promoted.
    (h1, _), _ = first_two_harmonics(friction_rig, 0.10, 11.55)
    assert h1 == pytest.approx(TABLE_4_5[0.10][0], rel=0.03)


def test_thesis_tables_disagree_with_each_other():
    # table 4.6 follows alpha_ddot_1 = c f^2 with c = 0.809 rad/s^2/Hz^2; at 11.55 Hz that is
    # 107.9 rad/s^2, 2.7 % above table 4.5's 105.0 for the same e/a = 0.1
    c = np.mean([v / f ** 2 for f, v in TABLE_4_6.items()])
    assert c * 11.55 ** 2 / TABLE_4_5[0.10][0] - 1 == pytest.approx(0.027, abs=0.003)


@pytest.mark.parametrize("speed", [2, 5, 8, 11, 14, 17])
def test_table_4_6_first_harmonic_within_10_percent(friction_rig, speed):
    (h1, _), ds = first_two_harmonics(friction_rig, 0.10, speed)
    assert int(ds.in_contact.min()) == 1
    assert h1 == pytest.approx(TABLE_4_6[speed], rel=0.10)


def test_table_4_6_at_21_hz_loses_contact(friction_rig):
    # docs/model.md section 5: with the listed spring data the rig loses contact near
    # 18.5 Hz at e/a = 0.1, so the thesis's 21 Hz row (permanent contact) cannot hold
    _, ds = first_two_harmonics(friction_rig, 0.10, 21.0)
    assert int(ds.in_contact.min()) == 0


def test_natural_frequency_matches_free_vibration(friction_rig):
    # linearized natural frequency (Jacobian at equilibrium) against the ring-down of the
    # nonlinear model: frozen cam, no damping, no friction, small initial velocity
    s = friction_rig.with_values(**{"motion.speed": 0.0, "contact.damping": "none", "friction.law": "none"})
    prep = prepare(s)
    fn = prep.equilibrium.natural_frequency
    ds = camdyn.simulate(s, duration=0.2, sample_rate=100e3, initial_state=(prep.equilibrium.angle, 1e-4))
    x = ds.alpha.values - prep.equilibrium.angle
    crossings = np.nonzero(np.diff(np.sign(x)) > 0)[0]
    t = ds.time.values
    # interpolate the upward zero crossings; their spacing is the period
    tc = t[crossings] - x[crossings] * (t[crossings + 1] - t[crossings]) / (x[crossings + 1] - x[crossings])
    measured = 1.0 / np.mean(np.diff(tc))
    assert measured == pytest.approx(fn, rel=2e-3)
