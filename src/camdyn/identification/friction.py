"""Coefficient of friction from the Fourier amplitudes of pivot forces and acceleration
(thesis 4.6, eqs 4.29-4.40; docs/model.md §6).

The force transducers at the pivot do not measure DC, so the mean pivot reaction
``(Nx_dc, Ny_dc)`` is unknown. The measured ``Nx``, ``Ny`` and ``alpha_ddot`` are fitted
by their cam harmonics over whole revolutions; the follower angle is rebuilt by
integrating ``alpha_ddot`` harmonic by harmonic, around the mean angle that inverse
kinematics gives. The force balance on the follower (the inverse of the pivot reaction,
eqs 4.29-4.30) then gives the normal and friction forces as functions of time that are
linear in the unknown DC reactions. With Coulomb friction and one sliding direction
``s = sgn(vr)``, ``Ff = s mu Fn`` holds at every instant; its DC part (eq 4.38) and its
complex first harmonic (eqs 4.39-4.40) are three real equations in
``(mu, Nx_dc, Ny_dc)``, solved by Levenberg-Marquardt.

``harmonics`` sets how many cam harmonics of each measured signal enter the products
of the force balance: 1 is the thesis's truncation (each signal rebuilt from its DC and
first harmonic); the default keeps 20, which removes the truncation error the thesis
reports (tables 4.5-4.7) because products of signals then keep their cross-harmonic
terms.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np
import xarray as xr
from scipy.optimize import least_squares

from camdyn.analysis.harmonics import (
    estimate_speed,
    fit_harmonics,
    synthesize_harmonics,
)
from camdyn.analysis.kinematics import check_regime, inverse_kinematics
from camdyn.errors import IdentificationError, ParameterError
from camdyn.model import layout as L
from camdyn.model.equilibrium import as_system
from camdyn.model.outputs import contact_forces_from_reaction
from camdyn.params.system import System
from camdyn.records.schema import (
    angular_acceleration,
    check_consistency,
    check_record,
    record_speed,
    require_record,
)

__all__ = ["FrictionEstimate", "estimate_friction"]

#: Fraction of the acceleration's variance the cam harmonics must explain [-].
PERIODIC_FRACTION = 0.9
#: Samples per revolution of the reconstructed signals [-].
GRID = 1024


@dataclass(frozen=True)
class FrictionEstimate:
    """Result of :func:`estimate_friction`.

    Attributes
    ----------
    mu : float
        Coefficient of friction [-].
    Nx_dc, Ny_dc : float
        Mean pivot reactions on the follower [N].
    speed_hz : float
        Cam speed used [Hz]; ``speed_source`` says whether it was given or estimated.
    residual : float
        Norm of the three equations at the solution over ``|Fn_1|`` [-].
    coulomb_misfit : float
        rms of ``Ff - s mu Fn`` over the rebuilt revolution, over the rms of ``Fn`` [-]:
        how well one Coulomb coefficient explains the whole waveform, not just the
        harmonics used.
    revolutions : int
        Whole cam revolutions analysed [-].
    harmonics : int
        Cam harmonics per signal in the force balance [-].
    sliding_sign : int
        ``sgn(vr)`` from inverse kinematics [-].
    amplitudes : dict
        DC and complex first-harmonic amplitudes [N, rad/s^2] as ``[re, im]`` pairs.
    checks : dict
        Each assumption: ``{"passed": bool, "detail": str}``; a check marked
        ``"enforced": False`` is advisory and does not refuse the estimate.
    """

    mu: float
    Nx_dc: float
    Ny_dc: float
    speed_hz: float
    speed_source: str
    residual: float
    coulomb_misfit: float
    revolutions: int
    harmonics: int
    sliding_sign: int
    amplitudes: dict = field(default_factory=dict)
    checks: dict = field(default_factory=dict)

    @property
    def accepted(self) -> bool:
        """True when every check passed."""
        return all(c["passed"] for c in self.checks.values() if c.get("enforced", True))

    def to_dict(self) -> dict:
        """JSON-ready dictionary (units in the keys' documentation above)."""
        out = asdict(self)
        out["accepted"] = self.accepted
        return out


def _project(x: np.ndarray) -> tuple[float, complex]:
    """DC and complex first-harmonic amplitude of one revolution sampled uniformly."""
    phase = np.exp(-2j * np.pi * np.arange(x.size) / x.size)
    return float(np.mean(x)), complex(2.0 * np.mean(x * phase))


def _rebuild(coef: np.ndarray, orders: int, omega: float, grid: int):
    """Signal, its integral and double integral (AC parts) over one revolution from the
    complex harmonics ``coef[1..orders]``."""
    k = np.arange(1, orders + 1)
    phase = np.exp(1j * np.outer(2 * np.pi * np.arange(grid) / grid, k))
    c = coef[1:orders + 1]
    value = np.real(phase @ c)
    first = np.real(phase @ (c / (1j * k * omega)))
    second = np.real(phase @ (-c / (k * omega) ** 2))
    return value, first, second


def _harmonic_check(name: str, x: np.ndarray, coef: np.ndarray, t: np.ndarray, speed: float) -> tuple[bool, str]:
    """Whether the cam harmonics ``coef`` explain enough of the variance of the signal
    ``x`` at times ``t`` [s] (speed [Hz]), and the check's detail."""
    fit = synthesize_harmonics(coef, speed, t)
    var = float(np.var(x))
    explained = 1.0 - float(np.var(x - fit)) / var if var > 0 else 0.0
    ok = explained >= PERIODIC_FRACTION
    return ok, (f"the cam harmonics explain {100 * explained:.2f} % of the variance of {name} "
                f"(needs {100 * PERIODIC_FRACTION:.0f} %: a periodic response without impacts)")


@dataclass(frozen=True)
class _Window:
    """The whole cam revolutions of a record that enter the estimate.

    Attributes
    ----------
    speed : float
        Cam speed [Hz]; ``source`` says whether it was given, read or estimated.
    revolutions : int
        Whole revolutions kept [-].
    fit_order : int
        Cam harmonics fitted to each signal [-].
    keep : ndarray of bool
        The record's samples inside the kept revolutions.
    time : ndarray
        Times of the kept samples [s].
    coefs : dict
        Complex harmonics of ``Nx``, ``Ny`` [N] and ``alpha_ddot`` [rad/s^2].
    """

    speed: float
    source: str
    revolutions: int
    fit_order: int
    keep: np.ndarray
    time: np.ndarray
    coefs: dict


def _record_window(record: xr.Dataset, speed: float | None, harmonics: int) -> _Window:
    """The last whole revolutions of ``record`` and the harmonics of its signals there.

    Parameters
    ----------
    record : xarray.Dataset
        ``Nx``, ``Ny`` [N] and ``alpha_ddot`` [rad/s^2] over ``time`` [s].
    speed : float or None
        Cam speed [Hz]; None reads the record's ``speed_hz`` or estimates it.
    harmonics : int
        Cam harmonics the force balance will use [-].

    Returns
    -------
    _Window

    Raises
    ------
    IdentificationError
        Fewer than three whole revolutions, or a sampling rate that cannot resolve
        ``harmonics`` cam harmonics.
    """
    t = record["time"].values
    fs = 1.0 / (t[1] - t[0])
    if speed is not None:
        source = "given"
    elif "speed_hz" in record.attrs:
        speed, source = float(record.attrs["speed_hz"]), "record metadata"
    else:
        speed, source = estimate_speed(t, record["alpha_ddot"].values), "estimated from alpha_ddot"
    speed = float(speed)
    if not (math.isfinite(speed) and speed > 0):
        raise ParameterError(f"the cam speed must be positive, got {speed!r} Hz")
    duration = t[-1] - t[0] + 1.0 / fs
    revolutions = int(math.floor(duration * speed + 1e-9))
    if revolutions < 3:
        raise IdentificationError(f"the record spans {duration * speed:.2f} cam revolutions at {speed:.4g} Hz; "
                                  "at least 3 whole revolutions are needed")
    fit_order = int(min(max(harmonics, 20), math.floor(0.45 * fs / speed)))
    if fit_order < harmonics:
        raise IdentificationError(f"sampling at {fs:.4g} Hz resolves only {fit_order} cam harmonics; "
                                  f"{harmonics} were asked for")
    keep = t >= t[-1] + 1.0 / fs - revolutions / speed - 0.5 / fs     # last whole revolutions
    tw = t[keep]
    coefs = {n: fit_harmonics(tw, record[n].values[keep], speed, fit_order) for n in ("Nx", "Ny", "alpha_ddot")}
    return _Window(speed, source, revolutions, fit_order, keep, tw, coefs)


def _assumption_checks(system: System, record: xr.Dataset, window: _Window):
    """The checks made before solving: a periodic record, contact kept and one sliding
    direction (both from inverse kinematics).

    Returns
    -------
    checks : dict
        ``{"passed": bool, "detail": str}`` per check.
    kinematics : xarray.Dataset
        Inverse kinematics over one revolution (:func:`inverse_kinematics`).
    sign : int
        Sliding direction ``sgn(vr)`` [-].
    """
    checks = {}
    ok, detail = _harmonic_check("alpha_ddot", record["alpha_ddot"].values[window.keep],
                                 window.coefs["alpha_ddot"], window.time, window.speed)
    checks["periodic"] = {"passed": ok, "detail": detail}
    kinematics = inverse_kinematics(system, speed=window.speed, points=GRID)
    kin = check_regime(system, window.speed, kinematics=kinematics)
    checks["contact_kept_kinematics"] = {
        "passed": kin.contact_kept,
        "detail": (f"inverse kinematics: the required normal force stays above {kin.min_contact_force:.3g} N"
                   if kin.contact_kept else "inverse kinematics: " + kin.reasons()[0])}
    checks["no_sliding_reversal"] = {
        "passed": not kin.sliding_reversal,
        "detail": ("inverse kinematics: vr keeps one sign" if not kin.sliding_reversal else
                   "inverse kinematics: the sliding velocity vr reverses during a revolution")}
    return checks, kinematics, kin.sliding_sign or 1


def _rebuilt_forces(coefs: dict, orders: int, omega: float, alpha_dc: float, p: np.ndarray):
    """Contact forces over one revolution rebuilt from the signals' cam harmonics.

    Parameters
    ----------
    coefs : dict
        Complex harmonics of ``Nx``, ``Ny`` [N] and ``alpha_ddot`` [rad/s^2].
    orders : int
        Harmonics used [-].
    omega : float
        Cam speed [rad/s].
    alpha_dc : float
        Mean follower angle [rad].
    p : ndarray
        Parameter vector (:mod:`camdyn.model.layout`).

    Returns
    -------
    fn0, ff0 : ndarray (GRID,)
        Normal and friction force [N] without the DC pivot reactions.
    sin_alpha, cos_alpha : ndarray (GRID,)
        Sine and cosine of the follower angle [-].
    """
    acc, vel, ang = _rebuild(coefs["alpha_ddot"], orders, omega, GRID)
    nx = _rebuild(coefs["Nx"], orders, omega, GRID)[0]
    ny = _rebuild(coefs["Ny"], orders, omega, GRID)[0]
    alpha = alpha_dc + ang
    fn0, ff0 = contact_forces_from_reaction(alpha, vel, acc, nx, ny, p)
    return fn0, ff0, np.sin(alpha), np.cos(alpha)


class _Balance:
    """DC and first-harmonic force balance, eqs 4.34-4.40, in ``(mu, Nx_dc, Ny_dc)``.

    Built from the rebuilt forces ``fn0``, ``ff0`` [N] (DC reactions left out) and
    ``sin alpha``, ``cos alpha`` [-] over one revolution, and the sliding sign [-].
    """

    def __init__(self, fn0, ff0, sa, ca, sign):
        self.fn0, self.sa, self.ca, self.sign = fn0, sa, ca, sign
        (self.fn0_0, self.fn0_1), (self.ff0_0, self.ff0_1) = _project(fn0), _project(ff0)
        (self.s_0, self.s_1), (self.c_0, self.c_1) = _project(sa), _project(ca)

    def equations(self, x):
        """The three real residuals [N] of eqs 4.38-4.40 at ``x = (mu, Nx_dc, Ny_dc)``."""
        mu, nx_dc, ny_dc = x
        fn_0 = self.fn0_0 + nx_dc * self.s_0 + ny_dc * self.c_0           # eq 4.36
        fn_1 = self.fn0_1 + nx_dc * self.s_1 + ny_dc * self.c_1           # eq 4.37
        ff_0 = self.ff0_0 - nx_dc * self.c_0 + ny_dc * self.s_0           # eq 4.34
        ff_1 = self.ff0_1 - nx_dc * self.c_1 + ny_dc * self.s_1           # eq 4.35
        r1 = ff_1 - self.sign * mu * fn_1                                  # eqs 4.39-4.40
        return np.array([ff_0 - self.sign * mu * fn_0, r1.real, r1.imag])   # eq 4.38

    def matrix(self, mu):
        """The equations as ``M(mu) @ (1, Nx_dc, Ny_dc)`` at the coefficient ``mu`` [-]."""
        sign = self.sign
        r1 = [self.ff0_1 - sign * mu * self.fn0_1, -self.c_1 - sign * mu * self.s_1,
              self.s_1 - sign * mu * self.c_1]
        return np.array([[self.ff0_0 - sign * mu * self.fn0_0, -self.c_0 - sign * mu * self.s_0,
                          self.s_0 - sign * mu * self.c_0],
                         [v.real for v in r1], [v.imag for v in r1]])

    def candidates(self) -> list:
        """Admissible ``(mu [-], Nx_dc [N], Ny_dc [N])``: the real roots of ``det M(mu)``
        with ``mu >= 0`` and a positive mean normal force.

        The equations are bilinear: for a fixed mu they are linear in (Nx_dc, Ny_dc), so
        solutions make det M(mu) = 0, a cubic in mu.
        """
        probes = np.array([0.0, 0.5, 1.0, 1.5])
        cubic = np.polyfit(probes, [np.linalg.det(self.matrix(m)) for m in probes], 3)
        candidates = []
        for root in np.roots(cubic):
            if abs(root.imag) > 1e-9 * max(1.0, abs(root.real)) or root.real < 0:
                continue
            mu0 = float(root.real)
            m = self.matrix(mu0)
            dc = np.linalg.lstsq(m[:, 1:], -m[:, 0], rcond=None)[0]
            fn_dc = self.fn0_0 + dc[0] * self.s_0 + dc[1] * self.c_0
            if fn_dc > 0:
                candidates.append((mu0, float(dc[0]), float(dc[1])))
        return candidates

    def solve(self, candidates: list):
        """Levenberg-Marquardt from the candidate whose rebuilt normal force stays most
        positive (or from ``mu = 0.3`` without one); the SciPy result."""
        def lowest_force(c):
            return float(np.min(self.fn0 + c[1] * self.sa + c[2] * self.ca))
        guess = np.array(max(candidates, key=lowest_force)) if candidates else np.array([0.3, 0.0, 0.0])
        return least_squares(self.equations, guess, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15,
                             max_nfev=2000)

    def amplitudes(self, coefs: dict, nx_dc: float, ny_dc: float) -> dict:
        """Measured first harmonics and the solved DC and first-harmonic forces [N,
        rad/s^2] as ``[re, im]`` pairs."""
        amplitudes = {"alpha_ddot_1": coefs["alpha_ddot"][1], "Nx_1": coefs["Nx"][1], "Ny_1": coefs["Ny"][1],
                      "Fn_dc": self.fn0_0 + nx_dc * self.s_0 + ny_dc * self.c_0,
                      "Fn_1": self.fn0_1 + nx_dc * self.s_1 + ny_dc * self.c_1,
                      "Ff_dc": self.ff0_0 - nx_dc * self.c_0 + ny_dc * self.s_0,
                      "Ff_1": self.ff0_1 - nx_dc * self.c_1 + ny_dc * self.s_1}
        return {k: [float(np.real(v)), float(np.imag(v))] for k, v in amplitudes.items()}


def _waveform_checks(forces, mu: float, nx_dc: float, ny_dc: float, sign: int):
    """How well one Coulomb coefficient explains the whole rebuilt waveform.

    Parameters
    ----------
    forces : tuple of ndarray
        :func:`_rebuilt_forces` with every fitted harmonic.
    mu : float
        Coefficient of friction [-].
    nx_dc, ny_dc : float
        Mean pivot reactions [N].
    sign : int
        Sliding direction [-].

    Returns
    -------
    misfit : float
        rms of ``Ff - s mu Fn`` over the rms of ``Fn`` [-].
    check : dict
        The advisory check that the rebuilt normal force stays positive.
    """
    fn_all, ff_all, sa_all, ca_all = forces
    fn_t = fn_all + nx_dc * sa_all + ny_dc * ca_all
    ff_t = ff_all - nx_dc * ca_all + ny_dc * sa_all
    misfit = float(np.sqrt(np.mean((ff_t - sign * mu * fn_t) ** 2)) / np.sqrt(np.mean(fn_t ** 2)))
    check = {
        "passed": bool(fn_t.min() > 0), "enforced": False,
        "detail": (f"the normal force rebuilt from the record ranges over {fn_t.min():.3g} to {fn_t.max():.3g} N "
                   "(advisory: its mean rests on the estimated DC reactions, which are far less certain "
                   "than mu)")}
    return misfit, check


def _refusal(checks: dict) -> str:
    """The message refusing an estimate: the details of the enforced checks that failed."""
    return "friction estimate refused: " + "; ".join(
        c["detail"] for c in checks.values() if not c["passed"] and c.get("enforced", True))


def estimate_friction(system: System, record: xr.Dataset, speed: float | None = None, harmonics: int = 20,
                      enforce: bool = True) -> FrictionEstimate:
    """Estimate the coefficient of friction from a steady-state record.

    Parameters
    ----------
    system : System
        The rig (geometry, mass, spring; ``cam.runout`` as in the record). Its friction
        settings are not used.
    record : xarray.Dataset
        ``Nx``, ``Ny`` [N] and ``alpha_ddot`` [rad/s^2] (or ``a_t`` [m/s^2]) over
        ``time`` [s] (see :mod:`camdyn.io.measurements`). Their DC parts are ignored.
    speed : float or str, optional
        Cam speed [Hz], or text with a unit as :func:`camdyn.simulate` reads it
        (``"11.55 Hz"``, ``"693 rpm"``); default the record's ``speed_hz`` attribute, else
        estimated from the acceleration's spectrum.
    harmonics : int
        Cam harmonics of each signal kept in the force balance (1: the thesis's method).
    enforce : bool
        Raise :class:`IdentificationError` when a check fails (default); otherwise
        return the estimate with the failed checks marked.

    Raises
    ------
    ParameterError
        ``system`` is not a System (or preset name), ``record`` not a Dataset (a file
        name is refused with the call that reads it), or ``speed`` not a positive speed.
    IdentificationError
        The record loses contact, has a reversing sliding velocity, is not periodic at
        the cam speed, or is shorter than three revolutions.
    """
    system = as_system(system)
    record = require_record(record)
    speed = record_speed(speed)
    if system.motion.kind != "constant":
        raise ParameterError("the friction estimator needs constant cam motion")
    if not (isinstance(harmonics, int) and harmonics >= 1):
        raise ParameterError(f"harmonics must be a positive integer, got {harmonics!r}")
    record = angular_acceleration(record, system.follower.sensor_distance)
    check_record(record, ("Nx", "Ny", "alpha_ddot"))
    check_consistency(record, speed=speed, runout=system.cam.runout, preset=system.name, what="the system and options")
    window = _record_window(record, speed, harmonics)
    checks, kinematics, sign = _assumption_checks(system, record, window)
    if enforce and not all(c["passed"] for c in checks.values()):
        raise IdentificationError(_refusal(checks))

    p = L.pack(system, initial_angle=0.0)
    omega = 2.0 * math.pi * window.speed
    alpha_dc = float(kinematics["alpha"].mean())
    balance = _Balance(*_rebuilt_forces(window.coefs, harmonics, omega, alpha_dc, p), sign)
    # every real root of the cubic det M(mu) is a candidate; the physical one has
    # mu >= 0 and a positive mean normal force; Levenberg-Marquardt polishes it
    candidates = balance.candidates()
    no_root = ("no physical solution (mu >= 0 with a positive mean normal force): the record does not fit "
               "Coulomb friction with one sliding direction")
    if not candidates and enforce:
        raise IdentificationError(no_root)
    sol = balance.solve(candidates)
    mu, nx_dc, ny_dc = (float(v) for v in sol.x)
    fn_1 = balance.fn0_1 + nx_dc * balance.s_1 + ny_dc * balance.c_1
    residual = float(np.linalg.norm(sol.fun) / max(abs(fn_1), 1e-300))

    misfit, checks["contact_kept_record"] = _waveform_checks(
        _rebuilt_forces(window.coefs, window.fit_order, omega, alpha_dc, p), mu, nx_dc, ny_dc, sign)
    checks["solved"] = {"passed": bool(candidates and sol.success and residual < 1e-6 and mu >= 0),
                        "detail": (f"Levenberg-Marquardt: {sol.message} (relative residual {residual:.2g}, "
                                   f"mu {mu:.4g})" if candidates else no_root)}
    est = FrictionEstimate(mu=mu, Nx_dc=nx_dc, Ny_dc=ny_dc, speed_hz=window.speed, speed_source=window.source,
                           residual=residual, coulomb_misfit=misfit, revolutions=window.revolutions,
                           harmonics=harmonics, sliding_sign=int(sign),
                           amplitudes=balance.amplitudes(window.coefs, nx_dc, ny_dc), checks=checks)
    if enforce and not est.accepted:
        raise IdentificationError(_refusal(checks))
    return est
