"""The linearized cam-follower model (thesis 2.8, eqs 2.36-2.38).

The thesis linearizes the equation of motion about the static equilibrium and keeps the
cam runout as a forcing term: ``I_P x'' + C_l x' + K_l x = F_l(t)`` with ``x = alpha -
alpha*``. Its printed coefficients are garbled, so camdyn derives them from the same
moment function the simulator integrates, by a first-order Taylor expansion about the
**concentric cam** (runout ``e = 0``, where the static equilibrium does not depend on
the cam angle):

- ``K_l = -dM/dalpha`` and ``C_l = -dM/dalpha_dot`` at ``(alpha*, 0)``;
- ``F_l(t) = e * dM/de`` at ``(alpha*, 0, Theta(t))``,

with ``M`` the moment about the pivot [N m]; all derivatives are central differences.
For a line contact without friction this gives ``K_l = k chi*^2 + k delta* (PEx sin a* +
PEy cos a*) + ks dx (dx sec^2 a* + wb/2 sec a* tan a*)`` and ``F_l = e k (chi* sin(a* +
Theta) - delta* cos(a* + Theta))`` (tested). Choices, written down:

- the damping laws D and E switch between two coefficients on the sign of the
  penetration rate; the central difference across ``delta_dot = 0`` gives their mean,
  the equivalent linear damper of a bilinear one under harmonic motion (half a cycle
  each);
- Coulomb friction keeps the sign the turning cam gives it (the model is only valid
  while ``vr`` does not reverse); tanh friction is linearized like everything else;
- restitution-parameterised laws use the reference approach velocity, as the static
  equilibrium does;
- only circular cams (an elliptic cam's profile is not a small perturbation).

Under constant cam speed the forcing is a single cam harmonic, so the linear model has
no super-harmonics at all (thesis fig 2.16). The forcing is periodic for either cam
motion (the cam period, or the oscillation period), so :meth:`LinearModel.steady_state`
sums its Fourier series through the receptance, in closed form, and
:meth:`LinearModel.simulate` adds the free response (the two eigen-solutions) that meets
any initial state. Both are exact; a time-stepped solution (e.g. ``scipy.signal.lsim``)
is not good enough here, because far below the contact resonance the acceleration
``(F - C x' - K x)/I`` is the small difference of two large terms (by ``(f_n/f)^2``, a
million at 5 Hz against 5 kHz), and interpolation errors of 1e-7 in ``x`` become 25 %
in ``alpha_ddot``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import xarray as xr

from camdyn.errors import ParameterError
from camdyn.model import layout as L
from camdyn.model.dynamics import evaluate
from camdyn.params.system import System

__all__ = ["LinearModel", "linearize"]


def _moment(p, t, alpha, alpha_dot, slip) -> float:
    mode = np.array([1.0, slip, 0.0, p[L.V_REFERENCE], 0.0])
    return evaluate(t, alpha, alpha_dot, mode, p)[0] * p[L.INERTIA]


@dataclass(frozen=True)
class LinearModel:
    """``I x'' + C x' + K x = F(t)``, ``x = alpha - alpha*`` [rad].

    Attributes
    ----------
    inertia : float
        ``I_P`` [kg m^2].
    stiffness : float
        ``K_l`` [N m/rad].
    damping : float
        ``C_l`` [N m s/rad].
    equilibrium_angle : float
        ``alpha*`` of the concentric cam [rad].
    runout : float
        ``e`` [m], the amplitude the forcing is scaled by.
    speed : float
        Cam speed [Hz] (constant motion; 0 for an oscillating cam).
    period : float
        Period of the forcing [s]: the cam's revolution or oscillation.
    """

    inertia: float
    stiffness: float
    damping: float
    equilibrium_angle: float
    runout: float
    speed: float
    period: float
    _p: np.ndarray
    _slip: float

    @property
    def natural_frequency(self) -> float:
        """Undamped natural frequency ``sqrt(K/I) / 2 pi`` [Hz]."""
        return math.sqrt(self.stiffness / self.inertia) / (2.0 * math.pi)

    @property
    def damping_ratio(self) -> float:
        """``C / (2 sqrt(K I))`` [-]."""
        return self.damping / (2.0 * math.sqrt(self.stiffness * self.inertia))

    def forcing(self, time) -> np.ndarray:
        """``F_l(t) = e dM/de`` [N m] at the sample times [s]."""
        t = np.atleast_1d(np.asarray(time, dtype=float))
        if self.runout == 0.0:
            return np.zeros_like(t)
        eps = 1e-7 * max(self._p[L.SEMI_A], 1e-3)
        plus, minus = self._p.copy(), self._p.copy()
        plus[L.RUNOUT], minus[L.RUNOUT] = eps, -eps
        a = self.equilibrium_angle
        out = np.empty_like(t)
        for i, ti in enumerate(t):
            d = _moment(plus, ti, a, 0.0, self._slip) - _moment(minus, ti, a, 0.0, self._slip)
            out[i] = self.runout * d / (2.0 * eps)
        return out

    def forcing_amplitude(self) -> complex:
        """Complex amplitude ``F^`` [N m] with ``F_l(t) = Re(F^ exp(i Omega t))`` (constant speed)."""
        if self.speed <= 0.0:
            raise ParameterError("the forcing is a single harmonic only under constant cam speed")
        return complex(self.forcing_series(1)[1])

    def receptance(self, frequency) -> np.ndarray:
        """``x^/F^ = 1/(K - I w^2 + i C w)`` [rad/(N m)] at ``frequency`` [Hz]."""
        w = 2.0 * np.pi * np.asarray(frequency, dtype=float)
        return 1.0 / (self.stiffness - self.inertia * w ** 2 + 1j * self.damping * w)

    def forcing_series(self, harmonics: int = 32) -> np.ndarray:
        """Complex Fourier coefficients ``c_k`` [N m], ``k = 0..harmonics``, of the periodic
        forcing: ``F_l(t) = Re(sum_k c_k exp(i k w t))``, ``w = 2 pi / period``."""
        n = 2 * harmonics + 2
        t = np.arange(n) * self.period / n
        c = np.fft.rfft(self.forcing(t)) / n
        c[1:] *= 2.0
        return c[:harmonics + 1]

    def steady_state(self, time, harmonics: int = 32) -> xr.Dataset:
        """The periodic response, in closed form (Fourier series of the forcing through the
        receptance; one term under constant cam speed)."""
        t = np.asarray(time, dtype=float)
        c = self.forcing_series(1 if self.speed > 0 else harmonics)
        w = 2.0 * np.pi / self.period
        k = np.arange(c.size)
        x_hat = c * self.receptance(k / self.period)
        z = np.exp(1j * w * np.outer(t, k))
        x = np.real(z @ x_hat)
        v = np.real(z @ (1j * k * w * x_hat))
        a = np.real(z @ (-(k * w) ** 2 * x_hat))
        return self._dataset(t, x, v, a, "steady state")

    def simulate(self, time, x0: float = 0.0, v0: float = 0.0, harmonics: int = 32) -> xr.Dataset:
        """Response from ``x(0) = x0`` [rad], ``x'(0) = v0`` [rad/s] at ``time`` [s]: the
        steady state plus the free response that meets the initial state (exact)."""
        t = np.asarray(time, dtype=float)
        steady = self.steady_state(np.concatenate([[0.0], t]), harmonics)
        dx = x0 - (float(steady.alpha[0]) - self.equilibrium_angle)
        dv = v0 - float(steady.alpha_dot[0])
        roots = np.roots([self.inertia, self.damping, self.stiffness]).astype(complex)
        if abs(roots[0] - roots[1]) < 1e-9 * abs(roots[0]):
            raise ParameterError("the linear model is critically damped; its free response is not "
                                 "two distinct eigen-solutions")
        a1 = (dv - roots[1] * dx) / (roots[0] - roots[1])
        a2 = dx - a1
        e1, e2 = a1 * np.exp(roots[0] * t), a2 * np.exp(roots[1] * t)
        x = steady.alpha.values[1:] - self.equilibrium_angle + np.real(e1 + e2)
        v = steady.alpha_dot.values[1:] + np.real(roots[0] * e1 + roots[1] * e2)
        a = steady.alpha_ddot.values[1:] + np.real(roots[0] ** 2 * e1 + roots[1] ** 2 * e2)
        return self._dataset(t, x, v, a, "transient and steady state")

    def _dataset(self, t, x, v, a, kind) -> xr.Dataset:
        ds = xr.Dataset(
            {"alpha": ("time", self.equilibrium_angle + x,
                        {"units": "rad", "long_name": "follower angle (linear model)"}),
             "alpha_dot": ("time", v, {"units": "rad/s", "long_name": "follower angular velocity (linear model)"}),
             "alpha_ddot": ("time", a, {"units": "rad/s^2",
                                        "long_name": "follower angular acceleration (linear model)"})},
            coords={"time": ("time", t, {"units": "s", "long_name": "time"})})
        ds.attrs.update(model="linearized (thesis eqs 2.36-2.38)", response=kind, speed_hz=self.speed,
                        natural_frequency_Hz=self.natural_frequency, damping_ratio=self.damping_ratio,
                        stiffness_N_m_per_rad=self.stiffness, damping_N_m_s_per_rad=self.damping)
        return ds


def linearize(system: System, speed=None) -> LinearModel:
    """The linearized model of ``system`` about its concentric-cam equilibrium.

    Parameters
    ----------
    system : System
        A circular cam in permanent contact at rest.
    speed : float or str, optional
        Cam speed [Hz] or a quantity (``"300 rpm"``); default the system's own.

    Raises
    ------
    ParameterError
        For an elliptic cam, or a follower that does not rest on the concentric cam.
    """
    from camdyn.model.equilibrium import as_system
    from camdyn.simulation.runner import prepare, with_speed
    system = with_speed(as_system(system), speed)
    if system.profile is not None:
        raise ParameterError("the linearized model needs the closed-form circular cam, not a cam profile")
    if system.cam.semi_major != system.cam.semi_minor:
        raise ParameterError("the linearized model needs a circular cam (cam.semi_major = cam.semi_minor)")
    concentric = prepare(system.with_values(**{"cam.runout": 0.0}))
    if not concentric.equilibrium.in_contact:
        raise ParameterError("the follower does not rest on the cam, so there is no contact to linearize")
    p = concentric.p.copy()
    own = prepare(system)
    p[L.VISCOUS_C] = own.viscous_c  # the simulated system's own law-A coefficient
    p[L.THETA0] = own.theta0        # and its own cam phase (the 0-state moves with e)
    a = concentric.equilibrium.angle
    from camdyn.model.equilibrium import static_parameters
    slip = 1.0 if static_parameters(system, concentric.theta0)[L.MU] >= 0 else -1.0
    eq = concentric.equilibrium   # a step small against the penetration (Hertz's delta^1.5 curves)
    ha = min(1e-7, 1e-3 * eq.penetration / abs(eq.moment_arm))
    hv = 1e-6
    k = -(_moment(p, 0.0, a + ha, 0.0, slip) - _moment(p, 0.0, a - ha, 0.0, slip)) / (2 * ha)
    c = -(_moment(p, 0.0, a, hv, slip) - _moment(p, 0.0, a, -hv, slip)) / (2 * hv)
    if not k > 0:
        raise ParameterError(f"the linearized stiffness is {k:.3g} N m/rad: the equilibrium is not stable")
    motion = system.motion
    hz = float(motion.speed) if motion.kind == "constant" else 0.0
    cycle = hz if motion.kind == "constant" else float(motion.frequency)   # [Hz]
    if not cycle > 0:
        raise ParameterError("the cam does not move (speed 0): the linearized model needs a forcing period")
    period = 1.0 / cycle
    p[L.RUNOUT] = 0.0
    return LinearModel(inertia=system.follower.inertia, stiffness=k, damping=c, equilibrium_angle=a,
                       runout=system.cam.runout, speed=hz, period=period, _p=p, _slip=slip)
