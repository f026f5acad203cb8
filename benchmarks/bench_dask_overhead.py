"""Where a sweep on a Dask LocalCluster started by the sweep (``--dask local``) spends the
time that the local pool does not (docs/sweeps.md, "Scaling").

On the bifurcation sweep of benchmarks/bench_sweep.py (400 speeds x 300 revolutions) on 2
workers, local pool against Dask, interleaved (``--repeat``, default 2), with every chunk
timed inside its worker:

- when the first chunk starts after the sweep begins (the workers' start);
- the chunks' summed wall time against their summed CPU time in the workers (the
  difference: the workers waiting for a core that the parent's scheduler, client and
  nannies, or the parent's own work, hold);
- the parent's CPU during the sweep.

Also the cost of the submission path alone (400 real chunks of 5 points x 2 revolutions,
four in flight, on already started workers) and the import time of ``distributed`` and of
camdyn's worker module in a fresh interpreter.

Usage:  python benchmarks/bench_dask_overhead.py [--repeat N]   (writes benchmarks/dask_overhead.json)
"""

from __future__ import annotations

import argparse
import json
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).parent


def timed_chunk(*args):
    """``worker.run_chunk`` with its wall time, its process's CPU time and its start
    (``time.perf_counter``, system-wide on Linux) added to the result. Defined in the
    script, so the local pool's workers find it in ``__mp_main__`` and Dask's receive it
    by value."""
    from camdyn.sweeps import worker

    start, cpu = time.perf_counter(), time.process_time()
    out = worker.run_chunk(*args)
    out["_timing"] = (time.perf_counter() - start, time.process_time() - cpu, start)
    return out


def chunk_timeline(tmp: Path, dask: str | None) -> dict:
    """One sweep on 2 workers with every chunk timed inside its worker."""
    from types import SimpleNamespace

    from bench_sweep import bifurcation

    import camdyn.sweeps.execution as execution
    from camdyn.sweeps import run_sweep, spec_from_dict

    timings = []
    finish, module = execution._finish, execution.worker

    def record(prepared, result):
        timings.append(result.pop("_timing"))
        return finish(prepared, result)

    execution._finish = record
    execution.worker = SimpleNamespace(run_chunk=timed_chunk, start_local=module.start_local, warm=module.warm)
    try:
        spec = spec_from_dict(bifurcation(tmp / "timeline.nc", 400, 300, 200))
        before = resource.getrusage(resource.RUSAGE_SELF)
        start = time.perf_counter()
        run_sweep(spec, workers=2, dask=dask, progress=False, restart=True).close()
        wall = time.perf_counter() - start
        after = resource.getrusage(resource.RUSAGE_SELF)
    finally:
        execution._finish, execution.worker = finish, module
    return {"wall_s": wall, "first_chunk_start_s": min(t[2] for t in timings) - start,
            "chunks_wall_s": sum(t[0] for t in timings), "chunks_cpu_s": sum(t[1] for t in timings),
            "parent_cpu_s": after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime}


def submission_cost(tmp: Path, dask: str | None, chunks: int = 400) -> float:
    """Seconds for ``chunks`` real chunks (5 points x 2 revolutions) through the executor,
    four in flight, on workers that have started."""
    import concurrent.futures as cf

    from bench_sweep import bifurcation

    from camdyn.sweeps import spec_from_dict, worker
    from camdyn.sweeps.execution import _executor, _run_args, prepare_chunk

    spec = spec_from_dict(bifurcation(tmp / "submit.nc", 400, 2, 1))
    args = _run_args(spec, prepare_chunk(spec, 10), 1)
    with _executor(2, dask, 1, None) as (pool, _n, _how):
        pool.submit(worker.run_chunk, *args).result()
        start = time.perf_counter()
        pending = set()
        for _ in range(chunks):
            pending.add(pool.submit(worker.run_chunk, *args))
            if len(pending) >= 4:
                done, pending = cf.wait(pending, return_when=cf.FIRST_COMPLETED)
                for future in done:
                    future.result()
        cf.wait(pending)
        return time.perf_counter() - start


def import_seconds(module: str) -> float:
    code = f"import time; s = time.perf_counter(); import {module}; print(time.perf_counter() - s)"
    return float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeat", type=int, default=2)
    args = parser.parse_args()
    sys.path.insert(0, str(HERE))
    result = {"machine": platform.machine(), "python": platform.python_version(), "sweep": "400 speeds x 300 "
              "revolutions, 2 workers", "timeline": {"local": [], "dask": []}, "submission_400_chunks_s": {}}
    labels = {"local": None, "dask": "local"}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for _ in range(args.repeat):   # interleaved
            for label, dask in labels.items():
                run = chunk_timeline(tmp, dask)
                result["timeline"][label].append(run)
                print(f"{label}: wall {run['wall_s']:.2f} s, first chunk at {run['first_chunk_start_s']:.2f} s, "
                      f"chunks {run['chunks_wall_s']:.2f} s wall / {run['chunks_cpu_s']:.2f} s CPU, parent CPU "
                      f"{run['parent_cpu_s']:.2f} s", flush=True)
        for label, dask in labels.items():
            result["submission_400_chunks_s"][label] = submission_cost(tmp, dask)
            print(f"{label}: 400 short chunks through the executor in "
                  f"{result['submission_400_chunks_s'][label]:.2f} s", flush=True)
    result["import_s"] = {m: import_seconds(m) for m in ("distributed", "camdyn.sweeps.worker")}
    print("imports in a fresh interpreter: " + ", ".join(f"{m} {s:.2f} s" for m, s in result["import_s"].items()))
    out = HERE / "dask_overhead.json"
    out.write_text(json.dumps(result, indent=2))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
