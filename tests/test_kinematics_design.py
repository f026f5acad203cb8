"""Inverse kinematics and the design map, checked against brute-force simulation."""

import math

import numpy as np
import pytest

from camdyn.analysis.harmonics import harmonic_amplitudes
from camdyn.analysis.kinematics import (
    check_regime,
    contact_start,
    inverse_kinematics,
    loss_of_contact_speed,
)
from camdyn.model.equilibrium import static_equilibrium
from camdyn.simulation.runner import simulate
from camdyn.tribology.design import design_map

A = 17.5e-3


def test_rigid_motion_matches_simulation(friction_rig):
    """Under permanent contact the simulated motion is the rigid-contact motion up to the
    Hertz compliance (delta ~ 1 um over a 90 mm arm: 1e-5 rad) and the resonance's
    small dynamic amplification at 1/85 of f_n (1.4e-4): 1e-3 covers both."""
    system = friction_rig.with_values(**{"cam.runout": 0.1 * A})
    ik = inverse_kinematics(system, 11.55)
    ds = simulate(system, 11.55, revolutions=15)
    first = harmonic_amplitudes(ds, "alpha_ddot", (1,), revolutions=5)[0]
    acc = ik["alpha_ddot"].values
    assert 2 * abs(np.fft.rfft(acc)[1]) / acc.size == pytest.approx(first, rel=1e-3)
    win = ds.isel(time=slice(-2000, None))
    theta = np.mod(win["cam_angle"].values, 2 * math.pi)
    fn = np.interp(theta, ik["cam_angle"].values, ik["Fn"].values, period=2 * math.pi)
    assert np.max(np.abs(win["Fn"].values - fn)) < 1e-3 * np.ptp(win["Fn"].values) + 2e-3


def test_loss_of_contact_speed_matches_simulation(friction_rig):
    """the loss-of-contact speed from inverse kinematics within 2 % of the
    speed at which a simulation first leaves the cam in steady state. Below it the run
    starts on the contact motion (contact_start): from rest at the chapter 4 0-state
    (runout parallel to the follower, the rigid motion at its fastest) the cam strikes
    the follower, and this close to the boundary the follower then stays on an impacting
    motion that coexists with the contact motion. Above it there is no contact motion and
    the run starts from rest; the first two revolutions are left out."""
    system = friction_rig.with_values(**{"cam.runout": 0.1 * A})
    speed = loss_of_contact_speed(system)
    assert 15.0 < speed < 22.0            # about 18.0 Hz for the listed data (docs/thesis-comparison.md)
    below = simulate(system, 0.98 * speed, revolutions=12, initial_state=contact_start(system, 0.98 * speed))
    assert contact_start(system, 1.02 * speed) is None
    above = simulate(system, 1.02 * speed, revolutions=12)
    for ds, expected in ((below, 1), (above, 0)):
        steady = ds["time"].values * ds.attrs["speed_hz"] > 2.0
        assert ds["in_contact"].values[steady].min() == expected


def test_check_regime_and_reasons(friction_rig):
    system = friction_rig.with_values(**{"cam.runout": 0.1 * A})
    ok = check_regime(system, 11.55)
    assert ok.ok and ok.sliding_sign == 1 and ok.reasons() == []
    bad = check_regime(system, 25.0)
    assert not bad.contact_kept
    assert "loses contact" in bad.reasons()[0]
    ik = inverse_kinematics(system, 11.55)
    vr = ik["sliding_velocity"].values
    assert bool(ik.attrs["sliding_reversal"]) == bool(vr.min() < 0 < vr.max())


def test_slide_to_roll_range_fig_4_5(friction_rig):
    """Fig 4.5: vr/ve between 0.75 and 1.25 at e/a = 0.116, 11.55 Hz."""
    ik = inverse_kinematics(friction_rig.with_values(**{"cam.runout": 0.116 * A}), 11.55)
    srr = ik["slide_to_roll"].values
    assert 0.7 < srr.min() < 0.85 and 1.15 < srr.max() < 1.3


def test_design_map_boundary_and_recommendation(friction_rig):
    ratios = np.array([0.1, 0.2])
    speeds = np.linspace(5, 30, 11)
    ds = design_map(friction_rig, "runout", ratios, speeds)
    for i, r in enumerate(ratios):
        loss = loss_of_contact_speed(friction_rig.with_values(**{"cam.runout": r * A}))
        kept = ds["contact_kept"].values[i]
        assert np.all(kept == (speeds < loss))
    rec_r, rec_s = ds.attrs["recommended_ratio"], ds.attrs["recommended_speed"]
    i = list(ratios).index(rec_r)
    j = list(speeds).index(rec_s)
    assert ds["admissible"].values[i, j]
    clear = 5 * speeds[None, :] <= 0.2 * ds["natural_frequency"].values[:, None]
    assert np.all(ds["harmonics_clear"].values == clear)


def test_design_map_refuses_bad_grid(friction_rig):
    from camdyn.errors import ParameterError
    with pytest.raises(ParameterError, match="axis ratios"):
        design_map(friction_rig, "axis_ratio", [1.2], [10.0])
    with pytest.raises(ParameterError, match="axis must be"):
        design_map(friction_rig, "speed", [0.1], [10.0])


def test_contact_start_is_on_the_contact_motion(friction_rig):
    """contact_start gives the rigid-contact angle and rate at Theta0, the angle
    compressed by delta*/chi* (1e-5 rad here), compared with the spectral inverse
    kinematics interpolated linearly to Theta0 (1024 points per revolution: the
    interpolation errs by at most max|f''| dTheta^2 / 8, 3.1e-7 rad for alpha and
    2.3e-5 rad/s for alpha_dot); a run from it never leaves the cam at e/a = 0.3 and
    11.55 Hz, where the required force dips to 0.6 N."""
    system = friction_rig.with_values(**{"cam.runout": 0.3 * A})
    alpha0, rate0 = contact_start(system, 11.55)
    ik = inverse_kinematics(system, 11.55)
    eq = static_equilibrium(system)
    theta0 = np.mod(eq.cam_angle, 2 * math.pi)
    period = dict(period=2 * math.pi)
    assert rate0 == pytest.approx(np.interp(theta0, ik["cam_angle"].values, ik["alpha_dot"].values, **period),
                                  abs=3e-5)
    rigid = np.interp(theta0, ik["cam_angle"].values, ik["alpha"].values, **period)
    assert alpha0 == pytest.approx(rigid - eq.penetration / eq.moment_arm, abs=4e-7)
    ds = simulate(system, 11.55, revolutions=10, initial_state=(alpha0, rate0))
    assert ds["in_contact"].values.min() == 1 and ds.sizes["impact"] == 0
    assert contact_start(system, 13.0) is None          # contact is lost above 12.0 Hz at e/a = 0.3
