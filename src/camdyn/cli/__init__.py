"""The ``camdyn`` command line.

:func:`run` is the console script's entry point. It installs the interrupt handling
before the commands' heavy imports (numpy, numba, xarray, typer: about a second), so
that Ctrl-C or SIGTERM during start-up also ends in one line and exit status 130 or 143,
not in a traceback; :func:`camdyn.cli.app.main` then takes over.
"""

import signal
import sys


def run() -> None:
    """Console-script entry point: ``sys.exit(camdyn.cli.app.main())``."""
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
        sys.exit(128 + int(arrived.get("signal", signal.SIGINT)))
    sys.exit(main())
