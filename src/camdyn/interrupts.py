"""Ctrl-C while numba loads or compiles, and while camdyn imports its compiled modules.

A ``KeyboardInterrupt`` raised in the middle of numba's loading of compiled code (its
on-disk cache, LLVM's linking, the typing registries) or in the middle of ``import
numba`` leaves numba half-initialised: the next call in the same interpreter failed with
``AttributeError: module 'numba' has no attribute 'core'`` or ``ImportError:
initialization failed`` (seen in 2 of 3 processes whose ``simulate`` was interrupted 40
times at random in its first half second), and an interrupt raised inside llvmlite's
calls was followed by a segmentation fault. In a script that ends anyway this does not
matter; in a notebook or any program that catches the interrupt and goes on, it does.

:func:`deferred` holds a Ctrl-C back until such a stretch is over, then raises it as
``KeyboardInterrupt``; a second Ctrl-C within the stretch raises at once (the user
insists; the interpreter may then be unusable). :func:`guard_numba` runs numba's slow
path of a call (``Dispatcher._compile_for_args``: a first call, which loads the cache or
compiles) inside :func:`deferred`. Only the main thread with Python's own SIGINT handler
is affected: the command line keeps its handler (it exits at once, status 130), and
worker processes ignore SIGINT.

Loading from the cache takes a few seconds at most; a compile from an empty cache can
take minutes, and Ctrl-C then waits for its end unless pressed twice.
"""

from __future__ import annotations

import contextlib
import signal
import threading

__all__ = ["deferred", "guard_numba"]


@contextlib.contextmanager
def deferred():
    """Hold SIGINT back until the block ends, then raise ``KeyboardInterrupt``; a second
    SIGINT raises at once. Does nothing outside the main thread or when SIGINT has a
    handler other than Python's default (``signal.default_int_handler``)."""
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGINT) is not signal.default_int_handler):
        yield
        return
    arrived = []

    def note(_signum, _frame):
        if arrived:
            raise KeyboardInterrupt
        arrived.append(True)

    signal.signal(signal.SIGINT, note)
    try:
        yield
    except BaseException:
        signal.signal(signal.SIGINT, signal.default_int_handler)
        if arrived:   # the user asked to stop: that is the outcome, whatever else failed
            raise KeyboardInterrupt from None
        raise
    signal.signal(signal.SIGINT, signal.default_int_handler)
    if arrived:
        raise KeyboardInterrupt


def guard_numba() -> None:
    """Run numba's compile-or-load path of every dispatcher inside :func:`deferred` (once
    per process)."""
    from numba.core import dispatcher

    original = dispatcher.Dispatcher._compile_for_args
    if getattr(original, "camdyn_deferred", False):
        return

    def _compile_for_args(self, *args, **kws):
        with deferred():
            return original(self, *args, **kws)

    _compile_for_args.camdyn_deferred = True
    dispatcher.Dispatcher._compile_for_args = _compile_for_args
