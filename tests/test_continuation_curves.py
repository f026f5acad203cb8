"""Two-parameter curves of bifurcations against outside references: the rigid-impact
oscillator's period-doubling curve over its wall position, solved in closed form here
(det(M + I) = 0 of the one-impact orbit's monodromy, from its free motion between
impacts, as in test_continuation), and the chapter 3 rig's period-doubling curve over
(speed, runout) against the brute-force regime map's boundary between period 1 and
period 2, a sweep computed here."""

import numpy as np
import pytest
from scipy.optimize import brentq
from test_continuation import _closed_form_multipliers, _impact_orbit, _rigid

from camdyn.continuation.curves import bifurcation_curve, system_curve
from camdyn.errors import ParameterError

WALLS = np.linspace(0.0, 0.1, 6)           # wall position sigma [m]


def _doubling(forcing, sigma):
    """det(M + I) of the closed-form one-impact orbit (a multiplier at -1 where it vanishes)."""
    t_impact, v = _impact_orbit(forcing, sigma, [1.1, -0.3])
    return float(np.real(np.prod(_closed_form_multipliers(forcing, sigma, t_impact, v) + 1.0)))


def test_period_doubling_curve_of_the_rigid_impact_oscillator_is_the_closed_form():
    expected = [brentq(_doubling, 2.2, 2.75, args=(sigma,), xtol=1e-14) for sigma in WALLS]
    curve = bifurcation_curve(lambda sigma: _rigid(2.5, sigma), "period-doubling", WALLS, 2.6589, 0.1,
                              second_name="sigma")
    assert "last value" in curve.stopped and curve.seconds.tolist() == WALLS.tolist()
    assert np.max(np.abs(curve.parameters - expected)) < 1e-9, curve.parameters - expected   # measured 2.6e-12
    assert np.ptp(expected) > 0.15                              # the curve moves: W from 2.659 to 2.457
    for point in curve.points:
        assert np.min(np.abs(point.orbit.multipliers + 1.0)) < 1e-6


def test_curve_refuses_bad_input_before_work():
    def never(sigma):
        raise AssertionError("no problem may be built for refused input")
    for kind, walls, near, window, words in [("neimark-sacker", WALLS, 2.6, 0.1, "not offered"),
                                             ("wobble", WALLS, 2.6, 0.1, "one of"),
                                             ("fold", [0.0], 2.6, 0.1, "at least two"),
                                             ("fold", [0.0, 0.1, 0.05], 2.6, 0.1, "monotonic"),
                                             ("fold", WALLS, 2.6, 0.0, "window > 0"),
                                             ("fold", WALLS, float("nan"), 0.1, "finite")]:
        with pytest.raises(ParameterError, match=words):
            bifurcation_curve(never, kind, walls, near, window)


def test_period_doubling_curve_of_the_chapter3_rig_bounds_the_brute_force_map(tmp_path):
    import camdyn
    from camdyn.sweeps import run_sweep, spec_from_dict
    runouts = [0.0035, 0.003, 0.0025, 0.002, 0.0015]       # m; e/rc from 0.2 down to 0.086
    speeds = np.round(np.arange(14.0, 17.51, 0.25), 10)     # Hz
    system = camdyn.load_system("sundar2014-impact")
    curve = system_curve(system, "period-doubling", "motion.speed", "cam.runout", runouts, 16.016, 0.5)
    assert "last value" in curve.stopped, curve.stopped
    table = {"system": {"source": "sundar2014-impact", "set": {}},
             "vary": [{"key": "cam.runout", "values": [f"{r} m" for r in runouts]},
                      {"key": "motion.speed", "values": [f"{v} Hz" for v in speeds]}],
             "run": {"revolutions": 150, "discard": 100, "rtol": 1e-9, "atol": 1e-11},
             "metrics": {"names": ["regime"]},
             "output": {"path": str(tmp_path / "map.nc")}}
    grid = run_sweep(spec_from_dict(table, name="map"), workers=0, progress=False).load()
    period = grid["period"].values                            # (runout, speed)
    for i, point in enumerate(curve.points):
        row = period[i]
        # the map doubles across the located point: period 1 below it, period 2 above it
        # (speeds within 0.1 Hz of it left out: a multiplier within 0.02 of -1 has not
        # settled in 100 revolutions)
        below, above = speeds < point.parameter - 0.1, speeds > point.parameter + 0.1
        assert np.all(row[below][-2:] == 1) and np.all(row[above][:2] == 2), (point.second, point.parameter, row)
    # the doubling moves to higher speeds by more than three of the map's speed steps
    # (measured 16.016 -> 16.992 Hz)
    assert np.all(np.diff(curve.parameters) > 0) and np.ptp(curve.parameters) > 3 * 0.25


def test_map_draws_the_curve_and_refuses_bad_curves_before_work(tmp_path, capsys):
    import xarray as xr

    from camdyn.cli.app import main
    out = tmp_path / "map.nc"
    base = ["map", "sundar2014-impact", "--x", "cam.runout=2.5mm:3.5mm:2", "--y", "speed=15Hz:17Hz:5",
            "--revolutions", "150", "--discard", "100", "--rtol", "1e-9", "--atol", "1e-11", "--workers", "1",
            "--quiet", "--out", str(out)]
    for curve in ("wobble=16Hz", "period-doubling", "neimark-sacker=16Hz", "period-doubling=16kg"):
        assert main([*base, "--curve", curve]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("error:") and len(err.splitlines()) == 1 and not out.exists()
    assert main([*base, "--curve", "period-doubling=16.3Hz"]) == 0
    assert "period-doubling: 2 points" in capsys.readouterr().out
    with xr.open_dataset(out) as ds:
        curve = ds["period_doubling_curve"].values        # at 2.5 and 3.5 mm: 16.314 and 16.016 Hz
        assert ds["period_doubling_curve"].attrs["units"] == "Hz" and curve[0] > curve[1]
        for i, speed in enumerate(curve):                 # the map's period changes across it
            periods = ds["period"].values[i]
            speeds = ds["motion.speed"].values
            assert periods[speeds < speed - 0.1][-1] == 1 and periods[speeds > speed + 0.1][0] == 2
    assert out.with_suffix(".png").stat().st_size > 10_000


def test_grazing_curve_of_the_rigid_impact_oscillator_is_the_closed_form():
    # the non-impacting orbit grazes the wall where the linear steady state's amplitude
    # A / sqrt((w^2 - W^2)^2 + (2 zeta w W)^2) reaches sigma, for each wall position sigma
    from test_continuation import FORCE, W_NATURAL, ZETA
    walls = np.array([1.5, 1.6, 1.7, 1.8])
    amplitude = lambda w: FORCE / np.hypot(W_NATURAL ** 2 - w ** 2, 2 * ZETA * W_NATURAL * w)
    expected = [brentq(lambda w: amplitude(w) - sigma, 0.3, 0.99, xtol=1e-14) for sigma in walls]
    curve = bifurcation_curve(lambda sigma: _rigid(0.5, sigma), "grazing", walls, 0.5795, 0.05, transient=300,
                              second_name="sigma")
    assert "last value" in curve.stopped, curve.stopped
    assert np.max(np.abs(curve.parameters - expected)) < 1e-7, curve.parameters - expected   # measured 4.6e-9
    assert all(p.orbit.impacts_per_period == 0 for p in curve.points)
