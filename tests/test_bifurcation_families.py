"""``camdyn bifurcation`` over every family whose cam is held at a speed: the sweep varies
the family's own speed key (``motion.speed``, a mechanism's ``system.motion.speed``, a
model's speed) with that family's metrics. The valve train's once-per-period samples are
checked against its periodic orbit found by Newton's method on the shooting residual (a
different computation from the sweep's plain run); a cam under its drive is refused."""

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from camdyn.cli.app import main

VALVE = str(Path(__file__).resolve().parents[1] / "examples" / "models" / "valve_train.py") + ":VALVE_TRAIN"


def test_the_valve_trains_diagram_is_its_periodic_orbit(tmp_path, capsys):
    from camdyn.cli.problems import source_problem
    from camdyn.continuation import find_orbit

    out = tmp_path / "valve.nc"
    assert main(["bifurcation", VALVE, "--speeds", "30Hz,40Hz", "--revolutions", "40", "--discard", "30",
                 "--workers", "0", "--out", str(out), "--quiet"]) == 0
    with xr.open_dataset(out) as ds:
        assert list(ds["speed"].values) == [30.0, 40.0] and list(ds["period"].values) == [1, 1]
        for i, speed in enumerate((30.0, 40.0)):
            orbit = find_orbit(source_problem(VALVE, None, speed), transient=60)
            section = np.array([ds[f"poincare_{name}"].values[i, -1] for name in ("x_v", "v_v", "x_s", "v_s")])
            scale = np.array([1e-2, 1.0, 1e-2, 1.0])          # m, m/s: a lift of about 10 mm
            assert np.all(np.abs(section - orbit.state) <= 1e-6 * scale), (speed, section, orbit.state)
            assert ds["events_seat"].values[i] >= 1          # the valve lands on its seat every period


def test_a_mechanism_held_at_its_speed_is_swept_in_its_systems_speed(tmp_path):
    out = tmp_path / "pivot.nc"
    assert main(["bifurcation", "flexible-pivot", "--speeds", "10Hz:11Hz:2", "--revolutions", "20",
                 "--discard", "10", "--workers", "0", "--out", str(out), "--quiet"]) == 0
    with xr.open_dataset(out) as ds:
        assert list(ds["system.motion.speed"].values) == [10.0, 11.0]
        assert {"poincare_alpha", "impacts_per_revolution", "regime", "max_normal_force"} <= set(ds.data_vars)


@pytest.mark.parametrize("source", ["driven-cam", "drum-brake"])
def test_a_cam_under_its_drive_is_refused_in_one_line(source, tmp_path, capsys):
    assert main(["bifurcation", source, "--speeds", "10Hz:11Hz:2", "--out", str(tmp_path / "b.nc")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "drive turns the cam" in err[0], err
    assert not any(tmp_path.iterdir())
