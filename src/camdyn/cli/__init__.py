"""The ``camdyn`` command line.

:func:`run` is the console script's entry point. It installs the interrupt handling
before the commands' heavy imports (numpy, numba, xarray, typer: about a second), so
that Ctrl-C, SIGTERM or SIGHUP (a closed terminal) during start-up also ends in one line
and exit status 130, 143 or 129, not in a traceback; :func:`camdyn.cli.app.main` then
takes over.
"""

import atexit
import os
import signal
import sys

#: The signals that stop a command as Ctrl-C does (workers stopped, temporaries removed,
#: checkpoints kept), with exit status 128 + the signal's number: SIGINT (130), SIGTERM
#: (143) and SIGHUP (129, the terminal was closed; absent on Windows).
STOP_SIGNALS = tuple(s for s in (signal.SIGINT, signal.SIGTERM, getattr(signal, "SIGHUP", None)) if s is not None)


def run() -> None:
    """Console-script entry point: ``sys.exit(camdyn.cli.app.main())``."""
    os.environ.setdefault("MPLBACKEND", "Agg")   # figures are written to files, never shown
    arrived = {}

    def stop(signum, frame):
        arrived["signal"] = signum
        raise KeyboardInterrupt

    try:
        for sig in STOP_SIGNALS:
            if signal.getsignal(sig) is not signal.SIG_IGN:
                signal.signal(sig, stop)
        from camdyn.cli.app import main
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        _leave(128 + int(arrived.get("signal", signal.SIGINT)))
    try:
        status = main()
    except KeyboardInterrupt:   # arrived as main() returned, after it put ``stop`` back
        print("interrupted", file=sys.stderr)
        status = 128 + int(arrived.get("signal", signal.SIGINT))
    _ignore_late_signals()
    _leave(status)


def _leave(status: int) -> None:
    """Exit with ``status``; after an interrupt (130, 143, 129), without the interpreter's
    finalization.

    An interrupted command has stopped its workers and kept its checkpoints. Its exit
    handlers still run (``atexit``: multiprocessing's releases an interrupted sweep's
    pool semaphores, whose resource tracker would otherwise print leaked-semaphore
    warnings after the one line), then the streams are flushed and the process leaves by
    ``os._exit``. A normal exit was turned by CPython into a death by SIGINT (status -2,
    no message) in 3 of 14 tries of Ctrl-C during the imports, and once in a full test
    run after ``main()`` had returned 130 (the path inside CPython was not pinned down).
    """
    if status in [128 + int(sig) for sig in STOP_SIGNALS]:
        _ignore_late_signals()
        try:
            atexit._run_exitfuncs()   # what a normal exit runs first; private but stable
        except BaseException:   # noqa: BLE001 - leaving anyway, with the status already decided
            pass
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(status)
    sys.exit(status)


def _ignore_late_signals() -> None:
    """The command is over: ignore :data:`STOP_SIGNALS` while the interpreter shuts down.

    Python's finalization puts back the default handlers of the signals it handled, so a
    signal arriving then (numba and dask make shutdown take a few tenths of a second)
    would kill the process without a word. Ignored handlers are left as they are.
    """
    for sig in STOP_SIGNALS:
        if signal.getsignal(sig) is not signal.SIG_IGN:
            signal.signal(sig, signal.SIG_IGN)
