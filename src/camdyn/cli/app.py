"""The ``camdyn`` command line: the one place where every command is registered.

Every failure prints one line on standard error, without a traceback: exit status 2
for bad input, 1 for a failure at run time, 130 for Ctrl-C, 143 for SIGTERM and 129 for
SIGHUP (a closed terminal) (:func:`main`).
"""

from __future__ import annotations

import _thread
import functools
import os
import signal
import sys
import threading
import warnings

import typer
from typer.core import TyperGroup

from camdyn import __version__
from camdyn.cli import STOP_SIGNALS, analysis, continuation, impact, records, simulate, sweep, warmup
from camdyn.cli.common import compile_notice
from camdyn.errors import RUNTIME_ERRORS, CamdynError, SweepInterrupted

try:  # recent typer vendors click
    from typer._click import exceptions as click_exceptions
except ImportError:  # pragma: no cover
    from click import exceptions as click_exceptions

#: The interrupt of the current command: its signal and, for a sweep, the exception that
#: says how to resume (typer turns KeyboardInterrupt into exit status 130 and drops it).
_interrupt = {"signal": signal.SIGINT, "exception": None, "arrived": False, "active": False, "later": None}


def _interruptible(command):
    """Register ``command`` so that an interrupt's message survives typer, and so that a
    first compilation of the core is announced (:func:`camdyn.cli.common.compile_notice`)."""
    @functools.wraps(command)
    def wrapper(*args, **kwargs):
        try:
            with compile_notice():
                return command(*args, **kwargs)
        except KeyboardInterrupt as exc:
            _interrupt["exception"] = exc
            raise
    return wrapper


class _PresetsGroup(TyperGroup):
    """``camdyn presets NAME`` is ``camdyn presets show NAME``: a first argument that is no
    subcommand is a preset's name."""

    def parse_args(self, ctx, args):
        if args and not args[0].startswith("-") and args[0] not in self.commands:
            args = ["show", *args]
        return super().parse_args(ctx, args)


app = typer.Typer(add_completion=False, no_args_is_help=True)
presets_app = typer.Typer(help="List the bundled presets (every kind), or show one: camdyn presets NAME.",
                          invoke_without_command=True, cls=_PresetsGroup)
identify_app = typer.Typer(help="Estimate model parameters from measured records.", no_args_is_help=True)


def _print_version(value: bool) -> None:
    if value:
        typer.echo(f"camdyn {__version__}")
        raise typer.Exit()


@app.callback()
def _root(version: bool = typer.Option(False, "--version", callback=_print_version, is_eager=True,
                                       help="Print camdyn's version and exit.")):
    """Nonlinear dynamics of cam-follower systems with rolling-sliding contact.

    Every file a command writes is announced with its size; an existing file is kept
    unless --force is given; --json prints one JSON document (docs/cli-json.md).
    """


presets_app.callback()(_interruptible(simulate.presets_list))
presets_app.command("show")(_interruptible(simulate.presets_show))
presets_app.command("keys")(_interruptible(simulate.presets_keys))
app.add_typer(presets_app, name="presets")
app.command("equilibrium")(_interruptible(simulate.equilibrium))
app.command("simulate")(_interruptible(simulate.simulate))
app.command("demo")(_interruptible(simulate.demo))
app.command("synthesize")(_interruptible(records.synthesize))
app.command("synthesize-impulse")(_interruptible(records.synthesize_impulse))
identify_app.command("friction")(_interruptible(records.identify_friction))
identify_app.command("modal-damping")(_interruptible(records.identify_modal))
identify_app.command("impact-damping")(_interruptible(impact.identify_impact_damping))
identify_app.command("restitution")(_interruptible(impact.identify_restitution))
app.add_typer(identify_app, name="identify")
app.command("tribology")(_interruptible(records.tribology))
app.command("design")(_interruptible(records.design))
app.command("sweep")(_interruptible(sweep.sweep))
app.command("bifurcation")(_interruptible(sweep.bifurcation))
app.command("lyapunov")(_interruptible(sweep.lyapunov))
app.command("map")(_interruptible(analysis.regime_map_command))
app.command("spectrum")(_interruptible(analysis.spectrum))
app.command("continue")(_interruptible(continuation.continue_branch))
app.command("compile")(_interruptible(warmup.compile_core))


def _on_signal(signum, frame):
    """SIGINT, SIGTERM and SIGHUP: remember which arrived and stop as Ctrl-C does (workers
    stopped, temporaries removed, checkpoints kept); the exit status is 128 + the signal's
    number (130, 143, 129). An
    interrupt that lands inside a library's callback (numba compiling on first use) comes
    out as that library's own error; the flag set here still marks it as an interrupt."""
    _interrupt["signal"] = signal.Signals(signum)
    _interrupt["arrived"] = True
    raise KeyboardInterrupt


#: Delay [s] before an interrupt swallowed in the main thread is delivered again.
REDELIVERY_DELAY = 0.01


def _quiet_unraisable(unraisable) -> None:
    """Drop the 'Exception ignored' report of an interrupt inside a C callback, and deliver
    the interrupt again to the main thread (the callback swallowed it: the command would
    otherwise run on to its end). In the main thread itself the delivery waits until this
    hook has returned: a signal handler run inside the hook would raise there, where
    Python ignores the exception and prints it with its traceback."""
    if not isinstance(unraisable.exc_value, KeyboardInterrupt):
        sys.__unraisablehook__(unraisable)
    elif _interrupt["arrived"]:
        number = int(_interrupt["signal"])
        if threading.current_thread() is threading.main_thread():
            later = threading.Timer(REDELIVERY_DELAY, _deliver, args=(number,))
            later.daemon = True
            _interrupt["later"] = later
            later.start()
        else:
            _thread.interrupt_main(number)


def _deliver(number: int) -> None:
    """The interrupt, delivered to the main thread while a command still runs (not once
    :func:`main` has restored the previous handlers and is reporting how it ended)."""
    if _interrupt["active"]:
        _thread.interrupt_main(number)


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Warnings as one line on standard error, without the source line."""
    print(f"warning: {message}", file=sys.stderr)


def _interrupted(exc: BaseException | None) -> int:
    exc = exc or _interrupt["exception"]
    reason = str(exc) if isinstance(exc, SweepInterrupted) else "interrupted"
    print(reason, file=sys.stderr)
    return 128 + int(_interrupt["signal"])


def main(argv=None) -> int:
    """Entry point: run the app and turn every failure into one line on standard error.

    Returns the exit status: 0 success; 2 bad input (a camdyn input error or a usage
    error); 1 a failure at run time (the solver stopped, a write failed, an unexpected
    error); 130 interrupted by Ctrl-C (143 by SIGTERM, 129 by SIGHUP). Set ``CAMDYN_DEBUG=1`` to see the
    traceback of an unexpected error.
    """
    _interrupt.update(signal=signal.SIGINT, exception=None, arrived=False, active=True, later=None)
    hooks = warnings.showwarning, sys.unraisablehook
    warnings.showwarning, sys.unraisablehook = _show_warning, _quiet_unraisable
    previous = {}
    try:
        for sig in STOP_SIGNALS:
            if signal.getsignal(sig) is not signal.SIG_IGN:
                previous[sig] = signal.signal(sig, _on_signal)
    except ValueError:   # not the main thread: leave the signals alone
        pass
    try:
        result = app(args=argv, standalone_mode=False, prog_name="camdyn")
    except typer.Abort as exc:
        return _interrupted(exc.__cause__)
    except KeyboardInterrupt as exc:
        return _interrupted(exc)
    except RUNTIME_ERRORS as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except CamdynError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except click_exceptions.UsageError as exc:
        if exc.format_message():   # no message: the help was printed (no arguments)
            print(f"error: {exc.format_message()}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"error: {exc.strerror or exc}{f' ({exc.filename})' if exc.filename else ''}", file=sys.stderr)
        return 1
    except Exception as exc:  # noqa: BLE001 - the promise is one line, never a traceback
        if _interrupt["arrived"]:
            return _interrupted(None)
        if os.environ.get("CAMDYN_DEBUG"):
            raise
        print(f"error: unexpected {type(exc).__name__}: {exc} (set CAMDYN_DEBUG=1 for the traceback)",
              file=sys.stderr)
        return 1
    finally:
        _interrupt["active"] = False
        if _interrupt["later"] is not None:
            _interrupt["later"].cancel()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        warnings.showwarning, sys.unraisablehook = hooks
    if result == 130 or _interrupt["arrived"]:   # typer's status for KeyboardInterrupt; or one swallowed
        return _interrupted(None)
    return result if isinstance(result, int) else 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
