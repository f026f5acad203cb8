"""``camdyn.simulate`` on a configuration of any family by its preset name or file: the
same run as the family's own entry, its speed in ``speed_hz`` [Hz], and the options only
the thesis's follower takes refused before any work."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import camdyn
from camdyn.errors import ParameterError

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "models" / "valve_train.py"


def test_a_translating_preset_by_name_is_the_entrys_own_run():
    from camdyn.io.lift_table import load_translating
    from camdyn.simulation.translating import simulate_translating

    ds = camdyn.simulate("alzate", speed="358 rpm", revolutions=2)
    follower, spec = load_translating("alzate")
    omega = 358 * 2 * math.pi / 60
    own = simulate_translating(follower, "358 rpm", 2 * 2 * math.pi / omega, sample_rate=20e3, phase=spec.phase)
    assert np.array_equal(ds["x"].values, own["x"].values)
    assert ds.attrs["speed_hz"] == pytest.approx(358 / 60, rel=1e-14)


def test_a_mechanism_preset_by_name_is_the_entrys_own_run():
    from camdyn.io.mechanism_config import load_mechanism, simulate_mechanism

    ds = camdyn.simulate("flexible-pivot", revolutions=1, sample_rate=5e3)
    own = simulate_mechanism(load_mechanism("flexible-pivot"), revolutions=1, sample_rate=5e3)
    assert np.array_equal(ds["alpha"].values, own["alpha"].values)
    assert ds.attrs["speed_hz"] == pytest.approx(16.0)   # the file's 16 Hz


@pytest.mark.parametrize("source, speed", [("rocking-roller", None), ("roller-friction", None),
                                           (f"{EXAMPLE}:VALVE_TRAIN", "2400 rpm"), ("sundar2014-impact", 16.0)])
def test_every_family_by_name_gives_its_speed_in_hz(source, speed):
    ds = camdyn.simulate(source, speed=speed, revolutions=1)
    assert ds.attrs["speed_hz"] > 0 and ds.sizes["time"] > 10
    if speed is not None:
        assert ds.attrs["speed_hz"] == pytest.approx(40.0 if speed == "2400 rpm" else speed)


def test_options_of_the_thesis_follower_only_are_refused_for_another_family():
    with pytest.raises(ParameterError, match="variables.*speed, revolutions, sample_rate and rtol"):
        camdyn.simulate("drum-brake", revolutions=2, variables=["alpha"])
    with pytest.raises(ParameterError, match="revolutions must be positive"):
        camdyn.simulate("drum-brake", revolutions=-1)
    with pytest.raises(camdyn.PresetError, match="no preset named"):
        camdyn.simulate("drum-brak", revolutions=1)
