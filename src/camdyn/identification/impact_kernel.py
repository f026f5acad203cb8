"""Compiled kernels of the impact-damping identification (thesis 3.5).

- :func:`simulate_impacts`: simulation S1, many (impact, beta, n) jobs per call, in
  parallel over jobs (``prange``); each job is one whole hybrid simulation of one impact
  event by the compiled driver, from contact onset to the end of the event.
- :func:`return_time`: the free flight of eq 3.9 from the end of contact until the
  follower angle comes back to a given level (the return-time map of eq 3.19).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.integrator import driver
from camdyn.model import layout as L
from camdyn.model.dynamics import evaluate, free_acceleration
from camdyn.systems import registry as systems

#: Status of a job whose simulation never separated from the cam.
STATUS_NO_SEPARATION = 100


@numba.njit(cache=True)
def parabola_peak(y0, y1, y2):
    """Extreme value of the parabola through three equally spaced samples whose middle one
    is the largest; ``y1`` itself when the three are not concave."""
    den = y0 - 2.0 * y1 + y2
    if den < 0.0:
        return y1 - 0.125 * (y0 - y2) ** 2 / den
    return y1


@numba.njit(cache=True)
def free_step(a, v, step, p):
    """One classical Runge-Kutta step [s] of the free flight (eq 3.9: spring and gravity)
    from ``(a [rad], v [rad/s])``; returns the angle and rate after it."""
    k1a = v
    k1v = free_acceleration(a, p)
    k2a = v + 0.5 * step * k1v
    k2v = free_acceleration(a + 0.5 * step * k1a, p)
    k3a = v + 0.5 * step * k2v
    k3v = free_acceleration(a + 0.5 * step * k2a, p)
    k4a = v + step * k3v
    k4v = free_acceleration(a + step * k3a, p)
    return (a + step * (k1a + 2.0 * k2a + 2.0 * k3a + k4a) / 6.0,
            v + step * (k1v + 2.0 * k2v + 2.0 * k3v + k4v) / 6.0)


@numba.njit(cache=True)
def free_flight(alpha, rate, duration, p, step_max=5e-6):
    """``(alpha [rad], alpha_dot [rad/s])`` after a free flight of ``duration`` [s]
    (negative: backwards) from ``(alpha, rate)``, in equal Runge-Kutta steps of at most
    ``step_max`` [s]."""
    n = max(1, int(math.ceil(abs(duration) / step_max)))
    h = duration / n
    a = alpha
    v = rate
    for _ in range(n):
        a, v = free_step(a, v, h, p)
    return a, v


@numba.njit(cache=True)
def return_time(alpha_start, alpha_dot_start, alpha_target, p, step, t_max):
    """Time [s] the free follower takes from ``(alpha_start [rad], alpha_dot_start [rad/s])``
    until its angle comes back to ``alpha_target`` [rad] after turning round.

    Classical Runge-Kutta with the fixed ``step`` [s] (the free flight is smooth and slow
    against the sampling), the crossing interpolated by a cubic Hermite polynomial. NaN if
    the follower does not come back within ``t_max`` [s].
    """
    a = alpha_start
    v = alpha_dot_start
    t = 0.0
    turned = False
    direction = 1.0 if alpha_dot_start >= 0.0 else -1.0
    while t < t_max:
        a1, v1 = free_step(a, v, step, p)
        if not turned and v1 * direction < 0.0:
            turned = True
        if turned and (a1 - alpha_target) * direction <= 0.0 < (a - alpha_target) * direction:
            # cubic Hermite on [t, t + step]; bisection for its root
            lo, hi = 0.0, 1.0
            for _ in range(60):
                s = 0.5 * (lo + hi)
                h00 = 2 * s ** 3 - 3 * s ** 2 + 1
                h10 = s ** 3 - 2 * s ** 2 + s
                h01 = -2 * s ** 3 + 3 * s ** 2
                h11 = s ** 3 - s ** 2
                val = h00 * a + h10 * step * v + h01 * a1 + h11 * step * v1 - alpha_target
                if val * direction > 0.0:
                    lo = s
                else:
                    hi = s
            return t + 0.5 * (lo + hi) * step
        a = a1
        v = v1
        t += step
    return math.nan


@numba.njit(cache=True)
def _output_times(offsets, t_end, grid_points):
    """Output times of one job, sorted: a uniform grid over the event and the wanted offsets.

    Parameters
    ----------
    offsets : ndarray (M,)
        Times after onset [s] at which force and penetration are wanted (NaN padded).
    t_end : float
        Length of the event [s].
    grid_points : int
        Samples of the uniform grid [-].

    Returns
    -------
    t_sorted : ndarray
        The grid and the offsets (clipped to the event) in increasing order [s].
    order : ndarray of int
        Position of each sorted time before sorting: below ``grid_points`` a grid
        sample, else ``grid_points`` plus the offset's column.
    """
    m = offsets.shape[0]
    wanted = 0
    for c in range(m):
        if math.isfinite(offsets[c]):
            wanted += 1
    n = grid_points + wanted
    t_out = np.empty(n)
    for g in range(grid_points):
        t_out[g] = t_end * g / (grid_points - 1)
    for c in range(wanted):
        t_out[grid_points + c] = min(max(offsets[c], 0.0), t_end)
    order = np.argsort(t_out, kind="mergesort")
    return t_out[order], order


@numba.njit(cache=True)
def _separation(events, t_end):
    """Time of the first separation [s] in an event log (NaN if none), and of the next
    contact onset after it (``t_end + 1`` [s] if none)."""
    t_sep = math.nan
    t_next = t_end + 1.0
    for e in range(events.shape[0]):
        if events[e, 1] == 0.0 and events[e, 2] < 0.0 and not math.isfinite(t_sep):
            t_sep = events[e, 0]
        elif events[e, 1] == 0.0 and events[e, 2] > 0.0 and math.isfinite(t_sep):
            t_next = events[e, 0]
            break
    return t_sep, t_next


@numba.njit(cache=True)
def _contact_outputs(q, t_sorted, y, modes, order, grid_points, force, penetration):
    """Fill ``force`` [N] and ``penetration`` [m] (one job's rows) at the wanted offsets
    from the simulated states ``y`` and ``modes`` at ``t_sorted`` [s]."""
    for r in range(t_sorted.shape[0]):
        c = order[r] - grid_points
        if c >= 0:
            res = evaluate(t_sorted[r], y[r, 0], y[r, 1], modes[r], q)
            force[c] = res[1]
            penetration[c] = res[5]


@numba.njit(cache=True)
def _flight_peak(t_sorted, y, order, grid_points, t_sep, t_next):
    """Extreme follower angle [rad] in the free flight between ``t_sep`` and ``t_next``
    [s], in the direction of separation, from the grid samples refined by a parabola.

    Returns
    -------
    found : bool
        False when no grid sample lies in the flight.
    peak : float
        The extreme angle [rad].
    """
    n = t_sorted.shape[0]
    direction = 1.0
    best = -1
    best_val = -np.inf
    for r in range(n):
        if order[r] < grid_points and t_sep < t_sorted[r] < t_next:
            if best < 0:
                direction = 1.0 if y[r, 1] >= 0.0 else -1.0
            val = direction * y[r, 0]
            if val > best_val:
                best_val = val
                best = r
    if best < 0:
        return False, math.nan
    # parabola through the neighbouring grid samples
    lo = best - 1
    while lo >= 0 and order[lo] >= grid_points:
        lo -= 1
    hi = best + 1
    while hi < n and order[hi] >= grid_points:
        hi += 1
    if lo >= 0 and hi < n:
        best_val = parabola_peak(direction * y[lo, 0], best_val, direction * y[hi, 0])
    return True, direction * best_val


@numba.njit(parallel=True, cache=True)
def simulate_impacts(params, impact, beta, exponent, alpha0, alpha_dot0, t_end, offsets, grid_points,
                     rtol, atol, h_max):
    """Simulation S1 of impact events, batched.

    Parameters
    ----------
    params : ndarray (K, SIZE)
        Parameter vector of the rig (:mod:`camdyn.model.layout`) for each impact, with the
        cam angle at onset in the ``THETA0`` slot (impacts of several records may be mixed).
    impact : ndarray of int (J,)
        Impact event of each job.
    beta, exponent : ndarray (J,)
        Trial damping ``beta`` [N s m^-(n+1)] and exponent ``n`` [-] of each job.
    alpha0, alpha_dot0 : ndarray (K,)
        Follower angle [rad] and rate [rad/s] at the onset of each impact.
    t_end : ndarray (K,)
        Length of each impact event [s] (onset to the next onset).
    offsets : ndarray (K, M)
        Times after onset [s] at which force and penetration are wanted (NaN padded).
    grid_points : int
        Samples of the uniform grid on which the peak angle is searched.
    rtol, atol, h_max : float
        Tolerances and largest step [s] of the driver.

    Returns
    -------
    peak : ndarray (J,)
        Extreme follower angle after separation, in the direction of separation [rad]
        (eq 3.22), refined by a parabola through the three grid samples around it.
    force, penetration : ndarray (J, M)
        Normal force [N] and penetration [m] at ``offsets``.
    separation : ndarray (J,)
        Time of separation after onset [s].
    status : ndarray of int (J,)
        0 for success, a driver status, or :data:`STATUS_NO_SEPARATION`.
    """
    jobs = impact.shape[0]
    m = offsets.shape[1]
    peak = np.full(jobs, np.nan)
    force = np.full((jobs, m), np.nan)
    penetration = np.full((jobs, m), np.nan)
    separation = np.full(jobs, np.nan)
    status = np.zeros(jobs, dtype=np.int64)
    for j in numba.prange(jobs):
        i = impact[j]
        q = params[i].copy()
        q[L.BETA] = beta[j]
        q[L.EXPONENT] = exponent[j]
        t_sorted, order = _output_times(offsets[i], t_end[i], grid_points)
        y0 = np.array([alpha0[i], alpha_dot0[i], 0.0])
        # typed values, not literals: each new argument type is a whole compile of the driver
        y, modes, events, counters = driver.integrate(
            systems.CAM_FOLLOWER, q, y0, 0.0, t_end[i], t_sorted, rtol, atol, h_max,
            driver.METHOD_AUTO, np.int64(10_000_000), np.int64(256), np.bool_(False), math.inf)
        status[j] = counters[driver.COUNT_STATUS]
        if status[j] != 0:
            continue
        t_sep, t_next = _separation(events, t_end[i])
        if not math.isfinite(t_sep):
            status[j] = STATUS_NO_SEPARATION
            continue
        separation[j] = t_sep
        _contact_outputs(q, t_sorted, y, modes, order, grid_points, force[j], penetration[j])
        found, value = _flight_peak(t_sorted, y, order, grid_points, t_sep, t_next)
        if not found:
            status[j] = STATUS_NO_SEPARATION
            continue
        peak[j] = value
    return peak, force, penetration, separation, status
