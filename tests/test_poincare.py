"""The Poincaré section of the translating follower (the bifurcation diagram's data)."""

import math

import numpy as np
import pytest

from camdyn.analysis.poincare import poincare_section
from camdyn.errors import ParameterError
from camdyn.plotting.translating import plot_poincare_diagram
from camdyn.simulation.translating import alzate_rig, simulate_translating


@pytest.fixture(scope="module")
def rig():
    return alzate_rig()


def test_below_and_just_above_liftoff(rig):
    # lift-off at 114.98 rpm (docs/profiles.md): at 100 rpm the follower rides the cam; at
    # 150 rpm it leaves the nose once a revolution and is captured back before the base
    # dwell, so at cam angle 0 (mid-dwell) it rests on the base circle: x = 0, x_dot = 0
    section = poincare_section(rig, ["100 rpm", "150 rpm"], transient=3, revolutions=4)
    assert list(section.status.values) == ["ok", "ok"]
    np.testing.assert_array_equal(section.x.values, 0.0)
    np.testing.assert_array_equal(section.x_dot.values, 0.0)
    assert section.impacts_per_revolution.values[0] == 0 and section.separations_per_revolution.values[0] == 0
    assert section.separations_per_revolution.values[1] == 1 and section.impacts_per_revolution.values[1] > 10


def test_one_revolution_map_continues_the_run(rig, tmp_path):
    # iterating one-revolution runs gives the states of one continuous run at cam angle 0
    # (660 rpm: the follower never settles on the cam). Measured over three revolutions:
    # 1.6e-14 m and 2.2e-13 m/s; the bounds are about 50 times that.
    rpm = 660.0
    section = poincare_section(rig, [rpm / 60], transient=0, revolutions=3)   # [Hz]
    omega = rpm * 2 * math.pi / 60
    ds = simulate_translating(rig, omega / (2 * math.pi), 3 * 2 * math.pi / omega,
                              sample_rate=128 * omega / (2 * math.pi))
    np.testing.assert_allclose(section.x.values[0], ds.x.values[128::128], rtol=0, atol=1e-12)
    np.testing.assert_allclose(section.x_dot.values[0], ds.x_dot.values[128::128], rtol=0, atol=1e-11)
    assert np.all(section.x.values[0] > 0.0)     # in flight at cam angle 0
    plot_poincare_diagram(section, tmp_path / "diagram.png", {"660 rpm": rpm})
    assert (tmp_path / "diagram.png").stat().st_size > 5_000


@pytest.mark.parametrize("kwargs", [{"speeds": [-1.0]}, {"speeds": []}, {"speeds": ["-300 rpm"]}, {"speeds": [0.0]},
                                    {"transient": 1.5}, {"revolutions": 0}])
def test_refusals(rig, kwargs):
    arguments = {"speeds": [5.0], "transient": 1, "revolutions": 1, **kwargs}
    with pytest.raises(ParameterError):
        poincare_section(rig, **arguments)
