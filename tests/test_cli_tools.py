"""CLI: synthesize, identify friction and modal-damping, tribology and design."""

import json

import pytest

from camdyn.cli import main
from test_results_cli import run_cli


def test_synthesize_and_identify_friction(tmp_path, capsys):
    data = tmp_path / "meas.csv"
    assert main(["synthesize", "sundar2014-friction", "--set", "cam.runout=5.25mm", "--speed", "11.55Hz",
                 "--revolutions", "12", "--sample-rate", "9460Hz", "--noise", "0.01", "--out", str(data)]) == 0
    capsys.readouterr()
    assert main(["identify", "friction", "sundar2014-friction", str(data), "--set", "cam.runout=5.25mm",
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    for key in ("mu", "Nx_dc", "Ny_dc", "speed_hz", "checks"):
        assert key in out
    assert out["mu"] == pytest.approx(0.3, rel=0.02)
    assert out["speed_hz"] == pytest.approx(11.55)


def test_identify_friction_refusal_is_one_line(tmp_path):
    data = tmp_path / "meas.nc"
    assert main(["synthesize", "sundar2014-friction", "--speed", "21Hz", "--revolutions", "6",
                 "--settle", "4", "--out", str(data)]) == 0
    proc = run_cli("identify", "friction", "sundar2014-friction", str(data))
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: friction estimate refused") and "loses contact" in lines[0]


def test_modal_damping_cli(tmp_path, capsys):
    data = tmp_path / "impulse.uff"
    plot = tmp_path / "acc.png"
    assert main(["synthesize-impulse", "--damping", "0.02", "--noise", "0.01", "--out", str(data)]) == 0
    capsys.readouterr()
    assert main(["identify", "modal-damping", str(data), "--band", "500:1400", "--plot", str(plot), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["damping_ratio"] == pytest.approx(0.02, rel=0.03)
    assert plot.is_file()


def test_tribology_and_design_cli(tmp_path, capsys):
    plot = tmp_path / "t.png"
    assert main(["tribology", "sundar2014-friction", "--speed", "11.55Hz", "--lubricant", "iso-32",
                 "--plot", str(plot), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["regime"] in ("boundary", "mixed", "EHL")
    assert out["peak_pressure"]["units"] == "Pa" and plot.is_file()
    fig = tmp_path / "d.png"
    assert main(["design", "sundar2014-friction", "--ratios", "0.1,0.3", "--speeds", "8Hz:20Hz:4",
                 "--plot", str(fig), "--out", str(tmp_path / "d.nc"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["points"] == 8 and fig.is_file()


@pytest.mark.parametrize("args, words", [
    (["identify", "friction", "sundar2014-friction", "missing.csv"], "no such file"),
    (["identify", "modal-damping", "missing.csv"], "no such file"),
    (["design", "sundar2014-friction", "--ratios", "a:b"], "START:STOP:COUNT"),
    (["tribology", "sundar2014-friction", "--lubricant", "castor"], "unknown lubricant"),
])
def test_cli_tools_bad_input(args, words):
    proc = run_cli(*args)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and words in lines[0], proc.stderr
