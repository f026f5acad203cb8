"""What a sweep's worker process runs: the compiled kernel and the metrics of one chunk
of points that the parent has already prepared (parameter vectors, initial states).

This module imports only numpy, numba and camdyn's compiled modules: no SciPy,
pint, xarray, rich or configuration code, so a worker process starts in about half a
second (numba's own import is most of it) instead of 1.5 s, which is what lets a sweep
on 2 workers use both cores for nearly all of its wall time.
"""

from __future__ import annotations

import atexit
import os
import signal
import sys
import threading
import time

import numba
import numpy as np

from camdyn.integrator import driver
from camdyn.sweeps import kernel
from camdyn.sweeps import metrics as M

__all__ = ["warm", "start_local", "run_chunk"]


def _threads(threads: int) -> None:
    numba.set_num_threads(max(1, min(int(threads), numba.config.NUMBA_NUM_THREADS)))


def warm(threads: int = 1, point=None) -> None:
    """Load the compiled kernel (from numba's disk cache) and set the worker's threads.

    Parameters
    ----------
    threads : int
        Numba threads for the kernel's ``prange`` [-].
    point : tuple, optional
        ``(p, y0, period)`` of one prepared point (parameter vector, initial state, cam
        period [s]) to run for 2 revolutions; without it only the threads are set.
    """
    _threads(threads)
    if point is not None:
        p, y0, period = point
        kernel.simulate_points(np.asarray(p, float)[None, :].copy(), np.asarray(y0, float)[None, :].copy(),
                               np.array([float(period)]), 2, 1, 8, 1e-6, 1e-9, 10 ** 6)


def _leave() -> None:
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)


def start_local(threads: int = 1, point=None) -> None:
    """Initializer of a worker process that camdyn started itself (a local pool's, or a
    ``dask="local"`` LocalCluster's): :func:`warm`, and a quick exit.

    A spawned process ends with a full interpreter shutdown, which with numba loaded
    takes 0.2-0.4 s that the parent would spend waiting for the workers to close. Such a
    worker holds nothing to flush but its standard streams (each result has been sent
    whole before the next task is taken, and a closing Dask worker has closed its
    connections before its interpreter ends), so it flushes them and leaves by
    ``os._exit`` once it has been told to stop.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)   # the parent handles Ctrl-C and stops the workers
    # watch the parent from the start: warming may mean loading or compiling the kernel
    # (seconds, a minute on a fresh checkout), and a parent killed meanwhile must not
    # leave the worker behind
    threading.Thread(target=_watch_parent, args=(os.getppid(),), daemon=True, name="camdyn-parent-watch").start()
    warm(threads, point)
    atexit.register(_leave)


def _watch_parent(parent: int, interval: float = 0.5) -> None:
    """Leave when the parent process is gone, whatever killed it (SIGKILL included): the
    worker would otherwise wait on its task queue forever. The compiled kernel releases
    the GIL, so this thread runs while a chunk is computed [interval in s]."""
    while True:
        time.sleep(interval)
        if os.getppid() != parent:
            os._exit(1)


def run_chunk(params: np.ndarray, starts: np.ndarray, periods: np.ndarray, ok: np.ndarray, run: tuple,
              metrics, harmonics: int, threads: int = 1, abort: np.ndarray | None = None) -> dict:
    """Simulate a chunk of prepared points and reduce it to its metrics.

    Parameters
    ----------
    params, starts, periods : ndarray
        As :func:`camdyn.sweeps.kernel.simulate_points` takes them (NaN period: skip).
    ok : ndarray of bool
        Points that were prepared (the others are returned as NaN).
    run : tuple
        ``(revolutions, discard, samples_per_revolution, rtol, atol, max_steps)``.
    metrics, harmonics
        The spec's metric names and number of harmonics.
    threads : int
        Numba threads [-].
    abort : ndarray (1,) of int64, optional
        Stop flag another thread may set (see :func:`camdyn.sweeps.kernel.simulate_points`);
        the chunk then raises ``KeyboardInterrupt`` instead of returning.

    Returns
    -------
    dict
        The metric arrays (:func:`camdyn.sweeps.metrics.compute`) plus ``solver_status``,
        ``accepted_steps``, ``rejected_steps`` and ``events`` per point.
    """
    _threads(threads)
    revolutions, discard, samples, rtol, atol, max_steps = run
    if abort is None:
        abort = np.zeros(1, dtype=np.int64)
    window, onsets, impact_force, counters = kernel.simulate_points(
        params, starts, periods, revolutions, discard, samples, rtol, atol, max_steps, abort)
    if abort[0] != 0:
        raise KeyboardInterrupt
    solver = counters[:, driver.COUNT_STATUS]
    good = ok & (solver == driver.STATUS_OK)
    out = M.compute(window, onsets, impact_force, periods, good, metrics, harmonics, samples)
    out["solver_status"] = solver
    out["accepted_steps"] = counters[:, driver.COUNT_ACCEPTED]
    out["rejected_steps"] = counters[:, driver.COUNT_REJECTED]
    out["events"] = counters[:, driver.COUNT_EVENTS]
    return out
