"""The stick-slip oscillator (mass on a spring, dragged by a belt): its closed-form limit
cycle, an independent SciPy event-driven solution with damping, the event log of the
stick and slip transitions, and the refusal of bad parameters."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from camdyn.errors import ParameterError
from camdyn.integrator import driver
from camdyn.model import stick_slip
from camdyn.simulation.mechanisms import simulate_stick_slip
from camdyn.simulation.sensitivity import integrate_variational
from camdyn.systems import registry as systems

SYSTEM = systems.STICK_SLIP
M, K, V, MU_S, MU_K, G = 1.3, 250.0, 0.08, 0.6, 0.35, 9.81
N = M * G
GUARDS = stick_slip.GUARD_COUNT


def _integrate(p, y0, t_end, t_out):
    y, modes, events, counters = driver.integrate(SYSTEM, p, np.asarray(y0, float), 0.0, t_end, t_out, 1e-12,
                                                  1e-15, 0.05, driver.METHOD_AUTO, 10 ** 7, 10000, False, math.inf)
    assert counters[driver.COUNT_STATUS] == driver.STATUS_OK
    return y, modes, events


def _closed_form_cycle():
    """The undamped limit cycle, derived here. Stick: ``x' = v`` from ``x_a`` up to
    ``x_b = mu_s N / k``, where the spring force reaches the static limit. Slip (the
    mass behind the belt, friction ``+mu_k N``): ``x = x_k + D cos(w s) + (v/w) sin(w s)
    = x_k + R sin(w s + psi)`` with ``x_k = mu_k N / k``, ``D = x_b - x_k``,
    ``w = sqrt(k/m)``, ``R = sqrt(D^2 + (v/w)^2)``, ``tan psi = D w / v``; it ends when
    ``x' = w R cos(w s + psi)`` is ``v`` again, at ``w s = 2 pi - 2 psi``, where
    ``x = x_k - D = x_a``. The extremes are ``x_k +- R``."""
    w = math.sqrt(K / M)
    x_k, x_b = MU_K * N / K, MU_S * N / K
    d = x_b - x_k
    r = math.hypot(d, V / w)
    psi = math.atan2(d * w, V)
    slip = (2 * math.pi - 2 * psi) / w
    stick = 2 * d / V
    return dict(w=w, x_k=x_k, x_a=x_k - d, x_b=x_b, d=d, r=r, psi=psi, slip=slip, stick=stick,
                heat=MU_K * N * (V * slip + 2 * d))   # mu_k N times the slid distance v s + (x_b - x_a)


def test_the_undamped_cycle_matches_its_closed_form():
    c = _closed_form_cycle()
    period = c["stick"] + c["slip"]
    cycles = 6
    # start sticking at x_a: the cycle is exact from t = 0; sample where the closed form
    # puts the extremes of each slip (breakaway at t0 + stick, then w s + psi = pi/2, 3 pi/2)
    starts = c["stick"] + period * np.arange(cycles)
    t_max = starts + (math.pi / 2 - c["psi"]) / c["w"]
    t_min = starts + (3 * math.pi / 2 - c["psi"]) / c["w"]
    t_out = np.sort(np.r_[t_max, t_min])
    p = stick_slip.pack(M, K, V, MU_S, MU_K, gravity=G)
    y, modes, events = _integrate(p, [c["x_a"], V, 0.0], cycles * period + 0.5 * c["stick"], t_out)
    x = dict(zip(t_out, y[:, 0]))
    np.testing.assert_allclose([x[t] for t in t_max], c["x_k"] + c["r"], rtol=1e-8)
    np.testing.assert_allclose([x[t] for t in t_min], c["x_k"] - c["r"], rtol=1e-8)
    stick = events[events[:, driver.EVENT_GUARD] == 0]
    breakaway = events[events[:, driver.EVENT_GUARD] == 1]
    # the log: breakaway (guard 1, new mode -1 slipping behind the belt) and sticking
    # (guard 0) alternate, at x_b and x_a
    assert list(events[:, driver.EVENT_GUARD].astype(int)) == [1, 0] * cycles
    np.testing.assert_allclose(np.diff(stick[:, driver.EVENT_TIME]), period, rtol=1e-8)
    np.testing.assert_allclose(np.diff(breakaway[:, driver.EVENT_TIME]), period, rtol=1e-8)
    np.testing.assert_allclose(breakaway[:, driver.EVENT_TIME] - starts + c["stick"], c["stick"], rtol=1e-8)
    np.testing.assert_allclose(stick[:, driver.EVENT_GUARDS + GUARDS], c["x_a"], rtol=1e-8)
    np.testing.assert_allclose(breakaway[:, driver.EVENT_GUARDS + GUARDS], c["x_b"], rtol=1e-8)
    heat = stick[:, driver.EVENT_GUARDS + GUARDS + 2]
    np.testing.assert_allclose(np.diff(np.r_[0.0, heat]), c["heat"], rtol=1e-8)
    assert (modes == -1.0).all()   # every sample lies in a slip, the mass behind the belt


def _scipy_stick_slip(c, y0, t_end, t_out):
    """Event-driven solution written for this test: slip phases by solve_ivp up to the
    zero of the relative velocity, stick phases in closed form (``x = x_s + v (t - t_s)``
    until ``k x + c v`` reaches ``+-mu_s N``)."""
    out = np.full((t_out.size, 2), np.nan)
    events = []
    t, y = 0.0, np.asarray(y0, float)
    sign = math.copysign(1.0, y[1] - V)
    while t < t_end:
        if sign == 0.0:   # sticking
            held = K * y[0] + c * V
            t_next = t + ((MU_S * N - held) / (K * V) if V > 0 else (-MU_S * N - held) / (K * V))
            inside = (t_out >= t) & (t_out <= min(t_next, t_end))
            out[inside, 0] = y[0] + V * (t_out[inside] - t)
            out[inside, 1] = V
            if t_next >= t_end:
                break
            y = np.array([y[0] + V * (t_next - t), V])
            t, sign = t_next, -1.0 if V > 0 else 1.0
            events.append((t, 1, y[0]))
            continue

        def rhs(_, s, sign=sign):
            return [s[1], (-MU_K * N * sign - K * s[0] - c * s[1]) / M]

        def relative(_, s):
            return s[1] - V
        relative.terminal, relative.direction = True, -sign
        # skip the zero the phase starts on (breakaway): the first step moves off it
        sol = solve_ivp(rhs, (t, t_end), y, method="DOP853", rtol=1e-13, atol=1e-16, events=relative,
                        dense_output=True, first_step=1e-9)
        inside = (t_out >= t) & (t_out <= sol.t[-1])
        out[inside] = sol.sol(t_out[inside]).T
        t, y = sol.t[-1], sol.y[:, -1].copy()
        if sol.status == 1:
            held = K * y[0] + c * V
            if abs(held) <= MU_S * N:
                sign, y[1] = 0.0, V
                events.append((t, 0, y[0]))
            else:
                sign = -math.copysign(1.0, held)
                events.append((t, 0, y[0]))
    return out, np.array(events)


def test_a_damped_start_from_rest_matches_an_independent_event_driven_solution():
    damping = 1.5
    t_out = np.linspace(0.0, 3.0, 301)
    p = stick_slip.pack(M, K, V, MU_S, MU_K, damping=damping, gravity=G)
    y, modes, events = _integrate(p, [0.0, 0.0, 0.0], 3.0, t_out)
    reference, ref_events = _scipy_stick_slip(damping, [0.0, 0.0], 3.0, t_out)
    assert len(events) == len(ref_events) >= 6
    np.testing.assert_array_equal(events[:, driver.EVENT_GUARD], ref_events[:, 1])
    np.testing.assert_allclose(events[:, driver.EVENT_TIME], ref_events[:, 0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(events[:, driver.EVENT_GUARDS + GUARDS], ref_events[:, 2], rtol=0, atol=1e-10)
    np.testing.assert_allclose(y[:, :2], reference, rtol=0, atol=1e-9)


def test_a_reversal_when_the_belt_cannot_hold_the_mass():
    # launched ahead of the belt against a compressed spring that pushes it back harder
    # than static friction can hold: at x' = v it slips on, now behind the belt
    p = stick_slip.pack(M, K, V, MU_S, MU_K, gravity=G)
    x0 = 3.0 * MU_S * N / K
    y, modes, events = _integrate(p, [x0, V + 0.05, 0.0], 0.05, np.array([0.0, 0.05]))
    first = events[0]
    assert first[driver.EVENT_GUARD] == 0 and first[driver.EVENT_NEW_SIGN] == -1.0
    assert modes[0, 0] == 1.0 and modes[-1, 0] == -1.0


@pytest.mark.parametrize("kwargs, words", [
    (dict(static_friction=0.2, kinetic_friction=0.3), "must not be below the kinetic"),
    (dict(mass=-1.0), "mass must be positive"),
    (dict(belt_speed=math.nan), "belt speed must be finite"),
    (dict(damping=-0.1), "damping must not be negative"),
])
def test_bad_parameters_are_refused(kwargs, words):
    values = dict(mass=M, stiffness=K, belt_speed=V, static_friction=MU_S, kinetic_friction=MU_K) | kwargs
    with pytest.raises(ParameterError, match=words):
        stick_slip.pack(**values)


@pytest.mark.parametrize("kwargs, words", [
    (dict(initial_state=(0.0, math.inf)), "initial_state must be two finite numbers"),
    (dict(duration=-1.0), "duration must be positive"),
    (dict(method="euler"), "method must be one of"),
])
def test_bad_run_settings_are_refused(kwargs, words):
    values = dict(mass=M, stiffness=K, belt_speed=V, static_friction=MU_S, kinetic_friction=MU_K, duration=1.0)
    with pytest.raises(ParameterError, match=words):
        simulate_stick_slip(**(values | kwargs))


def test_the_dataset_reports_the_switches_with_units():
    ds = simulate_stick_slip(mass=M, stiffness=K, belt_speed=V, static_friction=MU_S, kinetic_friction=MU_K,
                             gravity=G, duration=2.0, sample_rate=2e3)
    c = _closed_form_cycle()
    assert ds.x.attrs["units"] == "m" and ds.friction_heat.attrs["units"] == "J"
    kinds = list(ds.transition_kind.values)
    assert kinds[:4] == ["stick", "slip", "stick", "slip"]   # from rest: slip, then the cycle
    np.testing.assert_allclose(ds.transition_x.values[1::2], c["x_b"], rtol=1e-8)   # breakaways
    # while sticking the belt holds the spring: friction force k x, within mu_s N
    sticking = ds.sticking.values == 1
    np.testing.assert_allclose(ds.friction_force.values[sticking], K * ds.x.values[sticking], rtol=1e-12)
    assert np.all(np.abs(ds.friction_force.values) <= MU_S * N * (1 + 1e-12))


def test_the_monodromy_matrix_of_the_cycle():
    # Over one period of the undamped cycle from the middle of a stick: a shift of x
    # moves the state along the flow (d x_T / d x_0 = 1); the next stick sets x' = v
    # whatever came before (the x' row is zero); the heat is a quadrature (d Q_T / d Q_0
    # = 1). So the Floquet multipliers are 1, 1 and 0 (sticking forgets the velocity).
    c = _closed_form_cycle()
    period = c["stick"] + c["slip"]
    p = stick_slip.pack(M, K, V, MU_S, MU_K, gravity=G)
    start = [0.5 * (c["x_a"] + c["x_b"]), V, 0.0]
    result = integrate_variational(SYSTEM, p, start, 0.0, period, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(result.state[:2], start[:2], rtol=0, atol=1e-10)   # back on the cycle
    phi = result.matrix
    assert phi[0, 0] == pytest.approx(1.0, abs=1e-6)
    np.testing.assert_allclose(phi[1], 0.0, atol=1e-9)
    assert phi[2, 2] == pytest.approx(1.0, abs=1e-9)
    np.testing.assert_allclose(np.sort(np.abs(np.linalg.eigvals(phi))), [0.0, 1.0, 1.0], atol=1e-6)
