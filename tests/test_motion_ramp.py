"""The ramp of the cam speed (uniform acceleration, then constant speed): the cam angle
against its closed form, a run-up from rest against the independent SciPy model, a
slow-down to a stop, and the refusal of a ramp without a duration."""

import math

import numpy as np
import pytest

import camdyn
from camdyn.errors import ParameterError
from camdyn.simulation.runner import prepare
from camdyn.testing.oracle import reference_simulate

RAMP = {"motion.kind": "ramp", "friction.law": "tanh", "motion.ramp_time": 0.1}


def _closed_form(t, theta0, start, end, duration):
    """Cam angle [rad] and speed [rad/s]: speed linear in time from ``start`` to ``end``
    [rad/s] over ``duration`` [s], then constant; the angle is its integral."""
    before = t < duration
    speed = np.where(before, start + (end - start) * t / duration, end)
    angle = np.where(before, theta0 + start * t + (end - start) * t ** 2 / (2 * duration),
                     theta0 + (start + end) * duration / 2 + end * (t - duration))
    return angle, speed


def test_a_run_up_from_rest_agrees_with_scipy(friction_rig):
    s = friction_rig.with_values(**RAMP, **{"motion.speed": 11.55, "motion.start_speed": 0.0})
    prep = prepare(s)
    ds = camdyn.simulate(s, duration=0.15, sample_rate=20e3, rtol=1e-11, atol=1e-13)
    t = ds.time.values
    angle, speed = _closed_form(t, prep.theta0, 0.0, 2 * math.pi * 11.55, 0.1)
    np.testing.assert_allclose(ds.cam_angle.values, angle, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ds.cam_speed.values, speed, rtol=0, atol=1e-10)
    _, ref, _ = reference_simulate(s, prep.theta0, prep.y0, t[-1], t, prep.viscous_c, method="DOP853",
                                   rtol=1e-12, atol=1e-14)
    scale = np.max(np.abs(ref[0]))
    np.testing.assert_allclose(ds.alpha.values, ref[0], rtol=0, atol=1e-6 * scale)
    np.testing.assert_allclose(ds.alpha_dot.values, ref[1], rtol=0, atol=1e-6 * np.max(np.abs(ref[1])))


def test_a_slow_down_stops_the_cam(friction_rig):
    s = friction_rig.with_values(**RAMP, **{"motion.speed": 0.0, "motion.start_speed": 8.0,
                                            "motion.direction": -1})
    prep = prepare(s)
    ds = camdyn.simulate(s, duration=0.2, sample_rate=10e3, rtol=1e-10, atol=1e-12)
    t = ds.time.values
    angle, speed = _closed_form(t, prep.theta0, -2 * math.pi * 8.0, 0.0, 0.1)
    np.testing.assert_allclose(ds.cam_angle.values, angle, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ds.cam_speed.values, speed, rtol=0, atol=1e-10)
    # stopped: the cam turned 0.4 revolution clockwise and stays there
    assert ds.cam_angle.values[-1] - prep.theta0 == pytest.approx(-0.4 * 2 * math.pi, rel=1e-12)


def test_a_ramp_needs_a_duration(friction_rig):
    with pytest.raises(ParameterError, match="ramp_time > 0"):
        friction_rig.with_values(**{"motion.kind": "ramp"})
    with pytest.raises(ParameterError, match="start_speed"):
        friction_rig.with_values(**{"motion.kind": "ramp", "motion.ramp_time": 0.1, "motion.start_speed": -1.0})
