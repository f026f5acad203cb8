"""Units, configuration files, presets and bad input."""

import math

import pytest

import camdyn
from camdyn.errors import (
    GeometryError,
    ParameterError,
    PresetError,
    UnitError,
    UnknownKeyError,
)
from camdyn.params.config import load_system, system_to_toml
from camdyn.params.units import parse_quantity, parse_speed


@pytest.mark.parametrize("text, hz", [("11.55Hz", 11.55), ("693 rpm", 11.55), ("11.55 1/s", 11.55),
                                      (f"{2 * math.pi * 11.55} rad/s", 11.55), (16, 16.0)])
def test_speed_units(text, hz):
    # pint alone would read '11.55 Hz' as 11.55 rad/s; speeds are revolutions per second
    assert parse_speed(text) == pytest.approx(hz, rel=1e-12)


def test_quantities_convert_to_si():
    assert parse_quantity("17.5 mm", "m") == pytest.approx(0.0175)
    assert parse_quantity("3300 kg*mm^2", "kg*m**2") == pytest.approx(3.3e-3)
    assert parse_quantity("24.7 GN*s/m^2.5", "N*s/m**2.5") == pytest.approx(24.7e9)


@pytest.mark.parametrize("text", ["17 kg", "seventeen mm", "12 parsecs/fortnight", ""])
def test_bad_units_raise(text):
    with pytest.raises(UnitError):
        parse_quantity(text, "m", "cam.radius")


def test_presets_load_and_cite():
    names = camdyn.list_presets()
    assert {"sundar2014-impact", "sundar2014-friction", "alzate2007-standin"} <= set(names)
    for name in names:
        system = load_system(name)
        assert system.citation, name


def test_preset_values_match_the_thesis(impact_rig, friction_rig):
    # docs/model.md section 4
    assert impact_rig.follower.inertia == pytest.approx(3.3e-3)
    assert impact_rig.follower.cg_distance == pytest.approx(0.086)
    assert impact_rig.contact.beta == pytest.approx(24.7e9)
    assert friction_rig.spring.stiffness == pytest.approx(2954.0)
    assert (friction_rig.cam.pivot_x, friction_rig.cam.pivot_y) == pytest.approx((0.086, 0.024))


@pytest.mark.parametrize("preset", ["sundar2014-impact", "sundar2014-friction", "alzate2007-standin",
                                    "alzate2007-standin-impacting"])
def test_toml_round_trip(tmp_path, preset):
    rig = load_system(preset)
    path = tmp_path / "rig.toml"
    path.write_text(system_to_toml(rig))  # citations hold apostrophes and quotes
    again = load_system(path)
    assert again == rig


def test_overrides_by_dotted_key():
    s = load_system("sundar2014-friction", {"cam.runout": "3.5 mm", "cam.semi_minor": "15 mm"})
    assert s.cam.runout == pytest.approx(3.5e-3)
    assert (s.cam.semi_major, s.cam.semi_minor) == pytest.approx((0.0175, 0.015))


@pytest.mark.parametrize("overrides, error, words", [
    ({"follower.mass": "-0.2 kg"}, ParameterError, "positive"),
    ({"follower.mass": "nan kg"}, ParameterError, "finite"),
    ({"cam.runoot": "1 mm"}, UnknownKeyError, "cam.runout"),
    ({"cam.runout": "1 kg"}, UnitError, "not convertible"),
    ({"cam.runout": "20 mm"}, GeometryError, "inside the cam"),
    ({"cam.pivot_y": "200 mm"}, GeometryError, "cannot reach"),
    ({"contact.damping": "magic"}, ParameterError, "contact.damping"),
    ({"contact.beta": "1 N*s/m"}, UnitError, "not convertible"),
])
def test_bad_input_is_refused_clearly(overrides, error, words):
    with pytest.raises(error, match=words):
        s = load_system("sundar2014-impact", overrides)
        camdyn.simulate(s, revolutions=1)


def test_unknown_preset():
    with pytest.raises(PresetError, match="sundar2014-impact"):
        load_system("sundar2014-impakt")
