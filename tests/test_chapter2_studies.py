"""Chapter 2 studies: the energy-balance restitution estimate, the impact map against the
contact model, friction direction and friction laws."""

import math

import numpy as np
import pytest

import camdyn
from camdyn.analysis.kinematics import loss_of_contact_speed
from camdyn.analysis.restitution import energy_balance_residual
from camdyn.errors import ParameterError
from camdyn.model.dynamics import free_acceleration
from camdyn.simulation.runner import prepare


def test_stand_in_loses_contact_where_the_thesis_says(impacting_standin):
    """The impacting stand-in is built to lose contact near the thesis's 130 rpm."""
    assert loss_of_contact_speed(impacting_standin) * 60 == pytest.approx(130, rel=0.03)


@pytest.mark.parametrize("xi", [0.05, 0.6])
def test_energy_balance_small_amplitude_limit(impacting_standin, xi):
    """Small excursions x: the free follower's potential is M0 x + 0.5 K0 x^2 (M0 the
    preload moment the cam carries at rest, K0 the spring's stiffness about alpha*), set
    equal to T = 0.5 I ((1 + xi) e Omega / chi*)^2."""
    prep = prepare(impacting_standin)
    a0, chi = prep.equilibrium.angle, prep.equilibrium.moment_arm
    inertia = impacting_standin.follower.inertia
    h = 1e-6
    k0 = -inertia * (free_acceleration(a0 + h, prep.p) - free_acceleration(a0 - h, prep.p)) / (2 * h)
    m0 = -inertia * free_acceleration(a0, prep.p)
    assert m0 > 0
    hz = 0.2
    kinetic = 0.5 * inertia * ((1 + xi) * impacting_standin.cam.runout * 2 * math.pi * hz / chi) ** 2
    expected = (-m0 + math.sqrt(m0 ** 2 + 2 * k0 * kinetic)) / k0
    assert energy_balance_residual(impacting_standin, [hz], xi)[0] == pytest.approx(expected, rel=1e-3)


def test_energy_balance_grows_with_speed_and_restitution_and_saturates(impacting_standin):
    speeds = np.array([1.0, 2.0, 5.0, 15.0, 1e4])
    low = energy_balance_residual(impacting_standin, speeds, 0.2)
    high = energy_balance_residual(impacting_standin, speeds, 0.6)
    assert np.all(np.diff(low) > 0) and np.all(high[:-1] > low[:-1])
    a0 = prepare(impacting_standin).equilibrium.angle
    assert low[-1] == pytest.approx(0.5 * math.pi - a0, abs=1e-5)  # the follower reaches 90 degrees


def test_energy_balance_refusals(impacting_standin):
    with pytest.raises(ParameterError, match="restitution"):
        energy_balance_residual(impacting_standin, [1.0], 1.5)
    with pytest.raises(ParameterError, match="speeds"):
        energy_balance_residual(impacting_standin, [-1.0], 0.5)


def test_impact_map_is_the_rigid_limit_of_the_contact_model(impact_rig):
    """Instantaneous restitution (eqs 3.24-3.27) against the contact model (Flores law),
    friction off, the impact map given the contact model's own per-impact restitution:
    the gap in approach velocity and impact phase shrinks with the contact duration as
    the contact is made stiffer (duration ~ k^-0.4)."""
    from camdyn.simulation.impact_map import simulate_impact_map
    rig = impact_rig.with_values(**{"friction.coefficient": 0.0})
    hz = 15.0
    gaps = []
    for scale in (1.0, 1000.0):
        stiff = rig.with_values(**{"contact.damping": "flores", "contact.restitution": 0.6,
                                   "cam.youngs_modulus": 210e9 * scale, "follower.youngs_modulus": 210e9 * scale})
        contact = camdyn.simulate(stiff, speed=hz, revolutions=40)
        assert contact.sizes["impact"] == 40  # one impact per revolution
        xi = float(contact.impact_separation_velocity[-1] / contact.impact_approach_velocity[-1])
        rigid = simulate_impact_map(rig, hz, revolutions=40, restitution=xi)
        velocity_gap = abs(float(contact.impact_approach_velocity[-1] / rigid.impact_approach_velocity[-1]) - 1)
        phase_gap = abs(float(contact.impact_time[-1] - rigid.impact_time[-1])) * hz
        gaps.append((velocity_gap, phase_gap))
    assert gaps[0][0] < 0.01 and gaps[0][1] < 0.005
    assert gaps[1][0] < gaps[0][0] / 8 and gaps[1][1] < gaps[0][1] / 8


def _fig_2_10_rig(rig, direction):
    """Thesis figs 2.10-2.11: 1.6 mm line contact, damping law D (zeta 0.01, beta 4.25 s/m)."""
    return rig.with_values(**{"contact.length": 1.6e-3, "contact.damping": "D", "contact.damping_ratio": 0.01,
                              "contact.beta": 4.25, "motion.direction": direction})


def test_self_energizing_rotation_raises_the_mean_normal_force(standin_rig):
    """Friction's moment h Ff about the pivot adds to or takes from the contact moment:
    statically Fn = M / (chi -/+ mu h), so the two directions' mean Fn differ by the
    ratio (chi + mu h)/(chi - mu h) (to first order in e the cam's motion averages out)."""
    means, arms = {}, {}
    for direction in (1, -1):
        ds = camdyn.simulate(_fig_2_10_rig(standin_rig, direction), speed=5.0, revolutions=10, sample_rate=20e3)
        win = ds.isel(time=slice(ds.sizes["time"] // 2, None))
        means[direction] = float(win.Fn.mean())
        arms[direction] = float(win.moment_arm.mean())
    mu, h = standin_rig.friction.coefficient, 0.5 * standin_rig.follower.width
    chi = 0.5 * (arms[1] + arms[-1])
    high, low = max(means.values()), min(means.values())
    assert high / low == pytest.approx((chi + mu * h) / (chi - mu * h), rel=2e-3)


def oscillating_rig(rig):
    """Thesis figs 2.14-2.15: e = 0.7 rc, the cam swinging Theta_p = pi rad at 40 rpm; the
    stand-in's cam pivot raised to the 0-state (h + rc + e) and its spring given enough
    preload to follow the larger lift."""
    e = 0.7 * rig.cam.semi_major
    return rig.with_values(**{"cam.runout": e, "cam.pivot_y": 0.5 * rig.follower.width + rig.cam.semi_major + e,
                              "spring.free_length": 0.085, "motion.kind": "oscillating",
                              "motion.amplitude": math.pi, "motion.frequency": 40 / 60})


def test_coulomb_and_tanh_friction_differ_only_where_vr_reverses(standin_rig):
    """Thesis 2.7.2: sigma = 10 s/m tanh friction equals Coulomb friction while |vr| is
    large; under the oscillating cam vr reverses twice a cycle and the laws differ there
    only."""
    def forces(system, law):
        ds = camdyn.simulate(system.with_values(**{"friction.law": law}), revolutions=2, sample_rate=10e3)
        win = ds.isel(time=slice(ds.sizes["time"] // 2, None))
        return win.Ff.values, win.sliding_velocity.values

    steady = standin_rig.with_values(**{"motion.speed": 5.0})
    ff_c, vr = forces(steady, "coulomb")
    ff_t, _ = forces(steady, "tanh")
    assert np.all(np.abs(vr) > 0.3)
    assert np.max(np.abs(ff_c - ff_t)) < 1e-4 * np.max(np.abs(ff_c))
    ff_c, vr = forces(oscillating_rig(standin_rig), "coulomb")
    ff_t, _ = forces(oscillating_rig(standin_rig), "tanh")
    assert np.mean(vr > 0) == pytest.approx(0.5, abs=0.1)   # vr < 0 for about half the cycle
    gap = np.abs(ff_c - ff_t)
    scale = np.max(np.abs(ff_c))
    assert gap.max() > 0.3 * scale                           # at the reversals
    # the slow swing keeps |vr| below 0.17 m/s, where tanh(10 vr) is not yet 1: the gap is
    # the law's own shortfall 1 - tanh(sigma |vr|), the motion being all but unchanged
    shortfall = np.abs(ff_c) * (1 - np.tanh(10 * np.abs(vr)))
    assert np.max(np.abs(gap - shortfall)) < 0.02 * scale
