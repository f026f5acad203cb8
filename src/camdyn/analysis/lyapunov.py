"""The Lyapunov spectrum of a hybrid system from its variational equations with saltation.

The state is integrated with its state-transition matrix (:mod:`camdyn.systems.variational`:
``Phi' = J Phi`` between events, ``Phi+ = S Phi-`` with the saltation matrix ``S`` at every
contact onset, separation, friction reversal and impact reset) over successive intervals
of one forcing period ``T`` [s]. The ``n`` tangent vectors, the columns of ``Q``, start
orthonormal; after each interval ``k`` they are mapped and re-orthonormalised by a QR
factorisation (Shimada and Nagashima 1979, doi:10.1143/PTP.61.1605; Benettin, Galgani,
Giorgilli and Strelcyn 1980, doi:10.1007/BF02128236)::

    D Phi_k D^-1 Q_(k-1) = Q_k R_k,        lambda_i = (1 / (N T)) sum_k ln |R_k[i, i]|      (1)

with ``D = diag(weights)`` the norm in which lengths are measured (the cam-follower's
``(1, 1 / Omega)``: alpha [rad] and alpha_dot / Omega [rad], as
:func:`camdyn.analysis.chaos.lyapunov_exponent` measures its gap). The limits do not
depend on ``D``; finite averages do, by ``ln(cond D) / (N T)`` at most. Across an event
the saltation matrix carries the tangent vectors through the jump, which makes (1) the
spectrum of the hybrid flow (Müller 1995, doi:10.1016/0960-0779(95)00015-3); its
determinant adds ``ln |det S|`` to the volume's growth, so that::

    sum_i lambda_i = (1 / (N T)) (integral of trace J dt + sum over events ln |det S|)   (2)

The exponents are those of the model's dynamic state, its ``controlled_size`` leading
components: a quadrature that feeds back into nothing (the cam-follower's friction work)
only adds an exponent 0. A motion that erases a perturbation in finite time (a rigid
follower captured on its cam) gives ``-inf``.

Each interval restarts the integration from the state, with the hybrid mode found again
from the guards, as :func:`~camdyn.analysis.chaos.lyapunov_exponent` restarts its two
trajectories (exact for every damping law whose force depends on the state only).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from camdyn.errors import ParameterError
from camdyn.integrator import driver
from camdyn.params.system import System
from camdyn.simulation import limits
from camdyn.systems import registry as systems

__all__ = ["LyapunovSpectrum", "model_spectrum", "lyapunov_spectrum", "check_periods", "count", "MAX_PERIODS",
           "standard_error", "BATCHES"]

#: Batches of the per-period growth whose means give an estimate's standard error [-].
BATCHES = 20


def standard_error(logs, period: float) -> float:
    """Standard error [1/s] of the mean of the per-period log growths ``logs`` [-]
    divided by ``period`` [s], by batch means: the ``N`` periods in :data:`BATCHES`
    consecutive batches (fewer for ``N < 2 BATCHES``: two periods a batch), the
    standard deviation of the batch means over the square root of their number. The
    batches, many periods long, carry the correlation between neighbouring periods
    that a per-period standard deviation would miss. It is the statistical spread of
    the finite-time average only; the start's bias (the initial direction's share of
    the slowest-decaying one), of order ``1 / (N T)``, is not in it. NaN for fewer than
    4 periods or a growth of -inf (a direction erased)."""
    logs = np.asarray(logs, dtype=float)
    if logs.size < 4 or not np.all(np.isfinite(logs)):
        return math.nan
    means = [batch.mean() for batch in np.array_split(logs, min(BATCHES, logs.size // 2))]
    return float(np.std(means, ddof=1) / math.sqrt(len(means)) / period)


#: Accepted steps allowed per interval [-], and events logged per interval [-].
MAX_STEPS = 50_000_000
MAX_EVENTS = 100_000


@dataclass(frozen=True)
class LyapunovSpectrum:
    """The Lyapunov exponents of one steady motion.

    Attributes
    ----------
    exponents : ndarray (n,)
        lambda_1 >= ... >= lambda_n [1/s] (the order of the QR columns, which converge
        to it).
    per_period : ndarray (n,)
        ``lambda_i T``, the mean log growth per forcing period [-] (per revolution for
        the cam-follower).
    running : ndarray (N, n)
        The estimates [1/s] after 1, 2, ... N periods (their convergence).
    period : float
        The forcing period T [s], the renormalisation interval.
    periods, transient : int
        Periods averaged, and simulated and dropped first [-].
    events : int
        Events passed while averaging (each applied its saltation matrix) [-].
    weights : ndarray (n,)
        The norm's scale of each state component (``D`` of eq. 1) [1/unit of the
        component].
    speed : float
        Cam speed [Hz] (NaN for a test model).
    errors : ndarray (n,)
        Standard error of each exponent [1/s] (:func:`standard_error`, from the
        per-period ``ln |R_k[i, i]|``): its statistical uncertainty over ``periods``.
    """

    exponents: np.ndarray
    per_period: np.ndarray
    running: np.ndarray
    period: float
    periods: int
    transient: int
    events: int
    weights: np.ndarray
    speed: float = math.nan
    errors: np.ndarray = dataclasses.field(default_factory=lambda: np.full(0, math.nan))

    @property
    def total(self) -> float:
        """``sum_i lambda_i`` [1/s], the mean rate of change of the log of a phase-space
        volume (eq. 2)."""
        return float(np.sum(self.exponents))

    @property
    def largest(self) -> float:
        """lambda_1 [1/s]: positive for chaotic motion."""
        return float(self.exponents[0])

    @property
    def kaplan_yorke_dimension(self) -> float:
        """``j + (lambda_1 + ... + lambda_j) / |lambda_(j+1)|``, ``j`` the largest count
        whose partial sum is not negative (Kaplan and Yorke 1979,
        doi:10.1007/BFb0064319) [-]: 0 for an attracting periodic orbit, between 1 and 2
        for a chaotic attractor of the cam-follower (n = 2)."""
        ordered = np.sort(self.exponents)[::-1]
        partial = np.cumsum(ordered)
        j = int(np.count_nonzero(partial >= 0.0))   # partial sums fall once the exponents turn negative
        if j == 0 or j == ordered.size:
            return float(j)
        return j + float(partial[j - 1]) / abs(float(ordered[j]))


def count(name: str, value, low: int) -> int:
    """``value`` as an int, or a ParameterError unless it is a whole number >= ``low``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
        raise ParameterError(f"{name} must be a whole number >= {low}, got {value!r}")
    return int(value)


#: Most forcing periods (transient and averaged together) a Lyapunov spectrum may run
#: [-]: one compiled call and a QR step each (about a millisecond), so 10^6 take hours;
#: the running exponents settle within thousands.
MAX_PERIODS = 10 ** 6


def check_periods(periods: int, transient: int, exponents: int) -> None:
    """Refuse, before any work, a spectrum of more than :data:`MAX_PERIODS` periods
    (:func:`camdyn.simulation.limits.check_request`; each averaged period keeps its
    ``exponents`` logarithms and running means, 8 B each)."""
    limits.check_request(f"a Lyapunov spectrum of {transient} + {periods} periods", periods + transient,
                         16 * max(int(exponents), 1), limit=MAX_PERIODS, unit="periods")


def _checked(system_id, p, y0, period, weights, rtol, atol):
    """The inputs of :func:`model_spectrum` as arrays, or a ParameterError."""
    if isinstance(system_id, bool) or not isinstance(system_id, (int, np.integer)) or not (
            0 <= system_id < systems.VARIATIONAL):
        raise ParameterError(f"system_id must be a registered model's id, got {system_id!r}")
    size, n = systems.state_size(int(system_id)), systems.controlled_size(int(system_id))
    y0 = np.asarray(y0, dtype=float).reshape(-1)
    if y0.size != size or not np.all(np.isfinite(y0)):
        raise ParameterError(f"the initial state must be {size} finite numbers, got {y0.size}")
    p = np.asarray(p, dtype=float).reshape(-1)
    period = limits.check_number("period", period, "s")
    if not (math.isfinite(period) and period > 0):
        raise ParameterError(f"the forcing period must be positive and finite, got {period!r} s")
    weights = np.ones(n) if weights is None else np.asarray(weights, dtype=float).reshape(-1)
    if weights.size != n or not np.all(np.isfinite(weights)) or not np.all(weights > 0):
        raise ParameterError(f"weights must be {n} positive numbers (one per dynamic state component)")
    limits.check_tolerances(rtol, atol)
    return int(system_id), p, y0, float(period), weights


def model_spectrum(system_id: int, p, y0, period: float, periods: int = 400, transient: int = 0,
                   t_start: float = 0.0, weights=None, rtol: float = 1e-10, atol: float = 1e-12,
                   max_step: float | None = None, progress: Callable[[int, int], None] | None = None
                   ) -> LyapunovSpectrum:
    """The Lyapunov spectrum of registered model ``system_id`` by eq. (1).

    Parameters
    ----------
    system_id : int
        A model of :mod:`camdyn.systems.registry` (``OSCILLATOR``, ``RIGID_IMPACT``,
        ``TRANSLATING_FOLLOWER``, ``CAM_FOLLOWER``, ...).
    p : array_like
        Its parameter vector (units in its module's docstring).
    y0 : array_like (state_size,)
        The state at ``t_start``.
    period : float
        Forcing period T [s]: the transient's unit and the renormalisation interval.
    periods : int
        Periods averaged, N [-].
    transient : int
        Periods simulated (without the matrix) and dropped first [-].
    t_start : float
        Time of ``y0`` [s].
    weights : array_like (n,), optional
        Scale of each dynamic state component in the norm [1/its unit]; default ones.
    rtol, atol : float
        Local error tolerances of the state and the matrix [-], [units of the state].
    max_step : float, optional
        Largest step [s]; default that of :func:`~camdyn.simulation.limits.step_limits`.
    progress : callable, optional
        ``progress(done, total)`` after each period [-].

    Returns
    -------
    LyapunovSpectrum
    """
    system_id, p, y0, period, weights = _checked(system_id, p, y0, period, weights, rtol, atol)
    periods = count("periods", periods, 1)
    transient = count("transient", transient, 0)
    check_periods(periods, transient, np.size(weights))
    t_start = limits.check_number("t_start", t_start, "s")
    h_max, scan = limits.step_limits(period, system_id)
    h_max = h_max if max_step is None else limits.check_number("max_step", max_step, "s")
    if not (math.isfinite(h_max) and h_max > 0):
        raise ParameterError(f"max_step must be a positive number of seconds, got {max_step!r}")
    size, n = y0.size, weights.size
    y, t = y0.copy(), t_start
    for k in range(transient):
        out, _, _, counters = driver.integrate(system_id, p, y, t, t + period, np.array([t + period]), float(rtol),
                                               float(atol), h_max, driver.METHOD_AUTO, MAX_STEPS, MAX_EVENTS, True,
                                               scan)
        limits.check_run(counters, "Lyapunov spectrum's transient")
        y, t = out[0].copy(), t + period   # summed period by period, as lyapunov_exponent does
        if progress:
            progress(k + 1, transient + periods)
    tangent = np.eye(n)
    logs = np.empty((periods, n))
    events = 0
    variational = systems.VARIATIONAL + system_id
    for k in range(periods):
        start = np.eye(size)
        start[:n, :n] = tangent / weights[:, None]   # D^-1 Q
        out, _, _, counters = driver.integrate(variational, p, np.concatenate([y, start.ravel()]), t, t + period,
                                               np.array([t + period]), float(rtol), float(atol), h_max,
                                               driver.METHOD_DOP853, MAX_STEPS, MAX_EVENTS, True, scan)
        limits.check_run(counters, "Lyapunov spectrum's variational run")
        events += int(counters[driver.COUNT_EVENTS])
        end = out[-1]
        y, t = end[:size].copy(), t + period
        mapped = weights[:, None] * end[size:].reshape(size, size)[:n, :n]   # D Phi D^-1 Q
        tangent, r = np.linalg.qr(mapped)
        diagonal = np.diag(r)
        tangent = tangent * np.where(diagonal < 0, -1.0, 1.0)   # R with a positive diagonal
        with np.errstate(divide="ignore"):
            logs[k] = np.log(np.abs(diagonal))   # eq. (1); -inf where a direction was erased
        if progress:
            progress(transient + k + 1, transient + periods)
    running = np.cumsum(logs, axis=0) / (np.arange(1, periods + 1)[:, None] * period)
    errors = np.array([standard_error(logs[:, i], period) for i in range(n)])
    return LyapunovSpectrum(exponents=running[-1].copy(), per_period=running[-1] * period, running=running,
                            period=period, periods=periods, transient=transient, events=events, weights=weights,
                            errors=errors)


def lyapunov_spectrum(system: System, speed: float | None = None, revolutions: int = 400, transient: int = 200,
                      rtol: float = 1e-8, atol: float = 1e-10,
                      progress: Callable[[int, int], None] | None = None) -> LyapunovSpectrum:
    """Both Lyapunov exponents of the rocking cam-follower's steady motion at one cam speed.

    The follower starts at its static equilibrium at t = 0, runs ``transient`` cam
    periods, then ``revolutions`` periods with its state-transition matrix (eq. 1), in
    the norm of ``(alpha [rad], alpha_dot / Omega [rad])``, Omega the cam's angular speed
    [rad/s].

    Parameters
    ----------
    system : System
        Constant cam motion.
    speed : float, optional
        Cam speed [Hz]; default ``system.motion.speed``.
    revolutions : int
        Cam periods averaged [-].
    transient : int
        Cam periods simulated and dropped first [-].
    rtol, atol : float
        Local error tolerances [-], [rad, rad/s]. The default is the looser pair of the
        shooting's variational runs (:func:`camdyn.continuation.problem.system_problem`):
        the matrix follows the contact resonance, whose error control then costs 25 to
        40 times less time than at 1e-10 (measured at 12 and 18 Hz); on the chapter 3 rig's period-1 orbit
        (12 Hz) the exponents moved by 5e-6 1/s of 11.7 and 28.8 1/s (measured).
    progress : callable, optional
        ``progress(done, total)`` after each cam period [-].

    Returns
    -------
    LyapunovSpectrum
        ``exponents`` [1/s]; ``per_period`` per revolution.
    """
    from camdyn.simulation.runner import prepare, with_speed

    limits.check_system(system)
    if system.motion.kind != "constant":
        raise ParameterError("the Lyapunov spectrum here needs constant cam motion (motion.kind = 'constant')")
    system = with_speed(system, speed)
    revolutions = count("revolutions", revolutions, 1)
    transient = count("transient", transient, 0)
    check_periods(revolutions, transient, 2)
    limits.check_tolerances(rtol, atol)
    period = system.motion.period
    if not (math.isfinite(period) and period > 0):
        raise ParameterError("the cam does not move (speed 0)")
    prep = prepare(system)
    result = model_spectrum(systems.CAM_FOLLOWER, prep.p, prep.y0, period, periods=revolutions, transient=transient,
                            weights=[1.0, period / (2.0 * math.pi)], rtol=rtol, atol=atol, progress=progress)
    return dataclasses.replace(result, speed=system.motion.speed)
