"""The batched compiled kernel: many parameter points per numba call, ``prange`` over points.

Each point is a whole hybrid simulation (:func:`camdyn.integrator.driver.integrate`) from its
static equilibrium, sampled ``samples`` times per cam period over the kept window (after
the discarded transient). The kernel returns the window's channels and, from the event
log, the contact onsets in the window and the peak impact force, so nothing but the
window ever leaves compiled code. Points are independent: a point's result does not
depend on the batch it runs in, or on the number of threads.

The kernel releases the GIL (``nogil``): a Dask worker runs it in a thread beside its
event loop, which must keep answering the scheduler's heartbeats through a chunk that
may take minutes (a worker silent for ``distributed.scheduler.worker-ttl``, 5 min by
default, is declared dead).
"""

from __future__ import annotations

import numba
import numpy as np

from camdyn.integrator import driver
from camdyn.model.geometry import rigid_angles
from camdyn.model.outputs import derived
from camdyn.simulation.limits import SCAN_FRACTION, STEP_FRACTION
from camdyn.systems import registry as systems

#: channels of the window, in the order of the kernel's ``window`` output
WINDOW = ("alpha", "alpha_dot", "alpha_ddot", "Fn", "sliding_velocity", "in_contact", "alpha_rigid")
N_WINDOW = len(WINDOW)
_DERIVED = (0, 3, 8, 14)   # columns of outputs.CHANNELS: alpha_ddot, Fn, sliding_velocity, in_contact


@numba.njit(cache=True, parallel=True, nogil=True)
def simulate_points(params, starts, periods, revolutions, discard, samples, rtol, atol, max_steps, abort=None):
    """Simulate every point of a batch.

    Parameters
    ----------
    params : ndarray (n, SIZE)
        Packed parameter vectors (:func:`camdyn.model.layout.pack`).
    starts : ndarray (n, 3)
        Initial states (alpha [rad], alpha_dot [rad/s], cam work [J]).
    periods : ndarray (n,)
        Cam period of each point [s]; NaN marks a point not to simulate.
    revolutions, discard : int
        Cam periods simulated, and discarded at the start [-].
    samples : int
        Window samples per cam period [-].
    rtol, atol : float
        Local error tolerances.
    max_steps : int
        Step limit per point.
    abort : ndarray (1,), optional
        Set ``abort[0]`` nonzero from another thread to stop: the points not yet begun are
        skipped with status ``STATUS_INTERRUPTED`` (the kernel releases the GIL, so the
        caller's thread can do this on Ctrl-C while it runs).

    Returns
    -------
    window : ndarray (n, N_WINDOW, (revolutions - discard) * samples)
        Channels :data:`WINDOW` at ``t = (discard + k / samples) * period``.
    onsets : ndarray (n,)
        Contact onsets (impacts) inside the window [-].
    impact_force : ndarray (n,)
        Largest normal force during impacts inside the window [N].
    counters : ndarray (n, driver.COUNT_SIZE) of int64
        Solver counters; column ``driver.COUNT_STATUS`` is the status.
    """
    n = params.shape[0]
    kept = revolutions - discard
    m = kept * samples
    window = np.full((n, N_WINDOW, m), np.nan)
    onsets = np.zeros(n)
    impact_force = np.zeros(n)
    counters = np.zeros((n, driver.COUNT_SIZE), dtype=np.int64)
    max_events = 64 + 64 * revolutions
    for i in numba.prange(n):
        period = periods[i]
        if not (period > 0.0):
            continue
        if abort is not None and abort[0] != 0:
            counters[i, driver.COUNT_STATUS] = driver.STATUS_INTERRUPTED
            continue
        p = params[i]
        t_start_window = discard * period
        t_out = np.empty(m)
        for k in range(m):
            t_out[k] = t_start_window + k * (period / samples)
        t_end = revolutions * period
        # np.bool_(False), not the literal: a literal is a type of its own to numba, and
        # each new argument type is a whole compile of the driver
        y, modes, events, count = driver.integrate(
            systems.CAM_FOLLOWER, p, starts[i], 0.0, t_end, t_out, rtol, atol, period * STEP_FRACTION,
            driver.METHOD_AUTO, max_steps, max_events, np.bool_(False), period * SCAN_FRACTION)
        if count[driver.COUNT_EVENTS_DROPPED] > 0 and count[driver.COUNT_STATUS] == driver.STATUS_OK:
            # the log ran out of room: the same run again, with room for every event
            y, modes, events, count = driver.integrate(
                systems.CAM_FOLLOWER, p, starts[i], 0.0, t_end, t_out, rtol, atol, period * STEP_FRACTION,
                driver.METHOD_AUTO, max_steps, count[driver.COUNT_EVENTS] + 16, np.bool_(False), period * SCAN_FRACTION)
        counters[i, :] = count
        if count[driver.COUNT_STATUS] != driver.STATUS_OK:
            continue
        chans = derived(t_out, y, modes, p)
        thetas = chans[:, 12]
        rigid = rigid_angles(thetas, p, starts[i, 0])
        for k in range(m):
            window[i, 0, k] = y[k, 0]
            window[i, 1, k] = y[k, 1]
            for j in range(4):
                window[i, 2 + j, k] = chans[k, _DERIVED[j]]
            window[i, 6, k] = rigid[k]
        peak = 0.0
        count_on = 0
        for e in range(events.shape[0]):
            if events[e, 0] < t_start_window:
                continue
            if events[e, 1] == 0 and events[e, 2] > 0:
                count_on += 1
            peak = max(peak, events[e, driver.EVENT_MONITOR])
        onsets[i] = count_on
        impact_force[i] = peak
    return window, onsets, impact_force, counters


__all__ = ["WINDOW", "simulate_points"]
