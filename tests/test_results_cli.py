"""Result Datasets, netCDF, restitution laws, impact detection and the command line."""

import json
import subprocess
import sys

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import camdyn
from camdyn.analysis.restitution import restitution_error_curve
from camdyn.cli.app import main
from camdyn.io.netcdf import load_netcdf, save_netcdf

REQUIRED = ["alpha", "alpha_dot", "alpha_ddot", "penetration", "Fn", "Ff", "Fs", "moment_arm",
            "sliding_velocity", "sum_velocity", "Nx", "Ny", "cam_angle", "in_contact"]


def test_dataset_has_every_channel_with_units(tmp_path, impact_rig):
    ds = camdyn.simulate(impact_rig, revolutions=3)
    for name in REQUIRED:
        assert name in ds, name
        assert ds[name].attrs["units"] and ds[name].attrs["long_name"], name
    assert ds.attrs["solver_accepted_steps"] > 0
    assert "[cam]" in ds.attrs["parameters_toml"]
    path = save_netcdf(ds, tmp_path / "run.nc")
    again = load_netcdf(path)
    np.testing.assert_array_equal(again.alpha.values, ds.alpha.values)
    assert again.Fn.attrs["units"] == "N"
    assert again.attrs["solver_rhs_calls"] == ds.attrs["solver_rhs_calls"]


def test_pivot_reaction_balances_static_load(friction_rig):
    # at rest on a frozen cam: N = Fn n - Ff u - Fs y + m g y (no inertia)
    s = friction_rig.with_values(**{"motion.speed": 0.0, "friction.law": "none"})
    ds = camdyn.simulate(s, duration=0.01, sample_rate=1e3)
    a = float(ds.alpha[-1])
    fn, fs = float(ds.Fn[-1]), float(ds.Fs[-1])
    assert float(ds.Nx[-1]) == pytest.approx(fn * np.sin(a), rel=1e-6)
    assert float(ds.Ny[-1]) == pytest.approx(fn * np.cos(a) - fs + s.follower.mass * s.gravity, rel=1e-6)


def test_no_impact_is_missed_with_huge_steps(impact_rig):
    # the step-size cap is lifted: free-flight steps may span half a revolution, yet the
    # guard's own cubic must still catch every impact
    base = camdyn.simulate(impact_rig, speed=16.0, revolutions=10, rtol=1e-10)
    long = camdyn.simulate(impact_rig, speed=16.0, revolutions=10, rtol=1e-10, max_step=1 / 32.0)
    assert base.sizes["impact"] == long.sizes["impact"] >= 9
    np.testing.assert_allclose(long.impact_time.values, base.impact_time.values, atol=1e-7)


def one_dof_restitution(factor):
    """Independent check: m x'' = -K x^1.5 (1 + factor x'/v0); any m, K, v0 give the same e."""
    rhs = lambda t, y: [y[1], -max(y[0], 0.0) ** 1.5 * (1 + factor * y[1])]
    out = lambda t, y: y[0]
    out.terminal, out.direction = True, -1
    sol = solve_ivp(rhs, (0, 50), [0.0, 1.0], events=out, rtol=1e-12, atol=1e-14, method="DOP853")
    return -sol.y_events[0][0][1]


FACTORS = {"hunt-crossley": lambda e: 1.5 * (1 - e), "lankarani-nikravesh": lambda e: 0.75 * (1 - e * e),
           "flores": lambda e: 1.6 * (1 - e) / e, "gonthier": lambda e: (1 - e * e) / e,
           "hu-guo": lambda e: 1.5 * (1 - e) / e}
E_VALUES = [0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.85, 0.9, 0.95]


@pytest.fixture(scope="module")
def restitution_curves(impact_rig):
    return {law: restitution_error_curve(impact_rig, law, E_VALUES) for law in FACTORS}


@pytest.mark.parametrize("law", sorted(FACTORS))
def test_single_impact_matches_the_laws_own_relation(restitution_curves, law):
    # the simulated impact of the follower on the frozen cam gives the same restitution as
    # an independent 1-DOF impact under the same law (follower rotation during 0.3 ms of
    # contact is negligible)
    values, measured, _ = restitution_curves[law]
    expected = [one_dof_restitution(FACTORS[law](e)) for e in values]
    np.testing.assert_allclose(measured, expected, rtol=2e-3)


def test_published_accuracy_of_the_restitution_laws(restitution_curves):
    err = {law: dict(zip(E_VALUES, curve[2])) for law, curve in restitution_curves.items()}
    # Hunt-Crossley and Lankarani-Nikravesh are first-order in (1 - e): within 3 % from e = 0.9
    for law in ("hunt-crossley", "lankarani-nikravesh"):
        assert all(abs(err[law][e]) < 0.03 for e in (0.9, 0.95)), err[law]
        assert abs(err[law][0.8]) > 0.03  # ... but not at 0.8 (3 % was hoped for there)
    # Flores et al.: within 5 % from e = 0.6; -6 % at 0.5 and -15 % at 0.3 (docs/restitution.md)
    assert all(abs(err["flores"][e]) < 0.05 for e in E_VALUES if e >= 0.6), err["flores"]
    # Gonthier et al. hold 5 % over the whole range 0.3 to 0.95
    assert all(abs(v) < 0.05 for v in err["gonthier"].values()), err["gonthier"]


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "camdyn.cli.app", *args], capture_output=True, text=True)


def test_cli_simulate_json(tmp_path):
    out = tmp_path / "run.nc"
    plot = tmp_path / "run.png"
    code = main(["simulate", "sundar2014-impact", "--set", "cam.runout=3.5mm", "--speed", "960rpm",
                 "--revolutions", "4", "--out", str(out), "--plot", str(plot), "--json"])
    assert code == 0
    assert out.is_file() and plot.is_file()


def test_cli_equilibrium_json(capsys):
    assert main(["equilibrium", "sundar2014-friction", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)["summary"]
    assert data["in_contact"] is True
    assert 500 < data["natural_frequency_Hz"] < 2000


@pytest.mark.parametrize("args, words", [
    (["simulate", "nope"], "no preset named"),
    (["simulate", "sundar2014-impact", "--set", "follower.mass=-1kg"], "must be positive"),
    (["simulate", "sundar2014-impact", "--set", "cam.radius=17.5 blorps"], "cannot read"),
    (["simulate", "sundar2014-impact", "--set", "cam.colour=red"], "unknown parameter"),
    (["simulate", "sundar2014-impact", "--speed", "fast"], "speed"),
    (["equilibrium", "sundar2014-impact", "--set", "cam.pivot_y=300mm"], "cannot reach"),
    (["simulate"], "Missing argument"),
])
def test_cli_bad_input_exits_2_with_one_line(args, words):
    proc = run_cli(*args)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith("error:") and words in lines[0]
    assert "Traceback" not in proc.stderr


def test_cli_presets(capsys):
    assert main(["presets"]) == 0
    assert "sundar2014-impact" in capsys.readouterr().out
    assert main(["presets", "show", "sundar2014-friction"]) == 0
    assert 'runout = "1.75 mm"' in capsys.readouterr().out
