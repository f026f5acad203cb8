"""The cam-follower equations written again for the peer solvers of bench_peers.py.

Nothing here imports camdyn's compiled model: the right-hand side below is written from
the plain SciPy reference model (camdyn.testing.oracle, class ``ReferenceModel``) and
docs/model.md section 3, as a user of another solver would write it. The geometry is
the cam's parametric form (the contact point minimises ``n . X(phi)`` over the ellipse
angle ``phi``), forces are the Hertz law plus the damping law, Coulomb friction and the
tilted spring, and moments are cross products about the pivot P.

The peers have no events: the right-hand side switches the contact on the sign of the
penetration (no force unless ``delta > 0``) and the friction on the sign of the sliding
velocity, and the solver steps straight through these switches.

State ``y = (alpha [rad], alpha_dot [rad/s], W_cam [J])``; parameters are packed, in SI
units, in a float vector whose slots are the module constants below.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba import carray
from numba.extending import register_jitable

# slots of the parameter vector (SI units)
THETA0, OMEGA, SEMI_MAJOR, SEMI_MINOR, RUNOUT, PIVOT_X, PIVOT_Y, HEIGHT = range(8)
EFFECTIVE_MODULUS, POINT_CONTACT, PIN_RADIUS, CONTACT_LENGTH = range(8, 12)
DAMPING_LAW, VISCOUS_C, BETA, EXPONENT, CLIP_ADHESION = range(12, 17)
FRICTION_LAW, FRICTION_COEFFICIENT, SMOOTHING = range(17, 20)
SPRING_STIFFNESS, FREE_LENGTH, GROUND_DEPTH, ATTACHMENT_X, TILT = range(20, 25)
WIDTH, CG_DISTANCE, MASS, GRAVITY, INERTIA, CALLS = range(25, 31)
SIZE = 31

DAMPING_CODES = {"none": 0.0, "viscous": 1.0, "power": 2.0, "stiffness-proportional": 3.0, "zhang-whiten": 4.0}
FRICTION_CODES = {"none": 0.0, "coulomb": 1.0, "tanh": 2.0}


def parameters(system, theta0: float, viscous_c: float) -> np.ndarray:
    """Pack ``system`` (a camdyn System, read for its numbers only), the initial cam angle
    ``theta0`` [rad] and the viscous coefficient ``viscous_c`` [N s/m] into a vector."""
    s = system
    if s.motion.kind != "constant":
        raise NotImplementedError("the peer models drive the cam at constant speed only")
    if s.contact.damping not in DAMPING_CODES or s.friction.law not in FRICTION_CODES:
        raise NotImplementedError(f"no peer model of {s.contact.damping!r} damping or {s.friction.law!r} friction")
    compliance = ((1 - s.cam.poisson_ratio ** 2) / s.cam.youngs_modulus
                  + (1 - s.follower.poisson_ratio ** 2) / s.follower.youngs_modulus)
    p = np.zeros(SIZE)
    p[THETA0], p[OMEGA] = theta0, s.motion.angular_speed
    p[SEMI_MAJOR], p[SEMI_MINOR], p[RUNOUT] = s.cam.semi_major, s.cam.semi_minor, s.cam.runout
    p[PIVOT_X], p[PIVOT_Y] = s.cam.pivot_x, s.cam.pivot_y
    p[HEIGHT] = 0.5 * s.follower.width + 2.0 * s.follower.pin_radius
    p[EFFECTIVE_MODULUS] = 1.0 / compliance
    p[POINT_CONTACT] = 1.0 if s.contact.kind == "point" else 0.0
    p[PIN_RADIUS], p[CONTACT_LENGTH] = s.follower.pin_radius, s.contact.length
    p[DAMPING_LAW], p[VISCOUS_C] = DAMPING_CODES[s.contact.damping], viscous_c
    p[BETA], p[EXPONENT], p[CLIP_ADHESION] = s.contact.beta, s.contact.exponent, float(s.contact.clip_adhesion)
    p[FRICTION_LAW] = FRICTION_CODES[s.friction.law]
    p[FRICTION_COEFFICIENT], p[SMOOTHING] = s.friction.coefficient, s.friction.smoothing
    sp = s.spring
    p[SPRING_STIFFNESS], p[FREE_LENGTH], p[GROUND_DEPTH] = sp.stiffness, sp.free_length, sp.ground_depth
    p[ATTACHMENT_X], p[TILT] = sp.attachment_x, sp.tilt
    p[WIDTH], p[CG_DISTANCE], p[MASS] = s.follower.width, s.follower.cg_distance, s.follower.mass
    p[GRAVITY], p[INERTIA] = s.gravity, s.follower.inertia
    return p


@register_jitable
def normal_force(delta, delta_dot, rho, p):
    """Normal force [N] at penetration ``delta`` [m] > 0, its rate [m/s] and the cam's
    curvature radius ``rho`` [m]: Hertz force plus the damping law."""
    if p[POINT_CONTACT] > 0.5:
        rho_e = rho if p[PIN_RADIUS] == 0.0 else 1.0 / (1.0 / rho + 1.0 / p[PIN_RADIUS])
        elastic = 4.0 / 3.0 * p[EFFECTIVE_MODULUS] * math.sqrt(rho_e) * delta ** 1.5
    else:
        elastic = math.pi / 4.0 * p[EFFECTIVE_MODULUS] * p[CONTACT_LENGTH] * delta
    law = p[DAMPING_LAW]
    damping = 0.0
    if law == 1.0:
        damping = p[VISCOUS_C] * delta_dot
    elif law == 2.0:
        damping = p[BETA] * delta ** p[EXPONENT] * delta_dot
    elif law == 3.0:
        damping = p[BETA] * elastic * delta_dot
    elif law == 4.0:
        damping = p[BETA] * delta ** 0.25 * delta_dot
    force = elastic + damping
    if p[CLIP_ADHESION] > 0.5 and force < 0.0:
        force = 0.0
    return force


def derivative(t, alpha, alpha_dot, p):
    """``(d alpha/dt [rad/s], d alpha_dot/dt [rad/s^2], d W_cam/dt [W])`` at time ``t`` [s]."""
    ca, sa = math.cos(alpha), math.sin(alpha)
    # spring (eq 4.44): compression along (sin tilt, cos tilt) at the lower face, x = dx
    tilt, width, dx = p[TILT], p[WIDTH], p[ATTACHMENT_X]
    spring = (p[SPRING_STIFFNESS] * (p[FREE_LENGTH] - p[GROUND_DEPTH] + dx * sa / ca + 0.5 * width / ca)
              * ca / math.cos(alpha - tilt))
    along = (dx + 0.5 * width * sa) / ca
    sx, sy = along * ca - 0.5 * width * sa, -along * sa - 0.5 * width * ca
    moment = -(sx * spring * math.cos(tilt) - sy * spring * math.sin(tilt))
    moment += p[CG_DISTANCE] * ca * p[MASS] * p[GRAVITY]  # gravity at the centre of gravity
    power = 0.0
    # geometry: contact point of the eccentric ellipse, penetration, rates
    theta, theta_dot = p[THETA0] + p[OMEGA] * t, p[OMEGA]
    ct, st = math.cos(theta), math.sin(theta)
    a, b, h = p[SEMI_MAJOR], p[SEMI_MINOR], p[HEIGHT]
    nx, ny, ux, uy = sa, ca, ca, -sa
    phi = math.atan2(-b * (-nx * st + ny * ct), -a * (nx * ct + ny * st))
    cp, sp = math.cos(phi), math.sin(phi)
    rx = -p[RUNOUT] * ct + a * cp * ct - b * sp * st  # contact point relative to the cam pivot
    ry = -p[RUNOUT] * st + a * cp * st + b * sp * ct
    x, y = p[PIVOT_X] + rx, p[PIVOT_Y] + ry
    delta = h - (nx * x + ny * y)
    if delta > 0.0:
        chi = ux * x + uy * y
        rho = (a * a * sp * sp + b * b * cp * cp) ** 1.5 / (a * b)
        vx, vy = -theta_dot * ry, theta_dot * rx  # cam surface velocity
        delta_dot = -alpha_dot * chi - (nx * vx + ny * vy)
        bx, by = chi * ux + h * nx, chi * uy + h * ny  # contact point on the follower
        sliding = (vx - alpha_dot * by) * ux + (vy + alpha_dot * bx) * uy
        fn = normal_force(delta, delta_dot, rho, p)
        ff = 0.0
        if p[FRICTION_LAW] == 1.0:
            ff = p[FRICTION_COEFFICIENT] * (1.0 if sliding >= 0.0 else -1.0) * fn
        elif p[FRICTION_LAW] == 2.0:
            ff = p[FRICTION_COEFFICIENT] * math.tanh(p[SMOOTHING] * sliding) * fn
        moment -= bx * (ff * uy - fn * ny) - by * (ff * ux - fn * nx)
        power = -fn * (nx * vx + ny * vy) + ff * (ux * vx + uy * vy)
    return alpha_dot, moment / p[INERTIA], power


def python_rhs(p: np.ndarray):
    """``fun(t, y)`` for :func:`scipy.integrate.solve_ivp`, in plain Python."""
    values = tuple(float(v) for v in p)

    def fun(t, y):
        return np.array(derivative(t, float(y[0]), float(y[1]), values))
    return fun


compiled_derivative = numba.njit(derivative)


@numba.njit
def compiled_derivative_array(t, y, p):
    """:func:`derivative` compiled, as an array."""
    out = np.empty(3)
    out[0], out[1], out[2] = compiled_derivative(t, y[0], y[1], p)
    return out


def numba_rhs(p: np.ndarray):
    """``fun(t, y)`` for :func:`scipy.integrate.solve_ivp`: a thin Python wrapper of a
    numba-compiled right-hand side."""
    return lambda t, y: compiled_derivative_array(t, y, p)


_double_pointer = numba.types.CPointer(numba.types.float64)
# numbalsoda's signature: f(t, u, du, p)
numbalsoda_signature = numba.types.void(numba.types.float64, _double_pointer, _double_pointer, _double_pointer)
# CyRK's (nbsolve2_ivp) signature: f(dy, t, y, args)
cyrk_signature = numba.types.void(_double_pointer, numba.types.float64, _double_pointer, _double_pointer)


@numba.cfunc(numbalsoda_signature)
def numbalsoda_rhs(t, u, du, data):
    """numbalsoda's right-hand side; counts its calls in ``data[CALLS]``."""
    p = carray(data, (SIZE,))
    du[0], du[1], du[2] = compiled_derivative(t, u[0], u[1], p)
    p[CALLS] += 1.0


@numba.cfunc(cyrk_signature)
def cyrk_rhs(dy, t, y, args):
    """CyRK's right-hand side."""
    p = carray(args, (SIZE,))
    dy[0], dy[1], dy[2] = compiled_derivative(t, y[0], y[1], p)
