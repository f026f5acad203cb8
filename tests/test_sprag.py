"""Sprag (self-locking) of two followers on one cam (examples/mechanisms/sprag.toml): the
jam condition mu h = chi in closed form from the geometry, a run below it that never
wedges and one above it that does, and the sprag margin against the geometry."""

import math
from pathlib import Path

import numpy as np
import pytest

from camdyn.io.mechanism_config import load_mechanism, simulate_mechanism

SPRAG = str(Path(__file__).resolve().parents[1] / "examples" / "mechanisms" / "sprag.toml")


def _arm(system, alpha, theta):
    """Moment arm chi [m] of the normal force about the pivot, in closed form for a circular
    cam of radius a and runout e: the contact point is G - a n, so chi = u.G with
    u = (cos alpha, -sin alpha) and G = E - e (cos Theta, sin Theta)."""
    e = system.cam.runout
    gx, gy = system.cam.pivot_x - e * np.cos(theta), system.cam.pivot_y - e * np.sin(theta)
    return np.cos(alpha) * gx - np.sin(alpha) * gy


def _jam_coefficients(system) -> tuple[float, float]:
    """The friction coefficients between which a follower sliding backwards wedges once a
    turn: rigid contact (sin(alpha) Gx + cos(alpha) Gy = h + a) gives
    chi = sqrt(|G|^2 - (h + a)^2), smallest and largest at |G| = |E| -+ e, and the margin
    chi - mu h vanishes at mu = chi / h."""
    h, a, e = system.follower.surface_offset, system.cam.semi_major, system.cam.runout
    reach = math.hypot(system.cam.pivot_x, system.cam.pivot_y)
    return (math.sqrt((reach - e) ** 2 - (h + a) ** 2) / h, math.sqrt((reach + e) ** 2 - (h + a) ** 2) / h)


def _run(mu: float):
    mechanism = load_mechanism(SPRAG, {"system.friction.coefficient": mu})
    return mechanism, simulate_mechanism(mechanism, revolutions=1.5, sample_rate=50e3)


def test_the_jam_coefficients_of_the_sprag_geometry():
    mechanism = load_mechanism(SPRAG)
    low, high = _jam_coefficients(mechanism.system)
    assert (round(low, 3), round(high, 3)) == (0.424, 0.904)
    assert low < mechanism.system.friction.coefficient < high


@pytest.mark.parametrize("below", [True, False])
def test_a_follower_wedges_above_the_jam_coefficient_and_not_below(below):
    # below mu* the margin of rigid contact stays positive; the compliant run, whose
    # angle departs from rigid contact as the normal force grows, wedges from a little
    # above it (at 1.1 mu* its margin closed to 33 um and the follower left the cam
    # first): the file's mu = 0.5 is 1.18 mu*
    low, _ = _jam_coefficients(load_mechanism(SPRAG).system)
    mu = 0.9 * low if below else 0.5
    mechanism, ds = _run(mu)
    s, h = mechanism.system, mechanism.system.follower.surface_offset
    theta = ds["cam_angle"].values
    wedges = 0
    for k, frame in ((1, theta), (2, theta - math.pi)):
        one = ds.sel(follower=k)
        sliding = (one["in_contact"].values > 0.5) & (one["sliding_velocity"].values < 0.0)
        assert sliding.mean() > 0.5
        # the margin is the geometry's chi - mu h (Ff = mu s Fn, s = -1)
        margin = _arm(s, one["alpha"].values, frame) - mu * h
        np.testing.assert_allclose(one["sprag_margin"].values[sliding], margin[sliding], rtol=0, atol=1e-12)
        wedged = (ds["transition_kind"].values == "sprag") & (ds["transition_follower"].values == k)
        wedges += int(wedged.sum())
        if below:
            assert margin[sliding].min() > 0.0
        elif wedged.any():
            # the first sprag: the margin of the samples around it crosses zero, where
            # mu h = chi of the geometry
            when = ds["transition_time"].values[wedged][0]
            j = int(np.searchsorted(ds["time"].values, when))
            assert margin[j - 1] > 0.0 > margin[j]
    assert (wedges == 0) if below else (wedges >= 1)
