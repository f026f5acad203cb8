"""camdyn map (regime map: simulation against inverse kinematics) and camdyn spectrum."""

import json

import numpy as np
import pytest
import xarray as xr

from camdyn.cli.app import main

FIG_2_10 = ["--set", "contact.length=1.6mm", "--set", "contact.damping=D", "--set", "contact.damping_ratio=0.01",
            "--set", "contact.beta=4.25 s/m"]


def test_map_boundary_agrees_with_brute_force_simulation(tmp_path, capsys):
    """Thesis fig 2.9 (ks against speed): every simulated point falls on the side of the
    inverse-kinematics loss-of-contact curve that the curve predicts, at least 10 points
    on each side."""
    out = tmp_path / "map.nc"
    rc = main(["map", "alzate2007-standin-impacting", "--x", "spring.stiffness=1500N/m:3000N/m:5",
               "--y", "speed=90rpm:190rpm:6", "--revolutions", "40", "--discard", "20", "--out", str(out),
               "--rtol", "1.5e-8", "--atol", "1e-11",
               "--workers", "2", "--quiet"])
    assert rc == 0
    printed = capsys.readouterr().out
    assert "agrees with inverse kinematics" in printed and "warning" not in printed
    assert out.with_suffix(".png").stat().st_size > 10_000
    ds = xr.open_dataset(out)
    assert int((ds.status != 0).sum()) == 0
    curve = ds.loss_of_contact_speed  # Hz, over spring.stiffness
    assert np.all(np.diff(curve.values) > 0)  # a stiffer spring holds contact longer (fig 2.9)
    below = ds["motion.speed"] < curve
    kept = ds.regime <= 1
    assert int(below.sum()) >= 10 and int((~below).sum()) >= 10
    assert bool((kept == below).all())
    assert ds.attrs["agreement_kept"] == ds.attrs["agreement_kept_agree"] == int(below.sum())
    assert ds.attrs["agreement_lost"] == ds.attrs["agreement_lost_agree"] == int((~below).sum())
    assert ds.regime.attrs["units"] and ds.loss_of_contact_speed.attrs["units"] == "Hz"


def test_map_refuses_bad_axes(tmp_path, capsys):
    for args in (["--x", "spring.stiffness"], ["--x", "spring.stiffness=1:2"],
                 ["--x", "speed=1Hz:2Hz:3", "--y", "speed=1Hz:2Hz:3"], ["--x", "spring.stiffnes=1N/m:2N/m:2"]):
        assert main(["map", "alzate2007-standin-impacting", *args, "--out", str(tmp_path / "m.nc")]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("error:") and len(err.splitlines()) == 1


def test_spectrum_lists_only_peaks_above_the_noise_threshold(tmp_path, capsys):
    """Thesis fig 2.10's stand-in (1 % damping, sustained contact): the bump near the
    linearized natural frequency is integration noise (its level falls 30-fold from rtol
    1e-8 to 1e-10, tests/test_figures.py), six orders below the first cam harmonic, so no
    resonance peak is listed, and the threshold and its rule are. The impacting stand-in
    at 200 rpm rings between the cam harmonics: three peaks, none at a cam order."""
    figure = tmp_path / "spectrum.png"
    rc = main(["spectrum", "alzate2007-standin", *FIG_2_10, "--speed", "300rpm", "--revolutions", "10",
               "--window", "8", "--plot", str(figure), "--json"])
    assert rc == 0
    doc = json.loads(capsys.readouterr().out)
    out = {**doc["summary"], **doc}
    assert figure.stat().st_size > 10_000
    assert out["peaks"] == [] and "median" in out["peak_rule"]
    assert out["peak_threshold"] >= 1e-4 * out["harmonics"][0]["amplitude"] * 0.999
    assert out["harmonics"][0]["amplitude"] > 10 * out["harmonics"][1]["amplitude"]
    assert out["harmonics"][0]["frequency_hz"] == pytest.approx(5.0)
    rc = main(["spectrum", "alzate2007-standin-impacting", *FIG_2_10, "--speed", "200rpm", "--revolutions", "10",
               "--window", "8", "--json"])
    assert rc == 0
    doc = json.loads(capsys.readouterr().out)
    out = {**doc["summary"], **doc}
    orders = np.array([p["frequency_hz"] for p in out["peaks"]]) / out["speed_hz"]
    assert len(orders) == 3 and np.all(np.abs(orders - np.round(orders)) >= 0.25)
    assert all(p["amplitude"] > out["peak_threshold"] for p in out["peaks"])


def test_spectrum_refusals(capsys):
    assert main(["spectrum", "alzate2007-standin", "--variable", "nope", "--revolutions", "4",
                 "--window", "2"]) == 2
    assert "--variable" in capsys.readouterr().err
    assert main(["spectrum", "alzate2007-standin", "--revolutions", "4", "--window", "9"]) == 2
    assert "window" in capsys.readouterr().err


def test_sweep_warns_when_the_tolerance_cannot_resolve_the_penetration():
    """The impacting stand-in rests on 0.4 nm of penetration: rtol = 3e-7 allows an error
    of 1.8 times that (the solver's error opened the contact in a 10 x 23 map); 1e-9 does not."""
    from camdyn.sweeps import spec_from_dict
    from camdyn.sweeps.execution import _check_resolution, _prepare_base

    def warnings(source, rtol, atol):
        spec = spec_from_dict({"system": {"source": source}, "vary": [{"key": "motion.speed", "values": [1.0]}],
                               "run": {"rtol": rtol, "atol": atol}, "output": {"path": "w.nc"}})
        said = []
        _check_resolution(spec, _prepare_base(spec), said.append)
        return said

    loose = warnings("alzate2007-standin-impacting", 3e-7, 1e-10)
    assert len(loose) == 1 and loose[0].startswith("warning:") and "penetration" in loose[0]
    assert warnings("alzate2007-standin-impacting", 1e-9, 1e-12) == []
    assert warnings("sundar2014-impact", 3e-7, 1e-10) == []
