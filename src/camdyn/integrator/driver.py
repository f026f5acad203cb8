"""The driver: a whole hybrid simulation per compiled call.

Algorithm (per accepted step from ``t`` to ``t + h``):

1. step with DOP853, Dormand-Prince 5(4) or the Rosenbrock method RODAS4 (chosen per mode by
   the system, or forced), accept if the scaled error norm is at most 1;
2. build the step's continuous extension (Dormand-Prince's own 4th-order dense output,
   or the cubic Hermite interpolant after a Rosenbrock step);
3. for every guard active in the current mode, look for a sign change against its
   expected sign at the step end and at the extrema of the guard's own cubic (from its
   exact rates at both ends, which the system computes from the acceleration; this
   catches grazing contacts that begin and end inside one step), or at the midpoint
   for a guard whose rate is unknown;
4. locate the earliest crossing by the Illinois method on the interpolant, cut the
   step there, log the event, switch mode and restart (the right-hand side is smooth
   within a mode, so no step straddles a discontinuity);
5. fill the requested output times passed over, from the interpolant.

Counters (``COUNT_*``) record accepted and rejected steps, right-hand-side calls,
Jacobians, steps per method, events and root-finding iterations, and the status.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.integrator.steppers import (
    KIND_DOP853,
    KIND_DP5,
    KIND_HERMITE,
    dense,
    dop853_error_norm,
    dop853_extend,
    dop853_step,
    dormand_prince_step,
    error_norm,
    rosenbrock_step,
)
from camdyn.systems import registry as systems

COUNT_ACCEPTED = 0
COUNT_REJECTED = 1
COUNT_RHS = 2
COUNT_JACOBIANS = 3
COUNT_EXPLICIT = 4
COUNT_ROSENBROCK = 5
COUNT_EVENTS = 6
COUNT_ROOT_ITERATIONS = 7
COUNT_STATUS = 8
COUNT_EVENTS_DROPPED = 9
COUNT_SIZE = 10
COUNTER_NAMES = ("accepted_steps", "rejected_steps", "rhs_calls", "jacobians", "explicit_steps",
                 "rosenbrock_steps", "events", "root_iterations", "status", "events_dropped")

STATUS_OK = 0
STATUS_MAX_STEPS = 1
STATUS_STEP_UNDERFLOW = 2
STATUS_NOT_FINITE = 3
STATUS_ZENO = 4
STATUS_MESSAGES = {
    STATUS_OK: "completed",
    STATUS_MAX_STEPS: "stopped: the maximum number of steps was reached",
    STATUS_STEP_UNDERFLOW: "stopped: the step size fell below the resolution of time",
    STATUS_NOT_FINITE: "stopped: the state became infinite or NaN",
    STATUS_ZENO: "stopped: events accumulated at one instant (sticking or chattering contact); "
                 "try tanh friction or another damping law",
}

METHOD_AUTO = 0  # the system chooses (systems.preferred_method)
METHOD_EXPLICIT = 1  # Dormand-Prince 5(4)
METHOD_ROSENBROCK = 2  # RODAS4
METHOD_DOP853 = 3  # DOP853

EVENT_COLUMNS = ("time", "guard", "new_sign", "alpha", "alpha_dot", "guard0", "guard1", "guard2",
                 "monitor_max")
N_EVENT_COLUMNS = len(EVENT_COLUMNS)
MODE_SIZE = 5
NG = systems.N_GUARDS


@numba.njit(cache=True)
def _guard_at(system, t, h, tau, y0, f0, y1, f1, work, kind, p, ytmp, vals, rates):
    dense(tau, h, y0, f0, y1, f1, work, kind, ytmp)
    systems.guards(system, t + tau * h, ytmp, math.nan, p, vals, rates)


@numba.njit(cache=True)
def _sample(t, h, t_stop, i_out, t_out, y0, f0, y1, f1, work, kind, mode, scratch, y_out, mode_out):
    """Fill the output times in (t, t_stop] of the current step; return the next index."""
    n_out = t_out.shape[0]
    while i_out < n_out and t_out[i_out] <= t_stop:
        dense((t_out[i_out] - t) / h, h, y0, f0, y1, f1, work, kind, scratch)
        for i in range(3):
            y_out[i_out, i] = scratch[i]
        for i in range(MODE_SIZE):
            mode_out[i_out, i] = mode[i]
        i_out += 1
    return i_out


@numba.njit(cache=True)
def _locate(system, k, sign, t, h, ta, tb, y0, f0, y1, f1, work, kind, p, ytmp, vals, rates, counters):
    """Illinois iteration for the crossing of guard ``k`` in (ta, tb] (fractions of h).

    ``sign * g`` is >= 0 at ``ta`` and < 0 at ``tb``; returns the right end of the final
    bracket, where the guard already has its new sign.
    """
    _guard_at(system, t, h, ta, y0, f0, y1, f1, work, kind, p, ytmp, vals, rates)
    fa = max(sign * vals[k], 0.0)
    _guard_at(system, t, h, tb, y0, f0, y1, f1, work, kind, p, ytmp, vals, rates)
    fb = sign * vals[k]
    side = 0
    tol = 4e-16 * max(1.0, abs(t)) / max(abs(h), 1e-300) + 1e-15
    for _ in range(200):
        if tb - ta <= tol:
            break
        tm = tb - fb * (tb - ta) / (fb - fa) if fb != fa else 0.5 * (ta + tb)
        if not (ta < tm < tb):
            tm = 0.5 * (ta + tb)
        _guard_at(system, t, h, tm, y0, f0, y1, f1, work, kind, p, ytmp, vals, rates)
        counters[COUNT_ROOT_ITERATIONS] += 1
        fm = sign * vals[k]
        if fm < 0.0:
            tb, fb = tm, fm
            if side == -1:
                fa *= 0.5
            side = -1
        else:
            ta, fa = tm, fm
            if side == 1:
                fb *= 0.5
            side = 1
    return tb


@numba.njit(cache=True)
def integrate(system, p, y_start, t_start, t_end, t_out, rtol, atol, h_max, method, max_steps,
              max_events):
    """Integrate a registered hybrid system from ``t_start`` to ``t_end``.

    Parameters
    ----------
    system : int
        System id (:mod:`camdyn.systems.registry`).
    p : ndarray
        Parameter vector.
    y_start : ndarray (3,)
        Initial state.
    t_start, t_end : float
        Time span [s].
    t_out : ndarray
        Increasing output times [s] within the span.
    rtol, atol : float
        Relative and absolute tolerances of the local error.
    h_max : float
        Largest step [s].
    method : int
        0 lets the system choose per mode (``systems.preferred_method``); 1 Dormand-Prince
        5(4), 2 RODAS4, 3 DOP853.
    max_steps, max_events : int
        Limits on accepted steps and on logged events.

    Returns
    -------
    y_out : ndarray (n_out, 3)
    mode_out : ndarray (n_out, 4)
        Hybrid mode at each output time.
    events : ndarray (n_events, 9)
        Event log, columns :data:`EVENT_COLUMNS`.
    counters : ndarray (10,) of int64
    """
    n_out = t_out.shape[0]
    y_out = np.full((n_out, 3), np.nan)
    mode_out = np.full((n_out, MODE_SIZE), np.nan)
    events = np.empty((max_events, N_EVENT_COLUMNS))
    counters = np.zeros(COUNT_SIZE, dtype=np.int64)
    work = np.empty((6, 3))
    stages = np.empty((6, 3))
    k16 = np.empty((16, 3))
    f7 = np.empty((7, 3))
    err3 = np.empty(3)
    h_regime = np.zeros(2)
    y = y_start.copy()
    y1 = np.empty(3)
    f = np.empty(3)
    f1 = np.empty(3)
    err = np.empty(3)
    ytmp = np.empty(3)
    ymid = np.empty(3)
    yo = np.empty(3)
    pts = np.empty(4)
    mode = np.zeros(MODE_SIZE)
    g = np.empty(NG)
    gr = np.empty(NG)
    g1 = np.empty(NG)
    gr1 = np.empty(NG)
    gv = np.empty(NG)
    grv = np.empty(NG)
    g_tmp = np.empty(NG)
    gr_tmp = np.empty(NG)
    t = t_start
    systems.initial_mode(system, t, y, p, mode)
    systems.rhs(system, t, y, mode, p, f)
    counters[COUNT_RHS] += 1
    systems.guards(system, t, y, f[1], p, g, gr)
    i_out = 0
    while i_out < n_out and t_out[i_out] <= t:
        for i in range(3):
            y_out[i_out, i] = y[i]
        for i in range(MODE_SIZE):
            mode_out[i_out, i] = mode[i]
        i_out += 1
    h = min(h_max, 1e-5, t_end - t_start)
    monitor_max = systems.monitor(system, t, y, mode, p)
    n_events = 0
    last_event_t = -math.inf
    zeno = 0
    while t < t_end:
        if counters[COUNT_ACCEPTED] >= max_steps:
            counters[COUNT_STATUS] = 1
            break
        h = min(h, h_max)
        last = False
        if t + h >= t_end or t + 1.01 * h >= t_end:
            h = t_end - t
            last = True
        if h <= 4e-16 * max(1.0, abs(t)):
            if last:
                break
            counters[COUNT_STATUS] = 2
            break
        chosen = systems.preferred_method(system, mode, p) if method == 0 else method
        if chosen == METHOD_ROSENBROCK:
            kind = KIND_HERMITE
            counters[COUNT_RHS] += rosenbrock_step(system, t, y, f, h, mode, p, work, stages, y1, err)
            counters[COUNT_JACOBIANS] += 1
            order = 4.0
            e = error_norm(y, y1, err, rtol, atol)
        elif chosen == METHOD_DOP853:
            kind = KIND_DOP853
            counters[COUNT_RHS] += dop853_step(system, t, y, f, h, mode, p, k16, ytmp, y1, f1, err, err3)
            order = 8.0
            e = dop853_error_norm(y, y1, err, err3, h, rtol, atol)
        else:
            kind = KIND_DP5
            counters[COUNT_RHS] += dormand_prince_step(system, t, y, f, h, mode, p, work, y1, f1, err)
            order = 5.0
            e = error_norm(y, y1, err, rtol, atol)
        dwork = f7 if kind == KIND_DOP853 else work
        ready = kind != KIND_DOP853
        if not (e == e) or not np.isfinite(y1[0]) or not np.isfinite(y1[1]):
            counters[COUNT_REJECTED] += 1
            h *= 0.25
            if h <= 4e-16 * max(1.0, abs(t)):  # else the next pass reports underflow
                counters[COUNT_STATUS] = 3
                break
            continue
        if e > 1.0:
            counters[COUNT_REJECTED] += 1
            h *= max(0.2, 0.9 * e ** (-1.0 / order))
            continue
        # accepted
        counters[COUNT_ACCEPTED] += 1
        if kind == KIND_HERMITE:
            counters[COUNT_ROSENBROCK] += 1
            systems.rhs(system, t + h, y1, mode, p, f1)
            counters[COUNT_RHS] += 1
        else:
            counters[COUNT_EXPLICIT] += 1
        systems.guards(system, t + h, y1, f1[1], p, g1, gr1)
        need_mid = False
        for k in range(NG):
            if systems.expected_sign(system, k, mode, p) != 0.0 and (math.isnan(gr[k]) or math.isnan(gr1[k])):
                need_mid = True
        if need_mid:
            if not ready:
                counters[COUNT_RHS] += dop853_extend(system, t, y, h, y1, f1, mode, p, k16, ytmp, f7)
                ready = True
            dense(0.5, h, y, f, y1, f1, dwork, kind, ymid)
            systems.guards(system, t + 0.5 * h, ymid, math.nan, p, gv, grv)
        else:
            for k in range(NG):
                gv[k] = 0.0   # not used: every active guard has its cubic
        tau_event = 2.0
        k_event = -1
        for k in range(NG):
            s = systems.expected_sign(system, k, mode, p)
            if s == 0.0:
                continue
            # candidate sample points in (0, 1]
            has_rate = not (math.isnan(gr[k]) or math.isnan(gr1[k]))
            val0 = s * gv[k]
            ext1 = -1.0
            ext2 = -1.0
            if has_rate:
                # cubic Hermite of the guard itself: extrema from its derivative
                d0 = h * gr[k]
                d1 = h * gr1[k]
                a3 = 2.0 * g[k] + d0 - 2.0 * g1[k] + d1
                a2 = -3.0 * g[k] - 2.0 * d0 + 3.0 * g1[k] - d1
                a1 = d0
                qa = 3.0 * a3
                qb = 2.0 * a2
                qc = a1
                if abs(qa) > 1e-300:
                    disc = qb * qb - 4.0 * qa * qc
                    if disc >= 0.0:
                        sq = math.sqrt(disc)
                        ext1 = (-qb - sq) / (2.0 * qa)
                        ext2 = (-qb + sq) / (2.0 * qa)
                elif abs(qb) > 1e-300:
                    ext1 = -qc / qb
            # ordered sample taus: the guard's extrema, the midpoint and the end
            pts[0] = min(ext1, ext2)
            pts[1] = max(ext1, ext2)
            pts[2] = -1.0 if has_rate else 0.5   # guards with a rate use their cubic instead
            pts[3] = 1.0
            for a_ in range(1, 4):
                b_ = a_
                while b_ > 0 and pts[b_ - 1] > pts[b_]:
                    tmp_ = pts[b_ - 1]
                    pts[b_ - 1] = pts[b_]
                    pts[b_] = tmp_
                    b_ -= 1
            prev = 0.0
            found = -1.0
            for j in range(4):
                tau = pts[j]
                if tau <= 0.0 or tau > 1.0:
                    continue
                if tau == 0.5:
                    v = val0
                elif tau == 1.0:
                    v = s * g1[k]
                else:
                    if not ready:
                        counters[COUNT_RHS] += dop853_extend(system, t, y, h, y1, f1, mode, p, k16, ytmp, f7)
                        ready = True
                    _guard_at(system, t, h, tau, y, f, y1, f1, dwork, kind, p, ytmp, g_tmp, gr_tmp)
                    v = s * g_tmp[k]
                if v < 0.0:
                    found = tau
                    break
                prev = tau
            if found > 0.0 and prev < tau_event:
                if not ready:
                    counters[COUNT_RHS] += dop853_extend(system, t, y, h, y1, f1, mode, p, k16, ytmp, f7)
                    ready = True
                tau_k = _locate(system, k, s, t, h, prev, found, y, f, y1, f1, dwork, kind, p,
                                ytmp, g_tmp, gr_tmp, counters)
                if tau_k < tau_event:
                    tau_event = tau_k
                    k_event = k
        if k_event >= 0:
            t_new = t + tau_event * h
            dense(tau_event, h, y, f, y1, f1, dwork, kind, ytmp)
            i_out = _sample(t, h, t_new, i_out, t_out, y, f, y1, f1, dwork, kind, mode, yo, y_out, mode_out)
            for i in range(3):
                y[i] = ytmp[i]
            systems.guards(system, t_new, y, math.nan, p, g, gr)
            monitor_max = max(monitor_max, systems.monitor(system, t_new, y, mode, p))
            if n_events < max_events:
                ev = events[n_events]
                ev[0] = t_new
                ev[1] = k_event
                ev[3] = y[0]
                ev[4] = y[1]
                ev[5] = g[0]
                ev[6] = g[1]
                ev[7] = g[2]
                ev[8] = monitor_max
            else:
                counters[COUNT_EVENTS_DROPPED] += 1
            systems.transition(system, k_event, t_new, y, g, mode, p)
            if n_events < max_events:
                events[n_events, 2] = systems.expected_sign(system, k_event, mode, p)
                n_events += 1
            counters[COUNT_EVENTS] += 1
            if t_new - last_event_t <= 1e-12 * max(1.0, abs(t_new)):
                zeno += 1
                if zeno > 1000:
                    counters[COUNT_STATUS] = 4
                    break
            else:
                zeno = 0
            last_event_t = t_new
            t = t_new
            systems.rhs(system, t, y, mode, p, f)
            counters[COUNT_RHS] += 1
            systems.guards(system, t, y, f[1], p, g, gr)   # the rates in the new mode
            monitor_max = systems.monitor(system, t, y, mode, p)
            h = max(h * tau_event, h * 0.1) if tau_event > 0.0 else h
            # a contact is far faster than free flight: start from this regime's last step
            r_new = systems.regime(system, mode, p)
            if h_regime[r_new] > 0.0:
                h = min(h, h_regime[r_new])
        else:
            if not ready and i_out < n_out and t_out[i_out] <= t + h:
                counters[COUNT_RHS] += dop853_extend(system, t, y, h, y1, f1, mode, p, k16, ytmp, f7)
                ready = True
            i_out = _sample(t, h, t + h, i_out, t_out, y, f, y1, f1, dwork, kind, mode, yo, y_out, mode_out)
            t = t_end if last else t + h
            for i in range(3):
                y[i] = y1[i]
                f[i] = f1[i]
            for i in range(NG):
                g[i] = g1[i]
                gr[i] = gr1[i]
            monitor_max = max(monitor_max, systems.monitor(system, t, y, mode, p))
            h_regime[systems.regime(system, mode, p)] = h
            factor = 0.9 * e ** (-1.0 / order) if e > 0.0 else 5.0
            h *= min(5.0, max(0.2, factor))
    return y_out, mode_out, events[:n_events].copy(), counters
