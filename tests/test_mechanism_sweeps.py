"""Sweeps over a mechanism file (camdyn.sweeps.mechanism_spec, mechanism_run,
mechanism_metrics): a point of the sweep against a direct run of the same mechanism, with
its metrics recomputed here from the run's own samples; the flexible pivot's stiff limit
against the rocking sweep of the rigid pivot, below and above the loss of contact that
inverse kinematics predicts; interrupt and resume; refusals before any work."""

import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from camdyn.analysis.kinematics import loss_of_contact_speed
from camdyn.errors import ParameterError
from camdyn.io.mechanism_config import load_mechanism, simulate_mechanism
from camdyn.params.config import load_system
from camdyn.sweeps import mechanism_run, run_sweep, spec_from_dict
from camdyn.sweeps.execution import SweepInterrupted

MECHANISMS = Path(__file__).resolve().parents[1] / "examples" / "mechanisms"
PIVOT = str(MECHANISMS / "flexible_pivot.toml")
DRIVEN = str(MECHANISMS / "driven_cam.toml")


@pytest.fixture(autouse=True)
def _in_tmp_path(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)


def _spec(source, vary, run, metrics=None, path="m.nc", set_=None):
    table = {"system": {"source": source, "set": set_ or {}}, "vary": vary, "run": run, "output": {"path": path}}
    if metrics:
        table["metrics"] = {"names": metrics}
    return spec_from_dict(table, name=Path(path).stem)


def _onsets(flag: np.ndarray, work: np.ndarray) -> np.ndarray:
    """Contacts begun in a sampled run (samples first): rises of the 0/1 contact flag, and
    intervals out of contact at both ends over which the cam's work on the follower grew
    (a contact between the samples)."""
    count = 0
    for k in range(1, len(flag)):
        if flag[k - 1] < 0.5 and (flag[k] > 0.5 or work[k] != work[k - 1]):
            count += 1
    return count


def test_a_point_of_the_sweep_equals_a_direct_run_of_its_mechanism():
    revolutions, discard, samples = 12, 6, 256
    spec = _spec(PIVOT, [{"key": "system.motion.speed", "values": ["16 Hz"]},
                         {"key": "pivot.stiffness", "values": ["5e7 N/m", "2e7 N/m"]}],
                 {"revolutions": revolutions, "discard": discard, "samples_per_revolution": samples, "chunk": 1},
                 set_={"system.cam.runout": "1 mm"})
    ds = run_sweep(spec, workers=0, progress=False).load()
    direct = simulate_mechanism(load_mechanism(PIVOT, {"system.cam.runout": "1 mm", "system.motion.speed": "16 Hz",
                                                       "pivot.stiffness": "2e7 N/m"}),
                                revolutions=revolutions, sample_rate=samples * 16.0, rtol=spec.rtol)
    point = ds.isel({"system.motion.speed": 0, "pivot.stiffness": 1})
    start = discard * samples                   # the window: from the 6th period of 16 Hz on
    np.testing.assert_array_equal(point["poincare_alpha"].values, direct["alpha"].values[start::samples][:6])
    np.testing.assert_array_equal(point["poincare_alpha_dot"].values, direct["alpha_dot"].values[start::samples][:6])
    rises = _onsets(direct["in_contact"].values[start - 1:], direct["cam_work"].values[start - 1:])
    assert rises > 0
    assert point["impacts_per_revolution"].item() == rises / (revolutions - discard)
    assert point["max_normal_force"].item() == direct["Fn"].values[start:].max()
    bearing = np.sqrt(direct["Nx"].values[start:] ** 2 + direct["Ny"].values[start:] ** 2)
    assert point["peak_bearing_force"].item() == pytest.approx(bearing.max(), rel=1e-15)
    assert point["accepted_steps"].item() == direct.attrs["accepted_steps"]
    assert point["peak_bearing_force"].attrs["units"] == "N"
    assert point["poincare_alpha"].attrs["units"] == "rad"


def test_a_driven_cam_point_is_sampled_by_cam_angle_and_carries_its_speed_fluctuation():
    revolutions, discard, samples = 10, 4, 256
    spec = _spec(DRIVEN, [{"key": "drive.stall_torque", "values": ["1 N*m"]}],
                 {"revolutions": revolutions, "discard": discard, "samples_per_revolution": samples})
    point = run_sweep(spec, workers=0, progress=False).load().isel({"drive.stall_torque": 0})
    direct = simulate_mechanism(load_mechanism(DRIVEN, {"drive.stall_torque": "1.0 N*m"}), revolutions=revolutions,
                                sample_rate=samples * 11.55, rtol=spec.rtol)
    start = discard * samples
    theta, alpha = direct["cam_angle"].values, direct["alpha"].values
    turns = (theta - theta[0]) / (2.0 * np.pi)
    # the follower angle where the cam passes each whole turn inside the window (np.interp
    # on the turns, which rise monotonically here)
    window_turns = turns[start:]
    whole = np.arange(np.ceil(window_turns[0]), np.floor(window_turns[-1]) + 1)[:revolutions - discard]
    expected = np.interp(whole, window_turns, alpha[start:])
    got = point["poincare_alpha"].values
    np.testing.assert_allclose(got[:len(whole)], expected, rtol=1e-12, atol=1e-15)
    assert np.all(np.isnan(got[len(whole):]))
    speed = direct["cam_speed"].values[start:]
    assert point["coefficient_of_fluctuation"].item() == (speed.max() - speed.min()) / speed.mean()
    assert point["mean_cam_speed"].attrs["units"] == "rad/s"
    rises = _onsets(direct["in_contact"].values[start - 1:], direct["cam_work"].values[start - 1:])
    assert point["impacts_per_revolution"].item() == pytest.approx(rises / (window_turns[-1] - window_turns[0]),
                                                                   rel=1e-12)


def test_a_stiff_pivot_gives_the_rigid_pivots_impacts_below_and_above_the_loss_of_contact():
    # inverse kinematics (an outside reference to both simulations) puts the rig's loss of
    # contact at runout 1 mm between the two speeds
    loss = loss_of_contact_speed(load_system("sundar2014-impact", {"cam.runout": "1 mm"}))
    assert 8.0 < loss < 16.0
    run = {"revolutions": 40, "discard": 20, "chunk": 2}
    speeds = {"values": ["8 Hz", "16 Hz"]}
    flexible = run_sweep(_spec(PIVOT, [{"key": "system.motion.speed", **speeds},
                                       {"key": "pivot.stiffness", "values": ["2e8 N/m"]}],
                               run, path="flexible.nc", set_={"system.cam.runout": "1 mm"}),
                         workers=0, progress=False).load().isel({"pivot.stiffness": 0})
    rigid = run_sweep(spec_from_dict({"system": {"source": "sundar2014-impact", "set": {"cam.runout": "1 mm"}},
                                      "vary": [{"key": "motion.speed", **speeds}], "run": run,
                                      "metrics": {"names": ["impacts", "regime"]}, "output": {"path": "rigid.nc"}}),
                      workers=0, progress=False).load()
    np.testing.assert_array_equal(flexible["impacts_per_revolution"].values, [0.0, 1.0])
    np.testing.assert_array_equal(rigid["impacts_per_revolution"].values, [0.0, 1.0])
    # contact kept (the sliding velocity keeps its sign), then period-1 impacts
    np.testing.assert_array_equal(flexible["regime"].values, [0, 2])
    np.testing.assert_array_equal(rigid["regime"].values, [0, 2])
    np.testing.assert_array_equal(flexible["period"].values, [1, 1])
    np.testing.assert_array_equal(rigid["period"].values, [1, 1])


def test_an_impact_between_two_samples_is_counted_from_the_cams_work():
    # at 64 samples per revolution the 0.4 ms contact of the 16 Hz impact falls between
    # samples: the sampled flag never shows it, the cam's work on the follower does
    spec = _spec(PIVOT, [{"key": "pivot.stiffness", "values": ["2e8 N/m"]}],
                 {"revolutions": 30, "discard": 20, "samples_per_revolution": 64},
                 set_={"system.cam.runout": "1 mm", "system.motion.speed": "16 Hz"})
    ds = run_sweep(spec, workers=0, progress=False).load()
    direct = simulate_mechanism(load_mechanism(PIVOT, {"system.cam.runout": "1 mm", "system.motion.speed": "16 Hz",
                                                       "pivot.stiffness": "2e8 N/m"}),
                                revolutions=30, sample_rate=64 * 16.0, rtol=spec.rtol)
    assert direct["in_contact"].values[20 * 64:].max() == 0.0
    assert ds["impacts_per_revolution"].values[0] == 1.0


def test_an_interrupted_mechanism_sweep_resumes_to_the_uninterrupted_result(monkeypatch):
    vary = [{"key": "pivot.damping_ratio", "values": [0.02, 0.05, 0.1, 0.2]}]
    run = {"revolutions": 8, "discard": 4, "samples_per_revolution": 128, "chunk": 1}
    reference = run_sweep(_spec(PIVOT, vary, run, path="reference.nc"), workers=0, progress=False).load()
    spec = _spec(PIVOT, vary, run, path="resumed.nc")
    real, calls = mechanism_run.run_chunk, []

    def interrupted(*args):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(*args)

    monkeypatch.setattr(mechanism_run, "run_chunk", interrupted)
    with pytest.raises(SweepInterrupted, match="2 of 4 chunks are saved"):
        run_sweep(spec, workers=0, progress=False)
    assert not Path("resumed.nc").exists()
    monkeypatch.setattr(mechanism_run, "run_chunk", real)
    notes = []
    result = run_sweep(spec, workers=0, progress=False, echo=notes.append).load()
    assert any(n.startswith("resuming: 2 of 4") for n in notes)
    for name in reference.variables:
        np.testing.assert_array_equal(result[name].values, reference[name].values, err_msg=name)


@pytest.mark.parametrize("vary, run, metrics, message", [
    ([{"key": "pivot.stifness", "values": ["1e7 N/m"]}], {}, None, "did you mean pivot.stiffness"),
    ([{"key": "cam.runout", "values": ["1 mm"]}], {}, None, "write it system.cam.runout"),
    ([{"key": "system.cam.runot", "values": ["1 mm"]}], {}, None, "system.cam.runout"),
    ([{"key": "drive.torque", "values": ["0.1 N*m"]}], {}, None, "not a key of a flexible-pivot"),
    ([{"key": "pivot.stiffness", "values": ["1e7 N/m", "-1 N/m"]}], {}, None,
     r"\[\[vary\]\] pivot.stiffness.*positive"),
    ([{"key": "system.cam.runout", "values": ["1 mm", "40 mm"]}], {}, None, r"\[\[vary\]\] system.cam.runout = 0.04"),
    ([{"key": "pivot.stiffness", "values": ["1e7 kg"]}], {}, None, r"\[\[vary\]\] pivot.stiffness"),
    ([{"key": "pivot.stiffness", "values": ["1e7 N/m"]}], {}, ["stick_slip"], r"\[metrics\] names.*flexible-pivot"),
    ([{"key": "pivot.stiffness", "values": ["1e7 N/m"]}], {"atol": 1e-9}, None, r"\[run\] atol"),
])
def test_bad_mechanism_sweeps_are_refused_before_any_run(monkeypatch, vary, run, metrics, message):
    def no_run(*args, **kwargs):
        raise AssertionError("a refused spec ran a simulation")

    monkeypatch.setattr("camdyn.io.mechanism_config.simulate_mechanism", no_run)
    with pytest.raises(ParameterError, match=message):
        _spec(PIVOT, vary, {"revolutions": 4, "discard": 2, **run}, metrics)


def test_the_example_spec_runs_on_the_cli_with_its_figure(tmp_path):
    from typer.testing import CliRunner

    from camdyn.cli.app import app

    example = Path(__file__).resolve().parents[1] / "examples" / "sweeps" / "mechanism_sweep.toml"
    spec = (example.read_text().replace('"../mechanisms/', f'"{MECHANISMS}/')
            .replace('["8 Hz", "12 Hz", "16 Hz"]', '["8 Hz", "16 Hz"]').replace('["2e7 N/m", "2e8 N/m"]', '["2e8 N/m"]')
            .replace("revolutions = 40", "revolutions = 24").replace("discard = 20", "discard = 12"))
    (tmp_path / "spec.toml").write_text(spec)
    result = CliRunner().invoke(app, ["sweep", "spec.toml", "--workers", "0", "--json"])
    assert result.exit_code == 0, result.output
    document = json.loads(result.stdout)
    assert document["schema"] == "camdyn.sweep/1"
    summary = document["summary"]
    assert {k: summary[k] for k in ("points", "failed", "mechanism")} == {"points": 2, "failed": 0,
                                                                          "mechanism": "flexible-pivot"}
    # 8 Hz keeps contact; 16 Hz impacts (periodic once its transient has gone, which 12
    # discarded revolutions do not promise)
    regimes = summary["regimes"]
    assert regimes["contact_kept"] == 1 and regimes["periodic_impacts"] + regimes["irregular_impacts"] == 1
    assert document["swept"] == {"system.motion.speed": "Hz", "pivot.stiffness": "N/m"}
    assert [Path(f["path"]).name for f in document["files"]] == ["mechanism_sweep.nc", "mechanism_sweep.png"]
    assert (tmp_path / "mechanism_sweep.png").stat().st_size > 0
    ds = xr.load_dataset(tmp_path / "mechanism_sweep.nc")
    assert ds.attrs["mechanism"] == "flexible-pivot"
    assert ds["system.motion.speed"].attrs["units"] == "Hz" and ds["pivot.stiffness"].attrs["units"] == "N/m"
    np.testing.assert_array_equal(ds["impacts_per_revolution"].values.ravel(), [0.0, 1.0])


def test_camdyn_map_over_a_mechanism_draws_the_rigid_pivots_loss_of_contact(tmp_path):
    from typer.testing import CliRunner

    from camdyn.cli.app import app

    result = CliRunner().invoke(app, ["map", PIVOT, "--x", "pivot.stiffness=2e8N/m,5e7N/m", "--y", "speed=8Hz,16Hz",
                                      "--set", "system.cam.runout=1 mm", "--revolutions", "24", "--discard", "12",
                                      "--workers", "0", "--quiet", "--out", "map.nc"])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "map.png").stat().st_size > 0
    ds = xr.load_dataset(tmp_path / "map.nc")
    # the map's curve is that of the rigid pivot at its grid of 512 cam angles
    loss = loss_of_contact_speed(load_system("sundar2014-impact", {"cam.runout": "1 mm"}), points=512)
    np.testing.assert_allclose(ds["loss_of_contact_speed"].values, [loss, loss], rtol=1e-12)
    # inverse kinematics keeps contact at 8 Hz and loses it at 16 Hz; so do both bearings
    np.testing.assert_array_equal(ds["kinematic_regime"].values, [[0, 2], [0, 2]])
    assert np.all(ds["regime"].values[:, 0] == 0) and np.all(ds["regime"].values[:, 1] >= 2)
    assert (ds.attrs["agreement_kept_agree"], ds.attrs["agreement_lost_agree"]) == (2, 2)


def test_two_followers_carry_the_follower_dimension_with_each_followers_own_values():
    brake = str(MECHANISMS / "drum_brake.toml")
    revolutions, discard, samples = 6, 2, 256
    spec = _spec(brake, [{"key": "second.placement", "values": ["170 deg"]}],
                 {"revolutions": revolutions, "discard": discard, "samples_per_revolution": samples})
    ds = run_sweep(spec, workers=0, progress=False).load()
    assert ds["max_normal_force"].dims == ("second.placement", "follower")
    assert ds["poincare_alpha"].dims == ("second.placement", "follower", "revolution")
    np.testing.assert_array_equal(ds["follower"].values, [1, 2])
    assert ds["second.placement"].attrs["units"] == "rad"
    placement = float(ds["second.placement"].values[0])     # 170 deg in radians, as the sweep read it
    assert placement == pytest.approx(np.deg2rad(170.0), rel=1e-15)
    mechanism = load_mechanism(brake, {"second.placement": f"{placement!r} rad"})
    direct = simulate_mechanism(mechanism, revolutions=revolutions, sample_rate=samples * mechanism.system.motion.speed,
                                rtol=spec.rtol)
    start = discard * samples
    np.testing.assert_array_equal(ds["max_normal_force"].values[0], direct["Fn"].values[start:].max(axis=0))
    assert ds["max_normal_force"].values[0, 0] != ds["max_normal_force"].values[0, 1]
