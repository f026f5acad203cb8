"""Periodic orbits by shooting, their Floquet multipliers and their continuation, against
closed forms: the forced linear oscillator's steady state (amplitude and phase) and
multipliers exp(lambda T); the rigid-impact oscillator's period-1 one-impact orbit, solved
here from its free motion between impacts written out, its monodromy with the impact's
saltation matrix, its period doubling (a multiplier at -1) and its grazing (the
non-impacting orbit's amplitude reaching the wall)."""

import dataclasses
import math

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq, fsolve, minimize_scalar

from camdyn.continuation import branches, find_orbit, model_problem
from camdyn.continuation.branches import _Continuation, continuation_scales, continue_orbits
from camdyn.continuation.orbits import flow
from camdyn.errors import ParameterError, SimulationError
from camdyn.systems import registry as systems

W_NATURAL, ZETA, FORCE, RESTITUTION = 1.0, 0.05, 1.0, 0.8


def test_linear_oscillator_orbit_is_the_steady_state_and_its_multipliers_exp_lambda_t():
    w, zeta, force, forcing = 2.0, 0.05, 0.7, 1.3
    problem = model_problem(systems.OSCILLATOR, [w, zeta, force, forcing, 0.0], [0.0, 0.0, 0.0])
    orbit = find_orbit(problem, start=[0.0, 0.0])
    # x = X cos(W t - phi), X = A / sqrt((w^2 - W^2)^2 + (2 zeta w W)^2), tan phi = 2 zeta w W / (w^2 - W^2)
    amplitude = force / math.hypot(w * w - forcing * forcing, 2 * zeta * w * forcing)
    phase = math.atan2(2 * zeta * w * forcing, w * w - forcing * forcing)
    np.testing.assert_allclose(orbit.state, [amplitude * math.cos(phase), amplitude * forcing * math.sin(phase)],
                               rtol=0, atol=1e-9)
    period = 2 * math.pi / forcing
    assert orbit.period == pytest.approx(period, rel=1e-15)
    # lambda = -zeta w +- i w sqrt(1 - zeta^2)
    lam = complex(-zeta * w, w * math.sqrt(1 - zeta * zeta))
    expected = np.exp(np.array([lam, lam.conjugate()]) * period)
    assert np.max(np.abs(np.sort_complex(orbit.multipliers) - np.sort_complex(expected))) < 1e-9
    assert orbit.stable and orbit.impacts_per_period == 0


def _free(forcing, t_impact, x0, v0, s):
    """The rigid-impact oscillator's free motion s [s] after leaving (x0, v0) at t_impact:
    steady state plus damped homogeneous solution."""
    w, z = W_NATURAL, ZETA
    amplitude = FORCE / math.hypot(w * w - forcing * forcing, 2 * z * w * forcing)
    phase = math.atan2(2 * z * w * forcing, w * w - forcing * forcing)
    xp = lambda t: amplitude * math.cos(forcing * t - phase)
    vp = lambda t: -amplitude * forcing * math.sin(forcing * t - phase)
    wd = w * math.sqrt(1 - z * z)
    c1 = x0 - xp(t_impact)
    c2 = (v0 - vp(t_impact) + z * w * c1) / wd
    decay = math.exp(-z * w * s)
    cos, sin = math.cos(wd * s), math.sin(wd * s)
    x = xp(t_impact + s) + decay * (c1 * cos + c2 * sin)
    v = vp(t_impact + s) + decay * (-z * w * (c1 * cos + c2 * sin) + wd * (c2 * cos - c1 * sin))
    return x, v


def _impact_orbit(forcing, sigma, guess):
    """Impact phase t_i [s] and rebound velocity v [m/s] of the period-1 one-impact orbit:
    leave the wall with v at t_i, return one period later with -v / r."""
    period = 2 * math.pi / forcing

    def residual(u):
        x, v = _free(forcing, u[0], sigma, u[1], period)
        return [x - sigma, v + u[1] / RESTITUTION]
    solution = fsolve(residual, guess, xtol=1e-14)
    assert np.max(np.abs(residual(solution))) < 1e-12 and solution[1] < 0
    return solution


HOMOGENEOUS = np.array([[0.0, 1.0], [-W_NATURAL ** 2, -2 * ZETA * W_NATURAL]])


def _saltation(forcing, sigma, t_impact, v):
    """The impact's saltation matrix at t_impact [s], rebound velocity v [m/s]."""
    v_minus = -v / RESTITUTION
    accel = FORCE * math.cos(forcing * t_impact) - W_NATURAL ** 2 * sigma
    f_minus = np.array([v_minus, accel - 2 * ZETA * W_NATURAL * v_minus])
    f_plus = np.array([v, accel - 2 * ZETA * W_NATURAL * v])
    reset, normal = np.diag([1.0, -RESTITUTION]), np.array([-1.0, 0.0])   # g = sigma - x
    return reset + np.outer(f_plus - reset @ f_minus, normal) / (normal @ f_minus)


def _by_modulus(values):
    return values[np.argsort(-np.abs(values))]


def _closed_form_multipliers(forcing, sigma, t_impact, v):
    """Eigenvalues of the monodromy: saltation at the impact times the free flow over T."""
    monodromy = _saltation(forcing, sigma, t_impact, v) @ expm(HOMOGENEOUS * 2 * math.pi / forcing)
    return _by_modulus(np.linalg.eigvals(monodromy))


def _rigid(forcing, sigma=0.0):
    return model_problem(systems.RIGID_IMPACT, [W_NATURAL, ZETA, FORCE, forcing, sigma, RESTITUTION],
                         [sigma - 1.0, 0.0, 0.0])


def test_rigid_impact_period_one_orbit_and_its_multipliers_match_the_closed_form():
    forcing, sigma = 2.5, 0.0
    t_impact, v = _impact_orbit(forcing, sigma, [1.1, -0.5])
    period = 2 * math.pi / forcing
    t_impact %= period
    # the state at t = 0 (= T): free flight from the impact over the rest of the period
    x0, v0 = _free(forcing, t_impact, sigma, v, period - t_impact)
    flight = [_free(forcing, t_impact, sigma, v, s)[0] for s in np.linspace(0.01, period - 0.01, 200)]
    assert max(flight) < sigma                                  # a true orbit: one impact, in flight otherwise
    orbit = find_orbit(_rigid(forcing))                         # from a 50-period transient
    np.testing.assert_allclose(orbit.state, [x0, v0], rtol=0, atol=1e-11)       # measured 4e-14
    expected = _closed_form_multipliers(forcing, sigma, t_impact, v)
    np.testing.assert_allclose(orbit.multipliers, expected, rtol=0, atol=1e-11)  # measured 4e-14
    assert orbit.stable and orbit.impacts_per_period == 1 and orbit.iterations <= 5


def test_rigid_impact_branch_locates_the_period_doubling_of_the_closed_form():
    def doubling(forcing):                                      # det(M + I): a multiplier at -1
        t_impact, v = _impact_orbit(forcing, 0.0, [1.1, -0.3])
        return float(np.real(np.prod(_closed_form_multipliers(forcing, 0.0, t_impact, v) + 1.0)))
    expected = brentq(doubling, 2.6, 2.7, xtol=1e-14)
    problem = _rigid(2.3)
    branch = continue_orbits(problem, find_orbit(problem), 3.0, step=0.02)
    kinds = [b.kind for b in branch.bifurcations]
    assert kinds == ["period-doubling"], kinds
    found = branch.bifurcations[0]
    assert abs(found.parameter - expected) < 1e-9, (found.parameter, expected)   # measured 2.3e-11
    assert np.min(np.abs(found.orbit.multipliers + 1.0)) < 1e-6
    stable = [o.stable for o in branch.orbits]
    assert all(o.parameter < expected for o, s in zip(branch.orbits, stable) if s)
    assert all(o.parameter > expected for o, s in zip(branch.orbits, stable) if not s)
    assert branch.orbits[-1].parameter == pytest.approx(3.0, abs=1e-12)


def test_rigid_impact_period_two_orbit_matches_the_closed_form():
    forcing, sigma = 2.68, 0.0                                  # just past the period doubling
    period = 2 * math.pi / forcing

    def residual(u):              # two impacts per 2T: (t1, v1) -> (t2, -v2 / r) -> (t1 + 2T, -v1 / r)
        t1, v1, t2, v2 = u
        x, v = _free(forcing, t1, sigma, v1, t2 - t1)
        first = [x - sigma, v + v2 / RESTITUTION]
        x, v = _free(forcing, t2, sigma, v2, t1 + 2 * period - t2)
        return first + [x - sigma, v + v1 / RESTITUTION]
    t1, v1, t2, v2 = fsolve(residual, [1.0, -0.2, 1.2 + period, -0.45], xtol=1e-14)
    assert np.max(np.abs(residual([t1, v1, t2, v2]))) < 1e-12 and abs(v1 - v2) > 0.01   # not the period-1 orbit
    for start, v, span in ((t1, v1, t2 - t1), (t2, v2, t1 + 2 * period - t2)):
        assert max(_free(forcing, start, sigma, v, s)[0] for s in np.linspace(0.01, span - 0.01, 200)) < sigma
    orbit = find_orbit(_rigid(forcing), periods=2, transient=400)
    # its state at t = 0 = 2T: flight from the last impact before 2T, either phase of the orbit
    phases = [_free(forcing, t, sigma, v, 2 * period - t) for t, v in ((t2, v2), (t1 + period, v1))]
    assert min(np.max(np.abs(orbit.state - np.array(phase))) for phase in phases) < 1e-9
    monodromy = (_saltation(forcing, sigma, t1, v1) @ expm(HOMOGENEOUS * (t1 + 2 * period - t2))
                 @ _saltation(forcing, sigma, t2, v2) @ expm(HOMOGENEOUS * (t2 - t1)))
    np.testing.assert_allclose(orbit.multipliers, _by_modulus(np.linalg.eigvals(monodromy)), rtol=0, atol=1e-9)
    assert orbit.period == pytest.approx(2 * period, rel=1e-15) and orbit.impacts_per_period == 2 and orbit.stable


def test_shooting_refuses_bad_input_and_reports_no_convergence():
    with pytest.raises(ParameterError, match="positive integer"):
        find_orbit(_rigid(2.5), periods=0)
    with pytest.raises(ParameterError, match="finite"):
        find_orbit(_rigid(2.5), start=[math.nan, 0.0])
    with pytest.raises(ParameterError, match="forcing frequency"):
        model_problem(systems.RIGID_IMPACT, [1.0, 0.05, 1.0, 0.0, 0.0, 0.8], [-1.0, 0.0, 0.0])
    with pytest.raises(SimulationError, match="did not converge"):
        find_orbit(_rigid(2.5), start=[-0.5, 0.3], max_iterations=1)


def test_non_impacting_branch_ends_at_the_grazing_of_the_closed_form():
    sigma = 1.5
    # the orbit touches the wall where the linear steady state's amplitude reaches sigma
    amplitude = lambda forcing: FORCE / math.hypot(W_NATURAL ** 2 - forcing ** 2, 2 * ZETA * W_NATURAL * forcing)
    expected = brentq(lambda forcing: amplitude(forcing) - sigma, 0.5, 0.99, xtol=1e-14)
    problem = _rigid(0.5, sigma)
    start = find_orbit(problem, transient=300)
    assert start.impacts_per_period == 0 and start.guard_minimum == pytest.approx(sigma - amplitude(0.5), abs=1e-6)
    branch = continue_orbits(problem, start, 0.8, step=0.02)
    assert [b.kind for b in branch.bifurcations] == ["grazing"]
    found = branch.bifurcations[0].parameter
    assert abs(found - expected) < 1e-7, (found, expected)  # measured 4.6e-9
    assert all(o.impacts_per_period == 0 and o.stable for o in branch.orbits)
    assert "step fell below" in branch.stopped


@pytest.fixture(scope="module")
def chapter4():
    """The chapter 4 rig at e/a = 0.05 in sustained contact, its problem in the cam speed
    and its period-1 orbit (Newton from a 1-revolution transient)."""
    import camdyn
    from camdyn.continuation import system_problem
    system = camdyn.load_system("sundar2014-friction").with_values(**{"cam.runout": 0.05 * 17.5e-3})
    problem = system_problem(system, "motion.speed")
    return system, problem, find_orbit(problem, transient=1)


def test_cam_follower_orbit_has_the_harmonics_of_a_long_simulation(chapter4):
    import camdyn
    system, problem, orbit = chapter4
    assert orbit.iterations >= 1 and orbit.impacts_per_period == 0 and orbit.stable
    speed = problem.value
    rate = 256 * speed                                         # a whole number of samples per revolution
    tight = {"rtol": 1e-10, "atol": 1e-12, "sample_rate": rate, "variables": ["alpha", "alpha_ddot"]}
    one = camdyn.simulate(system, revolutions=1, initial_state=orbit.state, **tight)
    long = camdyn.simulate(system, revolutions=12, **tight)    # from rest; the transient decays by 5e-5 a revolution
    for name in ("alpha", "alpha_ddot"):
        ours = np.fft.rfft(one[name].values[:256])[:6] / 256
        theirs = np.fft.rfft(long[name].values[-257:-1])[:6] / 256
        scale = np.abs(theirs[1:]).max()
        assert np.abs(ours - theirs).max() < 1e-6 * scale, (name, np.abs(ours - theirs).max() / scale)


def test_cam_follower_floquet_exponents_are_the_linear_models_eigenvalues(chapter4):
    from camdyn.analysis.linear import linearize
    system, problem, orbit = chapter4
    linear = linearize(system)
    eigenvalues = np.roots([linear.inertia, linear.damping, linear.stiffness])
    period = 1.0 / problem.value
    upper = eigenvalues[np.argmax(eigenvalues.imag)]
    mu = orbit.multipliers[np.argmax(orbit.multipliers.imag)]
    # ln(mu) / T is an eigenvalue up to 2 pi i k / T: take the turn count nearest the linear model's
    turns = round((upper.imag * period - np.angle(mu)) / (2 * math.pi))
    exponent = complex(math.log(abs(mu)), np.angle(mu) + 2 * math.pi * turns) / period
    assert abs(exponent.real - upper.real) < 0.01 * abs(upper.real), (exponent, upper)
    assert abs(exponent.imag - upper.imag) < 0.01 * abs(upper.imag), (exponent, upper)
    assert abs(orbit.multipliers[0]) == pytest.approx(abs(orbit.multipliers[1]), rel=1e-9)   # a complex pair


def test_continue_cli_json_netcdf_and_figure(tmp_path, capsys):
    import json

    import xarray as xr

    from camdyn.cli.app import main
    out, plot = tmp_path / "branch.nc", tmp_path / "branch.png"
    args = ["continue", "sundar2014-friction", "--set", "cam.runout=0.875mm", "--from", "11Hz", "--to", "11.6Hz",
            "--transient", "5", "--out", str(out), "--plot", str(plot), "--json", "--brute-force", "3"]
    assert main(args) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["schema"] == "camdyn.continue/1"
    points = doc["branches"][0]
    assert points[0]["parameter"] == pytest.approx(11.0) and points[-1]["parameter"] == pytest.approx(11.6, abs=1e-9)
    for point in points:
        assert point["stable"] and point["impacts_per_period"] == 0
        assert point["period"] == pytest.approx(1.0 / point["parameter"], rel=1e-12)
        assert point["max_normal_force"] > 0 and 0 < point["max_penetration"] < 1e-4
        assert len(point["multipliers"]) == 2 and all(math.hypot(*m) < 1e-3 for m in point["multipliers"])
    assert doc["bifurcations"] == []
    ds = xr.load_dataset(out, engine="h5netcdf")
    assert ds["parameter"].attrs["units"] == "Hz" and ds["max_normal_force"].attrs["units"] == "N"
    np.testing.assert_allclose(ds["parameter"].values, [p["parameter"] for p in points], rtol=1e-12)
    assert plot.stat().st_size > 1000


@pytest.mark.parametrize("args, words", [
    (["--parameter", "contact.damping", "--from", "1", "--to", "2"], "not a continuous parameter"),
    (["--parameter", "cam.nonsense", "--from", "1", "--to", "2"], "unknown parameter"),
    (["--from", "11Hz", "--to", "11Hz"], "must differ"),
    (["--from", "11Hz", "--to", "12Hz", "--period", "0"], "--period"),
    (["--from", "11Hz", "--to", "12Hz", "--out", "branch.txt"], ".nc"),
    (["--parameter", "cam.runout", "--from", "1.2", "--to", "1.4mm"], "has no unit"),
    (["--from", "11Hz", "--to", "12Hz", "--step", "1e-9"], "step at least"),
    (["--from", "11Hz", "--to", "12Hz", "--brute-force", "20"], "give --plot"),
    (["--from", "11Hz", "--to", "12Hz", "--doublings", "-1"], "--doublings"),
    (["--from", "11Hz", "--to", "12Hz", "--set", "motion.kind=ramp", "--set", "motion.ramp_time=1s"], "ramp"),
    (["--from", "11Hz", "--to", "12Hz", "--set", "motion.kind=oscillating", "--set", "motion.frequency=5Hz",
      "--set", "motion.amplitude=0.1"], "motion.frequency"),
])
def test_continue_cli_refuses_bad_input_in_one_line(args, words, capsys):
    from camdyn.cli.app import main
    assert main(["continue", "sundar2014-friction", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error:") and words in err[0], err


def test_cam_follower_branch_loses_contact_at_the_inverse_kinematics_speed():
    import camdyn
    from camdyn.analysis.kinematics import inverse_kinematics, loss_of_contact_speed
    from camdyn.continuation.results import trace_branch
    system = camdyn.load_system("sundar2014-friction")                  # e/a = 0.1
    # rigid contact: the lowest speed at which the cam's motion needs a pulling force
    expected = loss_of_contact_speed(system)
    _, branch = trace_branch(system, "motion.speed", 17.5, 18.1, transient=30, step=0.01, max_points=20)
    assert branch.orbits[0].impacts_per_period == 0 and branch.orbits[-1].impacts_per_period > 0
    grazing = [b for b in branch.bifurcations if b.kind == "grazing"]
    assert grazing, [b.kind for b in branch.bifurcations]
    # the rigid-contact kinematics leave out the Hertz contact's compliance and the follower's
    # dynamic response, of relative order (f / f_n)^2 = (18 Hz / 961 Hz)^2 = 4e-4
    assert abs(grazing[0].parameter - expected) < 2e-3 * expected, (grazing[0].parameter, expected)
    # min Fn = 0 is located too (measured 7.8e-4 below the kinematics), before the gap opens
    loss = [b for b in branch.bifurcations if b.kind == "contact-loss"]
    assert len(loss) == 1 and abs(loss[0].parameter - expected) < 2e-3 * expected, (loss, expected)
    assert loss[0].parameter <= grazing[0].parameter and abs(loss[0].orbit.force_minimum) < 1e-6
    # the test functions are the orbit's smallest Fn and vr: a simulation of the first orbit
    # (dense samples, its own output code) gives the same; the rigid kinematics' vr is
    # Omega (w - alpha_k' h) > 0 at every speed, so sliding never reverses on this branch
    orbit = branch.orbits[0]
    one = camdyn.simulate(system.with_values(**{"motion.speed": orbit.parameter}), revolutions=1,
                          initial_state=orbit.state, rtol=1e-10, atol=1e-12, sample_rate=4096 * orbit.parameter,
                          variables=["Fn", "sliding_velocity"])
    assert orbit.force_minimum == pytest.approx(float(one["Fn"].min()), rel=1e-5)
    assert orbit.sliding_minimum == pytest.approx(float(one["sliding_velocity"].min()), rel=1e-6)
    kinematic = inverse_kinematics(system, speed=orbit.parameter)["sliding_velocity"]
    assert orbit.sliding_minimum == pytest.approx(float(kinematic.min()), rel=1e-5)      # measured 1e-7
    assert "sliding-reversal" not in [b.kind for b in branch.bifurcations]


def test_branch_figure_draws_unstable_dashed_and_is_readable(tmp_path, monkeypatch):
    import xarray as xr

    from camdyn.continuation.results import branches_dataset
    from camdyn.plotting import layout_problems, style
    from camdyn.plotting.branches import plot_branches
    seen = []

    def hook(fig):
        styles = {(line.get_linestyle(), round(float(np.mean(line.get_xdata())), 3))
                  for line in fig.axes[0].get_lines()}
        dots = [line for line in fig.axes[0].get_lines() if line.get_marker() == "."]
        forces = np.concatenate([line.get_ydata() for line in fig.axes[1].get_lines() if len(line.get_ydata()) > 2])
        seen.append((layout_problems(fig), styles, fig.axes[-1].get_xlabel(), dots, forces, fig.axes[1].get_ylabel()))
    monkeypatch.setattr(style, "SAVE_HOOKS", [hook])
    speeds = np.linspace(10.0, 20.0, 11)
    records = [[{"parameter": s, "stable": s < 15.0, "multipliers": [[-0.1 * s / 1.5, 0.0], [0.01, 0.0]],
                 "period": 1 / s, "impacts_per_period": 1, "max_normal_force": 1e3 * (5.0 + s),
                 "max_penetration": 1e-6, "state": [0.07, 0.1]} for s in speeds]]
    problem = model_problem(systems.RIGID_IMPACT, [1.0, 0.05, 1.0, 2.0, 0.0, 0.8], [-1.0, 0.0, 0.0])
    problem = dataclasses.replace(problem, name="motion.speed", unit="Hz")
    ds = branches_dataset(problem, records, [{"kind": "period-doubling", "parameter": 15.0, "branch": 0}])
    assert ds["max_normal_force"].attrs["units"] == "N"
    assert ds["bifurcation_kind"].values.tolist() == ["period-doubling"]
    plot_branches(ds, tmp_path / "branch.png")
    problems, styles, xlabel, dots, forces, force_label = seen[0]
    assert problems == [], problems
    # stable 10-14 Hz solid (mean 12); unstable 15-20 Hz dashed, joined to the last stable point (mean 17)
    assert ("-", 12.0) in styles and ("--", 17.0) in styles, styles
    assert "Hz" in xlabel and dots == []
    # the forces, 15 to 25 kN, drawn in kN
    assert "kN" in force_label and forces.min() == pytest.approx(15.0) and forces.max() == pytest.approx(25.0)
    # over a brute-force diagram: its Poincare points drawn as dots, in degrees like the branches
    diagram = xr.Dataset({"poincare_alpha": (("motion.speed", "revolution"), np.full((6, 3), 0.07),
                                             {"units": "rad"})},
                         coords={"motion.speed": ("motion.speed", np.linspace(10.0, 20.0, 6), {"units": "Hz"})})
    plot_branches(ds, tmp_path / "overlay.png", diagram)
    problems, styles, _, dots, _, _ = seen[1]
    assert problems == [] and ("-", 12.0) in styles and len(dots) == 1, (problems, styles)
    np.testing.assert_allclose(dots[0].get_ydata(), math.degrees(0.07))
    np.testing.assert_allclose(dots[0].get_xdata(), np.repeat(np.linspace(10.0, 20.0, 6), 3))


def test_rigid_impact_branch_turns_round_the_fold_of_the_closed_form():
    # Wall beyond the rest position (sigma = 1.5): the one-impact orbit born at grazing is
    # unstable, and its forcing frequency W(v), written in closed form against the rebound
    # velocity v, falls to a minimum (a fold) before the stable side rises again.
    # Continued downwards from a stable orbit, the branch must turn round the fold and
    # come back along the unstable side, not retrace the stable one.
    sigma = 1.5

    def frequency(v, guess=(11.0, 0.53)):          # (t_i, W) of the closed-form orbit at rebound v
        def residual(u):
            x, velocity = _free(u[1], u[0], sigma, v, 2 * math.pi / u[1])
            return [x - sigma, velocity + v / RESTITUTION]
        solution = fsolve(residual, guess, xtol=1e-14)
        assert np.max(np.abs(residual(solution))) < 1e-12
        return solution
    fold = minimize_scalar(lambda v: frequency(v)[1], bounds=(-0.3, -0.1), method="bounded",
                           options={"xatol": 1e-10})
    expected = fold.fun                                          # the fold's W [rad/s]
    t_impact, forcing = frequency(-0.6, (9.7, 0.545))            # stable, one impact (grazing from
    period = 2 * math.pi / forcing                               # inside past v = -0.9)
    start_state = _free(forcing, t_impact % period, sigma, -0.6, period - t_impact % period)
    problem = _rigid(forcing, sigma)
    start = find_orbit(problem, start=list(start_state))
    assert start.stable and start.impacts_per_period == 1
    branch = continue_orbits(problem, start, 0.45, step=0.02)
    folds = [b for b in branch.bifurcations if b.kind == "fold"]
    assert len(folds) == 1 and abs(folds[0].parameter - expected) < 1e-7, (branch.bifurcations, expected)   # 4e-12
    parameters = np.array([o.parameter for o in branch.orbits])
    turn = int(np.argmin(parameters))
    assert parameters.min() > expected - 1e-9 and 0 < turn < parameters.size - 1
    assert all(o.stable for o in branch.orbits[:turn]) and not any(o.stable for o in branch.orbits[turn + 1:])
    assert branch.orbits[-1].parameter > forcing - 1e-9          # back past its start on the unstable side
    for orbit in branch.orbits[turn + 1::3]:                     # the unstable side is the closed form's
        v = brentq(lambda v: frequency(v, (11.0, 0.53))[1] - orbit.parameter, fold.x, -0.02, xtol=1e-14)
        t_impact = frequency(v, (11.0, 0.53))[0] % orbit.period
        expected_state = _free(orbit.parameter, t_impact, sigma, v, orbit.period - t_impact)
        np.testing.assert_allclose(orbit.state, expected_state, rtol=0, atol=1e-8)
        assert orbit.impacts_per_period == 1 and np.max(np.abs(orbit.multipliers)) > 1.0


def _oscillator_point():
    """The forced linear oscillator's orbit as a continuation point, and its job."""
    problem = model_problem(systems.OSCILLATOR, [2.0, 0.05, 0.7, 1.3, 0.0], [0.0, 0.0, 0.0])
    orbit = find_orbit(problem, start=[0.0, 0.0])
    scales = continuation_scales(orbit)
    job = _Continuation(problem, 1, scales, 1e-10, 15)
    return job, job.point(job.pack(orbit) / scales, np.r_[0.0, 0.0, 1.0], 0)


def test_corrector_tries_another_points_jacobian_before_newtons_iterations(monkeypatch):
    job, point = _oscillator_point()
    wrong = point.jacobian.copy()
    wrong[:, :-1] *= -3.0                 # chord steps with it grow by 4/3 per iteration
    guess, arclength = point.z + 0.01 * point.tangent, 0.01
    with pytest.raises(SimulationError):
        job._iterate(guess, point.tangent, point.z, arclength, wrong)
    runs = []
    monkeypatch.setattr(branches, "flow", lambda *args, **kw: runs.append(args) or flow(*args, **kw))
    found = job.correct(guess, point.tangent, point.z, arclength, wrong, (point.jacobian,))
    assert len(runs) == 1                 # the new point's own variational run: no Newton iteration
    runs.clear()
    newton = job.correct(guess, point.tangent, point.z, arclength, wrong)
    assert len(runs) > 1                  # Newton's renewed Jacobians, then the point's run
    np.testing.assert_allclose(found.z, newton.z, rtol=0, atol=1e-9)
    # the orbit at the corrected parameter, solved on its own
    x, value = job.unscale(found.z)
    alone = find_orbit(job.problem, start=x, value=value)
    np.testing.assert_allclose(x, alone.state, rtol=0, atol=1e-9)


def test_guard_samples_are_the_guards_at_each_sample():
    problem = model_problem(systems.RIGID_IMPACT, [1.0, 0.05, 1.0, 2.0, 0.0, 0.8], [-1.0, 0.0, 0.0])
    p, _ = problem.build(problem.value)
    times = np.linspace(0.0, 3.0, 7)
    states = np.column_stack([np.sin(times), np.cos(times), times])
    out = np.empty(times.size)
    systems.guard_samples(problem.system_id, p, times, states, 0, out)
    values, rates = np.empty(systems.guard_count(problem.system_id)), np.empty(systems.guard_count(problem.system_id))
    for t, y, got in zip(times, states, out):
        systems.guards(problem.system_id, t, y, y, False, p, values, rates)
        assert got == values[0]
