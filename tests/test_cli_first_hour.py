"""What a new user meets in the first hour with the command line: the version, flags shown
as flags, every written file announced with its size, JSON that parses with its schema
and summary first, no silent overwrite, results in the working directory, and a notice
while the core compiles."""

import contextlib
import io
import json
import os
import re
import subprocess
import sys

import numba
import pytest

import camdyn
from camdyn.cli import common
from camdyn.cli.app import main
from camdyn.cli.outputs import human_size

SHORT = ["--revolutions", "2"]
IMPACT = ["sundar2014-impact", "--set", "cam.runout=3.5mm", "--speed", "16Hz"]


def run(*argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main([str(a) for a in argv])
    return status, out.getvalue(), err.getvalue()


def test_version():
    status, out, err = run("--version")
    assert status == 0 and out.strip() == f"camdyn {camdyn.__version__}" and err == ""


@pytest.mark.parametrize("command, flags", [
    (["sweep"], ["--restart", "--keep-parts", "--no-plot", "--quiet", "--force"]),
    (["simulate"], ["--json", "--force"]),
    (["bifurcation"], ["--restart", "--quiet"]),
    (["identify", "impact-damping"], ["--json", "--force"]),
])
def test_help_shows_flags_as_flags(command, flags):
    status, out, _ = run(*command, "--help")
    assert status == 0
    assert "<bool>" not in out and "<list[str]>" not in out
    assert "--no-restart" not in out and "--no-quiet" not in out
    for flag in flags:
        assert re.search(rf"{flag}\s{{2,}}[A-Z]", out), (flag, out)     # the help text follows, no type
    if command != ["sweep"]:
        assert "KEY=VALUE" in out


def test_human_size():
    assert [human_size(n) for n in (850, 85_000, 3_200_000, 123_000_000)] == ["850 B", "85 kB", "3.2 MB", "123 MB"]


def test_simulate_announces_sizes_and_refuses_to_overwrite(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    status, out, _ = run("simulate", *IMPACT, *SHORT, "--out", "run.nc", "--plot", "run.png")
    assert status == 0
    assert re.search(r"^wrote run\.nc \(\d+(\.\d)? [kM]B\)$", out, re.M), out
    assert re.search(r"^wrote run\.png \(\d+(\.\d)? kB\)$", out, re.M), out
    before = (tmp_path / "run.nc").stat().st_mtime_ns
    status, out, err = run("simulate", *IMPACT, *SHORT, "--out", "run.nc")
    assert status == 2 and out == ""
    assert err.strip() == "error: run.nc exists; pass --force to overwrite"
    assert (tmp_path / "run.nc").stat().st_mtime_ns == before
    status, out, _ = run("simulate", *IMPACT, *SHORT, "--out", "run.nc", "--force")
    assert status == 0 and "wrote run.nc" in out


def test_simulate_json_stdout_parses_with_schema_and_files(tmp_path):
    status, out, err = run("simulate", *IMPACT, *SHORT, "--out", tmp_path / "run.nc", "--json")
    assert status == 0
    doc = json.loads(out)
    assert list(doc)[:2] == ["schema", "summary"] and doc["schema"] == "camdyn.simulate/1"
    assert {"speed_hz", "revolutions", "impacts", "Fn_max_N", "natural_frequency_Hz"} <= set(doc["summary"])
    assert doc["summary"]["speed_hz"] == 16.0 and doc["summary"]["alpha_ddot_harmonic1_rad_s2"] is None
    assert {"last_impact", "solver", "files"} <= set(doc)
    assert doc["files"] == [{"path": str(tmp_path / "run.nc"), "bytes": (tmp_path / "run.nc").stat().st_size}]
    assert f"wrote {tmp_path / 'run.nc'} (" in err        # announced, on standard error


@pytest.mark.parametrize("argv, name", [
    (["--out", "x.csv"], "must end in .nc"),
    (["--out", "x.h5"], "must end in .nc"),
    (["--plot", "x.xyz"], "unknown image format"),
])
def test_simulate_formats_follow_the_suffix(tmp_path, monkeypatch, argv, name):
    monkeypatch.chdir(tmp_path)
    status, _, err = run("simulate", *IMPACT, *SHORT, *argv)
    assert status == 2 and name in err and not any(tmp_path.iterdir())


def test_records_and_identification_json(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    status, out, _ = run("synthesize-impulse", "--damping", "0.02", "--out", "imp.csv")
    assert status == 0 and re.search(r"^wrote imp\.csv \(\d+(\.\d)? [kM]B\): modes at", out, re.M), out
    assert run("synthesize-impulse", "--out", "imp.csv")[0] == 2
    status, out, err = run("identify", "modal-damping", "imp.csv", "--band", "500:1400", "--plot", "acc.png",
                           "--json")
    assert status == 0 and "wrote acc.png (" in err
    doc = json.loads(out)
    assert doc["schema"] == "camdyn.identify-modal-damping/1"
    assert doc["summary"]["damping_ratio"] == pytest.approx(0.02, rel=0.05)
    assert doc["files"][0]["path"] == "acc.png"
    status, out, _ = run("identify", "modal-damping", "imp.csv", "--band", "500:1400", "--plot", "acc.png")
    assert status == 2
    status, out, _ = run("identify", "modal-damping", "imp.csv", "--band", "500:1400", "--plot", "acc.png",
                         "--force")
    assert status == 0 and "wrote acc.png (" in out


def test_design_with_json_writes_no_figure(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    grid = ["--ratios", "0.1,0.3", "--speeds", "8Hz:20Hz:3"]
    status, out, err = run("design", "sundar2014-friction", *grid, "--json")
    assert status == 0 and not any(tmp_path.iterdir())
    doc = json.loads(out)
    assert doc["schema"] == "camdyn.design/1" and doc["summary"]["points"] == 6 and doc["files"] == []
    status, out, _ = run("design", "sundar2014-friction", *grid)
    assert status == 0 and "wrote design.png (" in out and (tmp_path / "design.png").is_file()
    status, _, err = run("design", "sundar2014-friction", *grid)
    assert status == 2 and "design.png exists; pass --force to overwrite" in err


def test_tribology_and_lyapunov_json_schemas(tmp_path):
    status, out, _ = run("tribology", "sundar2014-friction", "--speed", "11.55Hz", "--lubricant", "iso-32",
                         "--json")
    doc = json.loads(out)
    assert status == 0 and doc["schema"] == "camdyn.tribology/1"
    assert doc["summary"]["regime"] in ("boundary", "mixed", "EHL")
    assert doc["quantities"]["peak_pressure"]["units"] == "Pa"
    status, out, _ = run("lyapunov", *IMPACT, "--revolutions", "10", "--transient", "4", "--json")
    doc = json.loads(out)
    assert status == 0 and list(doc)[:2] == ["schema", "summary"] and doc["schema"] == "camdyn.lyapunov/1"
    assert {"speed_hz", "exponent_per_s", "exponent_error_per_s", "per_revolution", "chaotic"} == set(doc["summary"])


SPEC = """
[system]
source = "sundar2014-impact"
set = { "cam.runout" = "3.5 mm" }
[[vary]]
key = "motion.speed"
values = ["10 Hz", "14 Hz"]
[run]
revolutions = 12
discard = 4
[output]
path = "result.nc"
"""


def test_sweep_output_is_relative_to_the_working_directory(tmp_path, monkeypatch):
    specs, work = tmp_path / "specs", tmp_path / "work"
    specs.mkdir()
    work.mkdir()
    (specs / "s.toml").write_text(SPEC)
    monkeypatch.chdir(work)
    status, out, err = run("sweep", specs / "s.toml", "--workers", "0", "--quiet")
    assert status == 0, err
    assert (work / "result.nc").is_file() and (work / "result.png").is_file()
    assert sorted(p.name for p in specs.iterdir()) == ["s.toml"]          # nothing beside the spec
    assert re.search(r"^wrote result\.nc \(\d+(\.\d)? kB\): 2 points, 0 failed$", out, re.M), out
    assert re.search(r"^wrote result\.png \(\d+ kB\)$", out, re.M), out
    status, _, err = run("sweep", specs / "s.toml", "--workers", "0", "--quiet")
    assert status == 2 and "result.nc exists; pass --force to overwrite" in err
    status, out, _ = run("sweep", specs / "s.toml", "--workers", "0", "--quiet", "--force", "--no-plot")
    assert status == 0 and "wrote result.nc" in out and "result.png" not in out


def test_an_absolute_sweep_output_is_kept(tmp_path):
    from camdyn.sweeps import load_spec

    (tmp_path / "s.toml").write_text(SPEC.replace('"result.nc"', f'"{tmp_path / "abs.nc"}"'))
    assert load_spec(tmp_path / "s.toml").output == tmp_path / "abs.nc"
    (tmp_path / "r.toml").write_text(SPEC)
    assert str(load_spec(tmp_path / "r.toml").output) == "result.nc"


def test_demo_refuses_to_overwrite_its_files(tmp_path):
    (tmp_path / "demo.json").write_text("{}")
    status, out, err = run("demo", "--out", tmp_path)
    assert status == 2 and "demo.json exists; pass --force to overwrite" in err and out == ""


def test_compile_notice_when_the_core_compiles(capsys):
    def core_function(x):
        return x + 1
    core_function.__module__ = "camdyn.integrator.first_hour"   # as if it lived in the core

    def other_function(x):
        return x + 2

    with common.compile_notice():
        numba.njit(other_function)(1)
    assert common.COMPILE_NOTICE not in capsys.readouterr().err
    common._notice["shown"] = False
    try:
        with common.compile_notice():
            numba.njit(core_function)(1)
            numba.njit(core_function)(2.0)
        captured = capsys.readouterr()
        assert captured.err.count(common.COMPILE_NOTICE) == 1 and captured.out == ""
    finally:
        common._notice["shown"] = False


def test_core_cache_detection(tmp_path):
    camdyn.simulate(camdyn.load_system("sundar2014-impact"), revolutions=0.1)   # compiled or loaded
    assert common.core_cached()
    code = "from camdyn.cli.common import core_cached; print(core_cached())"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env={**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)})
    assert proc.stdout.strip() == "False", proc.stderr


def test_compile_says_what_it_made_ready():
    """``camdyn compile --all``: every part of the core made ready, with its time; after
    it, a simulation and a sweep point need no compile in this process."""
    from camdyn.integrator import driver
    from camdyn.sweeps import kernel

    status, out, err = run("compile", "--all", "--json")
    assert status == 0, err
    summary = json.loads(out)["summary"]
    assert set(summary) == {"simulation_s", "sweeps_s", "lyapunov_s"} and all(v > 0 for v in summary.values())
    assert driver.integrate.signatures and kernel.simulate_points.signatures
    compiled = len(driver.integrate.signatures)
    camdyn.simulate(camdyn.load_system("sundar2014-friction"), revolutions=1)   # another preset: the same code
    assert len(driver.integrate.signatures) == compiled
