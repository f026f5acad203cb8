"""Output-error identification of the impact damping: round trips on records from the
independent event-driven SciPy model of tests/test_impact_direct.py (no camdyn synthesis),
with n free and fixed; one-line refusals through the command line."""

import json

import numpy as np
import pytest
from test_impact_direct import E_RUN, SPEED, noisy_record, simulate_independent
from test_results_cli import run_cli

import camdyn
from camdyn.cli.app import main
from camdyn.errors import IdentificationError, ParameterError
from camdyn.identification.impact_output_error import estimate_impact_damping_output_error
from camdyn.io.measurements import write_measurement
from camdyn.records.schema import make_record

LAWS = {"thesis S2": (24.7e9, 1.5), "n = 1.2": (1.2e9, 1.2)}
RIG = ["sundar2014-impact", "--set", "friction.coefficient=0"]


@pytest.fixture(scope="module")
def rig():
    return camdyn.load_system("sundar2014-impact").with_values(**{"cam.runout": E_RUN,
                                                                  "friction.coefficient": 0.0})


@pytest.fixture(scope="module", params=list(LAWS))
def transient(request):
    """The independent model from 20 mrad off the cam, 0.6 s at 204.8 kHz (impacts of
    different approach velocity and peak penetration)."""
    beta, n = LAWS[request.param]
    return (beta, n) + simulate_independent(beta, n, duration=0.6)


@pytest.mark.parametrize("noise, n_tol, c_tol", [(0.005, 0.01, 0.03), (0.02, 0.03, 0.10)])
def test_round_trip_on_independent_model(rig, transient, noise, n_tol, c_tol):
    """n within 1 % and beta delta_peak^n within 3 % at 0.5 % noise; 3 % and 10 % at 2 %
    (the task's tolerances). Measured: n +0.01 % (1.5) and +0.02 % (1.2) at 0.5 %, damping
    at the peak +0.07 % and +0.02 %; before the rebuilt force's free-flight offset was
    removed, n +0.23 % and the damping -0.45 %. The simulated peak penetration within 3 %
    of the independent model's median."""
    beta, n, t, channels, peaks = transient
    est = estimate_impact_damping_output_error(rig, noisy_record(t, channels, noise))
    truth = beta * est.peak_penetration ** n
    assert abs(est.exponent / n - 1) < n_tol
    assert abs(est.damping_at_peak / truth - 1) < c_tol
    assert abs(est.peak_penetration / np.median(peaks) - 1) < 0.03
    assert est.mode == "free" and est.impacts_used >= 8
    lo, hi = est.confidence["n"]
    assert lo < est.exponent < hi
    assert -1.0 <= est.correlation <= 1.0


def test_interval_of_n_covers_the_truth(rig, transient):
    """The truth lies within 3 half-widths of the Jacobian's 95 % interval of n (0.5 %
    noise). Measured: n = 1.5 error 0.0002 against a half-width 0.0003, n = 1.2 error
    0.0002 against 0.0033."""
    beta, n, t, channels, _ = transient
    est = estimate_impact_damping_output_error(rig, noisy_record(t, channels, 0.005))
    lo, hi = est.confidence["n"]
    assert abs(est.exponent - n) < 3 * (hi - lo) / 2


def test_fixed_exponent(rig, transient):
    """n fixed at the truth: beta within 3 % (0.5 % noise), n untouched, no correlation."""
    beta, n, t, channels, _ = transient
    est = estimate_impact_damping_output_error(rig, noisy_record(t, channels, 0.005), exponent=n)
    assert est.exponent == n and est.mode == "fixed"
    assert abs(est.beta / beta - 1) < 0.03
    assert np.isnan(est.correlation)


def test_refusals(rig, transient):
    _, _, t, channels, _ = transient
    slow = make_record(t[::12], {k: v[::12] for k, v in channels.items()}, speed_hz=SPEED, runout=E_RUN)
    with pytest.raises(IdentificationError, match="too low to rebuild the penetration"):
        estimate_impact_damping_output_error(rig, slow)
    rec = noisy_record(t, channels, 0.005)
    with pytest.raises(ParameterError, match="one record at a time"):
        estimate_impact_damping_output_error(rig, [rec, noisy_record(t, channels, 0.005, seed=1)])


@pytest.fixture(scope="module")
def record_file(tmp_path_factory):
    t, channels, _ = simulate_independent(*LAWS["thesis S2"], duration=0.6)
    path = tmp_path_factory.mktemp("output_error") / "transient.nc"
    write_measurement(noisy_record(t, channels, 0.005), path)
    return path


def test_cli_json(record_file, capsys):
    assert main(["identify", "impact-damping", *RIG, str(record_file), "--method", "output-error", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    out = doc["summary"]
    assert out["method"] == "output-error"
    assert set(doc["confidence_95"]) == {"beta", "n", "damping_at_peak"}
    beta, n = LAWS["thesis S2"]
    assert abs(out["n"] / n - 1) < 0.01
    assert abs(out["damping_at_peak"] / (beta * out["peak_penetration"] ** n) - 1) < 0.03


@pytest.mark.parametrize("extra, words", [
    (["--fit-stiffness"], "--fit-stiffness applies to --method direct only"),
    (["--bootstrap", "8"], "--bootstrap applies to --method residue only"),
    (["--fix-n", "7"], "between 0 and 3"),
    (["SECOND"], "fits one record at a time"),
])
def test_bad_input_is_one_line(record_file, tmp_path, extra, words):
    if extra == ["SECOND"]:
        second = tmp_path / "second.nc"
        second.write_bytes(record_file.read_bytes())
        extra = [str(second)]
    proc = run_cli("identify", "impact-damping", *RIG, str(record_file), "--method", "output-error", *extra)
    assert proc.returncode == 2
    lines = [line for line in (proc.stderr + proc.stdout).splitlines() if line.strip()]
    assert len(lines) == 1 and words in lines[0], proc.stderr
