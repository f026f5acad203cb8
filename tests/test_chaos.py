"""The largest Lyapunov exponent across impacts, and the bifurcation / lyapunov commands.

The exponent is checked against values computed without it: the decay rate -zeta w_n of
the follower resting on a round cam (a closed form), the Floquet multipliers of a periodic
impact orbit (the finite-difference Jacobian of the once-per-period map), and, in the
chaotic band, the product of those Jacobians along the orbit (the tangent-map estimate).
"""

import json
import math

import numpy as np
import pytest

import camdyn
from camdyn.analysis.chaos import START_ALLOWANCE, agreement, lyapunov_exponent
from camdyn.analysis.lyapunov import lyapunov_spectrum
from camdyn.cli.app import main
from camdyn.errors import ParameterError
from camdyn.integrator import driver
from camdyn.simulation import limits
from camdyn.simulation.runner import prepare
from camdyn.sweeps import compute_chunk, spec_from_dict
from camdyn.systems import registry as systems

RIG = {"cam.runout": "3.5 mm"}
RTOL, ATOL = 1e-10, 1e-13   # lyapunov_exponent's defaults: the orbits below are the same


@pytest.fixture(scope="module")
def rig():
    return camdyn.load_system("sundar2014-impact", RIG)


def _period_map(system):
    """y -> state one cam period later (starting at t), as lyapunov_exponent advances it."""
    prep = prepare(system)
    period = system.motion.period
    largest, scan = limits.step_limits(period)   # [s], as lyapunov_exponent steps

    def advance(y, t):
        out, _, _, counters = driver.integrate(systems.CAM_FOLLOWER, prep.p, y, t, t + period, np.array([t + period]),
                                               RTOL, ATOL, largest, driver.METHOD_AUTO, 10 ** 8, 16, False, scan)
        assert counters[driver.COUNT_STATUS] == driver.STATUS_OK
        return out[0].copy()

    return prep.y0, period, advance


def _map_jacobian(advance, y, t, omega, eps=1e-7):
    """Central-difference Jacobian of the period map in (alpha, alpha_dot / Omega) [rad]."""
    m = np.empty((2, 2))
    for j in range(2):
        d = np.zeros(3)
        d[j] = eps * (omega if j == 1 else 1.0)
        m[:, j] = (advance(y + d, t)[:2] - advance(y - d, t)[:2]) / (2 * eps)
    m[1] /= omega
    return m


def test_exponent_on_a_round_cam_is_minus_zeta_omega_n():
    """With no runout the cam is a circle about its axis and nothing depends on time: the
    follower rests at its equilibrium and a disturbance decays as exp(-zeta w_n t), so the
    exponent is -zeta w_n with the preset's zeta = 1.8 % (viscous law A, defined on the
    undamped linearization) and w_n the linearized natural frequency. Friction is off
    (it would couple the damping force into the moment). The cam speed only sets the
    renormalization period; at Omega = w_n the gap's (alpha, alpha_dot / Omega) norm is
    round and the estimate measured 3e-5 off, at 200 Hz (an elongated ellipse, 4.7:1)
    0.5 % off: the phase of the gap on its ellipse at the end moves the estimate by
    ln(4.7) / (zeta w_n N T) = 0.7 % at most (N T = 2 s); 1 % allowed, and 0.1 % at w_n.

    The variational spectrum gives the same closed form for both exponents (a complex
    pair -zeta w_n +- i w_d), to the same tolerances; the two largest agree within their
    stated uncertainty (``agreement``), and the closed form lies within each one's: twice
    its standard error plus the start allowance ln(10) / (N T). (At 200 Hz the growth per
    revolution swings with the gap's phase on its ellipse, and the stated standard error,
    1.7 1/s, overstates the error, 0.5 1/s.)"""
    system = camdyn.load_system("sundar2014-friction", {"cam.runout": "0 mm", "friction.law": "none"})
    eq = prepare(system).equilibrium
    assert eq.in_contact
    zeta = system.contact.damping_ratio   # the preset's 0.018
    omega_n = 2 * math.pi * eq.natural_frequency
    for speed, tolerance in ((eq.natural_frequency, 0.001), (200.0, 0.01)):
        result = lyapunov_exponent(system, speed=speed, revolutions=400, transient=0)
        assert result.exponent == pytest.approx(-zeta * omega_n, rel=tolerance), speed
        spectrum = lyapunov_spectrum(system, speed=speed, revolutions=400, transient=0)
        np.testing.assert_allclose(spectrum.exponents, -zeta * omega_n, rtol=tolerance)
        assert agreement(result, spectrum)[0], speed
        start = START_ALLOWANCE * speed / 400
        assert abs(result.exponent + zeta * omega_n) <= 2 * result.error + start
        assert np.all(np.abs(spectrum.exponents + zeta * omega_n) <= 2 * spectrum.errors + start)


def test_periodic_impacts_exponent_is_the_floquet_multiplier(rig):
    """12 Hz: one impact per revolution (period 1). The exponent must be ln|mu| / T of the
    largest Floquet multiplier mu, the eigenvalue of the Jacobian of the period map at the
    orbit (finite differences of the map, independent of the two-trajectory scheme).
    Measured: multipliers 0.09 and 0.38, both real and inside the unit circle (the orbit
    is stable, and period 1 as the sweep finds below); exponent -11.65 1/s against
    ln(0.38) * 12 = -11.62. They differ by ln|c| / (N T), with c the start direction's
    component along the dominant eigenvector (about 1 in 400 periods: 0.3 %); 1 %
    allowed."""
    system = rig.with_values(**{"motion.speed": 12.0})
    y, period, advance = _period_map(system)
    for k in range(200):
        y = advance(y, k * period)
    multipliers = np.linalg.eigvals(_map_jacobian(advance, y, 200 * period, 2 * math.pi / period))
    assert np.all(np.abs(multipliers) < 1)
    floquet = math.log(np.max(np.abs(multipliers))) / period
    result = lyapunov_exponent(rig, speed=12.0, revolutions=400, transient=200)
    assert result.exponent == pytest.approx(floquet, rel=0.01)


def test_chaotic_exponent_matches_the_tangent_map_estimate(rig):
    """18 Hz, inside the irregular band of the bifurcation diagram (docs/sweeps.md): along
    the same orbit (same start, transient and tolerances, so the reference trajectory is
    the same), the product of the period map's finite-difference Jacobians, renormalized
    each period, gives the exponent without a second trajectory. Measured 6.2927 against
    6.2925 1/s: the two differ by the finite gap (1e-7 rad) against the linearized one
    at the impacts; 3 % allowed. The exponent is positive: chaotic motion. (The period
    starts are summed as lyapunov_exponent sums them: with k * period instead, a few
    ulps away, the two orbits parted within the 400 periods and agreed only by luck.)"""
    system = rig.with_values(**{"motion.speed": 18.0})
    y, period, advance = _period_map(system)
    omega = 2 * math.pi / period
    t = 0.0   # summed period by period, as lyapunov_exponent does: on a chaotic orbit
    for _ in range(200):   # k * period, a few ulps away, gives another orbit within 400 periods
        y = advance(y, t)
        t += period
    v = np.array([1.0, 1.0]) / math.sqrt(2.0)
    total = 0.0
    for _ in range(200, 600):
        v = _map_jacobian(advance, y, t, omega) @ v
        y = advance(y, t)
        t += period
        total += math.log(np.linalg.norm(v))
        v /= np.linalg.norm(v)
    tangent = total / (400 * period)
    result = lyapunov_exponent(rig, speed=18.0, revolutions=400, transient=200)
    assert tangent > 1.0
    assert result.exponent == pytest.approx(tangent, rel=0.03)


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
    doc = json.loads(capsys.readouterr().out)
    out = {**doc["summary"], **doc}
    # the command passes the preset, --set, --speed and --revolutions through: its number is
    # the library's for the same system (the exponent itself is checked above)
    direct = lyapunov_exponent(camdyn.load_system("sundar2014-impact", RIG), speed=18.0, revolutions=200)
    assert out["speed_hz"] == 18.0 and out["revolutions"] == 200 and out["transient"] == 200
    assert out["exponent_per_s"] == pytest.approx(direct.exponent, rel=1e-12)
    assert out["per_revolution"] == pytest.approx(direct.exponent / 18.0, rel=1e-12)
    assert main(["bifurcation", "sundar2014-impact", "--set", "cam.runout=3.5mm", "--speeds", "10Hz:20Hz:4",
                 "--revolutions", "40", "--discard", "20", "--workers", "0", "--quiet",
                 "--out", str(tmp_path / "b.nc")]) == 0
    assert (tmp_path / "b.nc").is_file() and (tmp_path / "b.png").is_file()
    assert "regimes:" in capsys.readouterr().out
