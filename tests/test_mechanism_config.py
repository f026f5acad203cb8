"""The mechanisms in TOML (``[mechanism] kind = ...``): the example files run bitwise as
the Python presets, ``camdyn simulate`` writes a readable netCDF file with units, every
bad key is refused by name with exit status 2 before any work, and ``camdyn presets
show`` writes a file that reads back to the same mechanism."""

import contextlib
import io
import json
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from camdyn.cli.app import main
from camdyn.errors import ParameterError, UnknownKeyError
from camdyn.io.mechanism_config import load_mechanism, simulate_mechanism
from camdyn.params.config import load_system
from camdyn.simulation.flexible_pivot import chapter3_flexible_pivot, simulate_flexible_pivot
from camdyn.simulation.mechanisms import CamDrive, simulate_driven_cam
from camdyn.simulation.two_followers import drum_brake, simulate_two_followers

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "mechanisms"


def run(*argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main([str(a) for a in argv])
    return status, out.getvalue(), err.getvalue()


def assert_same_run(left: xr.Dataset, right: xr.Dataset):
    """Every variable and coordinate of two runs bitwise equal, with the same units."""
    assert set(left.variables) == set(right.variables)
    for name in right.variables:
        a, b = left[name].values, right[name].values
        assert a.shape == b.shape, name
        if a.dtype.kind == "f":
            assert np.array_equal(a, b, equal_nan=True), name
        else:
            assert (a == b).all(), name
        assert left[name].attrs.get("units") == right[name].attrs.get("units"), name


def test_drum_brake_file_runs_as_the_preset():
    mechanism = load_mechanism(EXAMPLES / "drum_brake.toml")
    rig = drum_brake()
    assert (mechanism.system, mechanism.drive, mechanism.spec.placement) == (rig.system, rig.drive, rig.placement)
    ds = simulate_mechanism(mechanism, revolutions=0.3, sample_rate=5e3)
    reference = simulate_two_followers(rig.system, rig.drive, rig.second, rig.placement, revolutions=0.3,
                                       sample_rate=5e3)
    assert_same_run(ds, reference)
    # with a stick phase: the static friction key gives the Python argument
    sticking = load_mechanism(EXAMPLES / "drum_brake.toml", {"second.static_friction": "0.35"})
    ds = simulate_mechanism(sticking, revolutions=0.3, sample_rate=5e3)
    reference = simulate_two_followers(rig.system, rig.drive, rig.second, rig.placement, revolutions=0.3,
                                       sample_rate=5e3, static_friction=0.35)
    assert_same_run(ds, reference)
    # follower 2 changed from follower 1 by the [second.system] table
    stiffer = load_mechanism(EXAMPLES / "drum_brake.toml", {"second.system.spring.stiffness": "3200 N/m"})
    second = rig.second.with_values(**{"spring.stiffness": 3200.0})
    assert stiffer.second == second and stiffer.system == rig.system
    reference = simulate_two_followers(rig.system, rig.drive, second, rig.placement, revolutions=0.3,
                                       sample_rate=5e3)
    assert_same_run(simulate_mechanism(stiffer, revolutions=0.3, sample_rate=5e3), reference)


def test_flexible_pivot_file_runs_as_the_preset():
    mechanism = load_mechanism(EXAMPLES / "flexible_pivot.toml")
    rig = chapter3_flexible_pivot()
    assert (mechanism.system, mechanism.spec.pivot_stiffness, mechanism.pivot_damping) == tuple(rig)
    ds = simulate_flexible_pivot(*rig, revolutions=0.3, sample_rate=5e3)
    assert_same_run(simulate_mechanism(mechanism, revolutions=0.3, sample_rate=5e3), ds)


def test_driven_cam_command_writes_the_python_run(tmp_path):
    nc = tmp_path / "driven.nc"
    status, out, err = run("simulate", EXAMPLES / "driven_cam.toml", "--revolutions", "0.5", "--sample-rate",
                           "5kHz", "--out", nc, "--json")
    assert status == 0, err
    document = json.loads(out)
    assert document["schema"] == "camdyn.simulate-mechanism/2"
    # the docs' Python example: the rig at 11.55 Hz on a motor running free at 1.2 times that
    system = load_system("sundar2014-friction")
    drive = CamDrive(shaft_inertia=3e-4, kind="motor", stall_torque=1.0, free_speed=2.0 * math.pi * 13.86)
    reference = simulate_driven_cam(system, drive, revolutions=0.5, sample_rate=5e3)
    saved = xr.load_dataset(nc, engine="h5netcdf")
    assert_same_run(saved[list(reference.data_vars)], reference)
    assert saved.cam_speed.attrs["units"] == "rad/s" and saved.contact_torque.attrs["units"] == "N m"
    assert saved.attrs["mechanism"] == "driven-cam"
    summary = document["summary"]
    assert summary["coefficient_of_fluctuation"] == reference.attrs["coefficient_of_fluctuation"]
    assert summary["speed_max_rad_s"] == float(reference.cam_speed.max())
    assert [f["path"] for f in document["files"]] == [str(nc)]


def test_summary_table_names_units(tmp_path):
    status, out, err = run("simulate", EXAMPLES / "drum_brake.toml", "--revolutions", "0.3", "--sample-rate",
                           "5kHz", "--set", "second.static_friction=0.35")
    assert status == 0, err
    for row in ("coefficient of speed fluctuation", "rpm", "N m", "sticks / slips / reversals",
                "followers 1 / 2"):
        assert row in out


BASE = """
[mechanism]
kind = {kind}
system = "sundar2014-friction"
[system.environment]
gravity = "0 m/s^2"
"""
DRIVE = """
[drive]
shaft_inertia = "2e-4 kg*m^2"
torque = "0.1 N*m"
"""


@pytest.mark.parametrize("kind, extra, key", [
    ("two-followers", DRIVE + "torgue = \"1 N*m\"\n", "drive.torgue"),
    ("two-followers", DRIVE.replace("2e-4", "-2e-4"), "drive.shaft_inertia"),
    ("three-followers", DRIVE, "mechanism.kind"),
    ("[1, 2]", DRIVE, "mechanism.kind"),
    ("driven-cam", DRIVE + "[second]\nplacement = \"90 deg\"\n", "second.placement"),
    ("two-followers", DRIVE + "[pivot]\nstiffness = \"1e7 N/m\"\n", "pivot.stiffness"),
    ("flexible-pivot", "[pivot]\nstiffness = \"1e7 N/m\"\n" + DRIVE, "drive.shaft_inertia"),
    ("two-followers", DRIVE + "stall_torque = \"1 N*m\"\n", "drive.stall_torque"),
    ("two-followers", DRIVE.replace('"0.1 N*m"', "0.1"), "drive.torque"),
    ("two-followers", DRIVE.replace("kg*m^2", "kg"), "drive.shaft_inertia"),
    ("driven-cam", DRIVE.replace('torque = "0.1 N*m"', 'kind = "motor"'), "drive.free_speed"),
    ("driven-cam", DRIVE + "bearing_speed = \"0 rad/s\"\n", "drive.bearing_speed"),
    ("flexible-pivot", "[pivot]\nstiffness = \"1e7 N/m\"\n", "pivot.damping"),
    ("flexible-pivot", "[pivot]\nstiffness = \"1e7 N/m\"\ndamping = \"10 N*s/m\"\ndamping_ratio = 0.1\n",
     "pivot.damping_ratio"),
    ("flexible-pivot", "[pivot]\nstiffness = \"1e7 N/m\"\ndamping = \"-1 N*s/m\"\n", "pivot.damping"),
    ("two-followers", DRIVE + "[second]\nstatic_friction = [0.4, 0.4, 0.4]\n", "second.static_friction"),
    ("two-followers", DRIVE + "[system.cam]\nrunnout = \"2 mm\"\n", "cam.runnout"),
])
def test_bad_keys_are_refused_by_name(tmp_path, kind, extra, key):
    path = tmp_path / "bad.toml"
    path.write_text(BASE.format(kind=kind if kind.startswith("[") else f'"{kind}"') + extra)
    nc = tmp_path / "never.nc"
    status, out, err = run("simulate", path, "--out", nc)
    assert status == 2, (out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and key in lines[0] and "bad.toml" in lines[0], err
    assert not nc.exists()


@pytest.mark.parametrize("assignment, words", [
    ("second.static_friction=0.1", "must not be below the kinetic one"),     # mu_s < mu = 0.3
    ("system.environment.gravity=9.8 m/s^2", "environment.gravity = 0"),   # placement with gravity
    ("drive.kind=turbine", "drive.kind"),
])
def test_physical_refusals_before_any_work(tmp_path, assignment, words):
    status, out, err = run("simulate", EXAMPLES / "drum_brake.toml", "--set", assignment)
    assert status == 2 and words in err and len(err.strip().splitlines()) == 1, err


def test_overrides_and_unit_of_speeds():
    mechanism = load_mechanism(EXAMPLES / "driven_cam.toml", {"drive.free_speed": "900 rpm",
                                                              "system.cam.runout": "2 mm"})
    assert mechanism.drive.free_speed == 2.0 * math.pi * 15.0          # 900 rpm = 15 rev/s
    assert mechanism.system.cam.runout == 2e-3
    mechanism = load_mechanism(EXAMPLES / "driven_cam.toml", {"drive.free_speed": "90 rad/s"})
    assert mechanism.drive.free_speed == 90.0
    with pytest.raises(UnknownKeyError, match="drive.target_speed"):
        load_mechanism(EXAMPLES / "driven_cam.toml", {"drive.target_speed": "10 Hz"})
    with pytest.raises(ParameterError, match="drive.free_speed"):
        load_mechanism(EXAMPLES / "driven_cam.toml", {"drive.free_speed": "90"})


def test_stick_slip_file_is_the_python_example():
    # examples/two_followers.py: the drum brake under a PI controller, mu_s = 0.4, from 2 rad/s
    mechanism = load_mechanism(EXAMPLES / "drum_brake_stick_slip.toml")
    rig = drum_brake()
    drive = CamDrive(shaft_inertia=2e-4, kind="controller", proportional=0.01, integral=0.5, target_speed=2.0)
    assert (mechanism.system, mechanism.second, mechanism.drive) == (rig.system, rig.second, drive)
    assert (mechanism.spec.initial_speed, mechanism.spec.static_friction, mechanism.spec.placement) == (
        2.0, 0.4, rig.placement)


@pytest.mark.parametrize("name, assignments", [
    ("drum_brake", ()), ("flexible_pivot", ()), ("driven_cam", ()),
    ("drum_brake", ("second.system.spring.stiffness=3200 N/m", "second.static_friction=0.35",
                    "drive.initial_speed=70 rad/s")),
])
def test_presets_show_reads_back(tmp_path, name, assignments):
    source = EXAMPLES / f"{name}.toml"
    if assignments:   # the same changes written into the file (presets show takes no --set)
        source = tmp_path / "changed.toml"
        text = (EXAMPLES / f"{name}.toml").read_text()
        text = text.replace('[second]\n', '[second]\nstatic_friction = 0.35\n')
        text = text.replace('[drive]\n', '[drive]\ninitial_speed = "70 rad/s"\n')
        source.write_text(text + '\n[second.system.spring]\nstiffness = "3200 N/m"\n')
    status, out, err = run("presets", "show", source)
    assert status == 0, err
    written = tmp_path / "shown.toml"
    written.write_text(out)
    assert "system =" not in out    # the whole system is written in [system.*] tables
    again, first = load_mechanism(written), load_mechanism(source)
    assert again.system == first.system and again.drive == first.drive and again.second == first.second
    assert again.pivot_damping == first.pivot_damping and again.spec.placement == first.spec.placement
    assert again.spec.static_friction == first.spec.static_friction
    assert again.spec.initial_speed == first.spec.initial_speed
    if assignments:
        assert first.second.spring.stiffness == 3200.0 and first.spec.initial_speed == 70.0


@pytest.mark.parametrize("example, labels", [
    ("drum_brake.toml", ["rad/s", "deg", "$F_n$ [N]", "$F_f$ [N]"]),
    ("flexible_pivot.toml", ["deg", "pivot [µm]", "N]"]),
    ("driven_cam.toml", ["rad/s", "deg", "$F_n$ [N]", "torque [N m]"]),
])
def test_plot_draws_each_body_from_the_run_in_its_units(tmp_path, monkeypatch, example, labels):
    from camdyn.plotting import layout_problems, style
    seen = []

    def hook(fig):
        seen.append({"problems": layout_problems(fig),
                     "ylabels": [ax.get_ylabel() for ax in fig.axes if ax.get_ylabel()],
                     "lines": {ax.get_ylabel(): [line.get_ydata() for line in ax.get_lines()
                                                 if len(line.get_ydata()) > 2] for ax in fig.axes}})
    monkeypatch.setattr(style, "SAVE_HOOKS", [hook])
    nc, png = tmp_path / "run.nc", tmp_path / "run.png"
    status, _, err = run("simulate", EXAMPLES / example, "--revolutions", "1.5", "--sample-rate", "4kHz",
                         "--out", nc, "--plot", png)
    assert status == 0, err
    assert png.stat().st_size > 10_000
    drawn = seen[-1]
    assert drawn["problems"] == [], drawn["problems"]
    for label, shown in zip(labels, drawn["ylabels"]):
        assert label in shown, (label, shown)
    ds = xr.load_dataset(nc, engine="h5netcdf")
    # the follower angle panel holds the run's alpha in degrees over the last revolution(s)
    angle = next(v for k, v in drawn["lines"].items() if "deg" in k)
    alpha = np.degrees(ds["alpha"].values)
    alpha = alpha if alpha.ndim == 1 else alpha[:, 0]
    assert np.array_equal(angle[0], alpha[-angle[0].size:])


def test_plot_refuses_an_unknown_mechanism_kind(tmp_path):
    from camdyn.plotting.mechanisms import plot_mechanism_history
    ds = xr.Dataset({"alpha": ("time", np.zeros(3))}, coords={"time": [0.0, 1.0, 2.0]}, attrs={"mechanism": "lever"})
    with pytest.raises(ParameterError, match="no figure for the mechanism kind 'lever'"):
        plot_mechanism_history(ds, tmp_path / "x.png")
    assert not (tmp_path / "x.png").exists()
