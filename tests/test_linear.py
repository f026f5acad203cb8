"""The linearized model (thesis eqs 2.36-2.38) against closed form and the nonlinear model."""

import math

import numpy as np
import pytest

import camdyn
from camdyn.analysis.harmonics import fit_harmonics, steady_window
from camdyn.analysis.linear import linearize
from camdyn.errors import ParameterError
from camdyn.model.equilibrium import static_equilibrium

SPEED = 5.0  # Hz (300 rpm, thesis fig 2.16)


def _harmonics(ds, variable, order=3, revolutions=10):
    win = steady_window(ds, revolutions, SPEED)
    return fit_harmonics(win.time.values, win[variable].values, SPEED, order)


@pytest.mark.parametrize("kind", ["line", "point"])
def test_closed_form_without_friction_or_damping(standin_rig, kind):
    """K_l and F_l(t) of a frictionless, undamped contact on the bar face, derived by hand:
    line contact (F = k delta) and the pinless point contact of eq 2.34 (F = (4/3) E*
    sqrt(rc) delta^1.5, whose contact stiffness dF/d delta is 2 E* sqrt(rc delta))."""
    s = standin_rig.with_values(**{"friction.coefficient": 0.0, "contact.damping": "none", "cam.runout": 1e-3,
                                   "contact.kind": kind})
    lm = linearize(s, SPEED)
    a = lm.equilibrium_angle
    pex, pey = s.cam.pivot_x, s.cam.pivot_y
    h = 0.5 * s.follower.width
    rc = s.cam.semi_major
    e_star = 1 / (2 * (1 - 0.3 ** 2) / 200e9)
    chi = pex * math.cos(a) - pey * math.sin(a)
    delta = h + rc - (pex * math.sin(a) + pey * math.cos(a))
    if kind == "line":
        force = math.pi / 4 * e_star * s.contact.length * delta
        k = math.pi / 4 * e_star * s.contact.length
    else:
        force = 4 / 3 * e_star * math.sqrt(rc) * delta ** 1.5
        k = 2 * e_star * math.sqrt(rc * delta)
    ks, dx, wb = s.spring.stiffness, s.spring.attachment_x, s.follower.width
    sec = 1 / math.cos(a)
    stiffness = k * chi ** 2 + force * (pex * math.sin(a) + pey * math.cos(a)) \
        + ks * dx * (dx * sec ** 2 + 0.5 * wb * sec * math.tan(a))
    assert lm.stiffness == pytest.approx(stiffness, rel=1e-6)
    assert abs(lm.damping) < 1e-9 * stiffness
    t = np.linspace(0.0, 1.0 / SPEED, 17)
    theta = lm._p[camdyn.model.layout.THETA0] + 2 * math.pi * SPEED * t
    expected = 1e-3 * (k * chi * np.sin(a + theta) - force * np.cos(a + theta))
    assert np.allclose(lm.forcing(t), expected, rtol=0, atol=1e-6 * np.abs(expected).max())


def test_natural_frequency_is_the_equilibrium_jacobians(standin_rig):
    lm = linearize(standin_rig, SPEED)
    concentric = static_equilibrium(standin_rig.with_values(**{"cam.runout": 0.0}))
    assert lm.natural_frequency == pytest.approx(concentric.natural_frequency, rel=1e-6)
    assert lm.equilibrium_angle == pytest.approx(concentric.angle, abs=1e-12)


def test_small_runout_linear_and_nonlinear_agree(standin_rig):
    """e = 0.01 rc: first harmonics of alpha and alpha_ddot (complex) within 1 %."""
    s = standin_rig.with_values(**{"cam.runout": 0.01 * standin_rig.cam.semi_major})
    nonlinear = camdyn.simulate(s, speed=SPEED, revolutions=20, sample_rate=20e3)
    lm = linearize(s, SPEED)
    linear = lm.steady_state(nonlinear.time.values)
    for var in ("alpha", "alpha_ddot"):
        cn = _harmonics(nonlinear, var)
        cl = _harmonics(linear, var)
        assert abs(cn[1] - cl[1]) < 0.01 * abs(cl[1]), var
        assert np.all(np.abs(cl[2:]) < 1e-9 * abs(cl[1]))  # the linear model has no super-harmonics


def test_large_runout_shows_super_harmonics_growing_as_e_squared(standin_rig):
    """The kinematic nonlinearity: second harmonic / first grows linearly with e."""
    ratios = []
    for frac in (0.1, 0.2):
        s = standin_rig.with_values(**{"cam.runout": frac * standin_rig.cam.semi_major})
        c = _harmonics(camdyn.simulate(s, speed=SPEED, revolutions=20, sample_rate=20e3), "alpha_ddot")
        ratios.append(abs(c[2]) / abs(c[1]))
        lin = _harmonics(linearize(s, SPEED).steady_state(np.arange(0, 4.0, 1 / 20e3)), "alpha_ddot")
        assert abs(lin[2]) < 1e-9 * abs(lin[1])
    assert ratios[0] > 0.02
    assert ratios[1] / ratios[0] == pytest.approx(2.0, rel=0.1)


def test_transient_meets_the_initial_state_and_settles_on_the_steady_state(standin_rig):
    s = standin_rig.with_values(**{"cam.runout": 1e-3, "contact.damping_ratio": 0.01})
    lm = linearize(s, SPEED)
    t = np.arange(0.0, 0.4, 1 / 50e3)
    response = lm.simulate(t, x0=1e-4, v0=-0.2)
    assert response.alpha.values[0] - lm.equilibrium_angle == pytest.approx(1e-4, rel=1e-9)
    assert response.alpha_dot.values[0] == pytest.approx(-0.2, rel=1e-9)
    # the free response obeys the homogeneous equation: I a + C v + K x = F at every sample
    x = response.alpha.values - lm.equilibrium_angle
    residual = lm.inertia * response.alpha_ddot.values + lm.damping * response.alpha_dot.values \
        + lm.stiffness * x - lm.forcing(t)
    assert np.max(np.abs(residual)) < 1e-6 * np.max(np.abs(lm.forcing(t)))
    steady = lm.steady_state(t)
    tail = slice(-2000, None)   # 3.7 s of decay at 1 %: 100 time constants
    for var in ("alpha", "alpha_ddot"):
        scale = np.ptp(steady[var].values)
        assert np.allclose(response[var].values[tail], steady[var].values[tail], atol=1e-6 * scale), var


def test_oscillating_cam_small_runout_agrees_with_the_nonlinear_model(standin_rig):
    """The oscillating cam's forcing holds many harmonics of the swing; the linear steady
    state sums them. Friction off: Coulomb friction reverses with the swing."""
    s = standin_rig.with_values(**{"cam.runout": 0.01 * standin_rig.cam.semi_major, "friction.coefficient": 0.0,
                                   "motion.kind": "oscillating", "motion.amplitude": math.pi,
                                   "motion.frequency": 2.0})
    nonlinear = camdyn.simulate(s, revolutions=6, sample_rate=20e3)
    lm = linearize(s)
    linear = lm.steady_state(nonlinear.time.values)
    win = slice(-4 * 10000 - 1, -1)
    cn = fit_harmonics(nonlinear.time.values[win], nonlinear.alpha_ddot.values[win], 2.0, 6)
    cl = fit_harmonics(linear.time.values[win], linear.alpha_ddot.values[win], 2.0, 6)
    assert np.max(np.abs(cn[1:] - cl[1:])) < 0.01 * np.max(np.abs(cl[1:]))
    assert np.abs(cl[2:]).max() > 0.1 * np.abs(cl[1])  # the swing itself is rich in harmonics


def test_refusals(friction_rig, standin_rig):
    with pytest.raises(ParameterError, match="circular cam"):
        linearize(friction_rig.with_values(**{"cam.semi_minor": 0.015}), 10.0)
    with pytest.raises(ParameterError, match="single harmonic"):
        osc = standin_rig.with_values(**{"motion.kind": "oscillating", "motion.amplitude": math.pi,
                                         "motion.frequency": 40 / 60})
        linearize(osc).forcing_amplitude()
