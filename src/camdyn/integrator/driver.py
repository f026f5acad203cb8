"""The driver: a whole hybrid simulation per compiled call.

Algorithm (per accepted step from ``t`` to ``t + h``):

1. step with DOP853, Dormand-Prince 5(4), the Rosenbrock method RODAS4 or Radau IIA
   (chosen per mode by the system, or forced, or DOP853 switched to Radau IIA in
   sustained contact, :mod:`camdyn.integrator.implicit`), or with the Adams method of :mod:`camdyn.integrator.nordsieck`
   when forced (``METHOD_ADAMS``), or with Adams and BDF switched automatically
   (``METHOD_MULTISTEP``, :mod:`camdyn.integrator.multistep`; the history is started from
   a DOP853 step after every event); accept if the scaled error norm is at most 1;
2. build the step's continuous extension (Dormand-Prince's own 4th-order dense output,
   the cubic Hermite interpolant after a Rosenbrock step, the collocation polynomial after
   a Radau IIA step, the Nordsieck polynomial after an Adams or BDF step);
3. for every guard active in the current mode, look for a sign change against its
   expected sign at the step end and at the extrema of the guard's own cubic (from its
   exact rates at both ends, which the system computes from the acceleration; this
   catches grazing contacts that begin and end inside one step), or at the midpoint
   for a guard whose rate is unknown;
4. locate the earliest crossing by the Illinois method on the interpolant; unless it
   lies within the step's first 1 % or last 0.1 %, take the step again so that it ends
   just past the crossing (its end state then has the step's error control, not the
   interpolant's) and locate it again; cut the step there, log the event, switch mode
   and restart (the right-hand side is smooth within a mode, so no step straddles a
   discontinuity; a retaken step counts as rejected);
5. fill the requested output times passed over, from the interpolant.

Counters (``COUNT_*``, :mod:`camdyn.integrator.counters`) record accepted and rejected
steps, right-hand-side calls, Jacobians, steps per method, events and root-finding
iterations, and the status. Steps 3-4 are :mod:`camdyn.integrator.crossings` (the crossing)
and :mod:`camdyn.integrator.events` (retake, cut, log, restart); each of
the other steps of the loop is one function of this module, compiled into ``integrate``
(numba IR inlining, :mod:`camdyn.integrator.inlining`).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from camdyn.integrator.control import STEP_FAILED, STEP_RETRY, stabilized, verdict
from camdyn.integrator.counters import (
    COUNT_ACCEPTED,
    COUNT_BDF,
    COUNT_EVENTS,
    COUNT_EVENTS_DROPPED,
    COUNT_EXPLICIT,
    COUNT_JACOBIANS,
    COUNT_RADAU,
    COUNT_REJECTED,
    COUNT_RHS,
    COUNT_ROOT_ITERATIONS,
    COUNT_ROSENBROCK,
    COUNT_SIZE,
    COUNT_STATUS,
    COUNTER_NAMES,
    STATUS_INTERRUPTED,
    STATUS_MAX_STEPS,
    STATUS_MESSAGES,
    STATUS_NOT_FINITE,
    STATUS_OK,
    STATUS_STEP_UNDERFLOW,
    STATUS_ZENO,
)
from camdyn.integrator.crossings import earliest_crossing, ensure_extension, midpoint_guards
from camdyn.integrator.events import (
    EVENT_GUARD,
    EVENT_GUARDS,
    EVENT_MONITOR,
    EVENT_NEW_SIGN,
    EVENT_RETRY_ABOVE,
    EVENT_RETRY_BELOW,
    EVENT_RETRY_LOST,
    EVENT_RETRY_MARGIN,
    EVENT_STEP_FLOOR,
    EVENT_TIME,
    cut_at_event,
    event_columns,
    log_event,
    restart,
    retake,
)
from camdyn.integrator.implicit import (
    implicit_proposal,
    implicit_reset,
    implicit_step,
    implicit_workspace,
    is_stiff,
    stiffness_test,
)
from camdyn.integrator.inlining import InlinedPipeline
from camdyn.integrator.interrupt import POLL_STEPS, interrupted
from camdyn.integrator.multistep import history_rows, multistep_step
from camdyn.integrator.nordsieck import BDF, FAMILY, TIME, adams_accept, adams_ready, adams_start
from camdyn.integrator.sampling import sample
from camdyn.integrator.steppers import (
    KIND_DOP853,
    KIND_DP5,
    KIND_HERMITE,
    KIND_NORDSIECK,
    KIND_RADAU,
    dop853_error_norm,
    dop853_step,
    dormand_prince_step,
    error_norm,
    rosenbrock_step,
)
from camdyn.systems import registry as systems

__all__ = [
    "integrate", "COUNT_ACCEPTED", "COUNT_REJECTED", "COUNT_RHS", "COUNT_JACOBIANS", "COUNT_EXPLICIT",
    "COUNT_ROSENBROCK", "COUNT_EVENTS", "COUNT_ROOT_ITERATIONS", "COUNT_STATUS", "COUNT_EVENTS_DROPPED",
    "COUNT_BDF", "COUNT_RADAU", "COUNT_SIZE", "COUNTER_NAMES", "STATUS_OK", "STATUS_MAX_STEPS", "STATUS_STEP_UNDERFLOW",
    "STATUS_NOT_FINITE", "STATUS_ZENO", "STATUS_INTERRUPTED", "STATUS_MESSAGES", "METHOD_AUTO", "METHOD_EXPLICIT",
    "METHOD_ROSENBROCK", "METHOD_DOP853", "METHOD_ADAMS", "METHOD_MULTISTEP", "METHOD_RADAU", "METHOD_SWITCHING",
    "EVENT_TIME", "EVENT_GUARD",
    "EVENT_NEW_SIGN", "EVENT_MONITOR", "EVENT_GUARDS", "EVENT_RETRY_ABOVE", "EVENT_RETRY_BELOW", "EVENT_RETRY_LOST",
    "EVENT_RETRY_MARGIN", "EVENT_STEP_FLOOR", "event_columns",
]

METHOD_AUTO = 0  # the system chooses (systems.preferred_method)
METHOD_EXPLICIT = 1  # Dormand-Prince 5(4)
METHOD_ROSENBROCK = 2  # RODAS4
METHOD_DOP853 = 3  # DOP853
METHOD_ADAMS = 4  # variable-order Adams-Moulton, Nordsieck form, functional iteration
METHOD_MULTISTEP = 5  # Adams and BDF in Nordsieck form, switched automatically
METHOD_RADAU = 6  # Radau IIA of order 5 (RADAU5's method), camdyn.integrator.implicit
METHOD_SWITCHING = 7  # DOP853, and Radau IIA from stiffness detection to the next event



# --- the steps of the driver's loop, compiled into it (inline="always": numba IR
# inlining; camdyn.integrator.inlining removes the copies of their arguments), so that
# splitting the loop adds no cost per step


@numba.njit(cache=True, inline="always")
def _allocate(system, y_start, n_out, max_events):
    """The run's results, filled as it goes: outputs ``y_out`` (NaN until reached), their
    modes, the event log and the counters; and its state ``y`` and mode. Refuses an
    initial state whose size is not the system's."""
    n = y_start.shape[0]
    if n != systems.state_size(system):
        raise ValueError("the initial state's size is not the system's state_size")
    m = systems.guard_count(system)
    y_out = np.full((n_out, n), np.nan)
    modes = systems.mode_size(system)
    mode_out = np.full((n_out, modes), np.nan)
    events = np.empty((max_events, EVENT_GUARDS + m + n))
    counters = np.zeros(COUNT_SIZE, dtype=np.int64)
    return y_out, mode_out, events, counters, y_start.copy(), np.zeros(modes)


@numba.njit(cache=True, inline="always")
def _workspace(n, columns):
    """Scratch arrays of one run: stepper stages, the Rosenbrock iteration matrix and its
    pivots, the Adams history, states [n], guard values [m], the guard scan's, and what
    Radau IIA keeps between steps (:func:`camdyn.integrator.implicit.implicit_workspace`);
    ``columns`` is the event log's past its fixed columns, ``m + n``."""
    m = columns - n
    history = np.zeros((history_rows(n), n))
    history[TIME, 0] = np.nan   # no history yet: the first Adams step starts at order 1
    stage_arrays = (np.empty((6, n)), np.empty((6, n)), np.empty((16, n)), np.empty((7, n)), np.empty(n),
                    np.zeros(2), np.empty(4), np.empty((n, n)), np.empty(n, dtype=np.int64), history)
    states = (np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n))
    guards = (np.empty(m), np.empty(m), np.empty(m), np.empty(m), np.empty(m), np.empty(m), np.empty(m),
              np.empty(m))
    scan_arrays = (np.empty(n), np.empty(m), np.empty(m), np.empty(m), np.empty(m), np.empty(m), np.empty(m))
    return stage_arrays, states, guards, scan_arrays, implicit_workspace(n)


@numba.njit(cache=True, inline="always")
def _start(system, t, t_end, h_max, y, f, mode, p, g, gr, t_out, y_out, mode_out, counters):
    """Initial mode, rates and guards at ``t`` [s]; fill the output times up to ``t``.

    Returns
    -------
    i_out : int
        Index of the next output time.
    h : float
        First trial step [s].
    monitor_max : float
        The monitored quantity at ``t``.
    """
    systems.initial_mode(system, t, y, p, mode)
    systems.rhs(system, t, y, mode, p, f)
    counters[COUNT_RHS] += 1
    systems.guards(system, t, y, f, True, p, g, gr)
    n_out = t_out.shape[0]
    i_out = 0
    while i_out < n_out and t_out[i_out] <= t:
        for i in range(y.shape[0]):
            y_out[i_out, i] = y[i]
        for i in range(mode.shape[0]):
            mode_out[i_out, i] = mode[i]
        i_out += 1
    h = min(h_max, 1e-5, t_end - t)
    return i_out, h, systems.monitor(system, t, y, mode, p)


@numba.njit(cache=True, inline="always")
def _next_step(t, h, h_max, t_end, max_steps, counters):
    """Size [s] of the next step from ``t`` [s], whether it is the last, and whether the
    run stops here (the step limit reached, with the status set; or a step below the
    resolution of time: the end reached, or an underflow, with the status set)."""
    if counters[COUNT_ACCEPTED] >= max_steps:
        counters[COUNT_STATUS] = STATUS_MAX_STEPS
        return h, False, True
    h = min(h, h_max)
    last = False
    if t + h >= t_end or t + 1.01 * h >= t_end:
        h = t_end - t
        last = True
    if h <= 4e-16 * max(1.0, abs(t)):
        if not last:
            counters[COUNT_STATUS] = STATUS_STEP_UNDERFLOW
        return h, last, True
    return h, last, False


@numba.njit(cache=True, inline="always")
def _multistep(method):
    """Whether ``method`` is one of the Nordsieck multistep methods."""
    return method == METHOD_ADAMS or method == METHOD_MULTISTEP


@numba.njit(cache=True, inline="always")
def _trial_step(system, method, t, y, f, h, mode, p, rtol, atol, work, stages, matrix, pivots, k16, ytmp, y1, f1,
                err, err3, history, implicit, counters):
    """One step of ``h`` [s] from ``(t, y)`` by the method chosen for the mode into ``y1``
    (and ``f1`` after an explicit step).

    Returns
    -------
    kind : int
        Its continuous extension (``KIND_*``).
    order : float
        Its order, for the step-size control.
    e : float
        Scaled error norm (at most 1 to accept).
    """
    chosen = systems.preferred_method(system, mode, p) if method == 0 else method
    if chosen == METHOD_SWITCHING:
        chosen = METHOD_RADAU if is_stiff(implicit[0]) else METHOD_DOP853
    if _multistep(chosen) and not adams_ready(history, t, y):
        chosen = METHOD_DOP853   # a step that (re)starts the multistep history: _adams_start
    if chosen == METHOD_RADAU:
        kind = KIND_RADAU
        e, calls, jacobians = implicit_step(system, t, y, f, h, mode, p, rtol, atol, systems.controlled_size(system),
                                            implicit[0], implicit[1], work, y1, err)
        counters[COUNT_RHS] += calls
        counters[COUNT_JACOBIANS] += jacobians
        order = 4.0
    elif chosen == METHOD_ROSENBROCK:
        kind = KIND_HERMITE
        counters[COUNT_RHS] += rosenbrock_step(system, t, y, f, h, mode, p, work, stages, matrix, pivots, y1, err)
        counters[COUNT_JACOBIANS] += 1
        order = 4.0
        e = error_norm(y, y1, err, rtol, atol, systems.controlled_size(system))
    elif _multistep(chosen):
        kind = KIND_NORDSIECK
        e, order, calls, jacobians = multistep_step(system, t, y, f, h, mode, p, history, y1, f1, err, matrix, pivots,
                                                    rtol, atol, chosen == METHOD_MULTISTEP)
        counters[COUNT_RHS] += calls
        counters[COUNT_JACOBIANS] += jacobians
    elif chosen == METHOD_DOP853:
        kind = KIND_DOP853
        counters[COUNT_RHS] += dop853_step(system, t, y, f, h, mode, p, k16, ytmp, y1, f1, err, err3,
                                            systems.controlled_size(system))
        plain = systems.plain_error_estimate(system)
        order = 8.0
        e = dop853_error_norm(y, y1, err, err3, h, rtol, atol, systems.controlled_size(system), plain)
        if method == METHOD_SWITCHING and e <= 1.0:
            counters[COUNT_JACOBIANS] += stiffness_test(system, t + h, y1, f1, h, mode, p, implicit[0], implicit[1])
    else:
        kind = KIND_DP5
        counters[COUNT_RHS] += dormand_prince_step(system, t, y, f, h, mode, p, work, y1, f1, err)
        order = 5.0
        e = error_norm(y, y1, err, rtol, atol, systems.controlled_size(system))
    return kind, order, e


@numba.njit(cache=True, inline="always")
def _step_end(system, kind, t, h, y1, f1, mode, p, g1, gr1, history, counters):
    """Count the accepted step; rates ``f1`` (after a Rosenbrock or Radau step) and guards ``g1``
    with their rates ``gr1`` at its end ``t + h`` [s]."""
    counters[COUNT_ACCEPTED] += 1
    if kind == KIND_NORDSIECK and history[FAMILY, 0] == BDF:
        counters[COUNT_BDF] += 1
    elif kind == KIND_HERMITE or kind == KIND_RADAU:
        counters[COUNT_ROSENBROCK if kind == KIND_HERMITE else COUNT_RADAU] += 1
        systems.rhs(system, t + h, y1, mode, p, f1)
        counters[COUNT_RHS] += 1
    else:
        counters[COUNT_EXPLICIT] += 1
    systems.guards(system, t + h, y1, f1, True, p, g1, gr1)


@numba.njit(cache=True, inline="always")
def _advance(system, t, h, t_stop, e, order, y, f, y1, f1, dwork, kind, mode, p, k16, ytmp, f7, yo, g, gr,
             g1, gr1, t_out, i_out, y_out, mode_out, monitor_max, h_regime, ready, counters):
    """Take the whole step: fill the output times it passes, move to its end ``t_stop``
    [s] (``t + h``, or the end of the run after the last step), and size the next step
    from the error norm ``e``.

    (At most 30 arguments: CPython passes more as ``*args``, which numba cannot inline.)

    Returns
    -------
    t : float
        The step's end [s].
    i_out : int
        Index of the next output time.
    monitor_max : float
        Largest monitored value since the last event.
    h : float
        The next trial step [s].
    """
    if i_out < t_out.shape[0] and t_out[i_out] <= t + h:
        ready = ensure_extension(ready, system, t, y, h, y1, f1, mode, p, k16, ytmp, f7, counters)
    i_out = sample(t, h, t + h, i_out, t_out, y, f, y1, f1, dwork, kind, mode, yo, y_out, mode_out)
    t = t_stop
    for i in range(y.shape[0]):
        y[i] = y1[i]
        f[i] = f1[i]
    for i in range(g.shape[0]):
        g[i] = g1[i]
        gr[i] = gr1[i]
    monitor_max = max(monitor_max, systems.monitor(system, t, y, mode, p))
    h_regime[systems.regime(system, mode, p)] = h
    if kind == KIND_NORDSIECK:
        return t, i_out, monitor_max, adams_accept(dwork, t, h)
    factor = 0.9 * e ** (-1.0 / order) if e > 0.0 else 5.0
    h *= min(5.0, max(0.2, factor))
    return t, i_out, monitor_max, h


@numba.njit(cache=True, inline="always")
def _proposal(system, method, kind, h_taken, h, h_adams, e, e_accepted, implicit):
    """The step [s] after an accepted step of ``kind`` and size ``h_taken`` [s] for which
    :func:`_advance` proposed ``h``: the multistep history's first step after its DOP853
    start, the stabilized DOP853 step (:func:`~camdyn.integrator.control.stabilized`) where the system's DOP853
    steps are controlled by their plain estimate, RADAU5's control after a Radau IIA
    step (:func:`camdyn.integrator.implicit.implicit_proposal`), else ``h``."""
    if _multistep(method) and kind == KIND_DOP853:
        return h_adams
    if kind == KIND_RADAU:
        return implicit_proposal(implicit[0], h_taken, e, h)
    if kind == KIND_DOP853 and systems.plain_error_estimate(system):
        return stabilized(h, e, e_accepted)
    return h


@numba.njit(cache=True, inline="always")
def _adams_start(system, method, kind, ready, t, h, y, y1, f1, mode, p, k16, ytmp, f7, history, rtol, atol, err,
                 counters):
    """After a DOP853 step that the Adams method took to (re)start, its history at the
    step's end from the step's continuous extension. Returns whether the extension is
    ready and the first Adams step [s] (``h`` otherwise)."""
    if not _multistep(method) or kind != KIND_DOP853:
        return ready, h
    ready = ensure_extension(ready, system, t, y, h, y1, f1, mode, p, k16, ytmp, f7, counters)
    return ready, adams_start(history, f7, y1, t + h, h, rtol, atol, systems.controlled_size(system), err)


@numba.njit(cache=True, inline="always")
def _fill_end(t, y, mode, t_out, i_out, y_out, mode_out, counters):
    """Fill the output times within the resolution of time past ``t`` [s] with the state
    there, after a completed run: an event cut a hair before the end (a joint of a cam
    profile at the end of a revolution) leaves a step too short to take, and its output
    time unfilled. Returns the next index."""
    while (counters[COUNT_STATUS] == STATUS_OK and i_out < t_out.shape[0]
           and t_out[i_out] - t <= 4e-16 * max(1.0, abs(t))):
        for i in range(y.shape[0]):
            y_out[i_out, i] = y[i]
        for i in range(mode.shape[0]):
            mode_out[i_out, i] = mode[i]
        i_out += 1
    return i_out


@numba.njit(cache=True, pipeline_class=InlinedPipeline)
def integrate(system, p, y_start, t_start, t_end, t_out, rtol, atol, h_max, method, max_steps,
              max_events, interruptible, scan):
    """Integrate a registered hybrid system from ``t_start`` to ``t_end``.

    Parameters
    ----------
    system, p : int, ndarray
        System id (:mod:`camdyn.systems.registry`) and its parameter vector.
    y_start : ndarray (n,)
        Initial state, of the system's ``state_size`` components.
    t_start, t_end, t_out : float, float, ndarray
        Time span [s] and the increasing output times [s] within it.
    rtol : float
        Relative tolerance of the local error [-].
    atol : float or ndarray
        Absolute tolerance of the local error, one number for every component or one per
        component of the state (``camdyn.integrator.tolerances``) [the components' units].
    h_max : float
        Largest step [s].
    method : int
        ``METHOD_*``: 0 the system's choice per mode, 1 Dormand-Prince 5(4), 2 RODAS4, 3
        DOP853, 4 Adams, 5 Adams and BDF switched, 6 Radau IIA, 7 DOP853 switched to
        Radau IIA in stiff stretches (:mod:`~camdyn.integrator.implicit`).
    max_steps, max_events : int
        Limits on accepted steps and on logged events.
    interruptible : bool
        Poll for Ctrl-C every :data:`~camdyn.integrator.interrupt.POLL_STEPS` steps and
        stop with ``STATUS_INTERRUPTED`` (the caller raises ``KeyboardInterrupt``). Only
        for calls that hold the GIL: not from ``nogil`` or ``parallel`` kernels.
    scan : float
        Longest interval [s] whose guards one cubic checks: a longer step is scanned on
        sub-intervals (:mod:`camdyn.integrator.crossings`); ``math.inf`` for none. All
        required: an omitted argument or a literal is a new type, a whole compile.

    Returns
    -------
    y_out : ndarray (n_out, n)
    mode_out : ndarray (n_out, mode_size)
        Hybrid mode at each output time.
    events : ndarray (n_events, 4 + m + n)
        Event log, columns :func:`event_columns` (``m`` guards).
    counters : ndarray (COUNT_SIZE,) of int64
    """
    y_out, mode_out, events, counters, y, mode = _allocate(system, y_start, t_out.shape[0], max_events)
    stage_arrays, states, guards, scan_arrays, implicit = _workspace(y.shape[0], events.shape[1] - EVENT_GUARDS)
    work, stages, k16, f7, err3, h_regime, pts, matrix, pivots, history = stage_arrays
    y1, f, f1, err, ytmp, ymid, yo = states
    g, gr, g1, gr1, gv, grv, g_tmp, gr_tmp = guards
    t = t_start
    i_out, h, monitor_max = _start(system, t, t_end, h_max, y, f, mode, p, g, gr, t_out, y_out, mode_out, counters)
    n_events, e_accepted, last_event_t = 0, 1e-4, -math.inf
    zeno, retried, lost = 0, False, 0
    while t < t_end:
        h, last, stop = _next_step(t, h, h_max, t_end, max_steps, counters)
        if stop:
            break
        if interruptible and (counters[COUNT_ACCEPTED] + counters[COUNT_REJECTED]) % POLL_STEPS == 0:
            if interrupted():
                counters[COUNT_STATUS] = STATUS_INTERRUPTED
                break
        kind, order, e = _trial_step(system, method, t, y, f, h, mode, p, rtol, atol, work, stages, matrix, pivots,
                                     k16, ytmp, y1, f1, err, err3, history, implicit, counters)
        dwork = f7 if kind == KIND_DOP853 else (history if kind == KIND_NORDSIECK else work)
        ready = kind != KIND_DOP853
        h, outcome = verdict(t, h, e, order, y1, counters)
        if outcome == STEP_RETRY:
            continue
        if outcome == STEP_FAILED:
            break
        _step_end(system, kind, t, h, y1, f1, mode, p, g1, gr1, history, counters)
        ready = midpoint_guards(system, t, h, y, f, y1, f1, dwork, kind, mode, p, k16, ytmp, f7, ymid, gr, gr1,
                                gv, grv, ready, counters)
        tau_event, k_event, ready = earliest_crossing(system, t, h, y, f, y1, f1, dwork, kind, mode, p, k16, ytmp,
                                                      f7, g, gr, g1, gr1, gv, pts, g_tmp, gr_tmp, ready, scan,
                                                      scan_arrays, counters)
        h, retried, lost = retake(system, mode, p, h_regime, k_event, tau_event, h, retried, lost, counters)
        if k_event >= 0 and not retried:
            t_new, i_out, monitor_max = cut_at_event(system, tau_event, t, h, y, f, y1, f1, dwork, kind, mode, p,
                                                      ytmp, yo, g, gr, t_out, i_out, y_out, mode_out, monitor_max)
            n_events = log_event(system, k_event, t_new, y, g, mode, p, events, n_events, monitor_max, counters)
            zeno = zeno + 1 if t_new - last_event_t <= 1e-12 * max(1.0, abs(t_new)) else 0
            if zeno > 1000:
                counters[COUNT_STATUS] = STATUS_ZENO
                break
            last_event_t = t_new
            t = t_new
            monitor_max, h = restart(system, t, h, tau_event, y, f, g, gr, mode, p, h_regime, counters)
            implicit_reset(implicit[0])   # a new mode: DOP853 again, nothing of Radau's kept
        elif k_event < 0:
            ready, h_adams = _adams_start(system, method, kind, ready, t, h, y, y1, f1, mode, p, k16, ytmp, f7,
                                          history, rtol, atol, err, counters)
            h_taken = h
            t, i_out, monitor_max, h = _advance(system, t, h, t_end if last else t + h, e, order, y, f, y1, f1,
                                                dwork, kind, mode, p, k16, ytmp, f7, yo, g, gr, g1, gr1, t_out, i_out,
                                                y_out, mode_out, monitor_max, h_regime, ready, counters)
            h = _proposal(system, method, kind, h_taken, h, h_adams, e, e_accepted, implicit)
            e_accepted = max(e, 1e-4)
    i_out = _fill_end(t, y, mode, t_out, i_out, y_out, mode_out, counters)
    return y_out, mode_out, events[:n_events].copy(), counters
