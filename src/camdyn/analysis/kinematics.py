"""Inverse kinematics: the follower's motion under permanent rigid contact, the contact
force that motion needs, the loss-of-contact speed and sliding-velocity reversal
(thesis 2.4 and 4.5.1, eqs 4.23-4.25).

With the cam turning at a constant speed ``Omega``, permanent contact makes the follower
angle a function of the cam angle alone, ``alpha_k(Theta)``, found from ``delta = 0``
(rigid contact; the Hertz penetration, about 1 um, shifts ``alpha`` by about 1e-5 rad and
is left out). Then ``alpha_dot = Omega alpha_k'`` and ``alpha_ddot = Omega^2 alpha_k''``
(spectral derivatives over one revolution), and the moment balance about the pivot,
``I_P alpha_ddot = M_gravity + M_spring + Fn chi + Ff h`` with ``Ff = mu(vr) Fn``, gives
the normal force the motion requires (eq 4.25). Contact is lost where it would have to
pull (``Fn < 0``); Coulomb friction's assumption of one sliding direction fails where
``vr`` changes sign.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numba
import numpy as np
import xarray as xr
from scipy.optimize import brentq

from camdyn.errors import GeometryError, ParameterError
from camdyn.model import layout as L
from camdyn.model.dynamics import evaluate
from camdyn.model.equilibrium import as_system, static_equilibrium, touch_angle
from camdyn.model.friction import friction_coefficient
from camdyn.model.geometry import (
    cam_angle,
    contact_kinematics,
    contact_point,
    contact_point_rate,
    rigid_angles,
)
from camdyn.model.outputs import pivot_reaction
from camdyn.params.system import System
from camdyn.params.units import parse_speed

#: Highest cam speed inverse kinematics takes [Hz] (6 million rpm; far beyond any cam,
#: and the accelerations squared stay finite).
HIGHEST_SPEED = 1e5
#: Most samples per revolution [-] (the derivatives are spectral: 1024 is ample).
MOST_POINTS = 2 ** 20

__all__ = ["inverse_kinematics", "loss_of_contact_speed", "KinematicCheck", "check_regime", "contact_start"]


@numba.njit(cache=True)
def _required_forces(thetas, alpha, alpha_dot, alpha_ddot, theta_dot, p):
    """Columns: Fn, Ff, chi, vr, ve, rho_c, Fs, Nx, Ny of the rigid-contact motion."""
    n = thetas.size
    out = np.empty((n, 9))
    free = np.zeros(L.MODE_SIZE)
    for i in range(n):
        a = alpha[i]
        ad = alpha_dot[i]
        delta, delta_dot, chi, rho_c, vr, n_v, u_v = contact_kinematics(a, ad, thetas[i], theta_dot, p)
        res = evaluate(0.0, a, ad, free, p)          # gravity + spring only
        m_free = res[0] * p[L.INERTIA]
        fs = res[3]
        slip = 1.0 if vr >= 0.0 else -1.0
        mu = friction_coefficient(vr, slip, p)
        fn = (p[L.INERTIA] * alpha_ddot[i] - m_free) / (chi + mu * p[L.OFFSET])
        ff = mu * fn
        ub = -contact_point_rate(a, ad, thetas[i], theta_dot, p)
        nx, ny = pivot_reaction(a, ad, alpha_ddot[i], fn, ff, fs, p)
        out[i, 0] = fn
        out[i, 1] = ff
        out[i, 2] = chi
        out[i, 3] = vr
        out[i, 4] = vr + 2.0 * ub
        out[i, 5] = rho_c
        out[i, 6] = fs
        out[i, 7] = nx
        out[i, 8] = ny
    return out


def _spectral_derivatives(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """First and second derivatives with respect to the cam angle of a function sampled
    at ``n`` uniform points over one revolution [per rad, per rad^2]."""
    n = values.size
    k = np.fft.rfftfreq(n, 1.0 / n)             # wavenumbers 0..n/2 [1/rad]
    spec = np.fft.rfft(values)
    if n % 2 == 0:
        spec_odd = spec.copy()
        spec_odd[-1] = 0.0                      # the Nyquist term has no odd derivative
    else:
        spec_odd = spec
    first = np.fft.irfft(1j * k * spec_odd, n)
    second = np.fft.irfft(-(k ** 2) * spec, n)
    return first, second


def _angles(system: System, points: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if system.motion.kind != "constant":
        raise ParameterError("inverse kinematics needs constant cam motion (motion.kind = 'constant')")
    if not (isinstance(points, int) and 32 <= points <= MOST_POINTS):
        raise ParameterError(f"points must be an integer from 32 to {MOST_POINTS}, got {points!r}")
    p = L.pack(system, initial_angle=0.0)
    thetas = 2.0 * np.pi * np.arange(points) / points
    start = touch_angle(p, 0.0)
    alpha = rigid_angles(thetas, p, start)
    delta = np.array([contact_point(a, th, p)[0] for a, th in zip(alpha[::max(1, points // 64)],
                                                                   thetas[::max(1, points // 64)])])
    if not np.all(np.abs(delta) < 1e-12):
        raise GeometryError("the follower cannot follow the cam surface over a whole revolution "
                            "(no rigid-contact angle found at some cam angles)")
    return p, thetas, alpha


def inverse_kinematics(system: System, speed: float | None = None, points: int = 1024) -> xr.Dataset:
    """Follower motion and required forces under permanent rigid contact, over one revolution.

    Parameters
    ----------
    system : System
        Constant cam motion; ``system.motion.speed`` is used unless ``speed`` is given.
    speed : float, optional
        Cam speed [Hz].
    points : int
        Samples per revolution [-] (the derivatives are spectral, so 1024 is ample).

    Returns
    -------
    xarray.Dataset
        Over ``cam_angle`` [rad] (from 0, the direction of ``e`` along the x axis):
        ``time`` [s], ``alpha``, ``alpha_dot``, ``alpha_ddot``, the required ``Fn`` and
        ``Ff`` [N], ``moment_arm`` [m], ``sliding_velocity`` and ``sum_velocity`` [m/s],
        ``slide_to_roll`` [-], ``cam_curvature_radius`` [m], ``Fs``, ``Nx``, ``Ny`` [N].
        Attributes: ``speed_hz``, ``contact_kept`` (min Fn > 0), ``sliding_reversal``
        (vr changes sign), ``min_contact_force`` [N].
    """
    system = as_system(system)
    if speed is not None and (isinstance(speed, bool) or not isinstance(speed, (numbers.Real, str))):
        raise ParameterError(f"speed must be a number of Hz or text such as '960 rpm', got {speed!r:.60}")
    hz = system.motion.speed if speed is None else parse_speed(speed)
    if not (math.isfinite(hz) and 0 <= hz <= HIGHEST_SPEED):
        raise ParameterError(f"speed must be a number of Hz from 0 to {HIGHEST_SPEED:g}, got {speed!r}")
    p, thetas, alpha = _angles(system, points)
    omega = system.motion.direction * 2.0 * math.pi * hz
    d1, d2 = _spectral_derivatives(alpha)
    alpha_dot = omega * d1
    alpha_ddot = omega ** 2 * d2
    cols = _required_forces(thetas, alpha, alpha_dot, alpha_ddot, omega, p)
    vr = cols[:, 3]
    ve = cols[:, 4]
    with np.errstate(divide="ignore", invalid="ignore"):
        srr = np.where(ve != 0, vr / ve, np.nan)
    time = thetas / omega if omega != 0 else np.full_like(thetas, np.nan)
    if omega < 0:
        time = time + 1.0 / hz
    spec = {
        "time": (time, "s", "time since the cam passed Theta = 0"),
        "alpha": (alpha, "rad", "follower angle alpha_k under rigid contact"),
        "alpha_dot": (alpha_dot, "rad/s", "follower angular velocity"),
        "alpha_ddot": (alpha_ddot, "rad/s^2", "follower angular acceleration"),
        "Fn": (cols[:, 0], "N", "normal contact force the motion requires (eq 4.25)"),
        "Ff": (cols[:, 1], "N", "friction force on the follower along the bar"),
        "moment_arm": (cols[:, 2], "m", "moment arm chi of the normal force"),
        "sliding_velocity": (vr, "m/s", "sliding velocity vr"),
        "sum_velocity": (ve, "m/s", "sum (entraining) velocity ve"),
        "slide_to_roll": (srr, "1", "slide-to-roll ratio vr/ve"),
        "cam_curvature_radius": (cols[:, 5], "m", "cam radius of curvature at the contact"),
        "Fs": (cols[:, 6], "N", "spring force"),
        "Nx": (cols[:, 7], "N", "pivot reaction, horizontal"),
        "Ny": (cols[:, 8], "N", "pivot reaction, vertical"),
    }
    ds = xr.Dataset({k: ("cam_angle", v, {"units": u, "long_name": n}) for k, (v, u, n) in spec.items()},
                    coords={"cam_angle": ("cam_angle", thetas, {"units": "rad", "long_name": "cam angle Theta"})})
    fn_min = float(cols[:, 0].min())
    ds.attrs.update(speed_hz=hz, contact_kept=int(fn_min > 0), min_contact_force=fn_min,
                    sliding_reversal=int(bool(np.any(vr > 0)) and bool(np.any(vr < 0))))
    return ds


def loss_of_contact_speed(system: System, points: int = 1024, highest: float = 500.0) -> float:
    """Lowest cam speed [Hz] at which permanent contact needs a pulling force (``min Fn = 0``).

    Returns ``inf`` if contact holds up to ``highest`` [Hz], and 0 if it is lost at rest.
    """
    def margin(hz):
        return float(inverse_kinematics(system, speed=hz, points=points)["Fn"].min())

    lo = 1e-6
    if margin(lo) <= 0:
        return 0.0
    hi = 1.0
    while margin(hi) > 0:
        lo = hi
        hi *= 2.0
        if hi > highest:
            return math.inf
    return brentq(margin, lo, hi, xtol=1e-6, rtol=1e-10)


def contact_start(system: System, speed: float | None = None) -> tuple[float, float] | None:
    """A start on the permanent-contact motion at the cam's initial angle ``Theta0``.

    :func:`camdyn.simulate` starts by default from rest at the static equilibrium at
    ``Theta0`` (the thesis's initial condition, end of section 4.3). Where the rigid-contact
    motion is fast at ``Theta0`` (the chapter 4 0-state, runout parallel to the follower, is
    mid-lift, where ``alpha_dot`` is largest) the turning cam strikes the resting follower,
    and near the loss-of-contact speed the follower can settle on an impacting motion
    that coexists with the contact motion. This start avoids that: the rigid-contact
    angle and rate at ``Theta0``, the angle lowered by the static compression
    ``delta*/chi*`` so that the contact starts loaded.

    Parameters
    ----------
    system : System
        Constant cam motion.
    speed : float, optional
        Cam speed [Hz]; default ``system.motion.speed``.

    Returns
    -------
    (float, float) or None
        ``(alpha [rad], alpha_dot [rad/s])`` for ``simulate(..., initial_state=...)``, or
        None when there is no permanent-contact motion to start on (oscillating cam motion,
        a follower resting off the cam, or contact lost at this speed by inverse kinematics).
    """
    if system.motion.kind != "constant":
        return None
    if speed is not None:
        system = system.with_values(**{"motion.speed": float(speed)})
    eq = static_equilibrium(system)
    try:
        kept = eq.in_contact and bool(inverse_kinematics(system).attrs["contact_kept"])
    except GeometryError:      # no rigid-contact angle at some cam angles
        kept = False
    if not kept:
        return None
    p = L.pack(system, initial_angle=eq.cam_angle)
    theta, theta_dot = cam_angle(0.0, p)
    a_k = touch_angle(p, theta)
    # rigid contact keeps delta = 0: 0 = d delta/dt = -alpha_dot chi - n.v_cam, i.e. the
    # delta_dot at alpha_dot = 0 divided by chi
    _, delta_dot, chi = contact_kinematics(a_k, 0.0, theta, theta_dot, p)[:3]
    return a_k - eq.penetration / chi, delta_dot / chi


@dataclass(frozen=True)
class KinematicCheck:
    """Whether an operating point satisfies the friction estimator's assumptions.

    Attributes
    ----------
    contact_kept : bool
        The follower stays on the cam (required ``Fn`` positive throughout).
    sliding_reversal : bool
        The sliding velocity changes sign during a revolution.
    min_contact_force : float
        Smallest required normal force over a revolution [N].
    loss_of_contact_speed : float
        Speed at which contact would be lost [Hz].
    sliding_sign : int
        Sign of ``vr`` when it does not reverse (0 otherwise).
    """

    contact_kept: bool
    sliding_reversal: bool
    min_contact_force: float
    loss_of_contact_speed: float
    sliding_sign: int

    @property
    def ok(self) -> bool:
        return self.contact_kept and not self.sliding_reversal

    def reasons(self) -> list[str]:
        out = []
        if not self.contact_kept:
            out.append(f"the follower loses contact with the cam (the required normal force falls to "
                       f"{self.min_contact_force:.3g} N; contact is lost above "
                       f"{self.loss_of_contact_speed:.4g} Hz)")
        if self.sliding_reversal:
            out.append("the sliding velocity vr reverses during a revolution, so friction changes "
                       "direction and Ff = mu sgn(vr) Fn has no single sign")
        return out


def check_regime(system: System, speed: float, points: int = 1024,
                 kinematics: xr.Dataset | None = None) -> KinematicCheck:
    """Inverse-kinematics check of contact and sliding direction at ``speed`` [Hz].

    ``kinematics`` reuses a result of :func:`inverse_kinematics` at that speed.
    """
    ds = kinematics if kinematics is not None else inverse_kinematics(system, speed=speed, points=points)
    vr = ds["sliding_velocity"].values
    reversal = bool(ds.attrs["sliding_reversal"])
    sign = 0 if reversal else int(np.sign(np.median(vr)))
    kept = bool(ds.attrs["contact_kept"])
    loss = loss_of_contact_speed(system, points=points) if not kept else math.nan
    return KinematicCheck(contact_kept=kept, sliding_reversal=reversal,
                          min_contact_force=float(ds.attrs["min_contact_force"]),
                          loss_of_contact_speed=loss, sliding_sign=sign)
