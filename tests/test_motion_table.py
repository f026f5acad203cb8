"""A cam angle tabulated over one period (periodic cubic spline): a table of the
oscillating motion reproduces the oscillating cam, a table of constant speed the constant
speed, and bad tables are refused."""

import math

import numpy as np
import pytest

import camdyn
from camdyn.errors import ParameterError
from camdyn.simulation.mechanisms import simulate_tabulated, tabulated_motion
from camdyn.simulation.runner import prepare


def test_a_table_of_the_oscillation_reproduces_the_oscillating_cam(friction_rig):
    # Theta0 + 0.3 sin(2 pi 3 t) sampled at 400 points a period: the spline's error is
    # about (5/384) 0.3 (omega h)^4 ~ 2e-10 rad (the clamped cubic's bound, de Boor 1978)
    s = friction_rig.with_values(**{"motion.kind": "oscillating", "motion.amplitude": 0.6, "motion.frequency": 3.0,
                                    "friction.law": "tanh"})
    prep = prepare(s)
    reference = camdyn.simulate(s, revolutions=0.12, sample_rate=20e3, rtol=1e-11, atol=1e-13)
    times = np.linspace(0.0, 1 / 3.0, 401)
    angles = prep.theta0 + 0.3 * np.sin(2 * np.pi * 3.0 * times)
    ds = simulate_tabulated(s, times, angles, duration=float(reference.time[-1]), sample_rate=20e3, rtol=1e-11,
                            atol=1e-13)
    t = ds.time.values
    np.testing.assert_allclose(ds.cam_angle.values, prep.theta0 + 0.3 * np.sin(2 * np.pi * 3.0 * t), atol=1e-9)
    np.testing.assert_allclose(ds.cam_speed.values, 0.3 * 6 * np.pi * np.cos(6 * np.pi * t), atol=1e-6)
    scale = np.max(np.abs(reference.alpha.values))
    np.testing.assert_allclose(ds.alpha.values, reference.alpha.values, rtol=0, atol=1e-6 * scale)


def test_a_table_of_constant_speed_turns_the_cam_at_that_speed(friction_rig):
    s = friction_rig.with_values(**{"motion.speed": 11.55})
    prep = prepare(s)
    omega = s.motion.angular_speed
    reference = camdyn.simulate(s, revolutions=1, sample_rate=20e3, rtol=1e-11, atol=1e-13)
    times = np.linspace(0.0, 1 / 11.55, 9)
    ds = simulate_tabulated(s, times, prep.theta0 + omega * times, periods=1, sample_rate=20e3, rtol=1e-11,
                            atol=1e-13)
    np.testing.assert_allclose(ds.cam_angle.values, prep.theta0 + omega * ds.time.values, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ds.cam_speed.values, omega, rtol=1e-13)
    scale = np.max(np.abs(reference.alpha.values))
    np.testing.assert_allclose(ds.alpha.values, reference.alpha.values, rtol=0, atol=1e-6 * scale)


def test_the_spline_is_periodic_to_its_second_derivative():
    times = np.linspace(0.0, 0.5, 21)
    rng = np.random.default_rng(3)
    angles = rng.normal(size=times.size) + 4 * math.pi * times / 0.5
    angles[-1] = angles[0] + 4 * math.pi
    period, mean_speed, a = tabulated_motion(times, angles)
    assert period == 0.5 and mean_speed == pytest.approx(8 * math.pi)
    a = a.reshape(-1, 4)
    h = times[1]
    end = [a[-1, 0] + h * (a[-1, 1] + h * (a[-1, 2] + h * a[-1, 3])), a[-1, 1] + h * (2 * a[-1, 2] + 3 * a[-1, 3] * h),
           2 * a[-1, 2] + 6 * a[-1, 3] * h]
    np.testing.assert_allclose(end, [a[0, 0], a[0, 1], 2 * a[0, 2]], rtol=1e-10, atol=1e-9)
    # it interpolates: the knots' values plus the drift are the table
    np.testing.assert_allclose(a[:, 0] + mean_speed * times[:-1], angles[:-1], rtol=0, atol=1e-12)


@pytest.mark.parametrize("times, angles, words", [
    ([0.0, 0.1, 0.2], [0.0, 0.1, 0.2], "at least 4 samples"),
    ([0.0, 0.1, 0.3, 0.4], [0.0, 0.1, 0.2, 0.3], "uniform steps"),
    ([0.1, 0.2, 0.3, 0.4], [0.0, 0.1, 0.2, 0.3], "start at 0 s"),
    ([0.0, 0.1, 0.2, 0.3], [0.0, math.nan, 0.2, 0.3], "finite"),
])
def test_bad_tables_are_refused(times, angles, words):
    with pytest.raises(ParameterError, match=words):
        tabulated_motion(times, angles)
