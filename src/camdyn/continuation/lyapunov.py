"""Lyapunov exponents of any periodically forced model with a periodic problem
(:class:`~camdyn.continuation.problem.Problem`: a mechanism at a prescribed cam speed,
the translating follower, a model of your own, the test models), on the stroboscopic map
of one forcing period.

- The largest, from two nearby trajectories (Benettin et al., Meccanica 15, 9-20, 1980):
  both are carried over ``1 / m`` of a forcing period by the plain model (each through
  its own events), their gap measured and restored to ``d0`` along its own direction,
  ``lambda = (1 / (N T)) sum_k ln(d_k / d0)`` [1/s] over the ``N m`` intervals. ``m`` is
  1 unless the gap shrinks more than :data:`MOST_SHRINK` times in an interval: a motion
  that attracts strongly would otherwise shrink it into the integration error within
  one period (the valve train at 10 Hz contracts by e^-20 per period, and its estimate
  with ``m = 1`` was -58 1/s against the Floquet exponent's -199 1/s).
- All of them, from the state-transition matrix with saltation over each period
  (:func:`flow`), re-orthonormalised by a QR factorisation once per period,
  ``lambda_i = (1 / (N T)) sum_k ln |R_k[i, i]|`` [1/s] (eq. 1 of
  :mod:`camdyn.analysis.lyapunov`).

The gap is measured in the scaled norm ``|D dx|``, ``D`` one over each state
component's largest magnitude over the transient's last periods, sampled within them
(by no less than a tenth of the largest's; a follower that rests on its cam's base
circle at the section has no motion there to scale by); each period starts at the problem's phase from the state the
period before ended in, its hybrid mode found again from the geometry. The rocking
cam-follower of the thesis has its own compiled two-trajectory estimate
(:func:`camdyn.analysis.chaos.lyapunov_exponent`).
"""

from __future__ import annotations

import math

import numpy as np

from camdyn.analysis.chaos import LyapunovResult
from camdyn.analysis.lyapunov import LyapunovSpectrum, check_periods, count, standard_error
from camdyn.continuation.orbits import driver_settings, flow, transient_state
from camdyn.continuation.problem import Problem
from camdyn.errors import ParameterError
from camdyn.simulation import limits

__all__ = ["orbit_lyapunov", "orbit_spectrum", "MOST_SHRINK", "SCALE_SAMPLES"]

#: Forcing periods at the end of the transient over which each state component's scale
#: (its largest magnitude, sampled 64 times a period) is taken [-].
SCALE_SAMPLES = 16
#: Most the two trajectories' gap may shrink over one renormalisation interval [-].
MOST_SHRINK = 100.0
#: Most renormalisation intervals per forcing period [-].
MOST_INTERVALS = 256


def _advance(problem: Problem, p, period: float, y: np.ndarray, t0: float, t1: float) -> np.ndarray:
    """The full state ``y`` carried from ``t0`` to ``t1`` [s] by the plain model."""
    out, _, _, counters = problem.run(problem.system_id, p, y, t0, t1, np.array([t1]), problem.rtol, problem.atol,
                                      *driver_settings(problem, period))
    limits.check_run(counters, f"Lyapunov run at {problem.name} = {problem.value:g}")
    return out[-1].copy()


def _gap_logs(problem: Problem, p, period: float, y: np.ndarray, weights: np.ndarray, d0: float, t: float,
              periods: int, intervals: int) -> tuple[np.ndarray, np.ndarray, float]:
    """``ln(d_k / d0)`` over ``periods`` periods of ``intervals`` intervals each, the state
    and the time [s] at the end."""
    u = problem.unknowns
    direction = np.ones(u) / math.sqrt(u)
    z = y.copy()
    z[:u] += d0 * direction / weights
    logs = np.empty(periods * intervals)
    for k in range(periods * intervals):
        t1 = t + period / intervals
        y, z = _advance(problem, p, period, y, t, t1), _advance(problem, p, period, z, t, t1)
        gap = (z[:u] - y[:u]) * weights
        d = max(float(np.linalg.norm(gap)), 1e-300)
        logs[k] = math.log(d / d0)
        z = y.copy()
        z[:u] += gap * (d0 / d) / weights
        t = t1
    return logs, y, t


def _intervals(problem: Problem, p, period: float, y: np.ndarray, weights: np.ndarray, d0: float,
               t: float) -> tuple[int, np.ndarray, float]:
    """Renormalisation intervals per period that keep the gap's shrinking within
    :data:`MOST_SHRINK` per interval, from probe periods (which also advance the state)."""
    intervals = 1
    for _ in range(4):
        logs, y, t = _gap_logs(problem, p, period, y, weights, d0, t, 1, intervals)
        worst = float(np.min(logs))
        if worst >= -math.log(MOST_SHRINK) or intervals >= MOST_INTERVALS:
            break
        intervals = min(MOST_INTERVALS, intervals * max(2, math.ceil(-worst / math.log(10.0))))
    return intervals, y, t


def _start(problem: Problem, value: float | None, revolutions, transient) -> tuple[float, float, np.ndarray,
                                                                                  np.ndarray, int, int]:
    """``(value, period [s], state after the transient, weights, revolutions, transient)``."""
    if problem.clock is not None:
        raise ParameterError("a cam under its drive sets its own speed: its turns have no fixed period over "
                             "which to renormalise; hold the cam at a prescribed speed (drive.kind = "
                             "'prescribed')")
    value = problem.value if value is None else float(value)
    revolutions = count("revolutions", revolutions, 1)
    transient = count("transient", transient, 0)
    check_periods(revolutions, transient, problem.unknowns)
    _, period = problem.build(value)
    x = transient_state(problem, transient, value) if transient else np.asarray(
        problem.template[:problem.unknowns], dtype=float).copy()
    p, _ = problem.build(value)
    t0 = problem.t_start
    times = t0 + period * np.arange(SCALE_SAMPLES * 64 + 1) / 64
    states, _, _, counters = problem.run(problem.system_id, p, problem.full_state(x, value), t0, times[-1], times,
                                         problem.rtol, problem.atol, *driver_settings(problem, period))
    limits.check_run(counters, f"Lyapunov run at {problem.name} = {value:g}")
    scale = np.max(np.abs(states[:, :problem.unknowns]), axis=0)     # over the motion, not only the section
    scale = np.maximum(scale, max(0.1 * scale.max(), 1e-300))
    return value, period, states[-1, :problem.unknowns].copy(), 1.0 / scale, revolutions, transient


def orbit_lyapunov(problem: Problem, value: float | None = None, revolutions: int = 400, transient: int = 200,
                   separation: float = 1e-7) -> LyapunovResult:
    """The largest Lyapunov exponent of the problem's steady motion at ``value``, from two
    nearby trajectories.

    Parameters
    ----------
    problem : Problem
        A periodically forced model (not a cam under its drive).
    value : float, optional
        The problem's scalar parameter [its unit]; default the problem's.
    revolutions : int
        Forcing periods averaged [-].
    transient : int
        Forcing periods simulated and dropped first [-], then :data:`SCALE_SAMPLES`
        more whose samples give the norm's scales.
    separation : float
        Gap ``d0`` between the trajectories in the scaled norm [-] (a fraction of the
        motion), far above the integration error at the problem's tolerances.

    Returns
    -------
    LyapunovResult
        ``speed`` is the forcing frequency ``1 / T`` [Hz].
    """
    if not (isinstance(separation, (int, float)) and 0 < separation < 1e-3):
        raise ParameterError(f"separation must lie in (0, 1e-3) of the motion, got {separation!r}")
    value, period, x, weights, revolutions, transient = _start(problem, value, revolutions, transient)
    p, _ = problem.build(value)
    t = problem.t_start
    intervals, y, t = _intervals(problem, p, period, problem.full_state(x, value), weights, separation, t)
    logs, _, _ = _gap_logs(problem, p, period, y, weights, separation, t, revolutions, intervals)
    logs = logs.reshape(revolutions, intervals).sum(axis=1)             # per period
    running = np.cumsum(logs) / (np.arange(1, revolutions + 1) * period)
    return LyapunovResult(exponent=float(running[-1]), per_revolution=float(running[-1] * period), running=running,
                          speed=1.0 / period, revolutions=revolutions, transient=transient,
                          error=standard_error(logs, period))


def orbit_spectrum(problem: Problem, value: float | None = None, revolutions: int = 400,
                   transient: int = 200) -> LyapunovSpectrum:
    """Every Lyapunov exponent of the problem's steady motion at ``value``, from its
    state-transition matrix with saltation over each forcing period (at the problem's
    matrix tolerances).

    Parameters
    ----------
    problem : Problem
        A periodically forced model (not a cam under its drive).
    value : float, optional
        The problem's scalar parameter [its unit]; default the problem's.
    revolutions : int
        Forcing periods averaged [-].
    transient : int
        Forcing periods simulated and dropped first [-].

    Returns
    -------
    LyapunovSpectrum
        Over the problem's unknowns (the state components the period does not fix),
        ``speed`` the forcing frequency [Hz].
    """
    value, period, x, weights, revolutions, transient = _start(problem, value, revolutions, transient)
    n = x.size
    tangent = np.eye(n)
    logs = np.empty((revolutions, n))
    events = 0
    for k in range(revolutions):
        run = flow(problem, x, value, 1)
        events += run.events
        x = run.end                                  # at the matrix tolerances, as the matrix
        mapped = weights[:, None] * run.matrix @ (tangent / weights[:, None])   # D Phi D^-1 Q
        tangent, r = np.linalg.qr(mapped)
        diagonal = np.diag(r)
        tangent = tangent * np.where(diagonal < 0, -1.0, 1.0)
        with np.errstate(divide="ignore"):
            logs[k] = np.log(np.abs(diagonal))       # eq. (1) of camdyn.analysis.lyapunov
    running = np.cumsum(logs, axis=0) / (np.arange(1, revolutions + 1)[:, None] * period)
    errors = np.array([standard_error(logs[:, i], period) for i in range(n)])
    return LyapunovSpectrum(exponents=running[-1].copy(), per_period=running[-1] * period, running=running,
                            period=period, periods=revolutions, transient=transient, events=events,
                            weights=weights, speed=1.0 / period, errors=errors)
