"""Interrupting a Jupyter kernel that runs camdyn (``jupyter_client``'s ``interrupt_kernel``,
what the notebook's "interrupt" button does): every interrupt ends the cell in
``KeyboardInterrupt``, never in ``SystemError`` or a crash, and the kernel runs the next
cell.

The cells loop over their call until interrupted, so the work is always still running
when the interrupt lands, however fast the machine: the test waits for the cell's first
line (the loop has started), then after a seeded random delay interrupts the kernel. The
first cell imports camdyn and loads the compiled integrator from numba's cache, so its
interrupt may land in the import or the cache load. Skipped only where ``jupyter_client``
or ``ipykernel`` cannot be imported (both are in the ``test`` extras).
"""

from __future__ import annotations

import queue
import time

import numpy as np
import pytest

pytest.importorskip("ipykernel")
manager = pytest.importorskip("jupyter_client.manager")

#: Seed of the delays before each interrupt [-].
SEED = 20261201
#: Longest a cell may take to end after its interrupt [s] (generous: two busy cores).
PROMPT = 30.0

#: The first cell: from the import, through the cache load, to simulations until stopped.
FIRST = """
print("started", flush=True)
import camdyn
rig = camdyn.load_system("sundar2014-impact")
while True:
    camdyn.simulate(rig, speed=16.0, revolutions=2000, sample_rate=1000.0, variables=["alpha"])
"""

#: Later cells: a long simulation, then an inline sweep, each looping until stopped.
SIMULATE = """
print("started", flush=True)
while True:
    camdyn.simulate(rig, speed=18.0, revolutions=20000, sample_rate=1000.0, variables=["alpha"])
"""

SWEEP = """
from camdyn.sweeps import run_sweep, spec_from_dict
spec = spec_from_dict({"system": {"source": "sundar2014-impact"},
                       "vary": [{"key": "motion.speed", "start": "8 Hz", "stop": "25 Hz", "num": 64}],
                       "run": {"revolutions": 400, "discard": 10, "chunk": 64},
                       "metrics": {"names": ["impacts"]}, "output": {"path": %r}})
print("started", flush=True)
while True:
    run_sweep(spec, workers=0, progress=False, restart=True)
"""

#: After the interrupts: the kernel still simulates.
AFTER = """
r = camdyn.simulate(rig, speed=16.0, revolutions=2, sample_rate=1000.0, variables=["alpha"])
print("samples", r["alpha"].size > 0, flush=True)
"""


def _messages(client, msg_id: str, timeout: float):
    """The kernel's iopub messages for one cell until it is idle ([] pieces past ``timeout`` s)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            msg = client.get_iopub_msg(timeout=1.0)
        except queue.Empty:
            continue
        if msg["parent_header"].get("msg_id") != msg_id:
            continue
        yield msg
        if msg["msg_type"] == "status" and msg["content"]["execution_state"] == "idle":
            return


def _run_interrupted(kernel, client, code: str, delay: float) -> tuple[str, list[str]]:
    """Run ``code``, interrupt the kernel ``delay`` s after its first line; the error's name
    and the cell's stderr text."""
    msg_id = client.execute(code)
    stream = _messages(client, msg_id, 600.0)
    for msg in stream:   # wait for the cell's first line: its loop has started
        if msg["msg_type"] == "stream" and "started" in msg["content"]["text"]:
            break
    else:
        pytest.fail("the cell never started")
    time.sleep(delay)
    sent = time.monotonic()
    kernel.interrupt_kernel()
    error, stderr = "", []
    for msg in stream:
        if msg["msg_type"] == "error":
            error = msg["content"]["ename"]
        elif msg["msg_type"] == "stream" and msg["content"]["name"] == "stderr":
            stderr.append(msg["content"]["text"])
    assert time.monotonic() - sent < PROMPT, "the cell did not end after the interrupt"
    return error, stderr


@pytest.mark.slow
def test_jupyter_kernel_interrupts_end_in_keyboard_interrupt_and_the_kernel_goes_on(tmp_path):
    rng = np.random.default_rng(SEED)
    kernel = manager.KernelManager(kernel_name="python3")
    kernel.start_kernel(cwd=str(tmp_path))
    client = kernel.client()
    client.start_channels()
    try:
        client.wait_for_ready(timeout=120)
        cells = [FIRST] + [SIMULATE] * 3 + [SWEEP % str(tmp_path / "inline.nc")] * 2
        outcomes = []
        for code in cells:
            # the first cell anywhere in its import and first runs, the others in their first second
            delay = rng.uniform(0.0, 3.0) if code is FIRST else rng.uniform(0.0, 1.0)
            error, stderr = _run_interrupted(kernel, client, code, delay)
            text = "".join(stderr)
            assert error in ("KeyboardInterrupt", "SweepInterrupted"), (error, text)
            assert "SystemError" not in text and "Traceback" not in text, text
            assert kernel.is_alive()
            outcomes.append(error)
        msg_id = client.execute(AFTER)
        out = "".join(m["content"]["text"] for m in _messages(client, msg_id, 300.0)
                      if m["msg_type"] == "stream" and m["content"]["name"] == "stdout")
        assert "samples True" in out, out
        assert len(outcomes) == len(cells)
    finally:
        client.stop_channels()
        kernel.shutdown_kernel(now=True)
