"""Packing a :class:`~camdyn.params.system.System` into the flat float64 vector used by
the compiled core.

The compiled functions take one parameter vector ``p``; the integer constants below
name its slots. Integer codes (laws, kinds) are stored as floats.
"""

from __future__ import annotations

import math

import numpy as np

from camdyn.params.system import (
    CONTACT_KINDS,
    DAMPING_LAWS,
    FRICTION_LAWS,
    MOTION_KINDS,
    System,
)

# follower
MASS = 0            # m [kg]
INERTIA = 1         # I_P [kg m^2]
CG = 2              # l_cg [m]
WIDTH = 3           # wb [m]
OFFSET = 4          # h = wb/2 + 2 rd [m]
PIN = 5             # rd [m]
# cam
SEMI_A = 6          # a [m]
SEMI_B = 7          # b [m]
RUNOUT = 8          # e [m]
PIVOT_X = 9         # PE_x [m]
PIVOT_Y = 10        # PE_y [m]
# spring
KS = 11             # ks [N/m]
LS = 12             # Ls [m]
DX = 13             # dx [m]
DY = 14             # dy [m]
TILT = 15           # sigma [rad]
GRAVITY = 16        # g [m/s^2]
# contact
CONTACT_KIND = 17   # 0 point, 1 line
ESTAR = 18          # E* [Pa]
LINE_LENGTH = 19    # l [m]
DAMPING_LAW = 20    # code of DAMPING_LAWS
VISCOUS_C = 21      # c of law A [N s/m]
BETA = 22           # beta [law-dependent]
EXPONENT = 23       # n of the power law [-]
RESTITUTION = 24    # e [-]
V_REFERENCE = 25    # reference approach velocity [m/s]
CLIP = 26           # 1 clips adhesive force
# friction
FRICTION_LAW = 27   # code of FRICTION_LAWS
MU = 28             # mu_m [-]
SMOOTHING = 29      # sigma of tanh friction [s/m]
# motion
MOTION_KIND = 30    # 0 constant, 1 oscillating
THETA0 = 31         # Theta0 [rad]
OMEGA = 32          # signed cam angular speed [rad/s]
SWING = 33          # Theta_p, peak-to-peak [rad]
OMEGA_C = 34        # oscillation angular frequency [rad/s]
SIZE = 35

#: Mode slots passed with the state to the right-hand side (hybrid-system mode).
MODE_CONTACT = 0     # 1 in contact, 0 free flight
MODE_SLIP = 1        # sign of the sliding velocity for Coulomb friction (+1 / -1)
MODE_COMPRESSING = 2  # 1 while delta_dot > 0 (laws D and E switch on it)
MODE_APPROACH = 3    # approach velocity of the current contact [m/s] (restitution laws)
MODE_IMPACT = 4      # 1 if the current contact began with an impact (its peak is tracked)
MODE_SIZE = 5


def effective_modulus(system: System) -> float:
    """Contact modulus ``E*`` [Pa]: ``1/E* = (1-nu_c^2)/Y_c + (1-nu_b^2)/Y_b`` (eq 2.13, 3.12)."""
    c, f = system.cam, system.follower
    return 1.0 / ((1 - c.poisson_ratio ** 2) / c.youngs_modulus + (1 - f.poisson_ratio ** 2) / f.youngs_modulus)


def pack(system: System, viscous_c: float = 0.0, initial_angle: float | None = None) -> np.ndarray:
    """Parameter vector of ``system`` for the compiled core.

    Parameters
    ----------
    system : System
    viscous_c : float
        Viscous contact damping ``c`` [N s/m] of laws A, D and E, from eq 2.24 (computed
        by :func:`camdyn.model.equilibrium.viscous_coefficient`).
    initial_angle : float, optional
        Cam angle ``Theta0`` [rad]; defaults to ``system.motion.initial_angle``.
    """
    s = system
    p = np.zeros(SIZE)
    p[MASS] = s.follower.mass
    p[INERTIA] = s.follower.inertia
    p[CG] = s.follower.cg_distance
    p[WIDTH] = s.follower.width
    p[OFFSET] = s.follower.surface_offset
    p[PIN] = s.follower.pin_radius
    p[SEMI_A] = s.cam.semi_major
    p[SEMI_B] = s.cam.semi_minor
    p[RUNOUT] = s.cam.runout
    p[PIVOT_X] = s.cam.pivot_x
    p[PIVOT_Y] = s.cam.pivot_y
    p[KS] = s.spring.stiffness
    p[LS] = s.spring.free_length
    p[DX] = s.spring.attachment_x
    p[DY] = s.spring.ground_depth
    p[TILT] = s.spring.tilt
    p[GRAVITY] = s.gravity
    p[CONTACT_KIND] = CONTACT_KINDS[s.contact.kind]
    p[ESTAR] = effective_modulus(s)
    p[LINE_LENGTH] = s.contact.length
    p[DAMPING_LAW] = DAMPING_LAWS[s.contact.damping]
    p[VISCOUS_C] = viscous_c
    p[BETA] = s.contact.beta
    p[EXPONENT] = s.contact.exponent
    p[RESTITUTION] = s.contact.restitution
    p[V_REFERENCE] = s.contact.reference_velocity
    p[CLIP] = 1.0 if s.contact.clip_adhesion else 0.0
    p[FRICTION_LAW] = FRICTION_LAWS[s.friction.law]
    p[MU] = s.friction.coefficient
    p[SMOOTHING] = s.friction.smoothing
    p[MOTION_KIND] = MOTION_KINDS[s.motion.kind]
    theta0 = initial_angle if initial_angle is not None else s.motion.initial_angle
    p[THETA0] = 0.0 if theta0 is None else theta0
    p[OMEGA] = s.motion.angular_speed
    p[SWING] = s.motion.amplitude
    p[OMEGA_C] = 2.0 * math.pi * s.motion.frequency * s.motion.direction
    return p
