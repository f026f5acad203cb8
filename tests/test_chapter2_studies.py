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
from camdyn.simulation import prepare


def test_stand_in_loses_contact_where_the_thesis_says(impacting_standin):
    """The impacting stand-in is built to lose contact near the thesis's 130 rpm."""
    assert loss_of_contact_speed(impacting_standin) * 60 == pytest.approx(130, rel=0.03)


@pytest.mark.parametrize("xi", [0.05, 0.6])
def test_energy_balance_small_amplitude_limit(impacting_standin, xi):
    """Small speeds: 0.5 K0 x^2 = 0.5 I ((1 + xi) e Omega / chi*)^2 with K0 the free
    follower's stiffness about alpha*."""
    prep = prepare(impacting_standin)
    a0, chi = prep.equilibrium.angle, prep.equilibrium.moment_arm
    inertia = impacting_standin.follower.inertia
    h = 1e-6
    k0 = -inertia * (free_acceleration(a0 + h, prep.p) - free_acceleration(a0 - h, prep.p)) / (2 * h)
    hz = 0.05
    expected = (1 + xi) * impacting_standin.cam.runout * 2 * math.pi * hz / chi * math.sqrt(inertia / k0)
    assert energy_balance_residual(impacting_standin, [hz], xi)[0] == pytest.approx(expected, rel=1e-3)


def test_energy_balance_grows_with_speed_and_restitution_and_saturates(impacting_standin):
    speeds = np.array([1.0, 2.0, 5.0, 15.0, 1e4])
    low = energy_balance_residual(impacting_standin, speeds, 0.2)
    high = energy_balance_residual(impacting_standin, speeds, 0.6)
    assert np.all(np.diff(low) > 0) and np.all(high > low)
    a0 = prepare(impacting_standin).equilibrium.angle
    assert low[-1] == pytest.approx(0.5 * math.pi - a0, abs=1e-5)  # the follower reaches 90 degrees


def test_energy_balance_refusals(impacting_standin):
    with pytest.raises(ParameterError, match="restitution"):
        energy_balance_residual(impacting_standin, [1.0], 1.5)
    with pytest.raises(ParameterError, match="speeds"):
        energy_balance_residual(impacting_standin, [-1.0], 0.5)
