"""The ``camdyn`` command line.

:func:`run` is the console script's entry point. It installs the interrupt handling
before the commands' heavy imports (numpy, numba, xarray, typer: about a second), so
that Ctrl-C or SIGTERM during start-up also ends in one line and exit status 130 or 143,
not in a traceback; :func:`camdyn.cli.app.main` then takes over.
"""

import os
import signal
import sys


def run() -> None:
    """Console-script entry point: ``sys.exit(camdyn.cli.app.main())``."""
    os.environ.setdefault("MPLBACKEND", "Agg")   # figures are written to files, never shown
    arrived = {}

    def stop(signum, frame):
        arrived["signal"] = signum
        raise KeyboardInterrupt

    try:
        for sig in (signal.SIGINT, signal.SIGTERM):
            if signal.getsignal(sig) is not signal.SIG_IGN:
                signal.signal(sig, stop)
        from camdyn.cli.app import main
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        _leave_at_once(128 + int(arrived.get("signal", signal.SIGINT)))
    try:
        status = main()
    except KeyboardInterrupt:   # arrived as main() returned, after it put ``stop`` back
        print("interrupted", file=sys.stderr)
        status = 128 + int(arrived.get("signal", signal.SIGINT))
    _ignore_late_signals()
    sys.exit(status)


def _leave_at_once(status: int) -> None:
    """Exit with ``status`` at once, after an interrupt during the imports.

    Nothing has started yet, so nothing is left to clean up; leaving at once
    (``os._exit`` after flushing the standard streams) keeps CPython from turning the
    exit into a death by SIGINT (status -2, no message), which it did in 3 of 14 tries of
    Ctrl-C during the imports (once seen with the interrupt inside a dataclass that the
    standard library was creating through ``exec``; the path inside CPython was not
    pinned down). After ``main()`` the exit is a normal one: an interrupted sweep's pool
    still has semaphores that multiprocessing's exit handlers release, and skipping them
    makes its resource tracker print leaked-semaphore warnings after the one line.
    """
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)


def _ignore_late_signals() -> None:
    """The command is over: ignore SIGINT and SIGTERM while the interpreter shuts down.

    Python's finalization puts back the default handlers of the signals it handled, so a
    signal arriving then (numba and dask make shutdown take a few tenths of a second)
    would kill the process without a word. Ignored handlers are left as they are.
    """
    for sig in (signal.SIGINT, signal.SIGTERM):
        if signal.getsignal(sig) is not signal.SIG_IGN:
            signal.signal(sig, signal.SIG_IGN)
