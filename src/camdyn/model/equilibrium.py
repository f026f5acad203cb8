"""Static equilibrium, linearized natural frequency and the viscous damping constant
(docs/model.md §3; thesis eqs 2.16-2.24, 4.20).

The static equilibrium ``alpha*`` has ``alpha_dot = 0`` at the initial cam angle
``Theta0`` with the cam frozen, except that friction acts in the direction of the
sliding velocity the turning cam would produce (thesis 2.16-2.18). The natural
frequency comes from the eigenvalues of the Jacobian of the 2-state system at
``alpha*`` without damping (eqs 2.19-2.23).
"""

from __future__ import annotations

import math
import numbers
import os
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from camdyn.errors import GeometryError, ParameterError
from camdyn.model import layout as L
from camdyn.model.contact import contact_force
from camdyn.model.dynamics import evaluate
from camdyn.model.geometry import (
    cam_angle,
    contact_kinematics,
    contact_point,
    penetrations,
    zero_state,
)
from camdyn.params.system import System

__all__ = ["Equilibrium", "static_equilibrium", "natural_frequency", "viscous_coefficient"]


@dataclass(frozen=True)
class Equilibrium:
    """Static equilibrium of the follower.

    Attributes
    ----------
    angle : float
        Follower angle ``alpha*`` [rad].
    cam_angle : float
        Cam angle ``Theta0`` at which it was found [rad].
    in_contact : bool
        Whether the follower rests on the cam.
    contact_force : float
        Normal force ``Fn*`` [N].
    penetration : float
        ``delta*`` [m] (negative: gap).
    moment_arm : float
        ``chi*`` [m].
    natural_frequency : float
        Linearized undamped natural frequency [Hz].
    stiffness : float
        Linearized rotational stiffness ``-dM/dalpha`` [N m/rad].
    """

    angle: float
    cam_angle: float
    in_contact: bool
    contact_force: float
    penetration: float
    moment_arm: float
    natural_frequency: float
    stiffness: float


def static_parameters(system: System, theta0: float) -> np.ndarray:
    """Parameter vector with the cam frozen at ``theta0`` and no damping; friction keeps
    the direction (and, for tanh friction, the magnitude) the turning cam gives it."""
    p = L.pack(system, initial_angle=theta0)
    ps = p.copy()
    ps[L.DAMPING_LAW] = 0.0
    ps[L.MOTION_KIND] = 0.0
    ps[L.OMEGA] = 0.0
    if p[L.FRICTION_LAW] != 0.0:
        theta, theta_dot = cam_angle(0.0, p)
        a0 = touch_angle(ps, theta)
        vr = contact_kinematics(a0, 0.0, theta, theta_dot, p)[4]
        mu = p[L.MU] if p[L.FRICTION_LAW] == 1.0 else p[L.MU] * abs(math.tanh(p[L.SMOOTHING] * vr))
        ps[L.FRICTION_LAW] = 1.0
        ps[L.MU] = mu * (1.0 if vr >= 0 else -1.0)
    return ps


def touch_angle(p: np.ndarray, theta: float) -> float:
    """Follower angle [rad] at which the follower just touches the cam at ``theta``."""
    f = lambda a: contact_point(a, theta, p)[0]
    lo, hi = -0.6, 0.6
    grid = np.linspace(lo, hi, 121)
    vals = penetrations(grid, theta, p)
    idx = np.nonzero(np.diff(np.sign(vals)) < 0)[0]
    if idx.size == 0:
        raise GeometryError("the cam cannot reach the follower within ±34 degrees of horizontal; "
                            "check cam.pivot_x, cam.pivot_y, cam.radius and follower.width")
    i = idx[np.argmin(np.abs(grid[idx]))]
    return brentq(f, grid[i], grid[i + 1], xtol=1e-15, rtol=1e-15)


def _moment(alpha: float, p: np.ndarray, contact: bool) -> float:
    mode = np.array([1.0 if contact else 0.0, 1.0, 0.0, p[L.V_REFERENCE], 0.0])
    if contact and p[L.MU] < 0:
        q = p.copy()
        q[L.MU] = -p[L.MU]
        mode[L.MODE_SLIP] = -1.0
        return evaluate(0.0, alpha, 0.0, mode, q)[0] * p[L.INERTIA]
    return evaluate(0.0, alpha, 0.0, mode, p)[0] * p[L.INERTIA]


def as_system(system) -> System:
    """``system`` itself, or the system a preset name or TOML file (text or path) names
    (:func:`camdyn.params.config.load_system`: a file with a ``[profile]`` table needs
    :func:`camdyn.load_system`); anything else is refused with a :class:`ParameterError`."""
    if isinstance(system, System):
        return system
    if isinstance(system, (str, os.PathLike)):
        from camdyn.params.config import load_system
        return load_system(system)
    raise ParameterError(f"expected a System (from camdyn.load_system) or a preset name, got "
                         f"{type(system).__name__} {system!r:.60}")


def static_equilibrium(system: System | str, theta0: float | None = None) -> Equilibrium:
    """Static equilibrium ``alpha*`` and the linearized natural frequency.

    Parameters
    ----------
    system : System
    theta0 : float, optional
        Cam angle [rad]; default the system's initial angle or the 0-state.

    Raises
    ------
    ParameterError
        If ``system`` is neither a System nor the name of a preset or TOML file.
    GeometryError
        If the follower cannot touch the cam, or the cam cannot reach it.
    """
    system = as_system(system)
    if theta0 is not None and (isinstance(theta0, bool) or not isinstance(theta0, numbers.Real)
                               or not math.isfinite(theta0)):
        raise ParameterError(f"theta0 must be a finite cam angle in rad, got {theta0!r}")
    if theta0 is not None:
        theta0 = float(theta0)   # a float, as the compiled geometry takes it (an int would compile anew)
    if theta0 is None:
        theta0 = system.motion.initial_angle
    if theta0 is None:
        theta0 = zero_state(system)[1]
    ps = static_parameters(system, theta0)
    a_touch = touch_angle(ps, theta0)
    m_touch = _moment(a_touch, ps, contact=False)
    if m_touch < 0.0:  # spring pushes the follower into the cam: contact equilibrium
        chi = contact_point(a_touch, theta0, ps)[1]
        lo = a_touch - 2e-3 / abs(chi)
        while _moment(lo, ps, contact=True) < 0.0:
            lo = a_touch - 2.0 * (a_touch - lo)
            if a_touch - lo > 0.5:
                raise GeometryError("no contact equilibrium found: the spring preload is too large")
        alpha = brentq(lambda a: _moment(a, ps, True), lo, a_touch, xtol=1e-16, rtol=1e-15)
        contact = True
    else:
        hi = a_touch + 0.05
        while _moment(hi, ps, contact=False) > 0.0:
            hi += 0.05
            if hi - a_touch > 1.5:
                raise GeometryError("the follower has no equilibrium: gravity overcomes the spring "
                                    "at every angle")
        alpha = brentq(lambda a: _moment(a, ps, False), a_touch, hi, xtol=1e-16, rtol=1e-15)
        contact = False
        thetas = np.linspace(0, 2 * math.pi, 721)
        reach = max(contact_point(alpha, th, ps)[0] for th in thetas)
        size = system.cam.semi_major if system.profile is None else system.profile.base_radius
        if reach < -1e-6 * size and system.motion.kind == "constant":
            raise GeometryError(
                f"the cam cannot reach the follower: at its rest angle {math.degrees(alpha):.3g} deg the "
                f"closest approach over a revolution leaves a gap of {-reach*1e6:.3g} um")
    delta, chi, rho_c, _, _ = contact_point(alpha, theta0, ps)
    fn = contact_force(delta, 0.0, rho_c, ps[L.V_REFERENCE], ps)[1] if contact else 0.0
    eps = 1e-8 * max(abs(alpha), 1e-3)
    k = -(_moment(alpha + eps, ps, contact) - _moment(alpha - eps, ps, contact)) / (2 * eps)
    omega = math.sqrt(k / system.follower.inertia) if k > 0 else float("nan")
    return Equilibrium(angle=alpha, cam_angle=theta0, in_contact=contact, contact_force=fn,
                       penetration=delta, moment_arm=chi, natural_frequency=omega / (2 * math.pi),
                       stiffness=k)


def natural_frequency(system: System | str) -> float:
    """Linearized undamped natural frequency [Hz] about the static equilibrium (of a
    System, or of the preset or TOML file named, as :func:`static_equilibrium`)."""
    return static_equilibrium(system).natural_frequency


def viscous_coefficient(system: System, equilibrium: Equilibrium | None = None) -> float:
    """Viscous contact damping ``c = 2 zeta omega_n I_P / chi*^2`` [N s/m] (eq 2.24, 4.20)."""
    if not system.contact.law.needs_damping_ratio:  # laws A, D and E (camdyn.params.laws)
        return 0.0
    eq = equilibrium or static_equilibrium(system)
    if not eq.in_contact:
        raise GeometryError("viscous contact damping (law A) is defined at a static contact equilibrium, "
                            "but the follower rests off the cam")
    omega = 2 * math.pi * eq.natural_frequency
    return 2.0 * system.contact.damping_ratio * omega * system.follower.inertia / eq.moment_arm ** 2
