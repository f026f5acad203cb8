"""A hardening Duffing oscillator as a model of camdyn's model protocol: a smooth model whose
frequency response folds, for harmonic balance and its continuation.

    x'' + 2 zeta w0 x' + w0^2 x + gamma x^3 = F cos(2 pi f t)          (D1)

x [m] the displacement, f [Hz] the forcing frequency (the model's speed), w0 [rad/s] the
linear natural frequency, zeta [-] the damping ratio, gamma [1/(m^2 s^2)] the cubic
stiffness per unit mass and F [m/s^2] the forcing per unit mass. With w0 = 2 pi rad/s and
gamma = w0^2, F = 0.1 w0^2 (the defaults) the response over 0.8-1.6 Hz bends to the right
and folds twice. Use it as

    from camdyn.continuation.problem import bound_problem
    from camdyn.steady import continue_harmonic
    from duffing import DUFFING

    curve = continue_harmonic(bound_problem(DUFFING.bind({})), 0.8, 1.6, max_step=0.5, max_points=4000)
"""

import math

import numba

from camdyn import Model, Quantity

SPEED, W0, ZETA, GAMMA, FORCE = range(5)


@numba.njit(cache=True)
def rhs(t, y, mode, p, dydt):
    dydt[0] = y[1]
    dydt[1] = (p[FORCE] * math.cos(2.0 * math.pi * p[SPEED] * t) - 2.0 * p[ZETA] * p[W0] * y[1]
               - p[W0] ** 2 * y[0] - p[GAMMA] * y[0] ** 3)                      # eq. D1


@numba.njit(cache=True)
def jacobian(t, y, f0, mode, p, jac):
    jac[0, 0] = 0.0
    jac[0, 1] = 1.0
    jac[1, 0] = -p[W0] ** 2 - 3.0 * p[GAMMA] * y[0] ** 2
    jac[1, 1] = -2.0 * p[ZETA] * p[W0]


@numba.njit(cache=True)
def guards(t, y, f, known, p, values, rates):   # no events: one guard that never crosses
    values[0] = 1.0
    rates[0] = 0.0


@numba.njit(cache=True)
def expected_sign(k, mode, p):
    return 0.0


@numba.njit(cache=True)
def transition(k, t, y, values, mode, p):
    pass


@numba.njit(cache=True)
def initial_mode(t, y, p, mode):
    mode[0] = 0.0


DUFFING = Model(
    name="duffing",
    states=[Quantity("x", "m", "displacement"), Quantity("v", "m/s", "velocity")],
    parameters=[Quantity("speed", "Hz", "forcing frequency", 1.0),
                Quantity("w0", "rad/s", "linear natural frequency", 2.0 * math.pi),
                Quantity("zeta", "", "damping ratio", 0.05),
                Quantity("gamma", "1/(m^2*s^2)", "cubic stiffness per unit mass", 4.0 * math.pi ** 2),
                Quantity("force", "m/s^2", "forcing amplitude per unit mass", 0.4 * math.pi ** 2)],
    guards=["none"], modes=["unused"],
    functions={"rhs": rhs, "jacobian": jacobian, "guards": guards, "expected_sign": expected_sign,
               "transition": transition, "initial_mode": initial_mode},
    speed="speed")
