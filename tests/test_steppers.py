"""The steppers called one step at a time on the forced linear oscillator (system 1 of
:mod:`camdyn.systems.registry`), against its closed-form solution: DOP853 (the stepper
of every cam run) for its order, its continuous extension and its error estimate, the
error estimates of Dormand-Prince 5(4) and RODAS4 (their orders of convergence are in
test_integrator.py), and the work counters of the driver.

y'' + 2 zeta w y' + w^2 y = A cos(W t) is solved exactly through the matrix exponential
of the autonomous 4-state system (y, y', cos W t, sin W t). w = 3 rad/s, so a step h
spans h w radians of the free oscillation.
"""

import math

import numpy as np
import pytest
from scipy.linalg import expm
from test_bdf import STIFF_P  # the overdamped oscillator, stiff

from camdyn.integrator import driver
from camdyn.integrator.steppers import (
    KIND_DOP853,
    dense,
    dop853_error_norm,
    dop853_extend,
    dop853_step,
    dormand_prince_step,
    error_norm,
    rosenbrock_step,
)
from camdyn.systems import registry as systems

W0, ZETA, AMP, WF = 3.0, 0.1, 1.0, 2.0
P = np.array([W0, ZETA, AMP, WF, 0.0])
OSC = systems.OSCILLATOR
Y0 = np.array([1.0, 0.0, 0.0])


def exact(dt, y, t0=0.0):
    """(y, y') at t0 + dt from (y, y') at t0."""
    a = np.array([[0, 1, 0, 0], [-W0 ** 2, -2 * ZETA * W0, AMP, 0], [0, 0, 0, -WF], [0, 0, WF, 0]], float)
    return (expm(a * dt) @ np.array([y[0], y[1], math.cos(WF * t0), math.sin(WF * t0)]))[:2]


def slope(h, err):
    """Least-squares slope of log(err) against log(h): the observed order."""
    return np.polyfit(np.log(h), np.log(err), 1)[0]


class Dop853Step:
    """One DOP853 step of size h from Y0 at t0, with its continuous extension."""

    def __init__(self, h, t0=0.0):
        self.h, self.t0 = h, t0
        self.mode = np.zeros(5)
        self.f0 = np.empty(3)
        systems.rhs(OSC, t0, Y0, self.mode, P, self.f0)
        self.k, yt = np.empty((16, 3)), np.empty(3)
        self.y1, self.f1, self.err5, self.err3 = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
        self.calls = dop853_step(OSC, t0, Y0, self.f0, h, self.mode, P, self.k, yt, self.y1, self.f1,
                                 self.err5, self.err3, 2)
        self.coefficients = np.empty((7, 3))
        self.extension_calls = dop853_extend(OSC, t0, Y0, h, self.y1, self.f1, self.mode, P, self.k, yt,
                                             self.coefficients)

    def true_error(self):
        """rms over (y, y') of the true local error."""
        return math.sqrt(np.mean((self.y1[:2] - exact(self.h, Y0, self.t0)) ** 2))

    def estimate(self):
        """The step's error estimate, unscaled (atol = 1, rtol = 0): an rms like true_error."""
        return dop853_error_norm(Y0, self.y1, self.err5, self.err3, self.h, 0.0, 1.0, 2, False)

    def dense(self, tau):
        out = np.empty(3)
        dense(tau, self.h, Y0, self.f0, self.y1, self.f1, self.coefficients, KIND_DOP853, out)
        return out


def dop853_global_error(n, t_end=1.0):
    mode = np.zeros(5)
    y, f, k, yt = Y0.copy(), np.empty(3), np.empty((16, 3)), np.empty(3)
    y1, f1, e5, e3 = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    h, t = t_end / n, 0.0
    systems.rhs(OSC, t, y, mode, P, f)
    for _ in range(n):
        dop853_step(OSC, t, y, f, h, mode, P, k, yt, y1, f1, e5, e3, 2)
        y[:], f[:] = y1, f1
        t += h
    return np.max(np.abs(y[:2] - exact(t_end, Y0)))


# --- DOP853: orders ------------------------------------------------------------------------------

def test_dop853_global_order_is_8():
    # fixed steps over one second (h w = 0.75 down to 0.19): halving h divides the global
    # error by 2^8 (measured 8.16 and 8.07; the errors reach 4e-13, still 100 times above
    # round-off). A mistyped coefficient drops the order by at least one, to <= 7.
    errors = np.array([dop853_global_error(n) for n in (4, 8, 16)])
    observed = np.log2(errors[:-1] / errors[1:])
    assert observed == pytest.approx([8.0, 8.0], abs=0.35), observed


@pytest.mark.parametrize("t0", [0.0, 0.7, 2.0])
def test_dop853_local_error_order_is_9(t0):
    # one step: the local error of an order-8 method is O(h^9). Fitted over h w = 0.3 to
    # 0.9 it reads 8.6-8.9 (the h^10 term is not negligible at the top of the range; below
    # it the error meets round-off, 1e-15): [8.4, 9.6] keeps clear of the 8 of a method
    # one order lower.
    h = 0.3 * 2.0 ** -np.arange(0.0, 2.01, 0.5)
    errors = [Dop853Step(hi, t0).true_error() for hi in h]
    assert 8.4 < slope(h, errors) < 9.6, errors


@pytest.mark.parametrize("t0", [0.0, 0.7, 2.0])
def test_dop853_dense_output_is_7th_order(t0):
    # the 7th-order continuous extension: its error inside a step is O(h^8), at the
    # midpoint and over the whole step (measured slopes 8.1-8.2; a cubic Hermite
    # interpolant, the fall-back, would give 4, and one missing extra stage < 7)
    h = np.array([0.4, 0.2, 0.1])
    mid, worst = [], []
    for hi in h:
        step = Dop853Step(hi, t0)
        assert step.calls == 12 and step.extension_calls == 3   # DOP853's 12 stages (FSAL) + 3
        taus = np.linspace(0.05, 0.95, 19)
        errs = [np.max(np.abs(step.dense(tau)[:2] - exact(tau * hi, Y0, t0))) for tau in taus]
        mid.append(errs[9])
        worst.append(max(errs))
        # the interpolant passes through both ends of the step
        np.testing.assert_allclose(step.dense(0.0), Y0, rtol=0, atol=1e-15)
        np.testing.assert_allclose(step.dense(1.0), step.y1, rtol=1e-14, atol=1e-15)
    assert 7.6 < slope(h, mid) < 8.6, mid
    assert 7.6 < slope(h, worst) < 8.6, worst


# --- error estimates ------------------------------------------------------------------------------

def test_dop853_error_estimate_bounds_the_true_error():
    # Hairer's combination of the 5th- and 3rd-order estimates behaves as h^8 (measured
    # slope 7.8-7.9), one order above the true local error (h^9), so it overestimates it,
    # by a factor falling with h: true / estimate measured 0.03-0.14 for h w = 0.3-1.2.
    # Bounds: never below the true error (the step control would accept steps that miss
    # rtol), and not a thousand times above it (steps would be needlessly small), nor zero.
    h = np.array([0.4, 0.3, 0.2, 0.15, 0.1])
    for t0 in (0.0, 0.7, 2.0):
        steps = [Dop853Step(hi, t0) for hi in h]
        estimate = np.array([s.estimate() for s in steps])
        true = np.array([s.true_error() for s in steps])
        assert np.all(estimate > 0)
        assert np.all(true <= estimate) and np.all(true >= 1e-3 * estimate), true / estimate
        assert 7.5 < slope(h, estimate) < 8.5, estimate


def _one_step(method, h, t0):
    """(true local error, estimate) of one Dormand-Prince or RODAS4 step, both rms over (y, y')."""
    mode = np.zeros(5)
    f, y1, f1, err = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    systems.rhs(OSC, t0, Y0, mode, P, f)
    if method == "dp5":
        dormand_prince_step(OSC, t0, Y0, f, h, mode, P, np.empty((6, 3)), y1, f1, err)
    else:
        rosenbrock_step(OSC, t0, Y0, f, h, mode, P, np.empty((6, 3)), np.empty((6, 3)), np.empty((3, 3)),
                        np.empty(3, dtype=np.int64), y1, err)
    true = math.sqrt(np.mean((y1[:2] - exact(h, Y0, t0)) ** 2))
    return true, error_norm(Y0, y1, err, 0.0, 1.0, 2)


@pytest.mark.parametrize("method, order", [("dp5", 5), ("rosenbrock", 4)])
def test_embedded_error_estimates(method, order):
    # the embedded estimate of an order-p method (Dormand-Prince 5(4), RODAS4 4(3)) is the
    # local error of its order p-1 companion, O(h^p), one order above the true local error
    # O(h^(p+1)); it bounds the true error (measured true / estimate 0.015-0.06) and, being
    # the difference of two solutions, is not zero. Over h w = 0.075-0.3 the slopes
    # measured 5.03-5.04 and 4.17 for the estimates, 5.89-5.91 and 4.88-4.91 for the true
    # errors; each band excludes the neighbouring orders.
    h = 0.1 * 2.0 ** -np.arange(0.0, 2.01, 0.5)
    for t0 in (0.0, 0.7, 2.0):
        true, estimate = np.array([_one_step(method, hi, t0) for hi in h]).T
        assert np.all(estimate > 0)
        assert np.all(true <= estimate), true / estimate
        assert order - 0.35 < slope(h, estimate) < order + 0.35, estimate
        assert order + 0.6 < slope(h, true) < order + 1.4, true


# --- the driver with DOP853 -------------------------------------------------------------------------

def test_dop853_driver_global_error_follows_rtol():
    # adaptive DOP853 over 5 s (1.6 periods of the forcing, 2.4 of the free oscillation)
    # for rtol = 1e-5 ... 1e-11 (atol = rtol / 100): the largest error at 51 output times
    # (dense output included) measured 0.28-1.29 rtol. It must stay within 5 rtol, and fall
    # in proportion: error ~ rtol^s with s near 1 (the control keeps the local error per
    # step near rtol; measured s = 1.06).
    t_out = np.linspace(0.0, 5.0, 51)
    ref = np.array([exact(t, Y0)[0] for t in t_out])
    rtols = 10.0 ** -np.arange(5, 12)
    errors = []
    for rtol in rtols:
        y, _, _, counters = driver.integrate(OSC, P, Y0, 0.0, 5.0, t_out, rtol, rtol * 1e-2, 1.0,
                                             driver.METHOD_DOP853, 10 ** 6, 100, False, math.inf)
        assert counters[driver.COUNT_STATUS] == driver.STATUS_OK
        errors.append(np.max(np.abs(y[:, 0] - ref)))
    errors = np.array(errors)
    assert np.all(errors < 5 * rtols), errors / rtols
    assert 0.8 < slope(rtols, errors) < 1.2, errors


# --- work counters ----------------------------------------------------------------------------------

@pytest.mark.parametrize("method, per_attempt, per_accepted, jacobians", [
    # DOP853: 12 stages, the first reused from the step before (FSAL); + 3 for the one
    # continuous extension that fills the output at t_end
    (driver.METHOD_DOP853, 12, 0, False),
    # Dormand-Prince 5(4): 7 stages, FSAL: 6 new evaluations per attempt
    (driver.METHOD_EXPLICIT, 6, 0, False),
    # RODAS4: 5 new stage evaluations and two for df/dt (a central difference) per
    # attempt, one Jacobian per attempt, and f(t + h, y1) after each accepted step
    (driver.METHOD_ROSENBROCK, 7, 1, True),
])
def test_work_counters(method, per_attempt, per_accepted, jacobians):
    # the overdamped oscillator (zeta = 2) from y = 1 at rest decays without crossing
    # zero: no event, and output only at both ends
    p = np.array([W0, 2.0, 0.0, 0.0, 0.0])
    _, _, events, c = driver.integrate(OSC, p, Y0, 0.0, 3.0, np.array([0.0, 3.0]), 1e-9, 1e-11, 1.0, method,
                                       10 ** 6, 10, False, math.inf)
    assert c[driver.COUNT_STATUS] == driver.STATUS_OK and events.shape[0] == 0 == c[driver.COUNT_EVENTS]
    accepted, attempts = c[driver.COUNT_ACCEPTED], c[driver.COUNT_ACCEPTED] + c[driver.COUNT_REJECTED]
    assert accepted > 10
    extension = 3 if method == driver.METHOD_DOP853 else 0
    assert c[driver.COUNT_RHS] == 1 + per_attempt * attempts + per_accepted * accepted + extension
    assert c[driver.COUNT_JACOBIANS] == (attempts if jacobians else 0)
    if method == driver.METHOD_ROSENBROCK:
        assert c[driver.COUNT_ROSENBROCK] == accepted and c[driver.COUNT_EXPLICIT] == 0
    else:
        assert c[driver.COUNT_EXPLICIT] == accepted and c[driver.COUNT_ROSENBROCK] == 0


def test_dop853_error_norm_of_an_exact_step_with_an_underflowing_third_order_estimate_is_zero():
    # A step that is exact to the last bit (a follower held on a dwell: err5 = 0) whose
    # third-order estimate is so small that 0.01 e3 underflows to zero: Hairer's norm
    # h e5 / sqrt(e5 + 0.01 e3) was 0 / 0, and the compiled code raised ZeroDivisionError
    # out of the driver (a rocking arm run whose end fell on a dwell at 500 rpm).
    y = np.array([0.3, 0.0])
    err5 = np.zeros(2)
    err3 = np.array([1e-173, 0.0])
    e3 = (err3[0] / 1e-12) ** 2
    assert e3 > 0.0 and 0.01 * e3 == 0.0    # the underflow the norm meets
    assert dop853_error_norm(y, y, err5, err3, 1e-3, 0.0, 1e-12, 2, False) == 0.0
    assert dop853_error_norm(y, y, err5, err3, 1e-3, 0.0, 1e-12, 2, True) == 0.0
    # a nonzero fifth-order estimate still gives Hairer's norm, |h| e5 / sqrt((e5 + 0.01 e3) n)
    err5 = np.array([2e-15, 1e-15])
    err3 = np.array([4e-14, 0.0])
    e5, e3 = (2e-6) ** 2 + (1e-6) ** 2, (4e-5) ** 2     # (err / atol) squared, summed
    expected = 1e-3 * e5 / np.sqrt((e5 + 0.01 * e3) * 2)
    assert dop853_error_norm(y, y, err5, err3, 1e-3, 0.0, 1e-9, 2, False) == pytest.approx(expected, rel=1e-12)
    # the plain norm is the fifth-order estimate's rms, |h| sqrt(e5 / n), never below Hairer's
    plain = dop853_error_norm(y, y, err5, err3, 1e-3, 0.0, 1e-9, 2, True)
    assert plain == pytest.approx(1e-3 * np.sqrt(e5 / 2), rel=1e-12) and plain >= expected


# --- absolute tolerances per component -----------------------------------------------------------

# both runs with an array atol sit in this file: each new argument type of the driver is a
# whole compile (minutes), done once here rather than on two test workers at once
def test_an_absolute_tolerance_per_component():
    # the error norms read atol[i] for component i when atol is an array: the same norm as
    # one number when every entry is that number, and the RMS of err_i / (atol_i + rtol |y_i|)
    # written out here otherwise
    y0, y1, err = np.array([0.5, -2.0]), np.array([0.6, -2.5]), np.array([3e-9, 4e-7])
    assert error_norm(y0, y1, err, 1e-6, np.array([1e-9, 1e-9]), 2) == error_norm(y0, y1, err, 1e-6, 1e-9, 2)
    by_hand = math.sqrt(((3e-9 / (1e-9 + 0.6e-6)) ** 2 + (4e-7 / (1e-5 + 2.5e-6)) ** 2) / 2)
    assert error_norm(y0, y1, err, 1e-6, np.array([1e-9, 1e-5]), 2) == pytest.approx(by_hand, rel=1e-14)
    # the driver: an array of equal entries runs bitwise the run of one number; loosening the
    # velocity's atol a thousandfold (rtol 0, so that atol alone sets the tolerance) takes
    # fewer steps, and the position's error stays within 5 of its own atol as the velocity's
    # error grows
    t_out = np.linspace(0.0, 5.0, 51)
    ref = np.array([exact(t, Y0) for t in t_out])
    runs = {}
    for name, atol in (("number", 1e-9), ("equal", np.full(3, 1e-9)), ("loose", np.array([1e-9, 1e-6, 1e-9]))):
        runs[name] = driver.integrate(OSC, P, Y0, 0.0, 5.0, t_out, 0.0, atol, 1.0, driver.METHOD_DOP853, 10 ** 6, 100,
        False, math.inf)
        assert runs[name][3][driver.COUNT_STATUS] == driver.STATUS_OK
    assert np.array_equal(runs["number"][0], runs["equal"][0]) and np.array_equal(runs["number"][3], runs["equal"][3])
    assert runs["loose"][3][driver.COUNT_ACCEPTED] < runs["number"][3][driver.COUNT_ACCEPTED]
    assert np.max(np.abs(runs["loose"][0][:, 0] - ref[:, 0])) < 5e-9
    assert np.max(np.abs(runs["loose"][0][:, 1] - ref[:, 1])) > np.max(np.abs(runs["number"][0][:, 1] - ref[:, 1]))


def test_an_absolute_tolerance_per_component_reaches_the_bdf_norms():
    # the switching method's norms (the corrector's, the stiffness estimate's, the switch's)
    # read atol[i] per component: an array of equal entries runs bitwise the run of one number
    t_out = np.linspace(0.0, 2.0, 41)
    runs = []
    for atol in (1e-8, np.full(3, 1e-8)):
        runs.append(driver.integrate(systems.OSCILLATOR, STIFF_P, np.array([1.0, 0.0, 0.0]), 0.0, 2.0, t_out,
                                     1e-6, atol, 1.0, driver.METHOD_MULTISTEP, 10 ** 7, 100, False, math.inf))
    assert runs[0][3][driver.COUNT_STATUS] == driver.STATUS_OK
    assert runs[0][3][driver.COUNTER_NAMES.index("bdf_steps")] > 0
    assert np.array_equal(runs[0][0], runs[1][0]) and np.array_equal(runs[0][3], runs[1][3])
