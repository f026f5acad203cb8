"""Radau IIA in the hybrid driver (``method="radau"``) and DOP853 switched to it in
sustained contact (``method="switching"``): accuracy against an independent SciPy
solution, tolerance proportionality, events, the switch itself, and the spectral-radius
estimate that triggers it."""

from __future__ import annotations

import math

import numpy as np
import pytest

import camdyn
from camdyn.integrator import driver
from camdyn.integrator.implicit import spectral_radius
from camdyn.simulation.runner import prepare
from camdyn.systems import registry as systems
from camdyn.testing.oracle import reference_simulate

RATE = 20e3  # [Hz]


def _friction_rig():
    """The chapter 4 rig in sustained sliding contact (e/a 0.1 at 11.55 Hz)."""
    return camdyn.load_system("sundar2014-friction", {"cam.runout": "1.75 mm"}).with_values(
        **{"motion.speed": 11.55})


def _impact_rig():
    """The chapter 3 rig with one impact per revolution (16 Hz)."""
    return camdyn.load_system("sundar2014-impact", {"cam.runout": "3.5 mm"}).with_values(**{"motion.speed": 16.0})


def _truth(system, revolutions):
    """alpha [rad] at 20 kHz from SciPy's DOP853 with events at rtol 1e-13
    (camdyn.testing.oracle, written independently of the compiled model)."""
    prep = prepare(system)
    t = np.arange(int(revolutions * system.motion.period * RATE) + 1) / RATE
    _, y, _ = reference_simulate(system, prep.theta0, prep.y0, t[-1], t, prep.viscous_c, method="DOP853",
                                 rtol=1e-13, atol=1e-15)
    return y[0]


def _error(system, revolutions, method, rtol, truth):
    ds = camdyn.simulate(system, revolutions=revolutions, sample_rate=RATE, rtol=rtol, atol=1e-3 * rtol,
                         method=method, variables=["alpha"])
    alpha = ds["alpha"].values
    n = min(alpha.size, truth.size)
    return float(np.max(np.abs(alpha[:n] - truth[:n])) / np.max(np.abs(truth))), ds.attrs


@pytest.mark.slow
@pytest.mark.parametrize("method", ["radau", "switching"])
@pytest.mark.parametrize("rig", [_friction_rig, _impact_rig], ids=["sustained contact", "impacts"])
def test_the_error_follows_the_tolerance(rig, method):
    # 6 revolutions from rest: the error in alpha, relative to its amplitude, is at most
    # 10 rtol and falls at every decade of rtol from 1e-5 to 1e-9
    system = rig()
    truth = _truth(system, 6)
    rtols = (1e-5, 1e-6, 1e-7, 1e-8, 1e-9)
    errors = [_error(system, 6, method, rtol, truth)[0] for rtol in rtols]
    ratios = np.array(errors) / np.array(rtols)
    assert np.all(ratios <= 10.0), ratios
    assert np.all(np.diff(errors) < 0.0), errors


def test_radau_locates_the_same_contact_events_as_dop853():
    system = _impact_rig()
    runs = {m: camdyn.simulate(system, revolutions=4, rtol=1e-8, atol=1e-11, method=m, variables=["impact"])
            for m in ("dop853", "radau")}
    counts = {m: ds.attrs["solver_events"] for m, ds in runs.items()}
    assert counts["radau"] == counts["dop853"] > 0
    assert runs["radau"].attrs["solver_radau_steps"] > 0
    assert runs["radau"].attrs["solver_explicit_steps"] == 0


@pytest.mark.filterwarnings("ignore::camdyn.simulation.settling.TransientWarning")
def test_switching_runs_radau_in_sustained_contact_and_not_in_an_impact_run():
    # the chapter 4 rig settled into sustained contact (the state after 30 revolutions):
    # no event, and after DOP853's first 15 steps all steps are Radau's; the chapter 3 rig
    # flies freely between impacts, where DOP853's steps are far from the contact's time
    # scale, and never switches
    rig = _friction_rig()
    settled = camdyn.simulate(rig, revolutions=30, rtol=1e-10, atol=1e-13, variables=["alpha", "alpha_dot"])
    start = (float(settled["alpha"][-1]), float(settled["alpha_dot"][-1]))
    sustained = camdyn.simulate(rig, revolutions=5, rtol=1e-6, atol=1e-10, method="switching", variables=["alpha"],
                                initial_state=start).attrs
    assert sustained["solver_events"] == 0
    assert sustained["solver_explicit_steps"] == 15
    assert sustained["solver_radau_steps"] == sustained["solver_accepted_steps"] - 15
    impacts = camdyn.simulate(_impact_rig(), revolutions=10, rtol=1e-6, atol=1e-10, method="switching",
                              variables=["alpha"]).attrs
    plain = camdyn.simulate(_impact_rig(), revolutions=10, rtol=1e-6, atol=1e-10, method="dop853",
                            variables=["alpha"]).attrs
    assert impacts["solver_radau_steps"] == 0
    assert impacts["solver_accepted_steps"] == plain["solver_accepted_steps"]


@pytest.mark.parametrize("method", [driver.METHOD_RADAU, driver.METHOD_SWITCHING])
def test_a_grazing_dip_inside_a_radau_step_gives_both_crossings(method):
    # y'' + y = 1 from rest at y = 2 + 1e-6: y = 1 + (1 + 1e-6) cos t dips 1e-6 below the
    # guard y = 0 for 2.8e-3 s around t = pi (closed form), inside one step
    epsilon = 1e-6
    p = np.array([1.0, 0.0, 1.0, 0.0, 0.0])
    y0 = np.array([2.0 + epsilon, 0.0, 0.0])
    _, _, events, counters = driver.integrate(systems.OSCILLATOR, p, y0, 0.0, 4.0, np.array([0.0]), 1e-9, 1e-12,
                                              10.0, method, 10 ** 6, 100, False, math.inf)
    half_gap = math.acos(1.0 / (1.0 + epsilon))
    assert events.shape[0] == 2, events
    assert list(events[:, 2]) == [-1.0, 1.0]
    np.testing.assert_allclose(events[:, 0], [math.pi - half_gap, math.pi + half_gap], rtol=0, atol=1e-6)
    assert counters[driver.COUNT_STATUS] == driver.STATUS_OK


def test_radau_samples_come_from_its_collocation_polynomial():
    # the undamped oscillator y'' + y = 0 from y = 1: y = cos t at 1,000 samples between
    # Radau's long steps (about 0.1 s at rtol 1e-8), within 10 rtol of the closed form
    p = np.array([1.0, 0.0, 0.0, 0.0, 0.0])
    t_out = np.linspace(0.0, 3.0, 1001)
    y_out, _, _, counters = driver.integrate(systems.OSCILLATOR, p, np.array([1.0, 0.0, 0.0]), 0.0, 3.0, t_out,
                                             1e-8, 1e-11, 10.0, driver.METHOD_RADAU, 10 ** 6, 100, False, math.inf)
    assert counters[driver.COUNT_EXPLICIT] == 0 and 0 < counters[driver.COUNT_RADAU] < 200
    assert np.max(np.abs(y_out[:, 0] - np.cos(t_out))) < 1e-7


@pytest.mark.parametrize("stiffness, damping", [(3.6e7, 240.0), (3.6e7, 0.0), (1e4, 1.0), (1e2, 30.0)])
def test_the_spectral_radius_estimate_is_within_ten_percent(stiffness, damping):
    # a second-order mode in first-order form plus a quadrature row: |lambda| is
    # sqrt(k) for a complex pair (closed form), the larger real root otherwise
    jacobian = np.array([[0.0, 1.0, 0.0], [-stiffness, -damping, 0.0], [5.0, 3.0, 0.0]])
    disc = damping ** 2 - 4.0 * stiffness
    exact = math.sqrt(stiffness) if disc < 0 else 0.5 * (damping + math.sqrt(disc))
    estimate = spectral_radius(jacobian, np.empty(3), np.empty(3))
    assert abs(estimate / exact - 1.0) < 0.1, (estimate, exact)



def test_the_variational_jacobian_acts_on_the_columns_of_phi():
    # Phi' = J Phi is linear in Phi, so the Jacobian's columns for Phi's entries are the
    # right-hand side's exact response to a unit change of each entry (a difference of two
    # right-hand sides, computed here); the chapter 4 rig in contact, a random Phi
    prep = prepare(_friction_rig())
    n = 3
    system = systems.VARIATIONAL + systems.CAM_FOLLOWER
    size = systems.state_size(system)
    rng = np.random.default_rng(7)
    y = np.concatenate([prep.y0 + np.array([1e-5, 0.3, 0.0]), rng.normal(size=n * n)])
    mode = np.zeros(systems.mode_size(system))
    systems.initial_mode(system, 0.0, y, prep.p, mode)
    f0 = np.empty(size)
    systems.rhs(system, 0.0, y, mode, prep.p, f0)
    jac = np.empty((size, size))
    systems.jacobian(system, 0.0, y, f0, mode, prep.p, jac)
    moved = np.empty(size)
    for index in range(n, size):
        probe = y.copy()
        probe[index] += 1.0
        systems.rhs(system, 0.0, probe, mode, prep.p, moved)
        np.testing.assert_allclose(jac[n:, index], (moved - f0)[n:], rtol=1e-6, atol=1e-6 * np.abs(jac).max())
