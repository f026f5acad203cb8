"""Parameter sweeps: spec validation, the batched kernel against the single-run simulator
and the SciPy oracle, metrics against inverse kinematics, execution on the local pool,
inline and a Dask LocalCluster of 2 workers (bitwise identical), failed points, and
resuming after SIGKILL."""

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
import xarray as xr
from test_results_cli import run_cli

import camdyn
from camdyn.analysis.kinematics import inverse_kinematics, loss_of_contact_speed
from camdyn.cli.app import main
from camdyn.errors import ParameterError, UnitError, UnknownKeyError
from camdyn.simulation.runner import prepare
from camdyn.sweeps import compute_chunk, load_spec, run_sweep, spec_from_dict
from camdyn.sweeps.metrics import poincare_period
from camdyn.testing.oracle import reference_simulate


def _spec(tmp_path, speeds=("10 Hz", "16 Hz", "25 Hz"), revolutions=40, discard=20, chunk=2, name="s.nc", **run):
    return spec_from_dict({
        "system": {"source": "sundar2014-impact", "set": {"cam.runout": "3.5 mm"}},
        "vary": [{"key": "motion.speed", "values": list(speeds)}],
        "run": {"revolutions": revolutions, "discard": discard, "chunk": chunk, **run},
        "output": {"path": str(tmp_path / name)}})


# --- the spec --------------------------------------------------------------------------------

@pytest.mark.parametrize("change, error, words", [
    ({"tables": {"bogus": {}}}, ParameterError, "unknown table"),
    ({"vary": [{"key": "cam.runnout", "values": ["1 mm"]}]}, UnknownKeyError, "cam.runout"),
    ({"vary": [{"key": "cam.runout", "values": ["1 kg"]}]}, UnitError, "cam.runout"),
    ({"vary": [{"key": "follower.mass", "values": ["0.2 kg", "-0.1 kg"]}]}, ParameterError, "follower.mass"),
    ({"vary": [{"key": "cam.pivot_y", "values": ["27 mm", "60 mm"]}]}, ParameterError, "cannot reach"),
    ({"vary": [{"key": "cam.runout", "start": "1 mm", "stop": "2 mm"}]}, ParameterError, "num"),
    ({"vary": [{"key": "cam.runout", "values": ["1 mm"], "dimension": "d"},
               {"key": "motion.speed", "values": ["1 Hz", "2 Hz"], "dimension": "d"}]}, ParameterError, "equal"),
    ({"vary": [{"key": "contact.damping", "values": ["viscous"]}]}, ParameterError, "cannot be swept"),
    ({"run": {"revolutions": 10, "discard": 10}}, ParameterError, "discard"),
    ({"run": {"revolutions": 10.5}}, ParameterError, "whole number"),
    ({"run": {"rtol": 0.5}}, ParameterError, "rtol"),
    ({"metrics": {"names": ["chaos"]}}, ParameterError, "unknown metric"),
    ({"metrics": {"harmonics": 40}}, ParameterError, "harmonics"),
    ({"output": {"path": "x.zarr"}}, ParameterError, ".nc"),
    ({"system": {"source": "no-such-preset"}}, camdyn.errors.PresetError, "no preset"),
])
def test_bad_spec_is_refused_before_any_work(tmp_path, change, error, words):
    spec = {"system": {"source": "sundar2014-impact"},
            "vary": [{"key": "motion.speed", "values": ["10 Hz"]}],
            "output": {"path": str(tmp_path / "x.nc")}}
    spec.update({k: v for k, v in change.items() if k != "tables"})
    spec.update(change.get("tables", {}))
    with pytest.raises(error, match=words):
        spec_from_dict(spec)
    assert not list(tmp_path.iterdir())           # nothing written


def test_spec_grid_zip_and_units(tmp_path):
    spec = spec_from_dict({
        "system": {"source": "sundar2014-impact"},
        "vary": [{"key": "cam.runout", "start": "1 mm", "stop": "3 mm", "num": 3},
                 {"key": "motion.speed", "values": ["600 rpm", "20 Hz"], "dimension": "case"},
                 {"key": "spring.stiffness", "values": ["3 kN/m", "3.5 kN/m"], "dimension": "case"}],
        "output": {"path": str(tmp_path / "g.nc")}})
    assert spec.shape == (3, 2) and spec.points == 6
    assert spec.point_values(0) == pytest.approx({"cam.runout": 1e-3, "motion.speed": 10.0,
                                                  "spring.stiffness": 3000.0})
    assert spec.point_values(5) == pytest.approx({"cam.runout": 3e-3, "motion.speed": 20.0,
                                                  "spring.stiffness": 3500.0})


# --- the kernel and the metrics against independent computations ------------------------------

def test_kernel_poincare_matches_scipy_oracle(tmp_path):
    """Once-per-revolution samples of the batched kernel against an independent SciPy DOP853
    solution of the same equations (rtol 1e-11), in contact (8 Hz) and through impacts with
    separations (25 Hz, 1 impact every two revolutions). Tolerance: the kernel runs at
    rtol 1e-9; over 12 revolutions with impacts the two agree to about 1e-7 rad."""
    spec = _spec(tmp_path, speeds=("8 Hz", "25 Hz"), revolutions=12, discard=4, rtol=1e-9, atol=1e-12)
    out = compute_chunk(spec, 0)
    for i, hz in enumerate((8.0, 25.0)):
        system = camdyn.load_system("sundar2014-impact", {"cam.runout": "3.5 mm"}).with_values(
            **{"motion.speed": hz})
        prep = prepare(system)
        t = np.arange(4, 12) / hz
        _, y, _ = reference_simulate(system, prep.theta0, prep.y0, t[-1], t, prep.viscous_c, method="DOP853",
                                     rtol=1e-11, atol=1e-14)
        np.testing.assert_allclose(out["poincare_alpha"][i], y[0], rtol=0, atol=2e-7)
        np.testing.assert_allclose(out["poincare_alpha_dot"][i], y[1], rtol=0, atol=2e-5)


def test_kernel_agrees_with_simulate_and_its_impact_table(tmp_path):
    """Impacts per revolution and the largest force against camdyn.simulate's impact table
    over the same window (the same integrator: equal to round-off)."""
    spec = _spec(tmp_path, speeds=("16 Hz", "25 Hz"), revolutions=30, discard=10)
    out = compute_chunk(spec, 0)
    for i, hz in enumerate((16.0, 25.0)):
        ds = camdyn.simulate(camdyn.load_system("sundar2014-impact", {"cam.runout": "3.5 mm"}), speed=hz,
                             revolutions=30, rtol=3e-7, atol=1e-10, sample_rate=64 * hz)
        window = ds.impact_time.values >= 10 / hz
        assert out["impacts_per_revolution"][i] == pytest.approx(window.sum() / 20)
        assert out["max_normal_force"][i] == pytest.approx(ds.impact_peak_force.values[window].max(), rel=1e-6)
        np.testing.assert_allclose(out["poincare_alpha"][i], ds.alpha.values[640::64][:20], atol=1e-9)


@pytest.mark.parametrize("runout", ["0.5 mm", "1.5 mm"])
def test_regime_boundary_brackets_loss_of_contact_speed(tmp_path, runout):
    """Contact is kept 2-3 % below the inverse-kinematics loss-of-contact speed and lost
    (with impacts) 0.5 % above it.

    Closer below the boundary, the start from rest at the static equilibrium bounces
    through a chaotic transient whose length is erratic: at 0.995 of the speed (0.5 mm)
    it ended after 15 to more than 100 revolutions depending on the tolerance (rtol 1e-6
    to 1e-10) and on round-off, so no fixed window decides there; at 0.98 it ends after
    9-10 revolutions at every tolerance."""
    system = camdyn.load_system("sundar2014-impact", {"cam.runout": runout})
    v = loss_of_contact_speed(system)
    spec = spec_from_dict({"system": {"source": "sundar2014-impact", "set": {"cam.runout": runout}},
                           "vary": [{"key": "motion.speed", "values": [f"{v * f} Hz" for f in (0.97, 0.98,
                                                                                              1.005, 1.02)]}],
                           "run": {"revolutions": 100, "discard": 60, "chunk": 4},
                           "metrics": {"names": ["regime", "impacts"]},
                           "output": {"path": str(tmp_path / "b.nc")}})
    out = compute_chunk(spec, 0)
    assert list(out["regime"][:2]) == [0, 0] and list(out["impacts_per_revolution"][:2]) == [0, 0]
    assert all(out["regime"][2:] >= 2) and all(out["impacts_per_revolution"][2:] > 0)


def test_residual_and_spectrum_in_contact_match_inverse_kinematics(tmp_path):
    """Below the loss-of-contact speed the follower rides the cam: the residual response is
    the Hertz deflection (micro-radians) and the cam harmonics of alpha_ddot are those of
    the rigid-contact motion (inverse kinematics) to 1 % (the Hertz compliance and the
    decayed transient make the rest)."""
    spec = _spec(tmp_path, speeds=("6 Hz",), revolutions=80, discard=40, chunk=1, samples_per_revolution=128)
    out = compute_chunk(spec, 0)
    assert out["regime"][0] == 0
    assert out["residual_rms"][0] < 1e-4
    ik = inverse_kinematics(camdyn.load_system("sundar2014-impact", {"cam.runout": "3.5 mm"}), speed=6.0)
    spectrum = np.abs(np.fft.rfft(ik.alpha_ddot.values)) * 2 / ik.alpha_ddot.size
    np.testing.assert_allclose(out["harmonic_amplitude"][0, :3], spectrum[1:4], rtol=0.01)
    assert out["peak_frequency"][0] == pytest.approx(6.0)


def test_poincare_period_classification():
    rng = np.random.default_rng(1)
    n = 40
    period2 = np.tile([[0.1, 1.0], [0.2, -1.0]], (n // 2, 1))
    period3 = np.tile([[0.1, 1.0], [0.15, 0.0], [0.2, -1.0]], (n // 3 + 1, 1))[:n]
    noise = rng.normal(size=(n, 2))
    section = np.stack([period2, period3, noise, period2 + 1e-9 * noise])
    scale = np.ones((4, 2))
    assert list(poincare_period(section, scale)) == [2, 3, 0, 2]


def _impact_period(times, hz, start, end, max_k=4):
    """Smallest k such that every impact onset in [start, end] recurs k cam periods later
    (to 1e-4 of a period), from the event log alone; 0 if none up to max_k."""
    period = 1.0 / hz
    t = times[(times >= start) & (times <= end)]
    for k in range(1, max_k + 1):
        earlier = t[t + k * period <= end - 0.5 * period]
        if all(np.min(np.abs(t - (ti + k * period))) < 1e-4 * period for ti in earlier):
            return k
    return 0


def test_period_matches_the_impact_sequence(tmp_path):
    """The sweep's period (from the stroboscopic Poincare section) against the period of
    the impact sequence of camdyn.simulate over the same window (onset times, located by
    the event finder, not sampled): 12 Hz one impact per revolution at equal intervals
    (period 1; its Floquet multipliers are checked in test_chaos.py), 25 Hz one impact
    every two revolutions (period 2), 18 Hz irregular (no period up to 4, regime 3)."""
    speeds = (12.0, 18.0, 25.0)
    spec = spec_from_dict({"system": {"source": "sundar2014-impact", "set": {"cam.runout": "3.5 mm"}},
                           "vary": [{"key": "motion.speed", "values": [f"{hz} Hz" for hz in speeds]}],
                           "run": {"revolutions": 300, "discard": 200, "chunk": 3},
                           "metrics": {"names": ["regime", "impacts"]},
                           "output": {"path": str(tmp_path / "p.nc")}})
    out = compute_chunk(spec, 0)
    rig = camdyn.load_system("sundar2014-impact", {"cam.runout": "3.5 mm"})
    expected = []
    for hz in speeds:
        ds = camdyn.simulate(rig, speed=hz, revolutions=300, rtol=3e-7, atol=1e-10, sample_rate=64 * hz)
        expected.append(_impact_period(ds.impact_time.values, hz, 200 / hz, 300 / hz))
    assert expected == [1, 0, 2]
    assert list(out["period"]) == expected
    assert list(out["regime"]) == [2, 3, 2]
    assert out["impacts_per_revolution"][0] == 1.0 and out["impacts_per_revolution"][2] == 0.5


# --- execution ---------------------------------------------------------------------------------

def test_local_pool_inline_and_dask_are_bitwise_identical(tmp_path):
    spec = _spec(tmp_path, speeds=("8 Hz", "12 Hz", "16 Hz", "22 Hz", "25 Hz"), name="inline.nc")
    inline = run_sweep(spec, workers=0, progress=False).load()
    pool = run_sweep(spec.__class__(**{**spec.__dict__, "output": tmp_path / "pool.nc"}), workers=2,
                     progress=False).load()
    dask = run_sweep(spec.__class__(**{**spec.__dict__, "output": tmp_path / "dask.nc"}), workers=2,
                     dask="local", progress=False).load()
    assert inline.identical(pool) and inline.identical(dask)
    assert inline.poincare_alpha.attrs["units"] == "rad"
    assert inline["motion.speed"].attrs["units"] == "Hz"
    assert list(inline.status.values) == [0] * 5
    assert not (tmp_path / "inline.nc.parts").exists()


def test_camdyn_local_dask_cluster_runs_quiet_and_warm():
    """The LocalCluster of dask="local" passes QUIET_DASK to its worker processes (Dask's
    nannies hand their configuration to the workers they start), and they are warmed."""
    from camdyn.sweeps.execution import QUIET_DASK, _executor

    def worker_state():
        import sys

        import dask
        return ([dask.config.get(key) for key in QUIET_DASK], "camdyn.sweeps.kernel" in sys.modules)

    with _executor(2, "local", 1, None) as (pool, n, how):
        states = pool._client.run(worker_state)
    assert n == 2 and "2 workers" in how
    assert list(states.values()) == [(list(QUIET_DASK.values()), True)] * 2


def test_failed_point_is_recorded_and_the_sweep_goes_on(tmp_path):
    """With the pivot 20 mm above the cam centre, a 10 mm cam and a pivot raised to 27 mm are
    each fine alone, but together the cam cannot reach the follower: that point fails with
    its reason, and the others run."""
    spec = spec_from_dict({"system": {"source": "sundar2014-impact", "set": {"cam.pivot_y": "20 mm"}},
                           "vary": [{"key": "cam.pivot_y", "values": ["20 mm", "27 mm"]},
                                    {"key": "cam.radius", "values": ["17.5 mm", "10 mm"]}],
                           "run": {"revolutions": 6, "discard": 2, "chunk": 3},
                           "output": {"path": str(tmp_path / "f.nc")}})
    ds = run_sweep(spec, workers=0, progress=False)
    status = ds.status.values
    assert list(status.ravel()) == [0, 0, 0, 1]
    assert "cannot reach the follower" in str(ds.failure.values[1, 1])
    assert ds.failure.values[0, 0] == ""
    assert np.isnan(ds.impacts_per_revolution.values[status != 0]).all()
    assert (ds.regime.values[status != 0] == -1).all()


def test_result_assembled_in_blocks_equals_part_by_part(tmp_path, monkeypatch):
    """The parts are joined into blocks before they are written; a block per part (and
    blocks across rows of a 2-D grid, strings included) gives the same file."""
    from camdyn.sweeps import store
    spec = spec_from_dict({"system": {"source": "sundar2014-impact", "set": {"cam.pivot_y": "20 mm"}},
                           "vary": [{"key": "cam.pivot_y", "values": ["20 mm", "27 mm", "24 mm"]},
                                    {"key": "cam.radius", "values": ["17.5 mm", "10 mm"]}],
                           "run": {"revolutions": 6, "discard": 2, "chunk": 4},
                           "output": {"path": str(tmp_path / "b.nc")}})
    joined = run_sweep(spec, workers=0, progress=False, keep_parts=True).load()
    monkeypatch.setattr(store, "BLOCK_BYTES", 1)
    path = store.Checkpoint(spec).assemble(keep_parts=True)
    with xr.open_dataset(path, engine="h5netcdf") as parted:
        assert joined.identical(parted.load())
    assert "cannot reach the follower" in str(joined.failure.values[1, 1])
    assert joined.status.values.tolist() == [[0, 0], [0, 1], [0, 0]]


def test_changed_spec_refuses_old_checkpoints(tmp_path):
    spec = _spec(tmp_path, speeds=("10 Hz", "12 Hz"))
    run_sweep(spec, workers=0, progress=False, keep_parts=True)
    other = _spec(tmp_path, speeds=("10 Hz", "13 Hz"))
    with pytest.raises(ParameterError, match="different sweep"):
        run_sweep(other, workers=0, progress=False)
    assert run_sweep(other, workers=0, progress=False, restart=True).sizes["motion.speed"] == 2


SPEC_TOML = """
[system]
source = "sundar2014-impact"
set = {{ "cam.runout" = "3.5 mm" }}
[[vary]]
key = "motion.speed"
start = "6 Hz"
stop = "26 Hz"
num = {num}
[run]
revolutions = {revolutions}
discard = 20
chunk = 2
[output]
path = "{name}.nc"
"""


def test_sigkill_then_resume_gives_the_uninterrupted_result(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)     # a spec's relative output is the working directory's
    (tmp_path / "a.toml").write_text(SPEC_TOML.format(num=60, revolutions=300, name="a"))
    (tmp_path / "b.toml").write_text(SPEC_TOML.format(num=60, revolutions=300, name="b"))
    parts = tmp_path / "a.nc.parts"
    proc = subprocess.Popen([sys.executable, "-m", "camdyn.cli.app", "sweep", str(tmp_path / "a.toml"),
                             "--workers", "1", "--quiet", "--no-plot"], start_new_session=True,
                            stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    deadline = time.time() + 120
    while time.time() < deadline and len(list(parts.glob("chunk_*.npz"))) < 3:
        time.sleep(0.01)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    before = {p.name: (p.stat().st_ino, p.stat().st_mtime_ns) for p in parts.glob("chunk_*.npz")}
    assert 3 <= len(before) < 30, "the sweep was not caught midway"
    assert not (tmp_path / "a.nc").exists()
    resumed = run_cli("sweep", str(tmp_path / "a.toml"), "--workers", "1", "--quiet", "--keep-parts", "--no-plot")
    assert resumed.returncode == 0, resumed.stderr
    assert f"resuming: {len(before)} of 30 chunks" in resumed.stdout
    after = {p.name: (p.stat().st_ino, p.stat().st_mtime_ns) for p in parts.glob("chunk_*.npz")}
    assert all(after[name] == stamp for name, stamp in before.items())   # not recomputed
    fresh = load_spec(tmp_path / "b.toml")
    reference = run_sweep(fresh, workers=0, progress=False).load()
    result = xr.open_dataset(tmp_path / "a.nc").load()
    for name in reference.variables:
        np.testing.assert_array_equal(result[name].values, reference[name].values, err_msg=name)
    assert {k: v for k, v in result.attrs.items() if k != "title"} == \
           {k: v for k, v in reference.attrs.items() if k != "title"}


def test_cli_sweep_writes_result_and_figure(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)     # a spec's relative output is the working directory's
    spec = tmp_path / "c.toml"
    spec.write_text(SPEC_TOML.format(num=4, revolutions=30, name="c"))
    assert main(["sweep", str(spec), "--workers", "0", "--quiet"]) == 0
    assert (tmp_path / "c.nc").is_file() and (tmp_path / "c.png").is_file()
    assert "4 points, 0 failed" in capsys.readouterr().out


def test_cli_bad_spec_is_one_line(tmp_path):
    spec = tmp_path / "bad.toml"
    spec.write_text(SPEC_TOML.format(num=4, revolutions=30, name="bad").replace("motion.speed", "motion.sped"))
    proc = run_cli("sweep", str(spec))
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "motion.speed" in proc.stderr
