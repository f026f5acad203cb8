"""The rocking roller's configuration files and ``camdyn simulate`` on them: the TOML
example builds the follower written in Python, the command's summary counts the same run,
and bad input is one line with exit status 2."""

import contextlib
import io
import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from camdyn.cli.app import main
from camdyn.errors import ParameterError, UnitError, UnknownKeyError
from camdyn.io.rocking_config import load_rocking
from camdyn.model.profiles import rise_return_profile
from camdyn.model.rocking_roller import RockingGeometry
from camdyn.simulation.rocking_roller import RockingFollower, simulate_rocking

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "profiles" / "rocking_roller.toml"


def run(*argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main([str(a) for a in argv])
    return status, out.getvalue(), err.getvalue()


def python_follower():
    """The example file's follower written again in Python."""
    cam = rise_return_profile([("cycloidal", 2 * math.pi / 3, 8e-3), ("dwell", math.pi / 3, 0.0),
                               ("cycloidal", 2 * math.pi / 3, -8e-3), ("dwell", math.pi / 3, 0.0)], 30e-3)
    arm = RockingGeometry(cam, -0.07, 0.04, 0.07, 8e-3, 1)
    return RockingFollower(arm, inertia=2e-4, stiffness=0.5, preload=0.05, restitution=0.5)


def test_the_example_file_is_the_python_follower():
    follower, spec = load_rocking(EXAMPLE)
    expected = python_follower()
    assert follower == expected
    np.testing.assert_allclose(follower.geometry.profile.table, expected.geometry.profile.table, rtol=1e-15, atol=0)
    assert spec.profile.speed == pytest.approx(650 * 2 * math.pi / 60, rel=1e-15)


def test_simulate_on_the_example_file(tmp_path):
    nc = tmp_path / "run.nc"
    status, out, err = run("simulate", EXAMPLE, "--revolutions", "3", "--sample-rate", "2kHz", "--json",
                           "--out", nc)
    assert status == 0, err
    document = json.loads(out)
    assert document["schema"] == "camdyn.simulate-rocking/1"
    summary = document["summary"]
    omega = 650 * 2 * math.pi / 60
    ds = simulate_rocking(python_follower(), omega / (2 * math.pi), 3 * 2 * math.pi / omega, sample_rate=2000.0)
    kinds = ds.event_kind.values
    assert summary["impacts"] == np.count_nonzero(kinds == "impact") > 10
    assert summary["separations"] == np.count_nonzero(kinds == "separation") >= 2
    assert summary["contact_force_max_N"] == pytest.approx(float(ds.contact_force.max()), rel=1e-9)
    saved = xr.load_dataset(nc, engine="h5netcdf")
    assert saved.psi.attrs["units"] == "rad" and saved.contact_force.attrs["units"] == "N"


@pytest.mark.parametrize("change, error, match", [
    ({"spring.prelod": "1 N*m"}, UnknownKeyError, "spring.preload"),
    ({"spring.stiffness": "0.5 N/m"}, UnitError, "spring.stiffness"),
    ({"follower.face": "flat"}, ParameterError, "follower.face"),
    ({"follower.lift_direction": "up"}, ParameterError, "lift_direction"),
    ({"follower.roller_radius": "0 mm"}, ParameterError, "roller_radius"),
    ({"profile.face": "knife"}, ParameterError, "profile.face"),
    ({"profile.base_radius": "-3 mm"}, ParameterError, "profile.base_radius"),
])
def test_bad_files_are_refused_with_the_key(change, error, match):
    with pytest.raises(error, match=match):
        load_rocking(EXAMPLE, change)


def test_bad_input_is_one_line_with_status_2(tmp_path):
    for argv in (("--set", "spring.prelod=1 N*m"), ("--set", "follower.arm_length=10 mm"),
                 ("--plot", tmp_path / "run.png")):
        status, out, err = run("simulate", EXAMPLE, "--revolutions", "1", *argv)
        assert status == 2 and err.startswith("error:") and len(err.strip().splitlines()) == 1, (argv, err)
