"""Ctrl-C at random moments in the Python API: every interrupt ends in ``KeyboardInterrupt``
(caught by the script, or uncaught at start-up), never in ``SystemError`` or another
traceback, and the interpreter stays usable for the next call.

The tries run inside a few long-lived Python processes that loop: each try calls the API
afresh, the test sends SIGINT after a seeded random delay, and the process reports
``caught`` from its ``except KeyboardInterrupt``. Fresh processes are also interrupted
during ``import camdyn``, the first ``load_system`` and the loading of the compiled
integrator from numba's cache. A Jupyter kernel's interrupt is tried in
``test_jupyter_interrupt.py``.
"""

from __future__ import annotations

import queue
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

#: Seed of the moments at which the interrupts are sent [-].
SEED = 20261128
#: Longest an interrupt may take to surface as KeyboardInterrupt [s] (the integrator
#: polls every 256 steps, the inline sweep's kernel between points).
PROMPT = 10.0

PREAMBLE = """
import sys, time
print("alive", flush=True)
try:
    import camdyn
    {setup}
except KeyboardInterrupt:
    print("interrupted in start-up", flush=True)
    sys.exit(0)
print("ready", flush=True)
for _ in sys.stdin:
    try:
        print("go", flush=True)
        {call}
        print("finished", flush=True)
    except KeyboardInterrupt as exc:
        print("caught", type(exc).__name__, flush=True)
"""

SIMULATE = PREAMBLE.format(
    setup='rig = camdyn.load_system("sundar2014-impact", {"cam.runout": "3.5 mm"})',
    call='camdyn.simulate(rig, speed=18.0, revolutions=20000, sample_rate=1000.0, variables=["alpha"])')

SWEEP = PREAMBLE.format(
    setup="""from camdyn.sweeps import run_sweep, spec_from_dict
    spec = spec_from_dict({"system": {"source": "sundar2014-impact"},
                           "vary": [{"key": "motion.speed", "start": "8 Hz", "stop": "25 Hz", "num": 64}],
                           "run": {"revolutions": 400, "discard": 10, "chunk": 64},
                           "metrics": {"names": ["impacts"]}, "output": {"path": "inline.nc"}})""",
    call="run_sweep(spec, workers=0, progress=False, restart=True)")

#: A fresh process interrupted anywhere from its imports to inside its simulations: it
#: simulates until it is interrupted, so that the interrupt lands in the run however fast
#: the machine (a warm cache makes the first simulation take well under a second).
START_UP = """
import sys
print("alive", flush=True)
try:
    import camdyn
    rig = camdyn.load_system("sundar2014-impact")
    while True:
        camdyn.simulate(rig, speed=16.0, revolutions=2000, sample_rate=1000.0, variables=["alpha"])
except KeyboardInterrupt as exc:
    print("caught", type(exc).__name__, flush=True)
"""


def _default_sigint():
    # a CI runner may start the tests with SIGINT ignored; Python then installs no
    # KeyboardInterrupt handler: reset it, as a terminal has it
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _start(script: str, cwd) -> subprocess.Popen:
    proc = subprocess.Popen([sys.executable, "-c", script], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, cwd=cwd, preexec_fn=_default_sigint)
    proc.lines = queue.Queue()
    threading.Thread(target=lambda: [proc.lines.put(line.strip()) for line in proc.stdout], daemon=True).start()
    return proc


def _line(proc: subprocess.Popen, timeout: float) -> str:
    """The next line of the process's output ('' if none came within ``timeout`` s)."""
    try:
        return proc.lines.get(timeout=timeout)
    except queue.Empty:
        return ""


def _all_lines(proc: subprocess.Popen) -> list[str]:
    """The lines the process printed and the test has not read yet (it has ended)."""
    lines = []
    while (line := _line(proc, 2.0)) != "":
        lines.append(line)
    return lines


def _clean(err: str) -> bool:
    return not any(word in err for word in ("Traceback", "SystemError", "Exception ignored"))


def _loop(script: str, tries: int, rng: np.random.Generator, cwd) -> list[str]:
    """Interrupt ``tries`` calls of one process at random moments; the outcome of each."""
    proc = _start(script, cwd)
    outcomes = []
    try:
        assert _line(proc, 120) == "alive"
        assert _line(proc, 300) == "ready", proc.stderr.read() if proc.poll() is not None else ""
        for _ in range(tries):
            proc.stdin.write("\n")
            proc.stdin.flush()
            assert _line(proc, 60) == "go"
            # a third of the tries in the call's first 20 ms (checks, preparation, the
            # compiled call's start), the others anywhere in its first half second
            time.sleep(rng.uniform(0.0, 0.02) if rng.random() < 1 / 3 else rng.uniform(0.0, 0.5))
            sent = time.monotonic()
            proc.send_signal(signal.SIGINT)
            reply = _line(proc, PROMPT)
            outcomes.append(reply)
            assert reply in ("caught KeyboardInterrupt", "caught SweepInterrupted"), (
                reply, proc.poll(), proc.stderr.read() if proc.poll() is not None else "")
            assert time.monotonic() - sent < PROMPT
        proc.stdin.close()
        proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    err = proc.stderr.read()
    assert proc.returncode == 0 and _clean(err), err
    return outcomes


@pytest.mark.slow
def test_ctrl_c_at_random_moments_of_simulate_and_of_an_inline_sweep(tmp_path):
    rng = np.random.default_rng(SEED)
    simulated = _loop(SIMULATE, 24, rng, tmp_path)
    swept = _loop(SWEEP, 14, rng, tmp_path)
    assert len(simulated) + len(swept) == 38


@pytest.mark.slow
def test_ctrl_c_during_import_and_the_compiled_cache_load(tmp_path):
    rng = np.random.default_rng(SEED + 1)
    outcomes = []
    for _ in range(12):
        proc = _start(START_UP, tmp_path)
        try:
            assert _line(proc, 120) == "alive"
            time.sleep(rng.uniform(0.0, 2.5))     # import camdyn, load_system, the cache load, the run
            proc.send_signal(signal.SIGINT)
            proc.wait(timeout=60)
            out, err = "\n".join(_all_lines(proc)), proc.stderr.read()
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        assert proc.returncode == 0 and out.endswith("caught KeyboardInterrupt"), (proc.returncode, out, err)
        assert _clean(err), err
        outcomes.append(out)
    assert len(outcomes) == 12
