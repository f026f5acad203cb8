"""``camdyn simulate`` on a translating follower: the preset and TOML files dispatch on
``[follower] kind``, the summary counts the run's events, the outputs are written, and bad
input is one line with exit status 2."""

import contextlib
import io
import json
import math

import numpy as np
import pytest
import xarray as xr

from camdyn.cli.app import main
from camdyn.io.lift_table import load_translating
from camdyn.simulation.translating import simulate_translating


def run(*argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main([str(a) for a in argv])
    return status, out.getvalue(), err.getvalue()


def test_alzate_preset_summary_and_outputs(tmp_path):
    nc, png = tmp_path / "run.nc", tmp_path / "run.png"
    status, out, err = run("simulate", "alzate", "--revolutions", "6", "--sample-rate", "2kHz", "--json",
                           "--out", nc, "--plot", png)
    assert status == 0, err
    document = json.loads(out)
    assert document["schema"] == "camdyn.simulate-translating/1"
    summary = document["summary"]
    # the same run through the Python interface: counts and the largest force agree
    rig, spec = load_translating("alzate")
    omega = 358 * 2 * math.pi / 60
    ds = simulate_translating(rig, omega / (2 * math.pi), 6 * 2 * math.pi / omega, sample_rate=2000.0,
                              phase=math.pi / 2)
    kinds = ds.event_kind.values
    assert summary["impacts"] == np.count_nonzero(kinds == "impact") > 0
    assert summary["separations"] == np.count_nonzero(kinds == "separation") >= 1
    assert summary["contact_force_max_N"] == pytest.approx(float(ds.contact_force.max()), rel=1e-9)
    assert summary["speed_rpm"] == pytest.approx(358.0)
    assert summary["liftoff_speed_rpm"] == pytest.approx(114.98, abs=0.01)
    saved = xr.load_dataset(nc, engine="h5netcdf")
    assert saved.x.attrs["units"] == "m" and saved.sizes["time"] == ds.sizes["time"]
    assert png.stat().st_size > 10_000
    assert [f["path"] for f in document["files"]] == [str(nc), str(png)]


def test_toml_file_and_overrides(tmp_path):
    (tmp_path / "cam.toml").write_text("""
[follower]
kind = "translating"
face = "flat"
mass = "0.5 kg"
[spring]
stiffness = "2 kN/m"
preload = "20 N"
[profile]
kind = "eccentric-circle"
radius = "25 mm"
eccentricity = "5 mm"
""")
    # without a speed: refused before any work
    status, _, err = run("simulate", tmp_path / "cam.toml")
    assert status == 2 and "motion.speed" in err and err.count("\n") == 1
    status, out, err = run("simulate", tmp_path / "cam.toml", "--speed", "300rpm", "--revolutions", "4",
                           "--set", "spring.preload=30N")
    assert status == 0, err
    # an eccentric circle at 300 rpm: m e w^2 = 0.5 * 5e-3 * 31.4^2 = 2.5 N < F0, always in contact
    assert "impacts" in out and "0 (0 per revolution)" in out


@pytest.mark.parametrize("argv, words", [
    (["--set", "spring.prelod=3N"], "spring.preload"),
    (["--set", "follower.mass=3 m"], "follower.mass"),
    (["--method", "rosenbrock"], "--method"),
    (["--speed", "-5rpm"], "speed"),
])
def test_bad_input_is_one_line_exit_2(argv, words):
    status, _, err = run("simulate", "alzate", "--revolutions", "1", *argv)
    assert status == 2 and words in err and err.count("\n") == 1, err


def test_presets_list_and_show():
    status, out, _ = run("presets")
    assert status == 0 and "alzate " in out.replace("│", " ")
    status, out, _ = run("presets", "show", "alzate")
    assert status == 0 and 'kind = "translating"' in out


def test_a_misspelt_follower_kind_is_named(tmp_path):
    (tmp_path / "cam.toml").write_text('[follower]\nkind = "translatng"\nmass = "1 kg"\n')
    status, _, err = run("simulate", tmp_path / "cam.toml")
    assert status == 2 and "'translatng'" in err and "translating" in err and err.count("\n") == 1, err


def test_bifurcation_of_a_translating_follower(tmp_path):
    out = tmp_path / "section.nc"
    status, stdout, err = run("bifurcation", "alzate", "--speeds", "100rpm,150rpm", "--revolutions", "5",
                              "--discard", "3", "--out", out)
    assert status == 0, err
    section = xr.load_dataset(out, engine="h5netcdf")
    assert list(section.speed_rpm.values) == pytest.approx([100.0, 150.0])
    # below lift-off (114.98 rpm) on the cam; at 150 rpm captured again before cam angle 0
    np.testing.assert_array_equal(section.x.values, 0.0)
    assert section.sizes["revolution"] == 2 and (tmp_path / "section.png").is_file()
    status, _, err = run("bifurcation", "alzate", "--workers", "2", "--out", tmp_path / "other.nc")
    assert status == 2 and "--workers" in err and err.count("\n") == 1


@pytest.mark.parametrize("argv", [["continue", "roller-friction", "--from", "5Hz", "--to", "6Hz"],
                                  ["bifurcation", "roller-friction", "--speeds", "5Hz:6Hz:3"]])
def test_friction_at_the_contact_is_refused_where_it_would_be_ignored(argv, tmp_path):
    """The continuation and the diagram integrate the translating follower without its
    [friction] table; with one they refuse rather than return another system's results."""
    status, out, err = run(*argv, "--out", tmp_path / "x.nc")
    assert status == 2 and "does not take friction at the cam contact" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "x.nc").exists()
