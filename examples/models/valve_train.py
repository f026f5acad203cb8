"""A valve train written as a camdyn model outside the package (docs/user-models.md).

A cam drives a roller follower and a valve through a lash gap; the valve spring is two
masses' worth of spring (half its mass lumped at its middle), so that it can surge; the
valve lands on its seat as an impact. Four states, two contacts:

- ``x_v``, ``v_v``: the valve's lift [m] (0 on the seat, up positive) and its velocity
  [m/s]; the follower is rigid and massless beside the valve (its mass is in
  ``valve_mass``);
- ``x_s``, ``v_s``: the spring's middle coil's displacement [m] and velocity [m/s].

Forces (all [N]; ``delta_c = s(theta) - lash - x_v`` the cam contact's penetration [m],
``delta_s = -x_v`` the seat's [m]):

- cam contact, closed while ``delta_c > 0``:
  ``F_c = k_c delta_c (1 + alpha_c d(delta_c)/dt)``, at least 0 (eq. V1, a linear
  Hunt-Crossley law: the force vanishes with the penetration, so that contact ends
  where ``delta_c`` crosses zero);
- seat, closed while ``delta_s > 0``: ``F_s = k_seat delta_s (1 + alpha_s d(delta_s)/dt)``,
  at least 0 (eq. V2);
- spring, head half and retainer half, each of stiffness ``k1`` and ``k2``, preloaded by
  ``F0`` and damped by ``c`` [N*s/m]: ``F_2 = F0 + k2 (x_v - x_s) + c (v_v - v_s)`` on the
  retainer (eq. V3), ``F_1 = F0 + k1 x_s + c v_s`` on the head (eq. V4);
- ``m_v a_v = F_c + F_s - F_2`` (eq. V5) and ``m_s a_s = F_2 - F_1`` (eq. V6).

The cam's lift is ``s = h sin^4(pi phi / beta)`` over the opening window ``0 <= phi <=
beta`` of the cam angle ``phi = theta - theta_open`` (``theta = 2 pi f t``), and 0
elsewhere (eq. V7): continuous to its third derivative, so that the right-hand side is
smooth inside each mode.

Run it: ``python examples/models/valve_train.py`` (simulation, a speed sweep of the float
and the seating bounce, and a figure). The numbers are a stand-in for a passenger-car
valve (9 mm lift, 0.2 mm lash, 250 N preload), not a measured engine.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.systems.protocol import Model, Quantity

# parameter slots (the order of PARAMETERS)
SPEED, LIFT, WINDOW, OPEN, LASH, M_V, M_S, K1, K2, PRELOAD, C_SPRING, K_C, ALPHA_C, K_SEAT, ALPHA_S = range(15)


@numba.njit(cache=True)
def cam_lift(t, p):
    """The cam's lift [m] and its first two time derivatives [m/s, m/s^2] (eq. V7)."""
    omega = 2.0 * math.pi * p[SPEED]
    phi = (omega * t) % (2.0 * math.pi) - p[OPEN]
    if phi <= 0.0 or phi >= p[WINDOW]:
        return 0.0, 0.0, 0.0
    k = math.pi / p[WINDOW]
    x = k * phi
    s, c = math.sin(x), math.cos(x)
    h = p[LIFT]
    return (h * s ** 4, h * 4.0 * s ** 3 * c * k * omega,
            h * (12.0 * s * s * c * c - 4.0 * s ** 4) * (k * omega) ** 2)


@numba.njit(cache=True)
def forces(t, y, mode, p):
    """Cam contact, seat, retainer and head forces [N] (eqs. V1-V4)."""
    s, sd, _ = cam_lift(t, p)
    fc = 0.0
    if mode[0] > 0.5:
        d = s - p[LASH] - y[0]
        fc = max(0.0, p[K_C] * d * (1.0 + p[ALPHA_C] * (sd - y[1])))
    fs = 0.0
    if mode[1] > 0.5:
        fs = max(0.0, p[K_SEAT] * (-y[0]) * (1.0 + p[ALPHA_S] * (-y[1])))
    f2 = p[PRELOAD] + p[K2] * (y[0] - y[2]) + p[C_SPRING] * (y[1] - y[3])
    f1 = p[PRELOAD] + p[K1] * y[2] + p[C_SPRING] * y[3]
    return fc, fs, f2, f1


@numba.njit(cache=True)
def rhs(t, y, mode, p, dydt):
    fc, fs, f2, f1 = forces(t, y, mode, p)
    dydt[0] = y[1]
    dydt[1] = (fc + fs - f2) / p[M_V]   # eq. V5
    dydt[2] = y[3]
    dydt[3] = (f2 - f1) / p[M_S]        # eq. V6


@numba.njit(cache=True)
def jacobian(t, y, f0, mode, p, jac):
    """``d f / d y`` of eqs. V1-V6 (the variational system's, for periodic orbits)."""
    s, sd, _ = cam_lift(t, p)
    dfc_dx = dfc_dv = dfs_dx = dfs_dv = 0.0
    if mode[0] > 0.5:
        d = s - p[LASH] - y[0]
        factor = 1.0 + p[ALPHA_C] * (sd - y[1])
        if p[K_C] * d * factor > 0.0:
            dfc_dx, dfc_dv = -p[K_C] * factor, -p[K_C] * d * p[ALPHA_C]
    if mode[1] > 0.5:
        factor = 1.0 - p[ALPHA_S] * y[1]
        if -p[K_SEAT] * y[0] * factor > 0.0:
            dfs_dx, dfs_dv = -p[K_SEAT] * factor, p[K_SEAT] * y[0] * p[ALPHA_S]
    jac[:, :] = 0.0
    jac[0, 1] = 1.0
    jac[1, 0] = (dfc_dx + dfs_dx - p[K2]) / p[M_V]
    jac[1, 1] = (dfc_dv + dfs_dv - p[C_SPRING]) / p[M_V]
    jac[1, 2] = p[K2] / p[M_V]
    jac[1, 3] = p[C_SPRING] / p[M_V]
    jac[2, 3] = 1.0
    jac[3, 0] = p[K2] / p[M_S]
    jac[3, 1] = p[C_SPRING] / p[M_S]
    jac[3, 2] = -(p[K1] + p[K2]) / p[M_S]
    jac[3, 3] = -2.0 * p[C_SPRING] / p[M_S]


@numba.njit(cache=True)
def guards(t, y, f, known, p, values, rates):
    s, sd, _ = cam_lift(t, p)
    values[0] = s - p[LASH] - y[0]     # cam contact's penetration [m]
    rates[0] = sd - y[1]
    values[1] = -y[0]                  # seat's penetration [m]
    rates[1] = -y[1]


@numba.njit(cache=True)
def expected_sign(k, mode, p):
    return 1.0 if mode[k] > 0.5 else -1.0   # a closed contact keeps its penetration positive


@numba.njit(cache=True)
def transition(k, t, y, values, mode, p):
    mode[k] = 1.0 - mode[k]


@numba.njit(cache=True)
def initial_mode(t, y, p, mode):
    s, _, _ = cam_lift(t, p)
    mode[0] = 1.0 if s - p[LASH] - y[0] > 0.0 else 0.0
    mode[1] = 1.0 if y[0] < 0.0 else 0.0


@numba.njit(cache=True)
def monitor(t, y, mode, p):
    return forces(t, y, mode, p)[1]   # the seat's force: its peak at each landing


@numba.njit(cache=True)
def outputs(t, y, mode, p, out):
    fc, fs, f2, _ = forces(t, y, mode, p)
    out[0] = cam_lift(t, p)[0]
    out[1] = fc
    out[2] = fs
    out[3] = f2


def seated_state(p):
    """The valve at rest on its seat, its spring preloaded (eqs. V2-V6 with no motion)."""
    series = p[K1] * p[K2] / (p[K1] + p[K2])
    x_v = -p[PRELOAD] / (p[K_SEAT] + series)
    return np.array([x_v, 0.0, p[K2] * x_v / (p[K1] + p[K2]), 0.0])


VALVE_TRAIN = Model(
    name="valve train",
    states=[Quantity("x_v", "m", "valve lift"), Quantity("v_v", "m/s", "valve velocity"),
            Quantity("x_s", "m", "spring middle coil displacement"),
            Quantity("v_s", "m/s", "spring middle coil velocity")],
    parameters=[
        Quantity("speed", "Hz", "camshaft speed", 40.0),
        Quantity("cam.lift", "m", "cam lift", 9e-3),
        Quantity("cam.window", "rad", "cam angle of the opening", math.radians(130.0)),
        Quantity("cam.opening_angle", "rad", "cam angle where the opening starts", math.radians(90.0)),
        Quantity("lash", "m", "valve lash", 0.2e-3),
        Quantity("valve.mass", "kg", "valve, retainer and follower", 0.1),
        Quantity("spring.mass", "kg", "spring mass lumped at its middle coil", 0.025),
        Quantity("spring.head_stiffness", "N/m", "stiffness of the spring's head half", 80e3),
        Quantity("spring.retainer_stiffness", "N/m", "stiffness of the spring's retainer half", 80e3),
        Quantity("spring.preload", "N", "spring preload on the closed valve", 250.0),
        Quantity("spring.damping", "N*s/m", "damping of each spring half", 5.0),
        Quantity("contact.stiffness", "N/m", "cam to valve stiffness", 1e7),
        Quantity("contact.damping", "s/m", "Hunt-Crossley coefficient of the cam contact", 0.2),
        Quantity("seat.stiffness", "N/m", "seat stiffness", 2e7),
        Quantity("seat.damping", "s/m", "Hunt-Crossley coefficient of the seat", 0.2),
    ],
    guards=["cam_contact", "seat"],
    modes=["cam_contact", "seated"],
    outputs=[Quantity("cam_lift", "m", "cam lift"), Quantity("cam_force", "N", "cam contact force"),
             Quantity("seat_force", "N", "seat force"), Quantity("spring_force", "N", "spring force on the retainer")],
    functions={"rhs": rhs, "jacobian": jacobian, "guards": guards, "expected_sign": expected_sign,
               "transition": transition, "initial_mode": initial_mode, "monitor": monitor, "outputs": outputs},
    speed="speed",
    initial_state=seated_state,
    max_step_fraction=1.0 / 64.0,
)


if __name__ == "__main__":   # pragma: no cover - the gallery and docs run it
    import camdyn

    ds = camdyn.simulate(VALVE_TRAIN.bind(), speed="40 Hz", revolutions=3)
    print(ds)
