"""One vocabulary for the cam speed at the public entries of the translating, sliding and
rocking followers: a number is Hz (revolutions per second), text carries its unit, as for
``camdyn.simulate()``. ``N rpm``, ``N / 60`` Hz and ``2 pi N / 60 rad/s`` give the same run;
a speed that is not positive and finite is refused with camdyn's error.

The conversions expected here are the definitions of the units (1 rpm = 1/60 rev/s,
1 rev = 2 pi rad), not values read from camdyn.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from camdyn.analysis.poincare import poincare_section
from camdyn.continuation.translating import trace_translating, translating_problem
from camdyn.errors import ParameterError
from camdyn.model.profiles import eccentric_circle
from camdyn.model.rocking_roller import RockingGeometry
from camdyn.params.units import angular_speed
from camdyn.simulation.mechanisms import CamDrive
from camdyn.simulation.rocking_friction import simulate_rocking_friction
from camdyn.simulation.rocking_roller import RockingFollower, simulate_rocking
from camdyn.simulation.sliding import FollowerFriction, simulate_sliding
from camdyn.simulation.translating import alzate_rig, simulate_translating

RPM = 600.0   # the cam speed of every run [rpm]
DURATION = 0.05   # [s], half a revolution at RPM


def _arm():
    """A roller arm on an eccentric circle (radius 25 mm, runout 5 mm, roller 8 mm, arm 60 mm)."""
    profile = eccentric_circle(0.025, 0.005, follower="roller", roller_radius=0.008)
    geometry = RockingGeometry(profile, -0.06, 0.03, 0.06, 0.008, 1)
    return RockingFollower(geometry, 2e-4, 0.5, 0.05, restitution=0.5, samples=2048)


ENTRIES = {   # name: run(speed) -> Dataset
    "simulate_translating": lambda speed: simulate_translating(alzate_rig(), speed, DURATION, sample_rate=2000.0,
                                                               phase=math.pi / 2),
    "simulate_sliding": lambda speed: simulate_sliding(alzate_rig(), FollowerFriction(0.0), speed, DURATION,
                                                       sample_rate=2000.0, phase=math.pi / 2),
    "simulate_rocking": lambda speed: simulate_rocking(_arm(), speed, DURATION, sample_rate=2000.0),
    "simulate_rocking_friction": lambda speed: simulate_rocking_friction(_arm(), FollowerFriction(0.0), speed,
                                                                         DURATION, sample_rate=2000.0),
}


def test_the_three_spellings_of_a_speed_are_one_omega():
    omega = 2 * math.pi * (RPM / 60)   # [rad/s]
    assert angular_speed(f"{RPM} rpm") == omega
    assert angular_speed(RPM / 60) == omega
    assert angular_speed(f"{omega!r} rad/s") == omega
    assert angular_speed(f"{RPM / 60} Hz") == omega


@pytest.mark.parametrize("name", sorted(ENTRIES))
def test_each_entry_reads_rpm_hz_and_rad_per_s_alike(name):
    run = ENTRIES[name]
    omega = 2 * math.pi * (RPM / 60)   # [rad/s]
    runs = [run(f"{RPM} rpm"), run(RPM / 60), run(f"{omega!r} rad/s")]
    for ds in runs:
        assert ds.attrs["speed_rad_s"] == pytest.approx(omega, rel=1e-15)
    first = runs[0]
    variable = "psi" if "psi" in first else "x"
    for other in runs[1:]:
        np.testing.assert_array_equal(other[variable].values, first[variable].values)
        np.testing.assert_array_equal(other.event_time.values, first.event_time.values)


@pytest.mark.parametrize("name", sorted(ENTRIES))
@pytest.mark.parametrize("bad", [0.0, -1.0, math.nan, math.inf, "-600 rpm", "0 Hz", "nan rpm", "3 mm", True, None])
def test_a_speed_that_is_not_positive_and_finite_is_refused(name, bad):
    with pytest.raises(ParameterError, match="speed"):
        ENTRIES[name](bad)


def test_the_continuation_of_the_translating_follower_reads_the_same_vocabulary():
    """The problem's parameter stays omega [rad/s]; its start may be spelled in any unit."""
    omega = 2 * math.pi * (RPM / 60)   # [rad/s]
    for speed in (f"{RPM} rpm", RPM / 60, f"{omega!r} rad/s"):
        assert translating_problem(alzate_rig(), speed).value == omega
    for bad in (0.0, -1.0, math.nan, "-600 rpm", "3 mm"):
        with pytest.raises(ParameterError, match="speed"):
            translating_problem(alzate_rig(), bad)
        with pytest.raises(ParameterError, match="start"):
            trace_translating(alzate_rig(), bad, RPM / 60)
        with pytest.raises(ParameterError, match="stop"):
            trace_translating(alzate_rig(), RPM / 60, bad)


def test_the_poincare_section_reads_the_same_vocabulary():
    omega = 2 * math.pi * (RPM / 60)   # [rad/s]
    runs = [poincare_section(alzate_rig(), speed, transient=0, revolutions=1)
            for speed in (f"{RPM} rpm", [RPM / 60], [f"{omega!r} rad/s"])]
    for section in runs:
        np.testing.assert_allclose(section.speed_rpm.values, [RPM], rtol=1e-15)
        np.testing.assert_array_equal(section.x.values, runs[0].x.values)
    for bad in ([0.0], [-1.0], [math.nan], ["-600 rpm"]):
        with pytest.raises(ParameterError, match="speed"):
            poincare_section(alzate_rig(), bad, transient=0, revolutions=1)


def test_a_drive_takes_its_speeds_as_text_with_units_and_keeps_bare_numbers_in_rad_per_s():
    omega = 2 * math.pi * (RPM / 60)   # [rad/s]
    for text in (f"{RPM} rpm", f"{RPM / 60} Hz", f"{omega!r} rad/s"):
        motor = CamDrive(1e-3, "motor", stall_torque=1.0, free_speed=text)
        assert motor.free_speed == pytest.approx(omega, rel=1e-15)
        assert CamDrive(1e-3, "controller", target_speed=text).target_speed == pytest.approx(omega, rel=1e-15)
    assert CamDrive(1e-3, "motor", stall_torque=1.0, free_speed=omega).free_speed == omega   # documented rad/s
    for bad in ("3 mm", "nan rpm", "fast"):
        with pytest.raises(ParameterError, match="free_speed"):
            CamDrive(1e-3, "motor", stall_torque=1.0, free_speed=bad)
