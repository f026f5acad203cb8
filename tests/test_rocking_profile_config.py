"""The rocking flat-faced follower's ``[profile]`` table: the TOML system is the one built
in Python with ``dataclasses.replace`` (and simulates bit for bit the same), a CSV table
profile, ``camdyn simulate`` on the file, and refusals before any work."""

import contextlib
import dataclasses
import io
import json
import math
from pathlib import Path

import numpy as np
import pytest

import camdyn
from camdyn.cli.app import main
from camdyn.errors import GeometryError, ParameterError, UnitError, UnknownKeyError
from camdyn.io.system_config import load_system
from camdyn.model.profiles import eccentric_circle, rise_return_profile, tabulated_profile
from camdyn.params import config

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "profiles" / "rocking_flat.toml"
#: The example's cam: a cycloidal rise of 3.5 mm over 120 deg, dwell 60 deg, return, dwell [m, rad].
BASE = 15.75e-3
SEGMENTS = [("cycloidal", 2 * math.pi / 3, 3.5e-3), ("dwell", math.pi / 3, 0.0),
            ("cycloidal", 2 * math.pi / 3, -3.5e-3), ("dwell", math.pi / 3, 0.0)]


def run(*argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main([str(a) for a in argv])
    return status, out.getvalue(), err.getvalue()


def python_system():
    """The example file's system written in Python: the friction preset at 6 Hz with the cam replaced."""
    base = config.load_system("sundar2014-friction").with_values(**{"motion.speed": 6.0})
    toml = camdyn.load_system(EXAMPLE)
    return dataclasses.replace(base, profile=rise_return_profile(SEGMENTS, BASE), name=toml.name,
                               citation=toml.citation)


def with_profile(tmp_path, profile_lines, name="rig.toml"):
    """The example file with its [profile] table replaced by ``profile_lines``."""
    text = EXAMPLE.read_text(encoding="utf-8")
    text = text[:text.index("\n[profile]\n")] + "\n[profile]\n" + "\n".join(profile_lines) + "\n"
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_the_toml_system_is_the_python_one_and_runs_bit_for_bit():
    system, expected = load_system(EXAMPLE), python_system()
    assert system.profile is not None and system == expected
    assert np.array_equal(system.profile.table, expected.profile.table)
    a = camdyn.simulate(system, revolutions=1, sample_rate=2000.0)
    b = camdyn.simulate(expected, revolutions=1, sample_rate=2000.0)
    assert a.attrs["cam_profile"] and a.sizes["time"] > 300
    for name in b.data_vars:
        assert np.array_equal(a[name].values, b[name].values, equal_nan=a[name].dtype.kind == "f"), name


def test_an_eccentric_circle_file_is_the_python_circle(tmp_path):
    path = with_profile(tmp_path, ['kind = "eccentric-circle"', 'radius = "17.5 mm"', 'eccentricity = "1.75 mm"'])
    assert load_system(path).profile == eccentric_circle(17.5e-3, 1.75e-3)


def test_a_csv_table_profile(tmp_path):
    """An eccentric circle sampled in a CSV file (72 rows, mm): the lift of the flat face on
    it is e (1 + cos theta), within the periodic spline's bound 5/384 h^4 max|s''''|."""
    radius, ecc = 17.5e-3, 1.75e-3
    angles = np.arange(72) * 5.0
    lift_mm = 1e3 * ecc * (1.0 + np.cos(np.radians(angles)))
    rows = "\n".join(f"{a:g},{s:.12f}" for a, s in zip(angles, lift_mm))
    (tmp_path / "circle.csv").write_text(f"# e (1 + cos theta)\nangle [deg],lift [mm]\n{rows}\n", encoding="utf-8")
    path = with_profile(tmp_path, ['kind = "tabulated"', 'base_radius = "15.75 mm"', 'file = "circle.csv"'])
    profile = load_system(path).profile
    assert profile == tabulated_profile(np.array([float(f"{s:.12f}") for s in lift_mm]) * 1e-3, radius - ecc)
    theta = np.linspace(0.0, 2 * math.pi, 997)
    s = profile.lift(theta)[0]
    bound = 5 / 384 * math.radians(5.0) ** 4 * ecc
    error = np.max(np.abs(s - ecc * (1 + np.cos(theta))))
    assert bound / 100 < error < bound  # measured 2.6e-10 m against 1.3e-9 m


def test_overrides_of_scalar_profile_keys():
    system = load_system(EXAMPLE, {"profile.base_radius": "16 mm", "motion.speed": "5 Hz"})
    assert system.profile.base_radius == pytest.approx(16e-3, rel=1e-15)
    assert system.motion.speed == 5.0
    assert system.profile == rise_return_profile(SEGMENTS, system.profile.base_radius)


@pytest.mark.parametrize("lines, error, match", [
    (['kind = "rise-return"', 'base_radius = "5 mm"',
      'segments = [{law = "cycloidal", span = "30 deg", lift = "10 mm"}, {law = "dwell", span = "150 deg"},'
      ' {law = "cycloidal", span = "30 deg", lift = "-10 mm"}, {law = "dwell", span = "150 deg"}]'],
     GeometryError, "not convex"),
    (['kind = "eccentric-circle"', 'face = "roller"', 'radius = "17.5 mm"', 'eccentricity = "1.75 mm"'],
     ParameterError, "profile.face"),
    (['kind = "eccentric-circle"', 'face = "knife"', 'radius = "17.5 mm"', 'eccentricity = "1.75 mm"'],
     ParameterError, "profile.face"),
    (['kind = "eccentric-circle"', 'radius = "17.5 kg"', 'eccentricity = "1.75 mm"'], UnitError, "profile.radius"),
    (['kind = "eccentric-circle"', 'radius = 0.0175', 'eccentricity = "1.75 mm"'], UnitError, "profile.radius"),
    (['kind = "eccentric-circle"', 'radius = "17.5 mm"', 'eccentricty = "1.75 mm"'], UnknownKeyError,
     "profile.eccentricity"),
    (['kind = "eccentric-circle"', 'radius = "17.5 mm"', 'eccentricity = "1.75 mm"', 'offset = "1 mm"'],
     UnknownKeyError, "profile.offset"),
    (['kind = "eccentric-circle"', 'base_radius = "17.5 mm"', 'eccentricity = "1.75 mm"'], UnknownKeyError,
     "profile.base_radius"),
])
def test_bad_profiles_are_refused_naming_the_key(tmp_path, lines, error, match):
    with pytest.raises(error, match=match):
        load_system(with_profile(tmp_path, lines))


def test_readers_and_writer_that_build_the_ellipse_refuse_a_profile():
    with pytest.raises(ParameterError, match=r"\[profile\]"):
        config.load_system(EXAMPLE)
    with pytest.raises(ParameterError, match=r"\[profile\]"):
        config.system_from_toml(EXAMPLE.read_text(encoding="utf-8"))
    system = load_system(EXAMPLE)
    with pytest.raises(ParameterError, match="cannot be written back"):
        config.system_to_toml(system)
    ellipse = config.system_from_toml(config.system_to_toml(system, ignore_profile=True))
    assert ellipse == dataclasses.replace(system, profile=None)


def test_simulate_on_the_file(tmp_path):
    status, out, err = run("simulate", EXAMPLE, "--revolutions", "1", "--sample-rate", "2kHz", "--json",
                           "--set", "profile.base_radius=16mm")
    assert status == 0, err
    summary = json.loads(out)["summary"]
    ds = camdyn.simulate(load_system(EXAMPLE, {"profile.base_radius": "16 mm"}), revolutions=1,
                         sample_rate=2000.0)
    assert summary["impacts"] == ds.sizes.get("impact", 0)
    assert summary["Fn_max_N"] == float(ds.Fn.max()) and summary["Fn_min_N"] == float(ds.Fn.min())


@pytest.mark.parametrize("argv, match", [
    (["--set", "profile.face=roller"], "profile.face"),
    (["--set", "profile.base_radius=16kg"], "profile.base_radius"),
    (["--set", "profile.segments=cycloidal"], "profile.segments"),
    (["--set", "profile.radius=1mm"], "profile.radius"),
])
def test_bad_input_is_one_line_with_status_2(argv, match):
    status, out, err = run("simulate", EXAMPLE, "--revolutions", "1", *argv)
    assert status == 2
    assert len(err.strip().splitlines()) == 1 and match in err


def test_presets_show_writes_a_file_and_refuses_a_profile(tmp_path):
    plain = tmp_path / "plain.toml"
    plain.write_text(config.preset_text("sundar2014-friction"), encoding="utf-8")
    status, out, err = run("presets", "show", plain)
    assert status == 0, err
    assert config.system_from_toml(out) == config.load_system("sundar2014-friction")
    status, out, err = run("presets", "show", EXAMPLE)
    assert status == 2 and len(err.strip().splitlines()) == 1 and "cannot be written back" in err
