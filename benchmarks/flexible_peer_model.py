"""The rocking follower on a flexible pivot written again for the peer solvers of
bench_flexible_pivot.py.

Nothing here imports camdyn's compiled model: the equations are those of
docs/mechanisms.md (*The follower on a flexible pivot*, eqs (1)-(9)) on the cam-follower
of benchmarks/peer_models.py (its parameter slots, its contact law and its cam
geometry), as a user of another solver would write them. Like the rigid pivot's peer
model, it has no events: the contact switches on the sign of the penetration and
Coulomb friction on the sign of the sliding velocity.

State ``y = (alpha [rad], alpha_dot [rad/s], u [m], u_dot [m/s], v [m], v_dot [m/s])``;
the parameter vector is peer_models.parameters() followed by the bearing's stiffness
``kp`` [N/m], damping ``cp`` [N s/m] and a call counter. The rigid pivot's state is
``(alpha [rad], alpha_dot [rad/s])`` (peer_models.derivative without the cam's work).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba import carray
from peer_models import (
    ATTACHMENT_X,
    CG_DISTANCE,
    FREE_LENGTH,
    FRICTION_COEFFICIENT,
    FRICTION_LAW,
    GRAVITY,
    GROUND_DEPTH,
    HEIGHT,
    INERTIA,
    MASS,
    OMEGA,
    PIVOT_X,
    PIVOT_Y,
    RUNOUT,
    SEMI_MAJOR,
    SEMI_MINOR,
    SIZE,
    SMOOTHING,
    SPRING_STIFFNESS,
    THETA0,
    TILT,
    WIDTH,
    compiled_derivative,
    normal_force,
    numbalsoda_signature,
)

BEARING_STIFFNESS, BEARING_DAMPING, COUNT = SIZE, SIZE + 1, SIZE + 2
FLEXIBLE_SIZE = SIZE + 3


def flexible_parameters(rigid: np.ndarray, stiffness: float, damping: float) -> np.ndarray:
    """The rigid pivot's peer parameters ``rigid`` with the bearing's ``kp`` [N/m] and
    ``cp`` [N s/m] and a zeroed call counter appended."""
    return np.r_[rigid, stiffness, damping, 0.0]


@numba.njit
def flexible_derivative(t, y, p, out):
    """``dy/dt`` of the flexible pivot into ``out`` (6 values, SI units), eqs (4)-(9) of
    docs/mechanisms.md; counts the call in ``p[COUNT]``."""
    p[COUNT] += 1.0
    alpha, alpha_dot, u, u_dot, v, v_dot = y[0], y[1], y[2], y[3], y[4], y[5]
    ca, sa = math.cos(alpha), math.sin(alpha)
    m, lcg = p[MASS], p[CG_DISTANCE]
    # spring at the rigid pivot (eq 4.44) and its slope dFs/dalpha
    tilt, width, dx = p[TILT], p[WIDTH], p[ATTACHMENT_X]
    compression = p[FREE_LENGTH] - p[GROUND_DEPTH] + dx * sa / ca + 0.5 * width / ca
    tilted = math.cos(alpha - tilt)
    spring = p[SPRING_STIFFNESS] * compression * ca / tilted
    slope = p[SPRING_STIFFNESS] * ((dx + 0.5 * width * sa) / (ca * ca) * ca / tilted
                                   - compression * math.sin(tilt) / (tilted * tilted))
    along = (dx + 0.5 * width * sa) / ca
    sx, sy = along * ca - 0.5 * width * sa, -along * sa - 0.5 * width * ca
    shortening = math.sin(tilt) * u + math.cos(tilt) * v                     # s = d.P, eq (8)
    moment = -(sx * spring * math.cos(tilt) - sy * spring * math.sin(tilt)) + slope * shortening   # eq (9)
    moment += lcg * ca * m * p[GRAVITY]
    shortened = spring - p[SPRING_STIFFNESS] * shortening
    fx = shortened * math.sin(tilt) - p[BEARING_STIFFNESS] * u - p[BEARING_DAMPING] * u_dot
    fy = shortened * math.cos(tilt) - p[BEARING_STIFFNESS] * v - p[BEARING_DAMPING] * v_dot - m * p[GRAVITY]
    # the cam's contact point, the cam pivot at E0 - P from the moving pivot
    theta, theta_dot = p[THETA0] + p[OMEGA] * t, p[OMEGA]
    ct, st = math.cos(theta), math.sin(theta)
    a, b, h = p[SEMI_MAJOR], p[SEMI_MINOR], p[HEIGHT]
    nx, ny, ux, uy = sa, ca, ca, -sa
    phi = math.atan2(-b * (-nx * st + ny * ct), -a * (nx * ct + ny * st))
    cp, sp = math.cos(phi), math.sin(phi)
    rx = -p[RUNOUT] * ct + a * cp * ct - b * sp * st
    ry = -p[RUNOUT] * st + a * cp * st + b * sp * ct
    x, yy = p[PIVOT_X] - u + rx, p[PIVOT_Y] - v + ry
    delta = h - (nx * x + ny * yy)
    if delta > 0.0:
        chi = ux * x + uy * yy
        rho = (a * a * sp * sp + b * b * cp * cp) ** 1.5 / (a * b)
        vx, vy = -theta_dot * ry, theta_dot * rx
        delta_dot = -alpha_dot * chi - (nx * vx + ny * vy) + (nx * u_dot + ny * v_dot)        # eq (6)
        bx, by = chi * ux + h * nx, chi * uy + h * ny
        sliding = (vx - alpha_dot * by) * ux + (vy + alpha_dot * bx) * uy - (ux * u_dot + uy * v_dot)   # eq (7)
        fn = normal_force(delta, delta_dot, rho, p)
        ff = 0.0
        if p[FRICTION_LAW] == 1.0:
            ff = p[FRICTION_COEFFICIENT] * (1.0 if sliding >= 0.0 else -1.0) * fn
        elif p[FRICTION_LAW] == 2.0:
            ff = p[FRICTION_COEFFICIENT] * math.tanh(p[SMOOTHING] * sliding) * fn
        cx, cy = ff * ux - fn * nx, ff * uy - fn * ny
        moment -= bx * cy - by * cx
        fx += cx
        fy += cy
    alpha_ddot = (moment + lcg * (sa * fx + ca * fy)) / (p[INERTIA] - m * lcg * lcg)          # eq (4)
    w2 = alpha_dot * alpha_dot
    out[0] = alpha_dot
    out[1] = alpha_ddot
    out[2] = u_dot
    out[3] = fx / m + lcg * (alpha_ddot * sa + w2 * ca)                                      # eq (5)
    out[4] = v_dot
    out[5] = fy / m + lcg * (alpha_ddot * ca - w2 * sa)


@numba.njit
def rigid_derivative(t, y, p, out):
    """``dy/dt`` of the rigid pivot (peer_models.derivative, the cam's work left out) into
    ``out``; counts the call in ``p[COUNT]``."""
    p[COUNT] += 1.0
    out[0], out[1], _ = compiled_derivative(t, y[0], y[1], p)


@numba.njit
def flexible_array(t, y, p):
    out = np.empty(6)
    flexible_derivative(t, y, p, out)
    return out


@numba.njit
def rigid_array(t, y, p):
    out = np.empty(2)
    rigid_derivative(t, y, p, out)
    return out


def scipy_rhs(states: int, p: np.ndarray):
    """``fun(t, y)`` for :func:`scipy.integrate.solve_ivp`: a thin Python wrapper of the
    compiled right-hand side of the rigid (2 states) or flexible (6) pivot."""
    compiled = rigid_array if states == 2 else flexible_array
    return lambda t, y: compiled(t, y, p)


@numba.cfunc(numbalsoda_signature)
def numbalsoda_flexible(t, u, du, data):
    """numbalsoda's right-hand side of the flexible pivot."""
    flexible_derivative(t, carray(u, (6,)), carray(data, (FLEXIBLE_SIZE,)), carray(du, (6,)))


@numba.cfunc(numbalsoda_signature)
def numbalsoda_rigid(t, u, du, data):
    """numbalsoda's right-hand side of the rigid pivot."""
    rigid_derivative(t, carray(u, (2,)), carray(data, (FLEXIBLE_SIZE,)), carray(du, (2,)))
