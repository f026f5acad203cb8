"""``camdyn spectrum`` over the followers on a cam profile and the models of your own:
the cam harmonics of the cycloidal preset's lift (10 mm cycloidal rise and return over
120 deg each, dwells of 60 deg) are the Fourier coefficients of that closed form,
integrated here; the default series is alpha_ddot where the model has it, else its first
time series."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from camdyn.cli.app import main

VALVE = str(Path(__file__).resolve().parents[1] / "examples" / "models" / "valve_train.py") + ":VALVE_TRAIN"


def cycloidal_lift(theta: np.ndarray, h: float = 0.01) -> np.ndarray:
    """The preset's lift [m] at cam angle theta [rad]: s = h (u - sin(2 pi u) / (2 pi)),
    u the fraction of the 120 deg rise; then a dwell, the mirrored return and a dwell."""
    span, dwell = 2 * math.pi / 3, math.pi / 3
    t = np.mod(theta, 2 * math.pi)
    rise = h * (t / span - np.sin(2 * math.pi * t / span) / (2 * math.pi))
    u = (t - span - dwell) / span
    back = h * (1 - (u - np.sin(2 * math.pi * u) / (2 * math.pi)))
    return np.select([t < span, t < span + dwell, t < 2 * span + dwell], [rise, h, back], 0.0)


def test_the_cycloidal_lifts_harmonics_are_its_fourier_series(capsys):
    assert main(["spectrum", "cycloidal", "--variable", "lift", "--speed", "300rpm", "--revolutions", "6",
                 "--window", "4", "--harmonics", "5", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["summary"]["variable"] == "lift" and doc["summary"]["units"] == "m"
    theta = np.linspace(0.0, 2 * math.pi, 400_001)[:-1]
    lift = cycloidal_lift(theta)
    for harmonic in doc["harmonics"]:
        k = harmonic["order"]
        exact = 2 * abs(np.mean(lift * np.exp(-1j * k * theta)))
        if k % 2:
            assert harmonic["amplitude"] == pytest.approx(exact, rel=1e-6), k   # measured 1e-14
        else:
            assert harmonic["amplitude"] < 1e-12 and exact < 1e-12, k           # the half-wave symmetry


@pytest.mark.parametrize("source, series", [("rocking-roller", "psi"), (VALVE, "x_v"),
                                            ("sundar2014-impact", "alpha_ddot")])
def test_the_default_series_is_alpha_ddot_or_the_first(source, series, capsys):
    assert main(["spectrum", source, "--revolutions", "6", "--window", "4", "--harmonics", "2", "--json"]
                + (["--speed", "40Hz"] if source == VALVE else [])) == 0
    assert json.loads(capsys.readouterr().out)["summary"]["variable"] == series
