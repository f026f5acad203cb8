"""Running a sweep: chunks of points on local worker processes or a Dask cluster, through
the standard :class:`concurrent.futures.Executor` interface, with a progress bar and a
checkpoint per finished chunk.

- Local (default): a :class:`~concurrent.futures.ProcessPoolExecutor` of ``workers``
  processes (default: every core), started with ``spawn`` (numba's threads do not
  survive ``fork``); each loads the compiled kernel from numba's on-disk cache once (the
  first run on a machine compiles it, about 10 s; numba writes its cache atomically).
  The parent prepares every point (configuration, static equilibrium) and the workers
  run only :mod:`camdyn.sweeps.worker`, which imports no pint, xarray or configuration
  code, so they start in about half a second.
- Dask: ``dask="local"`` starts a ``LocalCluster`` of ``workers`` single-threaded worker
  processes; ``dask="tcp://HOST:PORT"`` connects to a running scheduler (for example one
  started by dask-jobqueue on an HPC system, see docs/sweeps.md). The client's executor
  (``Client.get_executor``) takes the same calls as the local pool, and ``Client.run``
  warms the compiled code once per worker. A LocalCluster that camdyn starts runs with
  Dask's background chores slowed down (:data:`QUIET_DASK`: at Dask's defaults an idle
  2-worker cluster takes 10-13 % of a core, which on a 2-core machine comes straight out of
  the workers' time), and its workers leave quickly when it closes, as the local pool's
  do (:func:`camdyn.sweeps.worker.start_local`).
- Inline: ``workers=0`` runs the chunks in this process, one after another, with the
  kernel's ``prange`` over the points of a chunk on ``threads`` threads.

Chunks are dealt out dynamically (at most two per worker in flight), which balances
points of very different cost (free flight against chattering contact) better than a
static split, and bounds memory: a finished chunk is written to disk and dropped.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import multiprocessing
import os
import re
import socket
import threading
import warnings

import numpy as np
import xarray as xr
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from camdyn.errors import CamdynError, ParameterError, SimulationError, SweepInterrupted
from camdyn.integrator import driver
from camdyn.model.layout import SIZE
from camdyn.simulation.runner import penetration_resolution, prepare
from camdyn.sweeps import families, worker
from camdyn.sweeps.families import STATUS_OK, STATUS_REFUSED, STATUS_SOLVER
from camdyn.sweeps.spec import SweepSpec
from camdyn.sweeps.store import Checkpoint

__all__ = ["check_dask_address", "check_threads", "probe_dask_scheduler", "quiet_resource_tracker", "compute_chunk",
           "prepare_chunk", "run_sweep", "default_workers", "QUIET_DASK"]

MAX_STEPS_PER_REVOLUTION = 200_000

#: Longest the check of a Dask scheduler's address waits for a TCP connection [s]; the
#: client's own connection then waits up to 20 s.
SCHEDULER_PROBE_TIMEOUT = 5.0

#: Dask settings for the LocalCluster of ``dask="local"`` (and this process's client):
#: the event-loop watchdog (default every 20 ms), the workers' statistical profiler
#: (every 10 ms, for the dashboard, which a camdyn LocalCluster does not serve), the
#: memory monitor (100 ms) and the system monitor (500 ms). Together they cut an idle
#: 2-worker cluster's CPU use from 0.10-0.13 to 0.015 cores (measured, benchmarks/bench_sweep.py).
QUIET_DASK = {"distributed.admin.tick.interval": "1s", "distributed.worker.profile.enabled": False,
              "distributed.worker.memory.monitor-interval": "1s",
              "distributed.admin.system-monitor.interval": "2s",
              "distributed.deploy.cluster-repr-interval": "10s"}


def default_workers() -> int:
    """Cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def check_workers(workers, dask: str | None = None) -> int:
    """The number of workers asked for: a whole number >= 0, refused otherwise; more
    local processes than this process's cores (:func:`default_workers`) only compete
    for them, so such a number is lowered to the cores, with a warning (a Dask
    cluster's workers are not counted against the local cores)."""
    if isinstance(workers, bool) or not isinstance(workers, (int, np.integer)) or workers < 0:
        raise ParameterError(f"workers must be a whole number >= 0, got {workers!r}")
    cores = default_workers()
    if dask is None and workers > cores:
        warnings.warn(f"workers = {workers} is more than the {cores} cores this process may use; using {cores}",
                      UserWarning, stacklevel=3)
        return cores
    return int(workers)


def check_threads(threads, workers: int, dask: str | None = None) -> int:
    """The numba threads per worker asked for: a whole number >= 1, refused otherwise.
    Local processes (``workers``, at least this one) times their threads beyond this
    process's cores only compete for them, so ``threads`` is lowered to the cores per
    process, with a warning (a Dask cluster's workers are not counted)."""
    if isinstance(threads, bool) or not isinstance(threads, (int, np.integer)) or threads < 1:
        raise ParameterError(f"threads must be a whole number >= 1, got {threads!r}")
    processes, cores = max(int(workers), 1), default_workers()
    if dask is None and processes * threads > cores:
        capped = max(1, cores // processes)
        warnings.warn(f"threads = {threads} per worker on {processes} process(es) is more than the {cores} cores "
                      f"this process may use; using {capped}", UserWarning, stacklevel=3)
        return capped
    return int(threads)


def prepare_chunk(spec: SweepSpec, chunk: int) -> dict:
    """Parameter vectors, initial states and cam periods of chunk ``chunk`` (in the parent).

    A point that cannot be prepared (impossible geometry, no equilibrium, speed 0) is
    marked refused with its reason and skipped by the kernel (NaN period).
    """
    start = chunk * spec.chunk
    n = min(start + spec.chunk, spec.points) - start
    base = spec.base_system()
    params = np.zeros((n, SIZE))
    starts = np.zeros((n, 3))
    periods = np.full(n, np.nan)
    status = np.zeros(n, dtype=np.int8)
    failure = [""] * n
    for i in range(n):
        try:
            prep = prepare(base.with_values(**spec.point_values(start + i)))
            period = prep.system.motion.period
            if not np.isfinite(period):
                raise ParameterError("the cam does not move (speed 0)")
        except (CamdynError, ValueError, ArithmeticError) as exc:
            status[i] = STATUS_REFUSED
            failure[i] = f"{type(exc).__name__}: {exc}"
            continue
        params[i] = prep.p
        starts[i] = prep.y0
        periods[i] = period
    return {"params": params, "starts": starts, "periods": periods, "status": status, "failure": failure}


def _run_args(spec: SweepSpec, prepared: dict, threads: int) -> tuple:
    """Arguments of :func:`camdyn.sweeps.worker.run_chunk` (arrays and plain values only:
    a worker unpickles them without importing the spec or configuration code)."""
    run = (spec.revolutions, spec.discard, spec.samples_per_revolution, spec.rtol, spec.atol,
           MAX_STEPS_PER_REVOLUTION * spec.revolutions)
    return (prepared["params"], prepared["starts"], prepared["periods"], prepared["status"] == STATUS_OK, run,
            tuple(spec.metrics), spec.harmonics, threads)


def _finish(prepared: dict, result: dict) -> dict:
    """Merge a worker's result with the chunk's preparation: status and failure reason."""
    status = prepared["status"].copy()
    failure = list(prepared["failure"])
    solver = result.pop("solver_status")
    for i in range(status.size):
        if status[i] == STATUS_OK and solver[i] != driver.STATUS_OK:
            status[i] = STATUS_SOLVER
            failure[i] = f"SimulationError: {driver.STATUS_MESSAGES[int(solver[i])]}"
    result["status"] = status
    result["failure"] = np.array(failure, dtype=str)
    return result


def compute_chunk(spec: SweepSpec, chunk: int, threads: int = 1) -> dict:
    """Simulate chunk ``chunk`` of ``spec`` in this process and return its metric and
    bookkeeping arrays (what a worker computes, merged with the preparation).

    The compiled kernel runs on a helper thread (it releases the GIL) while this thread
    waits, so that Ctrl-C raises ``KeyboardInterrupt`` here at once: the kernel is told
    to stop through its abort flag and skips the points it has not begun.
    """
    if spec.runner:   # Python runs, one point after another: Ctrl-C stops between two
        function, args, prepared, finish = _chunk_task(spec, chunk, threads)
        return finish(prepared, function(*args))
    prepared = prepare_chunk(spec, chunk)
    abort = np.zeros(1, dtype=np.int64)
    result = {}

    def run():
        try:
            result["value"] = worker.run_chunk(*_run_args(spec, prepared, threads), abort=abort)
        except BaseException as exc:   # handed to the waiting thread
            result["error"] = exc

    thread = threading.Thread(target=run, name="camdyn-chunk", daemon=True)
    thread.start()
    try:
        while thread.is_alive():
            thread.join(0.05)
    except BaseException:
        abort[0] = 1
        thread.join()
        raise
    if "error" in result:
        raise result["error"]
    return _finish(prepared, result["value"])


def _warm_point(base):
    """``(p, y0, period)`` of the prepared base system for warming workers, or None."""
    if base is None or not np.isfinite(base.system.motion.period):
        return None
    return base.p, base.y0, base.system.motion.period


#: The warnings filter that keeps multiprocessing's resource tracker quiet.
QUIET_TRACKER = "ignore::UserWarning:multiprocessing.resource_tracker"


def quiet_resource_tracker() -> None:
    """Keep the resource tracker process, which multiprocessing starts for the worker
    pools, from writing to this process's standard error.

    When an interrupt terminates the workers, the tracker may find a lock it still lists
    but which is already gone, and warns about it (two ``UserWarning`` lines with
    tracebacks) after camdyn has printed its one line. The tracker is a separate Python
    process that reads ``PYTHONWARNINGS`` when it starts, so the filter is added there
    before the first pool starts it; other warnings are untouched.
    """
    current = os.environ.get("PYTHONWARNINGS", "")
    if QUIET_TRACKER not in current.split(","):
        os.environ["PYTHONWARNINGS"] = f"{current},{QUIET_TRACKER}" if current else QUIET_TRACKER


@contextlib.contextmanager
def _executor(workers: int, dask: str | None, threads: int, point):
    """Yield ``(executor or None, number of workers, description)``."""
    if workers != 0 or dask is not None:
        quiet_resource_tracker()
    if dask is None:
        if workers == 0:
            yield None, 1, f"inline, {threads} thread(s)"
            return
        ctx = multiprocessing.get_context("spawn")
        pool = cf.ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=worker.start_local,
                                      initargs=(threads, point))
        try:
            yield pool, workers, f"{workers} local worker process(es)"
        except BaseException:
            _stop_workers(pool)
            raise
        pool.shutdown(wait=True)
        return
    try:
        import dask as dask_config
        from distributed import Client, LocalCluster
    except ImportError:
        raise ParameterError("running on Dask needs dask.distributed: pip install 'camdyn[cluster]'") from None
    with contextlib.ExitStack() as stack:
        if dask == "local":
            stack.enter_context(dask_config.config.set(QUIET_DASK))
            cluster = stack.enter_context(LocalCluster(n_workers=max(workers, 1), threads_per_worker=1,
                                                       processes=True, dashboard_address=None))
            client = stack.enter_context(Client(cluster))
            client.run(worker.start_local, threads, point)   # camdyn's own workers: warm, and a quick exit
        else:
            try:
                client = stack.enter_context(Client(dask, timeout="20s"))
            except (OSError, TimeoutError) as exc:
                raise ParameterError(f"cannot reach the Dask scheduler at {dask!r} ({exc})") from None
            client.run(worker.warm, threads, point)
        n = len(client.scheduler_info()["workers"])
        yield client.get_executor(), max(n, 1), f"Dask at {client.scheduler.address} ({n} workers)"


def check_dask_address(dask: str | None) -> None:
    """Refuse a ``dask`` setting that is neither ``"local"`` nor a scheduler address
    ``PROTOCOL://HOST:PORT`` (tcp, tls, ucx, ws, wss or inproc)."""
    if dask is None or (isinstance(dask, str) and dask == "local"):
        return
    if not (isinstance(dask, str) and re.fullmatch(r"(tcp|tls|ucx|ws|wss)://[\w.\-\[\]:]+:\d+|inproc://\S+", dask)):
        raise ParameterError(f"--dask must be 'local' or a scheduler address such as tcp://10.0.0.5:8786, "
                             f"got {dask!r}")


def probe_dask_scheduler(dask: str | None, timeout: float = SCHEDULER_PROBE_TIMEOUT) -> None:
    """Refuse a ``tcp://`` scheduler address that cannot be reached, before the sweep
    writes anything (its checkpoint folder, its lock): a host name that does not resolve
    or a port that refuses the connection at once, an unreachable host after ``timeout``
    seconds. Other protocols (tls, ucx, ws, inproc) and ``"local"`` are left to Dask.

    Raises
    ------
    ParameterError
        Naming the address and why it cannot be reached.
    """
    if not isinstance(dask, str) or not dask.startswith("tcp://"):
        return
    host, _, port = dask[len("tcp://"):].rpartition(":")
    host = host.strip("[]")
    try:
        socket.getaddrinfo(host, int(port), type=socket.SOCK_STREAM)
    except (socket.gaierror, UnicodeError, ValueError, OverflowError) as exc:
        raise ParameterError(f"cannot reach the Dask scheduler at {dask!r}: the host {host!r} is not known "
                             f"({getattr(exc, 'strerror', None) or exc})") from None
    try:
        with socket.create_connection((host, int(port)), timeout=timeout):
            pass
    except (OSError, ValueError, OverflowError) as exc:
        why = f"no answer within {timeout:g} s" if isinstance(exc, TimeoutError) else exc.strerror or str(exc)
        raise ParameterError(f"cannot reach the Dask scheduler at {dask!r} ({why})") from None


def _stop_workers(pool: cf.ProcessPoolExecutor) -> None:
    """Stop a local pool at once (an interrupt or a failure): queued chunks are cancelled
    and the worker processes terminated, not waited for."""
    processes = list(getattr(pool, "_processes", {}).values())   # the pool has no public handle on them
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        with contextlib.suppress(Exception):
            process.terminate()
    for process in processes:
        with contextlib.suppress(Exception):
            process.join(timeout=5)


def _prepare_base(spec: SweepSpec):
    """The base system made ready for the kernel, or None where it cannot be (its points
    are then refused one by one, with their reasons) or where the sweep's points run in
    Python (a mechanism's, a protocol model's), not in the kernel."""
    if spec.runner:
        return None
    try:
        return prepare(spec.base_system())
    except CamdynError:
        return None


def _check_resolution(spec: SweepSpec, base, say) -> None:
    """Warn when the tolerances cannot resolve the base system's static penetration."""
    if base is None:
        return
    ratio = penetration_resolution(base, spec.rtol, spec.atol)
    if ratio > 0.1:
        say(f"warning: rtol = {spec.rtol:g}, atol = {spec.atol:g} allow an error of {ratio:.2g} times the static "
            f"penetration, so the solver's own error may open the contact (spurious impacts); set [run] rtol "
            f"near {spec.rtol * 0.1 / ratio:.1g} (and atol lower) to resolve it")


def run_sweep(spec: SweepSpec, workers: int | None = None, dask: str | None = None, threads: int = 1,
              progress: bool = True, restart: bool = False, keep_parts: bool = False,
              echo=None) -> xr.Dataset:
    """Run ``spec`` (resuming from its checkpoints) and return the result.

    Parameters
    ----------
    spec : SweepSpec
        From :func:`camdyn.sweeps.load_spec` or :func:`camdyn.sweeps.spec_from_dict`.
    workers : int, optional
        Local worker processes (default every core); 0 runs inline in this process.
        With ``dask="local"``, the number of Dask workers.
    dask : str, optional
        ``"local"`` for a LocalCluster, or a scheduler address ``"tcp://HOST:PORT"``.
    threads : int
        Numba threads per worker for the kernel's ``prange`` (default 1: the
        processes already use every core).
    progress : bool
        Show a progress bar with the time remaining.
    restart : bool
        Discard existing checkpoints of this output instead of resuming.
    keep_parts : bool
        Keep the per-chunk checkpoint files after the result is written.
    echo : callable, optional
        Receives one-line status messages (default: none).

    Returns
    -------
    xarray.Dataset
        The result file opened lazily (the data stays on disk until used).
    """
    if not isinstance(spec, SweepSpec):
        hint = (f" (load it first: camdyn.sweeps.load_spec({spec!r}))" if isinstance(spec, (str, os.PathLike))
                else "")
        raise ParameterError(f"expected a SweepSpec (from camdyn.sweeps.load_spec or spec_from_dict), got "
                             f"{type(spec).__name__} {spec!r:.60}{hint}")
    workers = default_workers() if workers is None else check_workers(workers, dask)
    threads = check_threads(threads, workers, dask)
    check_dask_address(dask)
    probe_dask_scheduler(dask)
    say = echo or (lambda _msg: None)
    store = Checkpoint(spec, restart=restart, say=say)
    try:
        _compute_missing(spec, store, workers, dask, threads, progress, say)
        path = store.assemble(keep_parts=keep_parts)
    except KeyboardInterrupt:
        saved = len(store.done())
        raise SweepInterrupted(f"interrupted: {saved} of {spec.chunks} chunks are saved in {store.folder}; "
                               f"run the same command again to resume") from None
    except Exception:
        store.discard_if_unused()   # refused or failed before its first chunk: nothing left behind
        raise
    finally:
        store.close()
    return xr.open_dataset(path, engine="h5netcdf")


def _compute_missing(spec: SweepSpec, store: Checkpoint, workers, dask, threads, progress, say) -> None:
    """Compute and save the chunks not yet on disk."""
    done = store.done()
    todo = [c for c in range(spec.chunks) if c not in done]
    base = _prepare_base(spec)
    _check_resolution(spec, base, say)
    if done:
        say(f"resuming: {len(done)} of {spec.chunks} chunks already on disk in {store.folder}")
    if not todo:
        return
    columns = (TextColumn("[bold]{task.description}"), BarColumn(), MofNCompleteColumn(),
               TextColumn("points"), TimeElapsedColumn(), TimeRemainingColumn())
    with Progress(*columns, disable=not progress) as bar, \
            _executor(workers, dask, threads, _warm_point(base)) as (pool, n, how):
        say(f"{spec.points} points in {spec.chunks} chunks of {spec.chunk} on {how}")
        task = bar.add_task(spec.name, total=spec.points, completed=sum(_chunk_size(spec, c) for c in done))
        if pool is None:
            for c in todo:
                store.save(c, compute_chunk(spec, c, threads))
                bar.advance(task, _chunk_size(spec, c))
        else:
            _drain(pool, n, spec, todo, threads, store, lambda c: bar.advance(task, _chunk_size(spec, c)))


def _chunk_size(spec: SweepSpec, chunk: int) -> int:
    return min(spec.chunk, spec.points - chunk * spec.chunk)


def _chunk_task(spec: SweepSpec, chunk: int, threads: int) -> tuple:
    """``(function, arguments, preparation, finish)`` of one chunk: what a worker runs,
    prepared in the parent, and how its result is merged with the preparation (the
    compiled kernel of the rocking cam-follower, or the Python runs of the family's runner,
    :func:`camdyn.sweeps.families.chunk_task`)."""
    task = families.chunk_task(spec, chunk)
    if task is not None:
        return task
    prepared = prepare_chunk(spec, chunk)
    return worker.run_chunk, _run_args(spec, prepared, threads), prepared, _finish


def _drain(pool, n_workers, spec, todo, threads, store, advance) -> None:
    """Keep at most two chunks per worker in flight; the parent prepares each chunk just
    before it is submitted and saves each result as it arrives."""
    queue = list(reversed(todo))
    pending = {}
    try:
        while queue or pending:
            while queue and len(pending) < 2 * n_workers:
                c = queue.pop()
                function, args, prepared, finish = _chunk_task(spec, c, threads)
                pending[pool.submit(function, *args)] = (c, prepared, finish)
            finished, _ = cf.wait(pending, return_when=cf.FIRST_COMPLETED)
            for fut in finished:
                c, prepared, finish = pending.pop(fut)
                try:
                    result = fut.result()
                except CamdynError:
                    raise
                except Exception as exc:  # a worker died or the code failed: keep what is done
                    raise SimulationError(f"chunk {c} failed on its worker ({type(exc).__name__}: {exc}); "
                                          f"finished chunks are kept, rerun to resume") from exc
                store.save(c, finish(prepared, result))
                advance(c)
    finally:
        for fut in pending:
            fut.cancel()
