"""``camdyn identify impact-damping --method direct|residue`` on records written by the
independent event-driven SciPy model of tests/test_impact_direct.py (no camdyn
synthesis): the direct round trip through the command line, the JSON keys of both
methods, the text table, and one-line refusals of bad input."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from test_impact_direct import E_RUN, SPEED, noisy_record, simulate_independent
from test_results_cli import run_cli

from camdyn.cli.app import main
from camdyn.io.measurements import write_measurement
from camdyn.records.schema import make_record

BETA, N = 24.7e9, 1.5
RIG = ["sundar2014-impact", "--set", "friction.coefficient=0"]
HEADLINE = ("beta", "n", "damping_at_peak", "peak_penetration", "method", "correlation")


@pytest.fixture(scope="module")
def independent():
    """The independent model from 20 mrad off the cam, 0.6 s at 204.8 kHz."""
    t, channels, peaks = simulate_independent(BETA, N, duration=0.6)
    return t, channels, peaks


@pytest.fixture(scope="module")
def transient_file(independent, tmp_path_factory):
    t, channels, _ = independent
    path = tmp_path_factory.mktemp("direct") / "transient.nc"
    write_measurement(noisy_record(t, channels, 0.005), path)
    return path


def test_direct_round_trip_json(transient_file, independent, capsys):
    """n within 1 %, beta delta_peak^n within 3 % (0.5 % noise), the rebuilt peak
    penetration within 3 % of the independent model's; the keys of both methods."""
    assert main(["identify", "impact-damping", *RIG, str(transient_file), "--method", "direct", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    out = doc["summary"]
    for key in HEADLINE + ("identifiable", "impacts_used"):
        assert key in out
    assert set(doc["confidence_95"]) == {"beta", "n", "damping_at_peak"}
    assert out["method"] == "direct" and out["identifiable"] is True
    assert abs(out["n"] / N - 1) < 0.01
    assert abs(out["damping_at_peak"] / (BETA * out["peak_penetration"] ** N) - 1) < 0.03
    assert abs(out["peak_penetration"] / np.median(independent[2]) - 1) < 0.03
    assert -1.0 <= out["correlation"] <= 1.0
    assert len(doc["per_impact"]["peak_penetration"]) == out["impacts_used"]


def test_direct_text_table(transient_file):
    proc = subprocess.run([sys.executable, "-m", "camdyn.cli.app", "identify", "impact-damping", *RIG,
                           str(transient_file), "--method", "direct"], capture_output=True, text=True,
                          env=os.environ | {"COLUMNS": "200"})
    assert proc.returncode == 0, proc.stderr
    for words in ("direct", "damping at the peak penetration", "correlation of beta and n", "n identifiable"):
        assert words in proc.stdout


@pytest.mark.parametrize("options", [["--fix-n", "1.5", "--bootstrap", "0"], ["--bootstrap", "8"]])
def test_residue_json_has_method_and_correlation(independent, tmp_path, capsys, options):
    """The default method on the model's steady part (one impact per revolution) keeps
    today's keys and adds ``method`` and ``correlation``: null with n fixed, that of the
    bootstrap replicates' beta and n with n free (positive: a larger n needs a larger
    beta for the same damping at the peak, delta_peak < 1 m)."""
    t, channels, _ = independent
    keep = t >= 0.2
    path = tmp_path / "steady.nc"
    write_measurement(noisy_record(t[keep] - t[keep][0], {k: v[keep] for k, v in channels.items()}, 0.005), path)
    assert main(["identify", "impact-damping", *RIG, str(path), *options, "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    out = doc["summary"]
    for key in HEADLINE:
        assert key in out
    assert "confidence_95" in doc
    assert out["method"] == "residue"
    if "--fix-n" in options:
        assert out["correlation"] is None
        assert out["beta"] == pytest.approx(BETA, rel=0.05)
    else:
        assert 0.0 < out["correlation"] <= 1.0
        assert out["n"] == pytest.approx(N, rel=0.02)


@pytest.mark.parametrize("options, words", [
    (["--method", "bogus"], "unknown method 'bogus'"),
    (["--method", "direct", "--bootstrap", "8"], "--bootstrap applies to --method residue only"),
    (["--method", "direct", "--residue", "lambda1"], "--residue applies to --method residue only"),
    (["--method", "direct", "--plot-dir", "figs"], "--plot-dir applies to --method residue only"),
    (["--fit-stiffness"], "--fit-stiffness applies to --method direct only"),
    (["--method", "direct", "--fix-n", "7"], "between 0 and 3"),
])
def test_bad_input_is_one_line(transient_file, options, words):
    proc = run_cli("identify", "impact-damping", *RIG, str(transient_file), *options)
    assert proc.returncode == 2
    lines = [line for line in (proc.stderr + proc.stdout).splitlines() if line.strip()]
    assert len(lines) == 1 and words in lines[0], proc.stderr


def test_direct_refusal_is_one_line(independent, tmp_path):
    """A record sampled too slowly for the penetration to be rebuilt: exit 2, one line."""
    t, channels, _ = independent
    path = tmp_path / "slow.nc"
    write_measurement(make_record(t[::12], {k: v[::12] for k, v in channels.items()}, speed_hz=SPEED,
                                  runout=E_RUN), path)
    proc = run_cli("identify", "impact-damping", *RIG, str(path), "--method", "direct")
    assert proc.returncode == 2
    lines = [line for line in (proc.stderr + proc.stdout).splitlines() if line.strip()]
    assert len(lines) == 1 and "too low to rebuild the penetration" in lines[0], proc.stderr
