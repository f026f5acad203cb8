"""Events of the driver (its algorithm's step 4 after the crossing is located): whether to
retake the step so that it ends just past the event, the cut at the event, its entry in
the event log, and the restart in the new mode. Compiled into the driver's loop
(``inline="always"``).
"""

from __future__ import annotations

import numba

from camdyn.integrator.counters import COUNT_ACCEPTED, COUNT_EVENTS, COUNT_EVENTS_DROPPED, COUNT_REJECTED, COUNT_RHS
from camdyn.integrator.sampling import sample
from camdyn.integrator.steppers import dense
from camdyn.systems import registry as systems

#: Columns of the event log: the event's time [s], the guard that crossed, the guard's
#: new expected sign, the largest monitored value since the previous event, then the
#: ``m`` guard values and the ``n`` state components at the event (before any reset).
EVENT_TIME = 0
EVENT_GUARD = 1
EVENT_NEW_SIGN = 2
EVENT_MONITOR = 3
EVENT_GUARDS = 4
#: A step whose event lies between these fractions of it is taken again, ending just
#: past the event (by the margin, a fraction of the new step) [-]; near the step's start
#: the interpolant is as accurate as the state it starts from.
EVENT_RETRY_ABOVE = 0.01
EVENT_RETRY_BELOW = 0.999
EVENT_RETRY_MARGIN = 1e-6
#: Retaken steps in a row that may lose their crossing before the retakes stop until the
#: next event [-].
EVENT_RETRY_LOST = 2
#: The shortest step after an event, and the shortest retaken step, as a fraction of
#: the regime's last step [-].
EVENT_STEP_FLOOR = 1e-3


def event_columns(n: int, m: int) -> tuple[str, ...]:
    """Names of the event log's columns for a system of ``n`` states and ``m`` guards."""
    return (("time", "guard", "new_sign", "monitor_max") + tuple(f"guard{k}" for k in range(m))
            + tuple(f"state{i}" for i in range(n)))


@numba.njit(cache=True, inline="always")
def cut_at_event(system, tau_event, t, h, y, f, y1, f1, dwork, kind, mode, p, ytmp, yo, g, gr, t_out, i_out,
                  y_out, mode_out, monitor_max):
    """Cut the step at the event: fill the output times before it, move the state there
    and take its guards.

    Returns
    -------
    t_new : float
        Time of the event [s].
    i_out : int
        Index of the next output time.
    monitor_max : float
        Largest monitored value since the last event, the event included.
    """
    t_new = t + tau_event * h
    dense(tau_event, h, y, f, y1, f1, dwork, kind, ytmp)
    i_out = sample(t, h, t_new, i_out, t_out, y, f, y1, f1, dwork, kind, mode, yo, y_out, mode_out)
    for i in range(y.shape[0]):
        y[i] = ytmp[i]
    systems.guards(system, t_new, y, y, False, p, g, gr)
    return t_new, i_out, max(monitor_max, systems.monitor(system, t_new, y, mode, p))


@numba.njit(cache=True, inline="always")
def log_event(system, k_event, t_new, y, g, mode, p, events, n_events, monitor_max, counters):
    """Log the event (columns :func:`event_columns`, while the log has room) and switch
    the mode; returns the number of logged events."""
    max_events = events.shape[0]
    if n_events < max_events:
        ev = events[n_events]
        ev[EVENT_TIME] = t_new
        ev[EVENT_GUARD] = k_event
        ev[EVENT_MONITOR] = monitor_max
        m = g.shape[0]
        for k in range(m):
            ev[EVENT_GUARDS + k] = g[k]
        for i in range(y.shape[0]):
            ev[EVENT_GUARDS + m + i] = y[i]
    else:
        counters[COUNT_EVENTS_DROPPED] += 1
    systems.transition(system, k_event, t_new, y, g, mode, p)
    if n_events < max_events:
        events[n_events, EVENT_NEW_SIGN] = systems.expected_sign(system, k_event, mode, p)
        n_events += 1
    counters[COUNT_EVENTS] += 1
    return n_events


@numba.njit(cache=True, inline="always")
def restart(system, t, h, tau_event, y, f, g, gr, mode, p, h_regime, counters):
    """Rates and guards in the new mode at ``t`` [s].

    Returns
    -------
    monitor_max : float
        The monitored quantity at ``t``.
    h : float
        The next trial step [s]: the cut step, at least a tenth of the last, and between
        :data:`EVENT_STEP_FLOOR` times and once the new regime's last step (a contact is
        far faster than free flight; the floor keeps a guard that chatters on rounding
        noise, events a picosecond apart, from shrinking the step tenfold per event
        until it underflows: a longer step still cuts at its first crossing).
    """
    systems.rhs(system, t, y, mode, p, f)
    counters[COUNT_RHS] += 1
    systems.guards(system, t, y, f, True, p, g, gr)   # the rates in the new mode
    monitor_max = systems.monitor(system, t, y, mode, p)
    h = max(h * tau_event, h * 0.1) if tau_event > 0.0 else h
    r_new = systems.regime(system, mode, p)
    if h_regime[r_new] > 0.0:
        h = min(max(h, EVENT_STEP_FLOOR * h_regime[r_new]), h_regime[r_new])
    return monitor_max, h


@numba.njit(cache=True, inline="always")
def retake(system, mode, p, h_regime, k_event, tau_event, h, retaking, lost, counters):
    """Whether to take the step again so that it ends just past its event, and the step
    [s] to take: its end state then carries the step's own error control, not the
    interpolant's (unestimated) error, which is large where the step straddles a point
    at which the mode's right-hand side is not smooth (a Hertz force |delta|^1.5 at
    separation). Not twice in a row (``retaking``: this step is the retaken one), nor for
    an event near the step's start, where the interpolant is as accurate as the state it
    starts from; nor when the retaken step would be shorter than
    :data:`EVENT_STEP_FLOOR` times the regime's last step (a crossing that close is
    rounding noise or a restart's neighbour). A retaken step counts as rejected.

    A retaken step can lose the crossing: a guard that grazes zero moves its crossing
    with the step. ``lost`` counts such steps since the last event; after
    :data:`EVENT_RETRY_LOST` of them the crossing is taken from the interpolant until the
    next event, since each retake of a receding crossing shrinks the step by the
    fraction ``tau_event`` and a sequence of them would end in a vanishing step.

    Returns
    -------
    h : float
        The step to take next [s].
    retake : bool
    lost : int
    """
    if retaking:
        return h, False, lost + 1 if k_event < 0 else 0
    floor = EVENT_STEP_FLOOR * h_regime[systems.regime(system, mode, p)]
    if (k_event >= 0 and EVENT_RETRY_ABOVE < tau_event < EVENT_RETRY_BELOW and lost < EVENT_RETRY_LOST
            and tau_event * h > floor):
        counters[COUNT_ACCEPTED] -= 1
        counters[COUNT_REJECTED] += 1
        return h * tau_event * (1.0 + EVENT_RETRY_MARGIN), True, lost
    return h, False, 0 if k_event >= 0 else lost
