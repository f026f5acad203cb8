"""The largest Lyapunov exponent across impacts, and the bifurcation / lyapunov commands."""

import json

import pytest

import camdyn
from camdyn.analysis.chaos import lyapunov_exponent
from camdyn.cli.app import main
from camdyn.errors import ParameterError
from camdyn.sweeps import compute_chunk, spec_from_dict

RIG = {"cam.runout": "3.5 mm"}


@pytest.fixture(scope="module")
def rig():
    return camdyn.load_system("sundar2014-impact", RIG)


def test_periodic_impacts_have_a_negative_exponent_that_converges(rig):
    """12 Hz: one impact per revolution, period 1 (the sweep's classification, computed
    independently from the Poincare section). The exponent is the orbit's slowest decay rate;
    doubling the record changes it by < 1 %."""
    short = lyapunov_exponent(rig, speed=12.0, revolutions=300)
    long = lyapunov_exponent(rig, speed=12.0, revolutions=600)
    assert short.exponent < 0 and long.exponent < 0
    assert long.exponent == pytest.approx(short.exponent, rel=0.01)


def test_beyond_the_periodic_window_the_exponent_is_positive_and_converges(rig):
    """18 Hz, inside the irregular band of the bifurcation diagram (docs/sweeps.md): chaotic.
    Doubling the record changes the estimate by < 10 % (it moved 4 % from 400 to 800)."""
    short = lyapunov_exponent(rig, speed=18.0, revolutions=400)
    long = lyapunov_exponent(rig, speed=18.0, revolutions=800)
    assert short.exponent > 0 and long.exponent > 0
    assert long.exponent == pytest.approx(short.exponent, rel=0.10)


def test_sweep_classification_agrees_with_the_exponent(tmp_path):
    spec = spec_from_dict({"system": {"source": "sundar2014-impact", "set": RIG},
                           "vary": [{"key": "motion.speed", "values": ["12 Hz", "18 Hz"]}],
                           "run": {"revolutions": 300, "discard": 200, "chunk": 2},
                           "metrics": {"names": ["regime"]}, "output": {"path": str(tmp_path / "x.nc")}})
    out = compute_chunk(spec, 0)
    assert list(out["regime"]) == [2, 3] and out["period"][0] == 1


@pytest.mark.parametrize("kwargs, words", [({"revolutions": 0}, "revolutions"), ({"separation": 1.0}, "separation"),
                                           ({"transient": -1}, "transient")])
def test_bad_lyapunov_input(rig, kwargs, words):
    with pytest.raises(ParameterError, match=words):
        lyapunov_exponent(rig, speed=12.0, **kwargs)


def test_cli_lyapunov_and_bifurcation(tmp_path, capsys):
    assert main(["lyapunov", "sundar2014-impact", "--set", "cam.runout=3.5mm", "--speed", "18Hz",
                 "--revolutions", "200", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["exponent_per_s"] > 0 and out["speed_hz"] == 18.0
    assert main(["bifurcation", "sundar2014-impact", "--set", "cam.runout=3.5mm", "--speeds", "10Hz:20Hz:4",
                 "--revolutions", "40", "--discard", "20", "--workers", "0", "--quiet",
                 "--out", str(tmp_path / "b.nc")]) == 0
    assert (tmp_path / "b.nc").is_file() and (tmp_path / "b.png").is_file()
    assert "regimes:" in capsys.readouterr().out
