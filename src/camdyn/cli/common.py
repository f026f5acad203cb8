"""What every ``camdyn`` command shares: the consoles, the ``--set``, ``--json`` and
``--force`` options, loading a system from a preset or TOML file, grid and frequency
parsing, and the notice printed while numba compiles the core for the first time.

Output files and JSON documents are in :mod:`camdyn.cli.outputs`.
"""

from __future__ import annotations

import contextlib
import importlib
import os
import sys
from collections.abc import Iterable
from pathlib import Path

import numpy as np
import typer
from rich.console import Console

from camdyn.errors import OutputError, ParameterError
from camdyn.io.system_config import load_system
from camdyn.params.config import parse_assignments
from camdyn.params.units import parse_quantity, parse_speed

#: Results and tables (standard output); messages that must not mix with JSON go to ``err_console``.
console = Console()
err_console = Console(stderr=True)

SetOption = typer.Option(None, "--set", "-s", metavar="KEY=VALUE",
                         help="Override a parameter, e.g. cam.runout=3.5mm (repeat for more).")
JsonOption = typer.Option(False, "--json", help="Print JSON on standard output (docs/cli-json.md); "
                                                "messages go to standard error.")
ForceOption = typer.Option(False, "--force", help="Overwrite output files that already exist.")

#: The first compile of the core took 342 s on the 2-core development machine
#: (``camdyn compile`` on an empty cache, 2026-11-29; 387 s in benchmarks/bench_first_run.py
#: before the multistep step was compiled apart from the driver).
COMPILE_NOTICE = ("compiling camdyn's core for this machine, once (about 6 minutes on 2 cores; "
                  "'camdyn compile' does it ahead)...")
#: Modules whose compiled functions are the core: compiling any of them is the long wait.
_CORE_MODULES = ("camdyn.integrator.", "camdyn.sweeps.kernel", "camdyn.identification.impact_kernel")
_notice = {"shown": False}


def load_source(source: str, assignments):
    """The system of a preset name or TOML file, with ``--set`` assignments applied."""
    return load_system(source, parse_assignments(assignments))


def command_inputs() -> list[str]:
    """The files the running command reads: the values of its positional arguments (a
    preset name or TOML file, records, a sweep spec) that name existing files. Empty
    outside a command."""
    ctx = None
    for module in ("typer._click.globals", "click"):   # typer's own copy of click, or click
        with contextlib.suppress(ImportError, AttributeError):
            ctx = importlib.import_module(module).get_current_context(silent=True)
        if ctx is not None:
            break
    if ctx is None:
        return []
    found = []
    for param in ctx.command.params:
        if getattr(param, "param_type_name", None) != "argument":
            continue
        value = ctx.params.get(param.name)
        for item in value if isinstance(value, (list, tuple)) else [value]:
            if isinstance(item, (str, os.PathLike)) and os.path.isfile(item):
                found.append(os.fspath(item))
    return found


def refuse_inputs_as_outputs(outputs: Iterable, inputs: Iterable | None = None) -> None:
    """Refuse an output that is one of the command's inputs (the same file, by any name:
    a link, ``./``, ``..``), with or without ``--force``: writing it would replace the
    file the command reads. ``inputs`` defaults to :func:`command_inputs`.

    Raises
    ------
    OutputError
        Naming the output and the input.
    """
    inputs = command_inputs() if inputs is None else [os.fspath(p) for p in inputs]
    for out in outputs:
        if out is None or not os.path.exists(out):
            continue
        for source in inputs:
            try:
                same = os.path.samefile(out, source)
            except OSError:
                same = False
            if same:
                raise OutputError(f"cannot write {out}: it is the input {source} of this command "
                                  f"(--force does not change that); choose another output name")


def check_continue_settings(period: int, max_points: int, transient: int, step: float, doublings: int,
                            brute_force: int, plot: Path | None) -> None:
    """Refuse ``camdyn continue``'s settings out of range, before any work (every family's
    branch takes them alike)."""
    from camdyn.continuation.branches import MIN_STEP

    if period < 1 or max_points < 2 or transient < 1 or not step >= MIN_STEP:
        raise ParameterError(f"--period and --transient must be at least 1, --max-points at least 2, --step at "
                             f"least {MIN_STEP:g}")
    if doublings < 0 or brute_force < 0 or brute_force == 1:
        raise ParameterError("--doublings must be at least 0, --brute-force 0 or at least 2")
    if brute_force and plot is None:
        raise ParameterError("--brute-force draws the diagram under the branches of --plot: give --plot")


def parse_grid(text: str, what: str, unit: str | None = None) -> np.ndarray:
    """``START:STOP:COUNT`` (inclusive, COUNT points) or a comma list."""
    def value(s):
        return parse_speed(s, what) if unit == "Hz" else float(parse_quantity(s, "", what))
    try:
        if ":" in text:
            start, stop, count = text.split(":")
            n = int(count)
            if n < 1:
                raise ValueError
            return np.linspace(value(start), value(stop), n)
        return np.array([value(s) for s in text.split(",")])
    except ValueError:
        raise ParameterError(f"{what}: expected START:STOP:COUNT or a comma list, got {text!r}") from None


def parse_hertz(text: str) -> float:
    """A frequency [Hz]; a bare number is taken as Hz."""
    try:
        return float(text)
    except ValueError:
        return parse_quantity(text, "Hz", "frequency")


def say_compiling() -> None:
    """Print :data:`COMPILE_NOTICE` on standard error, once per process."""
    if not _notice["shown"]:
        _notice["shown"] = True
        print(COMPILE_NOTICE, file=sys.stderr, flush=True)


def core_cached(sweeps: bool = False) -> bool:
    """Whether numba's cache (the package's ``__pycache__`` or ``NUMBA_CACHE_DIR``) holds
    the compiled integrator for the current source: its cache index lists at least one
    signature. ``sweeps`` also asks for the sweep kernel. True when it cannot tell."""
    try:
        from camdyn.integrator import driver
        kernels = [driver.integrate]
        if sweeps:
            from camdyn.sweeps import kernel
            kernels.append(kernel.simulate_points)
        return all(bool(k._cache._cache_file._load_index()) for k in kernels)
    except Exception:  # noqa: BLE001 - numba's cache internals moved: say nothing
        return True


def notice_if_uncached(sweeps: bool = False) -> None:
    """Print the compile notice now if the core is not in numba's cache (for work that
    compiles in worker processes, out of this process's sight)."""
    if not core_cached(sweeps):
        say_compiling()


@contextlib.contextmanager
def compile_notice():
    """Within the block, print the compile notice when numba starts compiling a core
    function in this process (a cache miss; loading from the cache is silent)."""
    try:
        from numba.core import event
    except ImportError:  # pragma: no cover
        yield
        return

    class _Listener(event.Listener):
        def on_start(self, ev):
            function = getattr(ev.data.get("dispatcher"), "py_func", None)
            if (getattr(function, "__module__", None) or "").startswith(_CORE_MODULES):
                say_compiling()

        def on_end(self, ev):
            pass

    listener = _Listener()
    event.register("numba:compile", listener)
    try:
        yield
    finally:
        event.unregister("numba:compile", listener)


def _show_flags_as_flags() -> None:
    """typer's rich help prints a type after every option, ``--json <bool>`` for a flag
    that takes no value; show none for flags, as its plain help does."""
    try:
        from typer.core import TyperOption
    except ImportError:  # pragma: no cover
        return
    original = TyperOption.display_type_rich
    if getattr(original, "_flags_hidden", False):
        return

    def display_type_rich(self, ctx):
        if getattr(self, "is_flag", False) or getattr(self, "count", False):
            return None
        return original(self, ctx)

    display_type_rich._flags_hidden = True
    TyperOption.display_type_rich = display_type_rich


_show_flags_as_flags()
