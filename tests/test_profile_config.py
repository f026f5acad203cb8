"""Translating-follower configurations: TOML with units, CSV profiles with units in their
header, and their refusals. Expected lifts are closed forms written here (the cycloidal
law, the support function of an eccentric circle), not camdyn's own evaluation."""

import math

import numpy as np
import pytest

from camdyn.errors import DataError, GeometryError, ParameterError, PresetError, UnitError, UnknownKeyError
from camdyn.io.lift_table import load_translating, read_lift_table
from camdyn.params.config import list_presets, load_system
from camdyn.params.profiles import is_translating, list_translating_presets, read_translating
from camdyn.simulation.translating import alzate_rig

BASE = """
[follower]
kind = "translating"
face = "flat"
mass = "0.5 kg"

[spring]
stiffness = "2 kN/m"
preload = "20 N"

[motion]
speed = "600 rpm"
"""

RISE_RETURN = BASE + """
[profile]
kind = "rise-return"
base_radius = "40 mm"
segments = [{law = "cycloidal", span = "120 deg", lift = "10 mm"},
            {law = "dwell", span = "60 deg"},
            {law = "cycloidal", span = "120 deg", lift = "-10 mm"},
            {law = "dwell", span = "60 deg"}]
"""

ECCENTRIC = BASE + """
[profile]
kind = "eccentric-circle"
radius = "25 mm"
eccentricity = "5 mm"
"""


def write(tmp_path, text, name="rig.toml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_alzate_preset_equals_alzate_rig():
    follower, spec = load_translating("alzate")
    rig = alzate_rig()
    # the arcs are written with the source's digits: the packed tables agree to the bit
    np.testing.assert_array_equal(follower.profile.table, rig.profile.table)
    assert (follower.profile.follower, follower.profile.base_radius) == ("knife", rig.profile.base_radius)
    for name in ("mass", "stiffness", "damping", "gravity", "contact", "restitution", "capture_velocity"):
        assert getattr(follower, name) == getattr(rig, name), name
    # 143.08 N in the file; alzate_rig computes k (0.40 - 0.30) = 143.08000000000004 N
    assert follower.preload == pytest.approx(rig.preload, rel=1e-15)
    assert follower.citation == rig.citation
    assert spec.speed == pytest.approx(358 * 2 * math.pi / 60, rel=1e-15)
    assert spec.phase == pytest.approx(math.pi / 2, rel=1e-15)


def test_translating_presets_are_apart_from_the_rocking_ones():
    assert "alzate" in list_translating_presets() and "alzate" not in list_presets()
    assert is_translating("alzate") and not is_translating("sundar2014-impact")
    with pytest.raises(PresetError, match="translating follower"):
        load_system("alzate")


def test_rise_return_lift_is_the_cycloidal_law(tmp_path):
    follower, spec = load_translating(write(tmp_path, RISE_RETURN))
    assert (spec.mass, spec.stiffness, spec.preload, spec.speed) == pytest.approx((0.5, 2000.0, 20.0, 20 * math.pi))
    theta = np.radians(np.linspace(0.0, 359.0, 360))
    u = theta / math.radians(120.0)
    rise = 0.010 * (u - np.sin(2 * math.pi * u) / (2 * math.pi))            # Norton 2009, cycloidal
    u_back = (theta - math.radians(180.0)) / math.radians(120.0)
    back = 0.010 * (1 - (u_back - np.sin(2 * math.pi * u_back) / (2 * math.pi)))
    expected = np.select([theta < math.radians(120), theta < math.radians(180), theta < math.radians(300)],
                         [rise, 0.010, back], 0.0)
    np.testing.assert_allclose(follower.profile.lift(theta)[0], expected, rtol=0, atol=1e-15)


def test_eccentric_circle_lift_is_its_support_function(tmp_path):
    follower, spec = load_translating(write(tmp_path, ECCENTRIC))
    theta = np.linspace(0.0, 2 * math.pi, 50)
    assert spec.base_radius == pytest.approx(0.020)
    np.testing.assert_allclose(follower.profile.lift(theta)[0], 0.005 * (1 + np.cos(theta)), rtol=0, atol=1e-15)


@pytest.mark.parametrize("column, closing", [("lift", False), ("radius", False), ("lift", True)])
def test_csv_profile_sampled_from_an_eccentric_circle(tmp_path, column, closing):
    n = 72
    degrees = np.arange(n + (1 if closing else 0)) * 360.0 / n
    lift_mm = 5.0 * (1 + np.cos(np.radians(degrees)))             # flat face on R = 25 mm, e = 5 mm
    values = lift_mm + (20.0 if column == "radius" else 0.0)      # radius = r_base + s
    rows = "\n".join(f"{float(a)!r},{float(s)!r}" for a, s in zip(degrees, values))
    (tmp_path / "cam.csv").write_text(f"# eccentric circle\nangle [deg],{column} [mm]\n{rows}\n")
    text = BASE + '[profile]\nkind = "tabulated"\nbase_radius = "20 mm"\nfile = "cam.csv"\n'
    follower, spec = load_translating(write(tmp_path, text))
    theta = np.linspace(0.0, 2 * math.pi, 1001)
    h = 2 * math.pi / n
    bound = 5.0 / 384.0 * h ** 4 * 0.005          # Hall and Meyer 1976: 5/384 h^4 max|s''''|, s'''' = e cos
    error = np.max(np.abs(follower.profile.lift(theta)[0] - 0.005 * (1 + np.cos(theta))))
    assert error <= bound
    assert error > bound / 100    # a spline, not the closed form: the bound is not vacuous


def csv_error(tmp_path, text, **kwargs):
    path = tmp_path / "cam.csv"
    path.write_text(text)
    with pytest.raises(DataError) as info:
        read_lift_table(path, 0.02, **kwargs)
    return str(info.value)


def test_csv_refusals(tmp_path):
    good = "\n".join(f"{a},{5 * (1 + math.cos(math.radians(a)))}" for a in range(0, 360, 30))
    assert "line 5" in csv_error(tmp_path, "angle [deg],lift [mm]\n" + good.replace("\n90,", "\n91,"))
    assert "in brackets" in csv_error(tmp_path, "angle,lift\n" + good)
    assert "not a length" in csv_error(tmp_path, "angle [deg],lift [s]\n" + good)
    assert "not an angle" in csv_error(tmp_path, "angle [mm],lift [mm]\n" + good)
    assert "offset 0" in csv_error(tmp_path, "angle [deg],radius [mm]\n" + good, offset=0.001)
    assert "inside the base circle" in csv_error(tmp_path, "angle [deg],radius [mm]\n" + good)
    assert "at least 8" in csv_error(tmp_path, "angle [deg],lift [mm]\n0,1\n90,2\n180,1\n270,0\n")
    assert "line 3" in csv_error(tmp_path, "angle [deg],lift [mm]\n0,1\n30,x\n")


def error_of(tmp_path, text, overrides=None):
    with pytest.raises((ParameterError, UnitError, UnknownKeyError, GeometryError, DataError)) as info:
        load_translating(write(tmp_path, text), overrides)
    return info.type, str(info.value)


@pytest.mark.parametrize("edit, error, words", [
    ({"follower.mas": "1 kg"}, UnknownKeyError, "follower.mass"),
    ({"spring.stiffness": "2 kg"}, UnitError, "spring.stiffness"),
    ({"spring.preload": "20"}, UnitError, "has no unit"),
    ({"follower.mass": "-1 kg"}, ParameterError, "follower.mass must be positive"),
    ({"contact.restitution": "1.5"}, ParameterError, "contact.restitution"),
    ({"follower.face": "roller"}, ParameterError, "follower.roller_radius"),
    ({"profile.radius": "2 mm"}, GeometryError, "eccentricity"),
    ({"contact.law": "compliant"}, ParameterError, "contact.stiffness"),
    ({"profile.base_radius": "40 mm"}, UnknownKeyError, "eccentric-circle"),
])
def test_toml_refusals_name_the_key(tmp_path, edit, error, words):
    kind, message = error_of(tmp_path, ECCENTRIC, edit)
    assert kind is error and words in message, message


def test_refusals_inside_the_profile(tmp_path):
    no_unit = RISE_RETURN.replace('span = "60 deg"}]', 'span = 60}]')
    assert "profile.segments[3].span" in error_of(tmp_path, no_unit)[1]
    bare = RISE_RETURN.replace('span = "60 deg"}]', 'span = "60"}]')
    assert "has no unit" in error_of(tmp_path, bare)[1]
    typo = RISE_RETURN.replace('{law = "dwell", span = "60 deg"},', '{law = "dwell", spam = "60 deg"},')
    assert "profile.segments[1].spam; did you mean span" in error_of(tmp_path, typo)[1]
    # a cycloidal rise of 10 mm over 120 deg on a 1 mm base circle: r_base + s + s'' < 0 near
    # u = 3/4 of the rise (s'' = -2 pi L / beta^2 there), so the flat-faced cam is not convex
    steep = RISE_RETURN.replace('"40 mm"', '"1 mm"')
    kind, message = error_of(tmp_path, steep)
    assert kind is GeometryError and "not convex" in message and " deg" in message
    missing = RISE_RETURN.replace('mass = "0.5 kg"\n', "")
    assert "missing key 'follower.mass'" in error_of(tmp_path, missing)[1]


def test_overrides_take_units():
    spec = read_translating("alzate", {"spring.preload": "150 N", "motion.speed": "660 rpm"})
    assert (spec.preload, spec.speed) == pytest.approx((150.0, 660 * 2 * math.pi / 60))
    with pytest.raises(UnknownKeyError, match="motion.speed"):
        read_translating("alzate", {"motion.spead": "1 rpm"})
