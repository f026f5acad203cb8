"""``camdyn compile``: compile camdyn's core for this machine now (or load it from numba's
cache), part by part, with the time each took, for those who want every later command
to start at once (a cluster image, a classroom)."""

from __future__ import annotations

import time

import typer

from camdyn.cli.common import JsonOption, console, err_console
from camdyn.cli.outputs import emit_json

__all__ = ["compile_core"]


def _simulation():
    import camdyn

    camdyn.simulate(camdyn.load_system("sundar2014-impact"), revolutions=0.2)


def _sweeps():
    import camdyn
    from camdyn.simulation.runner import prepare
    from camdyn.sweeps import worker

    prep = prepare(camdyn.load_system("sundar2014-impact"))
    worker.warm(1, (prep.p, prep.y0, prep.system.motion.period))


def _lyapunov():
    import camdyn
    from camdyn.analysis.chaos import lyapunov_exponent

    lyapunov_exponent(camdyn.load_system("sundar2014-impact"), revolutions=2, transient=1)


#: The parts, in order: name, what uses it, the call that compiles (or loads) it.
PARTS = (("simulation", "simulate, continue, map, spectrum and identify, for camdyn's own models", _simulation),
         ("sweeps", "sweep and bifurcation", _sweeps),
         ("lyapunov", "lyapunov", _lyapunov))


def compile_core(all_: bool = typer.Option(False, "--all", help="Also the sweep kernel and the Lyapunov "
                                                                  "exponent's (default: the simulation core only)."),
                 json_: bool = JsonOption):
    """Compile camdyn's core for this machine now, or load it from numba's cache, and say
    how long each part took (the first compile of the simulation core takes minutes on a
    small machine; later commands then start at once). A model of your own compiles its
    driver on its first run (docs/user-models.md)."""
    parts = PARTS if all_ else PARTS[:1]
    timings = {}
    for name, use, call in parts:
        start = time.perf_counter()
        with err_console.status(f"compiling or loading the {name} core (for {use})..."):
            call()
        timings[name] = time.perf_counter() - start
        if not json_:
            console.print(f"{name}: ready in {timings[name]:.1f} s (used by {use})", highlight=False)
    if json_:
        emit_json("compile", {f"{name}_s": seconds for name, seconds in timings.items()})
