"""Meaningless settings are refused before the work starts, with one line and exit status
2, in the command line as in the Python API; records whose metadata contradict the
options are refused."""

import contextlib
import io
import time

import numpy as np
import pytest

import camdyn
from camdyn.cli.app import main
from camdyn.errors import DataError, GeometryError, ParameterError
from camdyn.identification.friction import estimate_friction
from camdyn.identification.modal import synthesize_impulse_test
from camdyn.records.schema import check_consistency, make_record
from camdyn.records.synthesis import synthesize
from camdyn.sweeps.execution import check_dask_address
from camdyn.tribology.design import design_map


def run(argv):
    out, err = io.StringIO(), io.StringIO()
    started = time.perf_counter()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main([str(a) for a in argv])
    return status, out.getvalue(), err.getvalue(), time.perf_counter() - started


@pytest.mark.parametrize("argv, words", [
    (["simulate", "sundar2014-impact", "--rtol", "10"], "outside the sensible range"),
    (["simulate", "sundar2014-impact", "--rtol", "1e-20"], "outside the sensible range"),
    (["simulate", "sundar2014-impact", "--speed", "16Hz", "--sample-rate", "20Hz"], "samples per cam period"),
    (["simulate", "sundar2014-impact", "--speed", "16Hz", "--revolutions", "1e9"], "memory"),
    (["simulate", "sundar2014-impact", "--sample-rate", "1THz"], "memory"),
    (["simulate", "sundar2014-impact", "--set", "follower.length=87mm"], "follower.length"),
    (["simulate", "sundar2014-impact", "--out", "run.csv"], "must end in .nc"),
    (["simulate", "sundar2014-impact", "--plot", "run.xyz"], "unknown image format"),
    (["simulate", "sundar2014-impact", "--set", "cam.runout=3,5mm"], "comma"),
    (["synthesize-impulse", "--damping", "-0.5", "--out", "x.csv"], "[0, 1)"),
    (["synthesize-impulse", "--damping", "2", "--out", "x.csv"], "[0, 1)"),
    (["synthesize-impulse", "--out", "x.xlsx"], "a record is"),
    (["design", "sundar2014-friction", "--ratios", "0.5:1.5:3", "--speeds", "5Hz:10Hz:2"], "[0, 1)"),
    (["bifurcation", "sundar2014-impact", "--speeds", "5Hz:30Hz:3", "--dask", "foo"], "--dask"),
    (["map", "sundar2014-impact", "--x", "cam.runout=1mm:5mm:100000", "--y", "speed=5Hz:30Hz:100000"],
     "points"),
])
def test_cli_refuses_before_the_work(tmp_path, monkeypatch, argv, words):
    monkeypatch.chdir(tmp_path)
    status, out, err, elapsed = run(argv)
    assert status == 2, (out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error:") and words in lines[0], lines
    assert elapsed < 20.0    # nothing was simulated (the slowest refusal prepares the system)
    assert not any(tmp_path.iterdir())   # and nothing was written


def test_contact_beyond_the_bar_is_a_geometry_error():
    rig = camdyn.load_system("sundar2014-impact", {"follower.length": "87 mm"})
    with pytest.raises(GeometryError, match="between 83.2 and 90.2 mm"):
        camdyn.simulate(rig, revolutions=1)


def test_api_refusals():
    with pytest.raises(ParameterError, match=r"\[0, 1\)"):
        synthesize_impulse_test(damping_ratios=(1.0, 0.02))
    with pytest.raises(ParameterError, match=r"\[0, 1\)"):
        design_map(camdyn.load_system("sundar2014-friction"), "runout", [0.2, 1.0], [10.0])
    for address in ("foo", "tcp://host", "http://host:8786"):
        with pytest.raises(ParameterError, match="scheduler address"):
            check_dask_address(address)
    check_dask_address("tcp://10.0.0.5:8786")   # a real address passes


def test_record_metadata_contradicting_the_options_is_refused():
    t = np.arange(64) / 1e3
    rec = make_record(t, {"alpha_ddot": np.sin(t)}, speed_hz=16.0, runout=3.5e-3, source="meas.csv")
    check_consistency(rec, speed=16.05, runout=3.51e-3)          # within 0.5 % and 1 %: accepted
    with pytest.raises(DataError, match="16 Hz"):
        check_consistency(rec, speed=17.0)
    with pytest.raises(DataError, match="cam.runout=3.5mm"):
        check_consistency(rec, runout=1.75e-3)
    with pytest.warns(UserWarning, match="sundar2014-friction"):
        check_consistency(make_record(t, {"alpha_ddot": np.sin(t)}, preset="sundar2014-friction"),
                          preset="sundar2014-impact")


@pytest.mark.slow
def test_friction_record_of_another_runout_is_refused_not_fitted():
    rig = camdyn.load_system("sundar2014-friction")
    record = synthesize(rig.with_values(**{"cam.runout": 3.5e-3}), 11.55, revolutions=10, sample_rate=9460)
    with pytest.raises(DataError, match="cam.runout=3.5mm"):
        estimate_friction(rig, record)      # the preset's 1.75 mm would fit the wrong rig
