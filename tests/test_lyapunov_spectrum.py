"""The Lyapunov spectrum from the variational equations with saltation, against values
found without it: the forced linear oscillator's decay rate -zeta w_n (closed form); the
rigid-impact oscillator's period-1 orbit, solved here from its free motion written out,
with the monodromy built from the impact's saltation matrix (det S = r^2, derived below)
and the closed-form sum of exponents; the cam-follower's Floquet multipliers from
shooting (continuation.find_orbit) on a periodic regime, and the two-trajectory estimate
(chaos.lyapunov_exponent) on a chaotic one.

Finite-time bound used below: after N periods from the tangent vector e_1, for a
monodromy B = U diag(mu) U^-1 (U's columns of unit length) and a = U^-1 e_1, the
estimate of lambda_1 = ln|mu_1| / T is off by at most max |ln(c)| / (N T) over the
bounds c of ||B^N e_1|| / |mu_1|^N: (|a_1| (1 - ...), ||a||_1) for real multipliers of
distinct moduli, (sigma_min(U) ||a||, sigma_max(U) ||a||) for a complex pair; the sum of
the exponents is exact (ln|det B| / T), so lambda_2 carries the same bound.
"""

import json
import math

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import fsolve

import camdyn
from camdyn.analysis.chaos import agreement, lyapunov_exponent
from camdyn.analysis.lyapunov import lyapunov_spectrum, model_spectrum
from camdyn.cli.app import main
from camdyn.continuation import find_orbit, system_problem
from camdyn.errors import ParameterError
from camdyn.integrator import driver
from camdyn.model import translating_follower as translating
from camdyn.simulation.sensitivity import integrate_variational
from camdyn.simulation.translating import alzate_rig
from camdyn.systems import registry as systems


def _finite_time_bound(monodromy, periods, period):
    """The bound [1/s] on |lambda_i - ln|mu_i| / T| after ``periods`` periods from e_1
    (module docstring)."""
    mu, vectors = np.linalg.eig(monodromy)
    order = np.argsort(-np.abs(mu))
    mu, vectors = mu[order], vectors[:, order]
    vectors = vectors / np.linalg.norm(vectors, axis=0)
    a = np.linalg.solve(vectors, np.array([1.0, 0.0]))
    if abs(abs(mu[0]) - abs(mu[1])) < 1e-12 * abs(mu[0]):    # a complex pair
        singular = np.linalg.svd(vectors, compute_uv=False)
        low, high = singular[-1] * np.linalg.norm(a), singular[0] * np.linalg.norm(a)
    else:
        ratio = abs(mu[1] / mu[0]) ** periods
        low, high = abs(a[0]) - ratio * abs(a[1]), np.sum(np.abs(a))
    return max(abs(math.log(low)), abs(math.log(high))) / (periods * period)


# --- (a) the forced damped linear oscillator: x'' + 2 zeta w x' + w^2 x = A cos(W t)
W_N, ZETA, FORCE = 1.0, 0.02, 0.7
OSCILLATOR_MATRIX = np.array([[0.0, 1.0], [-W_N ** 2, -2 * ZETA * W_N]])


def test_oscillator_forced_at_its_damped_frequency_decays_at_minus_zeta_omega_n():
    """Forced at the damped frequency w_d = w_n sqrt(1 - zeta^2), one period of the
    homogeneous flow is exp(A T) = exp(-zeta w_n T) I (a full turn of the damped
    rotation): every tangent vector shrinks by exactly that factor per period, so both
    exponents equal -zeta w_n after every period, not only in the limit. What remains is
    the integration error of the matrix (rtol = 1e-10 per step, a few dozen steps per
    period): measured 2e-14 1/s; 1e-9 allowed."""
    forcing = W_N * math.sqrt(1 - ZETA ** 2)
    period = 2 * math.pi / forcing
    np.testing.assert_allclose(expm(OSCILLATOR_MATRIX * period), math.exp(-ZETA * W_N * period) * np.eye(2),
                               atol=1e-14)
    result = model_spectrum(systems.OSCILLATOR, [W_N, ZETA, FORCE, forcing, 0.0], [0.3, 0.0, 0.0], period,
                            periods=50)
    np.testing.assert_allclose(result.running, -ZETA * W_N, rtol=0, atol=1e-9)
    np.testing.assert_allclose(result.per_period, -ZETA * W_N * period, rtol=0, atol=1e-9 * period)
    assert result.events == 100   # guard 0 marks x's zero crossings: two per period, no jump


def test_oscillator_at_any_forcing_converges_to_minus_zeta_omega_n_within_the_finite_time_bound():
    """At a forcing W = 1.3 w_n the period map exp(A T) has the complex multipliers
    exp((-zeta w_n +- i w_d) T): both exponents tend to -zeta w_n, each off by at most
    the finite-time bound (module docstring), 1.04e-6 1/s after 2000 periods here
    (measured off by 0.99e-6); their sum, -2 zeta w_n, is exact every period (the trace
    of A, Liouville's formula): measured 2e-15."""
    forcing = 1.3
    period = 2 * math.pi / forcing
    result = model_spectrum(systems.OSCILLATOR, [W_N, ZETA, FORCE, forcing, 0.0], [0.3, 0.0, 0.0], period,
                            periods=2000)
    bound = _finite_time_bound(expm(OSCILLATOR_MATRIX * period), 2000, period)
    assert bound < 2e-6
    np.testing.assert_allclose(result.exponents, -ZETA * W_N, rtol=0, atol=bound)
    assert result.total == pytest.approx(-2 * ZETA * W_N, abs=1e-12)


# --- (b) the rigid-impact oscillator: the same oscillator (W_N, ZETA_I, FORCE_I) against a
# wall at x = sigma = 0 with x'+ = -r x'-
ZETA_I, FORCE_I, RESTITUTION = 0.05, 1.0, 0.8
IMPACT_MATRIX = np.array([[0.0, 1.0], [-W_N ** 2, -2 * ZETA_I * W_N]])


def _steady(forcing, t):
    """The forced steady state (x [m], x' [m/s]) at t [s]: X cos(W t - phi)."""
    amplitude = FORCE_I / math.hypot(W_N ** 2 - forcing ** 2, 2 * ZETA_I * W_N * forcing)
    phase = math.atan2(2 * ZETA_I * W_N * forcing, W_N ** 2 - forcing ** 2)
    return np.array([amplitude * math.cos(forcing * t - phase), -amplitude * forcing * math.sin(forcing * t - phase)])


def _flight(forcing, t0, state, span):
    """Free flight from ``state`` at t0 [s] for ``span`` [s]: steady state plus the decaying
    homogeneous part."""
    return _steady(forcing, t0 + span) + expm(IMPACT_MATRIX * span) @ (np.asarray(state) - _steady(forcing, t0))


def _impact_saltation(forcing, t, v_minus):
    """Saltation matrix of the impact at t [s] with approach velocity v_minus > 0 [m/s]:
    g = sigma - x, grad g = (-1, 0), dg/dt = -v_minus, R_y = diag(1, -r); with
    f- = (v-, a-), f+ = (-r v-, a+) (a the acceleration at x = sigma, at either velocity),
    S = R_y + (f+ - R_y f-) grad^T / (-v-) = [[-r, 0], [(a+ + r a-) / v-, -r]], so
    det S = r^2 whatever the impact's phase and speed."""
    accel = lambda v: FORCE_I * math.cos(forcing * t) - 2 * ZETA_I * W_N * v   # - w^2 sigma = 0
    v_plus = -RESTITUTION * v_minus
    return np.array([[-RESTITUTION, 0.0], [(accel(v_plus) + RESTITUTION * accel(v_minus)) / v_minus, -RESTITUTION]])


def test_rigid_impact_period_one_orbit_exponents_are_its_closed_form_multipliers():
    """Forcing W = 2.5 w_n: one impact per period. The orbit (impact phase t_i, rebound
    velocity v) is solved from the free flight; its monodromy from t = 0 is
    exp(A (T - t_i)) S exp(A t_i). Its multipliers are a complex pair, so both exponents
    tend to ln|mu| / T, each within the finite-time bound after 400 periods (1.2e-3 1/s;
    measured off by 7.7e-4). Their sum is exact: -2 zeta w_n + ln(det S) / T =
    -2 zeta w_n + 2 ln(r) / T, to the integration error (measured 3e-14; 1e-10 allowed)."""
    forcing = 2.5
    period = 2 * math.pi / forcing

    def residual(u):   # leave the wall at t_i with v < 0, come back one period later with -v / r
        return _flight(forcing, u[0], [0.0, u[1]], period) - np.array([0.0, -u[1] / RESTITUTION])
    t_impact, v = fsolve(residual, [1.1, -0.5], xtol=1e-14)
    assert np.max(np.abs(residual([t_impact, v]))) < 1e-12 and v < 0
    t_impact %= period
    flight = [_flight(forcing, t_impact, [0.0, v], s)[0] for s in np.linspace(0.01, period - 0.01, 200)]
    assert max(flight) < 0.0   # a true orbit: in flight between the impacts
    start = _flight(forcing, t_impact, [0.0, v], period - t_impact)   # the orbit's state at t = 0 (= T)
    salt = _impact_saltation(forcing, t_impact, -v / RESTITUTION)
    assert np.linalg.det(salt) == pytest.approx(RESTITUTION ** 2, rel=1e-12)
    monodromy = expm(IMPACT_MATRIX * (period - t_impact)) @ salt @ expm(IMPACT_MATRIX * t_impact)
    expected = np.log(np.abs(np.linalg.eigvals(monodromy))) / period
    periods = 400
    result = model_spectrum(systems.RIGID_IMPACT, [W_N, ZETA_I, FORCE_I, forcing, 0.0, RESTITUTION],
                            [start[0], start[1], 0.0], period, periods=periods)
    assert result.events == periods
    bound = _finite_time_bound(monodromy, periods, period)
    assert bound < 5e-3
    np.testing.assert_allclose(result.exponents, np.sort(expected)[::-1], rtol=0, atol=bound)
    assert result.total == pytest.approx(-2 * ZETA_I * W_N + 2 * math.log(RESTITUTION) / period, abs=1e-10)


def test_rigid_impact_sum_of_exponents_is_the_divergence_plus_the_impacts_log_det():
    """Eq. (2) with the closed forms: trace J = -2 zeta w_n, and ln det S = 2 ln r at every
    impact, so sum(lambda) = -2 zeta w_n + 2 ln(r) (impacts per second), on any motion:
    here from rest at W = 2.68 w_n (past the period doubling: two impacts of different
    speeds per two periods) and W = 4.5 w_n (one impact every second period). Measured
    off by 2e-13 and 1e-11 (the matrix's integration error over 100-200 impacts); 1e-10
    allowed."""
    for forcing in (2.68, 4.5):
        period = 2 * math.pi / forcing
        result = model_spectrum(systems.RIGID_IMPACT, [W_N, ZETA_I, FORCE_I, forcing, 0.0, RESTITUTION],
                                [-1.0, 0.0, 0.0], period, periods=200, transient=20)
        assert result.events > 0
        rate = result.events / (result.periods * period)
        assert result.total == pytest.approx(-2 * ZETA_I * W_N + 2 * math.log(RESTITUTION) * rate, abs=1e-10)


# --- (c) the rocking cam-follower, chapter 3 rig at runout 3.5 mm (docs/sweeps.md)
@pytest.fixture(scope="module")
def rig():
    return camdyn.load_system("sundar2014-impact", {"cam.runout": "3.5 mm"})


def test_cam_follower_periodic_exponents_are_the_floquet_exponents_of_shooting(rig):
    """12 Hz: one impact per revolution. find_orbit's monodromy M (its own variational
    run from its own Newton-converged state) gives the multipliers 0.379 and 0.090. In
    the norm (alpha, alpha_dot / Omega), B = D M D^-1, the spectrum after N = 400
    revolutions from e_1 must be (1/NT) ln||B^N e_1|| and the rest of ln|det B| / T
    (computed here by power iteration on B), to the accuracy of the multipliers from a
    variational run at rtol = 1e-8 (system_problem's: within 5e-6 of those at 1e-10,
    measured there), 5e-6 / (0.090 T) = 6.7e-4 1/s on the smaller one; measured 6e-5.
    And ln|mu_i| / T within the finite-time bound plus that (3.5e-2 1/s; measured off
    by 3.4e-2: the start direction's share of the slow eigenvector, ln|a_1| / (N T), is
    nearly the whole bound)."""
    system = rig.with_values(**{"motion.speed": 12.0})
    orbit = find_orbit(system_problem(system))
    assert orbit.stable and orbit.impacts_per_period == 1 and orbit.multipliers.imag.max() == 0.0
    period, periods = 1.0 / 12.0, 400
    scale = np.diag([1.0, period / (2 * math.pi)])
    monodromy = scale @ orbit.monodromy @ np.linalg.inv(scale)
    vector, growth = np.array([1.0, 0.0]), 0.0
    for _ in range(periods):
        vector = monodromy @ vector
        growth += math.log(np.linalg.norm(vector))
        vector /= np.linalg.norm(vector)
    first = growth / (periods * period)
    finite = [first, math.log(abs(np.linalg.det(monodromy))) / period - first]
    result = lyapunov_spectrum(system, revolutions=periods, transient=200)
    accuracy = 5e-6 / (np.min(np.abs(orbit.multipliers)) * period)
    np.testing.assert_allclose(result.exponents, finite, rtol=0, atol=accuracy)
    floquet = np.log(np.abs(orbit.multipliers)) / period
    np.testing.assert_allclose(result.exponents, floquet, rtol=0,
                               atol=_finite_time_bound(monodromy, periods, period) + accuracy)
    assert result.per_period == pytest.approx(result.exponents * period, rel=1e-12)
    assert result.kaplan_yorke_dimension == 0.0 and result.speed == 12.0


def test_cam_follower_chaotic_largest_exponent_agrees_with_the_two_trajectory_estimate(rig):
    """18 Hz, inside the chaotic band (docs/sweeps.md). The two estimators follow
    different trajectories on the attractor (the variational run's error control also
    watches the matrix, so its steps differ and the orbits part within a few dozen
    revolutions), so they agree only within the spread of finite-time exponents.
    Measured over ten disjoint 1000-revolution windows (transients 200, 1200, ...
    9200): two trajectories 6.76 +- 0.18 1/s, spectrum 6.87 +- 0.27 1/s (means +-
    standard deviations; the means agree within their standard error, 0.10); the
    two-trajectory value hardly depends on the initial gap (6.847, 6.845 and 6.848
    1/s at 1e-7, 1e-8 and 1e-6 rad). Allowed: 3 standard deviations of the difference of
    two such windows, 3 sqrt(0.18^2 + 0.27^2) = 0.97 1/s; measured 6.85 against 6.65.
    Both positive: chaotic; the Kaplan-Yorke dimension of the attractor is between 1
    and 2 (1 + 6.65 / 39.8).

    Each estimate states its standard error (batch means of its own per-revolution
    growth); the spread of those ten windows, 0.18 and 0.27 1/s, is what a
    1000-revolution estimate's standard error should be: each stated one within a factor
    2 of it. The two agree within their stated uncertainty, and ``agreement`` says so."""
    spectrum = lyapunov_spectrum(rig, speed=18.0, revolutions=1000, transient=200)
    two = lyapunov_exponent(rig, speed=18.0, revolutions=1000, transient=200)
    assert spectrum.largest > 1.0 and two.exponent > 1.0
    assert abs(spectrum.largest - two.exponent) < 3 * math.hypot(0.18, 0.27)
    assert 1.0 < spectrum.kaplan_yorke_dimension < 2.0
    assert spectrum.kaplan_yorke_dimension == pytest.approx(1 + spectrum.exponents[0] / -spectrum.exponents[1])
    assert 0.18 / 2 < two.error < 0.18 * 2 and 0.27 / 2 < spectrum.errors[0] < 0.27 * 2
    agree, text = agreement(two, spectrum)
    assert agree and "agree within their uncertainty" in text
    assert abs(spectrum.largest - two.exponent) <= 2 * math.hypot(two.error, spectrum.errors[0]) + 2 * math.log(
        10.0) * 18.0 / 1000


# --- the translating follower on the Alzate / di Bernardo cam (Siconos example), rigid
# contact with Newton's restitution e = 0.8, no damping
def _alzate(rpm, phase=math.pi / 2):
    """(p, start on the cam at the cam angle ``phase`` [rad], by default the end of the
    base dwell, period [s]) at ``rpm``."""
    speed = rpm * 2 * math.pi / 60
    p = alzate_rig().pack(speed, phase)
    _, lift, lift_rate, _, _ = translating.cam(0.0, p)
    return p, np.array([lift, lift_rate]), 2 * math.pi / speed


def test_translating_follower_rebound_from_the_moving_cam_carries_the_reset_rate_in_time():
    """An impact on the cam's flank, where its lift accelerates (s_ddot = 1500 m/s^2 at
    660 rpm): the reset x'+ = s_dot(t) - e (x'- - s_dot(t)) moves with time, and the
    saltation matrix needs its rate R_t = (0, (1 + e) s_ddot) (Leine and Nijmeijer 2004,
    eq. 1 of camdyn.systems.variational). The state-transition matrix over one period
    across it must equal the central differences of two plain runs (steps 1e-8 m and
    1e-6 m/s; at steps ten and a hundred times smaller they move by 2.6e-6 and 1.5e-5 of
    the matrix, round-off). Measured 4e-7 of the matrix's largest entry; 1e-5 allowed.
    Without R_t the matrix was off by 0.88 of it (-16.5 against -133.9 m/s per m, and
    the spectrum at 660 rpm came out negative, -0.15 per revolution)."""
    p, y, period = _alzate(660)
    t = 0.0

    def advance(state, start, span):
        out, _, events, counters = driver.integrate(systems.TRANSLATING_FOLLOWER, p, state, start, start + span,
                                                    np.array([start + span]), 1e-12, 1e-14, period / 64,
                                                    driver.METHOD_AUTO, 10 ** 8, 1000, True, math.inf)
        events = events[:int(counters[driver.COUNT_EVENTS])]
        return out[0].copy(), events[events[:, driver.EVENT_GUARD] != translating.JOINT]   # the profile's joints
    for _ in range(150):
        y, _ = advance(y, t, period)
        t += period
    for _ in range(40):   # the first period whose one impact lands where the lift accelerates
        _, events = advance(y, t, period)
        if len(events) == 1 and abs(translating.cam(events[0, 0], p)[3]) > 100.0:
            break
        y, _ = advance(y, t, period)
        t += period
    else:
        pytest.fail("no impact on the flank within 40 periods")
    matrix = integrate_variational(systems.TRANSLATING_FOLLOWER, p, y, t, t + period, rtol=1e-12, atol=1e-14,
                                   max_step=period / 64).matrix
    differences = np.empty((2, 2))
    for j, step in enumerate((1e-8, 1e-6)):
        shift = np.zeros(2)
        shift[j] = step
        differences[:, j] = (advance(y + shift, t, period)[0] - advance(y - shift, t, period)[0]) / (2 * step)
    assert np.max(np.abs(matrix - differences)) < 1e-5 * np.max(np.abs(differences))


@pytest.mark.parametrize("rpm, chaotic", [(358, False), (660, True), (700, False)])
def test_translating_follower_spectrum_is_positive_only_at_660_rpm_and_sums_to_the_impacts(rpm, chaotic):
    """The Siconos benchmark's regimes (tests/test_siconos_benchmark.py: period 3 at 358
    rpm, period 1 at 700, chaotic at 660, where two runs part at about e^0.3 per
    revolution): the largest exponent is positive at 660 rpm only (measured 0.42 per
    revolution; -0.41 and -0.21 at 358 and 700). With no damping trace J = 0, and an
    impact on the moving cam has det S = e^2 (S = [[-e, 0], [(1 + e)(x'' - s_ddot) /
    (x'- - s_dot), -e]] from eq. 1 with R_t), so the sum is 2 ln(e) per impact per second
    (every event here is an impact, but for the cam's 7 joints a revolution, det S = 1:
    no reset, and the guard does not depend on the state; a capture into sustained
    contact would erase the perturbation, -inf). The periods start 0.3 rad past the end
    of the base dwell: at the dwell's end, itself a joint, the joint's event falls within
    the resolution of time of a period's start or end, in one period or the next, and
    the count of joints is off by one (the exponents do not depend on where the periods
    start). The runs take rtol 1e-12 (atol 1e-14): at the default 1e-10 the sum was off
    by 0.2e-10 to 5.0e-10 1/s on the AMD EPYC development machine but by 1.9e-9 and
    2.8e-9 1/s at 660 and 358 rpm on an Intel Xeon (numba compiles for the machine's
    instructions, and the rounding differs); at 1e-12 measured there 3.2e-10 to 6.5e-10
    1/s (the matrix's integration error over 400 to 1066 impacts); 1e-9 1/s allowed."""
    p, y, period = _alzate(rpm, math.pi / 2 + 0.3)
    result = model_spectrum(systems.TRANSLATING_FOLLOWER, p, y, period, periods=400, transient=200, rtol=1e-12,
                            atol=1e-14)
    if chaotic:
        assert result.largest * period > 0.2
    else:
        assert result.largest < 0.0
    joints = len(alzate_rig().profile.joints) * result.periods   # one event per joint and revolution
    rate = (result.events - joints) / (result.periods * period)
    assert result.total == pytest.approx(2 * math.log(0.8) * rate, abs=1e-9)


@pytest.mark.parametrize("call, words", [
    (lambda: model_spectrum(systems.VARIATIONAL + 1, [1.0] * 5, [0.0] * 3, 1.0), "registered model"),
    (lambda: model_spectrum(systems.OSCILLATOR, [1.0] * 5, [0.0, 0.0], 1.0), "3 finite numbers"),
    (lambda: model_spectrum(systems.OSCILLATOR, [1.0] * 5, [0.0] * 3, 0.0), "period must be positive"),
    (lambda: model_spectrum(systems.OSCILLATOR, [1.0] * 5, [0.0] * 3, 1.0, weights=[1.0, -1.0]), "weights"),
    (lambda: model_spectrum(systems.OSCILLATOR, [1.0] * 5, [0.0] * 3, 1.0, periods=0), "periods"),
    (lambda: model_spectrum(systems.OSCILLATOR, [1.0] * 5, [0.0] * 3, 1.0, transient=-1), "transient"),
    (lambda: model_spectrum(systems.OSCILLATOR, [1.0] * 5, [0.0] * 3, 1.0, rtol=1.0), "rtol"),
    (lambda: lyapunov_spectrum("sundar2014-impact"), "load it first"),
])
def test_bad_input_is_refused_before_any_work(call, words):
    with pytest.raises(ParameterError, match=words):
        call()


def test_cam_follower_refusals(rig):
    with pytest.raises(ParameterError, match="constant cam motion"):
        lyapunov_spectrum(rig.with_values(**{"motion.kind": "ramp", "motion.start_speed": 1.0,
                                             "motion.ramp_time": 1.0}))
    with pytest.raises(ParameterError, match="revolutions"):
        lyapunov_spectrum(rig, speed=12.0, revolutions=0)
    with pytest.raises(ParameterError, match="does not move"):
        lyapunov_spectrum(rig, speed=0.0)


def test_cli_lyapunov_spectrum_json_and_text(capsys):
    args = ["lyapunov", "sundar2014-impact", "--set", "cam.runout=3.5mm", "--speed", "12Hz", "--revolutions", "60",
            "--transient", "40", "--spectrum"]
    assert main(args + ["--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    direct = lyapunov_spectrum(camdyn.load_system("sundar2014-impact", {"cam.runout": "3.5 mm"}), speed=12.0,
                               revolutions=60, transient=40)
    # the command passes the preset, --set, --speed, --revolutions and --transient through
    np.testing.assert_allclose(doc["summary"]["spectrum_per_s"], direct.exponents, rtol=1e-12)
    np.testing.assert_allclose(doc["summary"]["spectrum_per_revolution"], direct.exponents / 12.0, rtol=1e-12)
    assert doc["summary"]["spectrum_sum_per_s"] == pytest.approx(direct.total, rel=1e-12)
    assert doc["kaplan_yorke_dimension"] == 0.0 and doc["spectrum_events"] == direct.events
    assert main(args) == 0
    assert "Lyapunov spectrum (variational equations with saltation)" in capsys.readouterr().out
    assert main(args[:-1] + ["--json"]) == 0
    assert "spectrum_per_s" not in json.loads(capsys.readouterr().out)["summary"]
