"""An interrupt that a library callback swallowed is delivered again to the main thread,
and never from inside the unraisable hook (where Python would print its traceback)."""

from __future__ import annotations

import signal
import threading
import time
import types

from camdyn.cli import app


def _wait_for_interrupt(seconds: float) -> bool:
    try:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            time.sleep(0.001)
    except KeyboardInterrupt:
        return True
    return False


def test_an_interrupt_swallowed_in_the_main_thread_arrives_after_the_hook(monkeypatch):
    assert threading.current_thread() is threading.main_thread()
    monkeypatch.setitem(app._interrupt, "signal", signal.SIGINT)
    monkeypatch.setitem(app._interrupt, "arrived", True)
    monkeypatch.setitem(app._interrupt, "active", True)
    previous = signal.signal(signal.SIGINT, app._on_signal)
    try:
        swallowed = types.SimpleNamespace(exc_type=KeyboardInterrupt, exc_value=KeyboardInterrupt(),
                                          exc_traceback=None, err_msg=None, object=None)
        try:
            app._quiet_unraisable(swallowed)
            raised_inside = False
        except KeyboardInterrupt:
            raised_inside = True
        delivered = _wait_for_interrupt(5.0)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert not raised_inside          # Python would report it as "Exception ignored" with a traceback
    assert delivered                  # and the command stops instead of running on


def test_no_interrupt_is_delivered_when_none_arrived(monkeypatch):
    monkeypatch.setitem(app._interrupt, "arrived", False)
    previous = signal.signal(signal.SIGINT, app._on_signal)
    try:
        app._quiet_unraisable(types.SimpleNamespace(exc_type=KeyboardInterrupt, exc_value=KeyboardInterrupt(),
                                                    exc_traceback=None, err_msg=None, object=None))
        delivered = _wait_for_interrupt(0.3)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert not delivered


def test_no_interrupt_is_delivered_once_the_command_has_ended(monkeypatch):
    monkeypatch.setitem(app._interrupt, "arrived", True)
    monkeypatch.setitem(app._interrupt, "active", True)
    previous = signal.signal(signal.SIGINT, app._on_signal)
    try:
        app._quiet_unraisable(types.SimpleNamespace(exc_type=KeyboardInterrupt, exc_value=KeyboardInterrupt(),
                                                    exc_traceback=None, err_msg=None, object=None))
        app._interrupt["active"] = False        # main() reports how the command ended
        delivered = _wait_for_interrupt(0.3)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert not delivered
