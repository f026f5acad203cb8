"""Harmonic balance (AFT) against outside references: the forced linear oscillator's
closed-form steady state and Floquet multipliers, the chapter 4 rig's orbit by shooting
(an independent method), its cam harmonics of alpha_ddot by a long simulation's last
revolutions (numpy FFT), and Liouville's formula for the product of its multipliers."""

import math

import numpy as np
import pytest

import camdyn
from camdyn.continuation import orbits
from camdyn.continuation.problem import model_problem, system_problem
from camdyn.steady import harmonic_balance
from camdyn.systems import registry as systems

W0, ZETA, AMP, WF = 3.0, 0.1, 1.0, 2.0   # [rad/s], [-], [1/s^2], [rad/s]


def oscillator():
    return model_problem(systems.OSCILLATOR, [W0, ZETA, AMP, WF, 0.0], [0.0, 0.0, 0.0])


def test_oscillator_closed_form_amplitude_phase_and_multipliers():
    orbit = harmonic_balance(oscillator(), harmonics=1)
    receptance = AMP / (W0 ** 2 - WF ** 2 + 2j * ZETA * W0 * WF)   # x = Re(G e^{i W t})
    a, b = orbit.coefficients[0, 1], orbit.coefficients[0, 2]
    assert abs(a - receptance.real) < 1e-12 and abs(b + receptance.imag) < 1e-12
    assert abs(math.hypot(a, b) - abs(receptance)) < 1e-12
    assert abs(math.atan2(-b, a) - np.angle(receptance)) < 1e-12
    exponent = -ZETA * W0 + 1j * W0 * math.sqrt(1 - ZETA ** 2)      # free-vibration exponent [1/s]
    expected = np.exp(exponent * 2 * math.pi / WF)
    assert np.allclose(np.sort_complex(orbit.multipliers), np.sort_complex([expected, expected.conjugate()]),
                       rtol=1e-12, atol=0)


@pytest.fixture(scope="module")
def rig():
    problem = system_problem(camdyn.load_system("sundar2014-friction"), "motion.speed")
    return problem, orbits.find_orbit(problem)


def test_rig_orbit_equals_shooting_and_auto_harmonics(rig):
    problem, shot = rig
    orbit = harmonic_balance(problem, guess=shot.state)
    assert orbit.tail < 1e-8 and orbit.harmonics >= 4
    assert np.allclose(orbit.samples[0], shot.state, rtol=1e-8, atol=0)


def test_hill_agrees_with_monodromy_and_liouville(rig):
    problem, shot = rig
    orbit = harmonic_balance(problem, harmonics=100, guess=shot.state)   # resolves the ~1 kHz contact mode
    assert np.allclose(np.abs(orbit.multipliers), np.abs(shot.multipliers), rtol=1e-5)
    # Liouville: det M = exp(int_0^T trace(df/dy) dt); its trapezoid sum is spectral here
    rates, jacs = np.empty((orbit.times.size, 3)), np.empty((orbit.times.size, 3, 3))
    p, period = problem.build(problem.value)
    mode = np.zeros(int(systems.mode_size(problem.system_id)))
    for j, t in enumerate(orbit.times):
        y = problem.full_state(orbit.samples[j], problem.value)
        if j == 0:
            systems.initial_mode(problem.system_id, t, y, p, mode)
        systems.rhs(problem.system_id, t, y, mode, p, rates[j])
        systems.jacobian(problem.system_id, t, y, rates[j], mode, p, jacs[j])
    det = math.exp(period * np.mean(np.trace(jacs[:, :2, :2], axis1=1, axis2=2)))
    assert abs(np.prod(orbit.multipliers).real - det) < 1e-5 * det


def test_deliberate_mistakes_are_caught(rig):
    problem, shot = rig
    too_few = harmonic_balance(problem, harmonics=3, guess=shot.state)
    assert not np.allclose(too_few.samples[0], shot.state, rtol=1e-6, atol=0)
    assert too_few.tail > 1e-6                          # the measure flags H = 3 as unresolved
    coarse = harmonic_balance(problem, harmonics=8, guess=shot.state)   # orbit resolved, contact mode not
    assert not np.allclose(np.abs(coarse.multipliers), np.abs(shot.multipliers), rtol=1e-2)


def test_rig_alpha_ddot_harmonics_equal_a_long_simulation(rig):
    problem, shot = rig
    orbit = harmonic_balance(problem, guess=shot.state)
    speed = problem.value                                              # [Hz]
    per_rev, revs, last = 256, 60, 10
    ds = camdyn.simulate("sundar2014-friction", revolutions=revs, sample_rate=speed * per_rev, rtol=1e-11)
    tail = ds.alpha_ddot.values[(revs - last) * per_rev:(revs - last) * per_rev + last * per_rev]
    assert bool(ds.in_contact.values[-last * per_rev:].all())
    spectrum = 2.0 * np.fft.fft(tail) / tail.size                      # c_k = A_k - i B_k at bin last k
    omega = 2 * math.pi * speed
    a, b = orbit.coefficients[1, 1::2], orbit.coefficients[1, 2::2]    # alpha_dot's [rad/s]
    k = np.arange(1, 5)                                                # alpha_ddot = d/dt alpha_dot
    hb = k * omega * b[:4] + 1j * k * omega * a[:4]
    # 1e-6 of the largest of harmonics 1-4 (the 4th, 1e-3 of the 1st, agrees to 1e-6 of itself)
    assert np.max(np.abs(spectrum[last * k] - hb)) < 1e-6 * np.max(np.abs(hb))


def test_cold_start_from_the_pressed_rigid_orbit(rig):
    problem, shot = rig
    # no guess: the problem's orbit guess (the follower riding the cam, pressed in by the
    # static penetration); the same orbit as shooting's, in fewer Newton iterations than
    # from the constant static state at the same H (measured 4 against 14)
    cold = harmonic_balance(problem)
    assert cold.tail < 1e-8 and np.allclose(cold.samples[0], shot.state, rtol=1e-8, atol=0)
    guessed = harmonic_balance(problem, harmonics=cold.harmonics)
    constant = harmonic_balance(problem, harmonics=cold.harmonics, guess=problem.template[:problem.unknowns])
    assert np.allclose(guessed.samples, constant.samples, rtol=1e-10, atol=1e-12)
    assert guessed.iterations <= 5 < constant.iterations


def test_the_pressed_angles_sit_at_the_penetration_asked_for():
    from camdyn.model.geometry import pressed_angles
    from camdyn.simulation.runner import prepare
    from camdyn.testing.oracle import ReferenceModel

    system = camdyn.load_system("sundar2014-friction", {"cam.runout": "3.5 mm"})
    prep = prepare(system)
    model = ReferenceModel(system, prep.theta0)                        # independent geometry
    times = np.linspace(0.0, system.motion.period, 17)
    for pressed in (0.0, 2e-6):
        alpha = pressed_angles(times, prep.p, prep.y0[0], pressed)
        delta = [model.geometry(t, a, 0.0)[0] for t, a in zip(times, alpha)]
        assert np.allclose(delta, pressed, rtol=0, atol=1e-13)
