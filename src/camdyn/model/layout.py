"""Packing a :class:`~camdyn.params.system.System` into the flat float64 vector used by
the compiled core.

The compiled functions take one parameter vector ``p``; the integer constants below
name its slots. Integer codes (laws, kinds) are stored as floats; the damping laws'
codes are those of their rows in :data:`camdyn.params.laws.TABLE`. The slots that hold
a parameter unchanged are listed in :data:`COPIED` by the parameter's dotted key
(:mod:`camdyn.params.schema`); :func:`pack` computes the others.
"""

from __future__ import annotations

import math

import numpy as np

from camdyn.params.schema import parameter_index
from camdyn.params.system import (
    CONTACT_KINDS,
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
DAMPING_LAW = 20    # code of the damping law (camdyn.params.laws.TABLE)
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
MOTION_KIND = 30    # 0 constant, 1 oscillating, 2 ramp, 3 tabulated (packed by simulation.mechanisms)
THETA0 = 31         # Theta0 [rad]
OMEGA = 32          # signed cam angular speed [rad/s]
SWING = 33          # Theta_p, peak-to-peak [rad]
OMEGA_C = 34        # oscillation angular frequency [rad/s]
START_OMEGA = 35    # signed cam angular speed a ramp starts from [rad/s]
RAMP_TIME = 36      # duration of a ramp [s]
TABLE_START = 37    # slot of the first spline coefficient of a tabulated motion (kind 3) [-]
TABLE_INTERVALS = 38  # number of spline intervals over the table's period [-]
TABLE_PERIOD = 39   # period of the tabulated motion [s]
TABLE_DRIFT = 40    # mean cam speed of the tabulated motion, (Theta(T) - Theta(0)) / T [rad/s]
# cam shape
CAM_SHAPE = 41      # 0 the ellipse of SEMI_A, SEMI_B, RUNOUT; 1 a profile table (camdyn.model.rocking_profile)
PROFILE_START = 42  # slot of the profile table (camdyn.model.profiles) of a cam of shape 1 [-]
BASE_RADIUS = 43    # base circle radius r_base of a cam of shape 1 [m]
SIZE = 44
#: Values of the CAM_SHAPE slot.
ELLIPSE = 0.0
PROFILE_TABLE = 1.0

#: Mode slots passed with the state to the right-hand side (hybrid-system mode).
MODE_CONTACT = 0     # 1 in contact, 0 free flight
MODE_SLIP = 1        # sign of the sliding velocity for Coulomb friction (+1 / -1)
MODE_COMPRESSING = 2  # 1 while delta_dot > 0 (laws D and E switch on it)
MODE_APPROACH = 3    # approach velocity of the current contact [m/s] (restitution laws)
MODE_IMPACT = 4      # 1 if the current contact began with an impact (its peak is tracked)
MODE_SIZE = 5

#: Slot -> dotted key of the parameter it holds unchanged, in SI (camdyn.params.config.SCHEMA).
COPIED = {
    MASS: "follower.mass", INERTIA: "follower.inertia", CG: "follower.cg_distance", WIDTH: "follower.width",
    PIN: "follower.pin_radius",
    SEMI_A: "cam.semi_major", SEMI_B: "cam.semi_minor", RUNOUT: "cam.runout", PIVOT_X: "cam.pivot_x",
    PIVOT_Y: "cam.pivot_y",
    KS: "spring.stiffness", LS: "spring.free_length", DX: "spring.attachment_x", DY: "spring.ground_depth",
    TILT: "spring.tilt", GRAVITY: "environment.gravity",
    LINE_LENGTH: "contact.length", BETA: "contact.beta", EXPONENT: "contact.exponent",
    RESTITUTION: "contact.restitution", V_REFERENCE: "contact.reference_velocity", CLIP: "contact.clip_adhesion",
    MU: "friction.coefficient", SMOOTHING: "friction.smoothing",
    SWING: "motion.amplitude",
}
_READERS = tuple((slot, parameter_index(System)[key].getter) for slot, key in COPIED.items())


def effective_modulus(system: System) -> float:
    """Contact modulus ``E*`` [Pa]: ``1/E* = (1-nu_c^2)/Y_c + (1-nu_b^2)/Y_b`` (eq 2.13, 3.12)."""
    # imported here: contact.py reads this module's slots
    from camdyn.model.contact import effective_modulus as modulus

    c, f = system.cam, system.follower
    return modulus(c.youngs_modulus, c.poisson_ratio, f.youngs_modulus, f.poisson_ratio)


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

    A cam given by a profile (``system.profile``) is packed as shape
    :data:`PROFILE_TABLE`, its table appended after the :data:`SIZE` slots.
    """
    s = system
    p = np.zeros(SIZE)
    for slot, read in _READERS:
        p[slot] = read(s)
    p[OFFSET] = s.follower.surface_offset
    p[CONTACT_KIND] = CONTACT_KINDS[s.contact.kind]
    p[ESTAR] = effective_modulus(s)
    p[DAMPING_LAW] = s.contact.law.code
    p[VISCOUS_C] = viscous_c
    p[FRICTION_LAW] = FRICTION_LAWS[s.friction.law]
    p[MOTION_KIND] = MOTION_KINDS[s.motion.kind]
    theta0 = initial_angle if initial_angle is not None else s.motion.initial_angle
    p[THETA0] = 0.0 if theta0 is None else theta0
    p[OMEGA] = s.motion.angular_speed
    p[OMEGA_C] = 2.0 * math.pi * s.motion.frequency * s.motion.direction
    p[START_OMEGA] = 2.0 * math.pi * s.motion.start_speed * s.motion.direction
    p[RAMP_TIME] = s.motion.ramp_time
    if s.profile is not None:
        p[CAM_SHAPE] = PROFILE_TABLE
        p[PROFILE_START] = SIZE
        p[BASE_RADIUS] = s.profile.base_radius
        p = np.concatenate([p, s.profile.table])
    return p
