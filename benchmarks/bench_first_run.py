"""The first hour, timed: a fresh clone of this repository, its set-up, and the first run of
each kind of command on an empty numba cache, as a new user meets them.

    python benchmarks/bench_first_run.py [--keep DIR]

It clones the current commit into a temporary folder, runs ``make install`` there (which
creates the clone's ``.venv``), then each command of :data:`COMMANDS` in order, in a
scratch folder, with the clone's numba cache and camdyn's model cache empty at the start
(so the first command compiles the core, and later ones show what they compile beyond
it). Wall times go to ``benchmarks/first_run.json`` and are printed.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: (label, arguments of the clone's camdyn), in the order a new user might run them
COMMANDS = (
    ("simulate alzate (translating follower)", ["simulate", "alzate", "--revolutions", "5"]),
    ("simulate sundar2014-impact (after it)", ["simulate", "sundar2014-impact", "--revolutions", "5"]),
    ("lyapunov", ["lyapunov", "sundar2014-impact", "--set", "cam.runout=3.5mm", "--speed", "18Hz",
                  "--revolutions", "40", "--transient", "20"]),
    ("sweep examples/sweeps/bifurcation.toml", ["sweep", "{clone}/examples/sweeps/bifurcation.toml", "--no-plot"]),
    ("simulate the valve train (a model of your own)",
     ["simulate", "{clone}/examples/models/valve_train.py:VALVE_TRAIN", "--speed", "40Hz", "--revolutions", "3"]),
    ("simulate sundar2014-impact again (warm)", ["simulate", "sundar2014-impact", "--revolutions", "5"]),
)


def timed(argv, cwd, env) -> tuple[float, int]:
    start = time.perf_counter()
    run = subprocess.run(argv, cwd=cwd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if run.returncode:
        print(run.stderr[-2000:], file=sys.stderr)
    return time.perf_counter() - start, run.returncode


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--keep", type=Path, help="clone into this folder and keep it")
    args = parser.parse_args()
    folder = args.keep or Path(tempfile.mkdtemp(prefix="camdyn-first-run-"))
    clone = folder / "camdyn"
    shutil.rmtree(clone, ignore_errors=True)
    subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
    env = dict(os.environ, CAMDYN_CACHE_DIR=str(folder / "models"))
    env.pop("NUMBA_CACHE_DIR", None)
    results = {}
    seconds, rc = timed(["make", "install"], clone, env)
    results["make install"] = {"seconds": round(seconds, 1), "status": rc}
    print(f"{seconds:7.1f} s  make install")
    scratch = folder / "scratch"
    scratch.mkdir(exist_ok=True)
    camdyn = str(clone / ".venv" / "bin" / "camdyn")
    for label, argv in COMMANDS:
        seconds, rc = timed([camdyn, *[a.format(clone=clone) for a in argv]], scratch, env)
        results[label] = {"seconds": round(seconds, 1), "status": rc}
        print(f"{seconds:7.1f} s  {label}" + (f"  (exit {rc})" if rc else ""))
    out = {"machine": f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores",
           "python": platform.python_version(), "results": results}
    (ROOT / "benchmarks" / "first_run.json").write_text(json.dumps(out, indent=1) + "\n")
    if args.keep is None:
        shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
