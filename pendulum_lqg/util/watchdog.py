"""A watchdog for user code: a plug-in or agent call that has not returned within a time limit ends
the run with one line naming the call (``pendulum-lqg run/score --call-timeout S``).

Every call into user code goes through :func:`pendulum_lqg.policies.loading.guard`, which tells the active
:class:`Watchdog` (if any) when the call starts and ends. A monitor thread checks the running calls;
one past its limit is interrupted in the main thread by a ``SIGALRM`` whose handler raises
:class:`CallTimeout` there (a one-line :class:`~pendulum_lqg.errors.PluginError`). That reaches
Python code that loops, sleeps, waits on a lock or a socket — anything that returns to the
interpreter. Code that never does (a C extension computing without releasing the GIL, a call in a
worker thread) cannot be interrupted: after a further :attr:`Watchdog.grace` seconds the monitor
prints the line itself and ends the process with status 2 (``os._exit``: no ``finally`` runs, so a
results folder keeps its finished units, and its lock, held by a dead process, is free again).
A call that holds the GIL for ever stops the monitor as well; nothing inside the process can end it.

The watchdog is process-wide, as signals are: one is active at a time, entered by the command.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass
from types import FrameType

from pendulum_lqg.errors import PluginError

#: The default of ``--call-timeout`` [s]: far beyond any sane single call of a controller (one act
#: of a batch, one reset, one factory), short enough that a stuck run says so.
DEFAULT_CALL_TIMEOUT = 600.0


class CallTimeout(PluginError):
    """A call into user code has not returned within the watchdog's limit (names the call)."""


@dataclass
class _Call:
    label: str            # "policy 'REF'" or "agent 'REF'"
    what: str             # "act", "reset", "the factory", …
    thread: int
    start: float


_active: Watchdog | None = None


class Watchdog:
    """``with Watchdog(seconds):`` — calls into user code longer than ``seconds`` end the run."""

    grace = 5.0

    def __init__(self, seconds: float) -> None:
        if not seconds > 0:
            raise PluginError(f"call_timeout: expected a positive number of seconds, got {seconds!r}")
        self.seconds = float(seconds)
        self._calls: dict[int, _Call] = {}
        self._expired: _Call | None = None
        self._stop = threading.Event()
        self._old_handler: object = None

    def __enter__(self) -> Watchdog:
        global _active
        if threading.current_thread() is not threading.main_thread():
            raise RuntimeError("Watchdog: enter it in the main thread (it uses SIGALRM)")
        self._old_handler = signal.signal(signal.SIGALRM, self._on_alarm)
        self._thread = threading.Thread(target=self._monitor, name="pendulum-lqg watchdog",
                                        daemon=True)
        self._thread.start()
        _active = self
        return self

    def __exit__(self, exc_type: object, exc: object, tb: object) -> None:
        global _active
        _active = None
        self._stop.set()
        self._thread.join()
        signal.signal(signal.SIGALRM, self._old_handler)       # type: ignore[arg-type]
        main = threading.main_thread().ident
        if isinstance(exc, CallTimeout) and any(c.thread != main for c in self._calls.values()):
            # the stuck call runs on a worker thread (a shard of the batch), which the
            # interpreter would wait for at exit, for ever: the line, then the end
            sys.stderr.write(f"error: {exc}\n")
            sys.stderr.flush()
            os._exit(2)

    def message(self, call: _Call) -> str:
        return (f"{call.label}: {call.what} has not returned after {self.seconds:g} s "
                "(--call-timeout); the run is stopped")

    def watch(self, label: str, what: str) -> _Watch:
        """The context of one call into user code (registered while it runs)."""
        return _Watch(self, label, what)

    def _on_alarm(self, signum: int, frame: FrameType | None) -> None:
        call = self._expired
        if call is not None and call in self._calls.values():
            raise CallTimeout(self.message(call))

    def _monitor(self) -> None:
        main = threading.main_thread().ident
        while not self._stop.wait(min(0.1, self.seconds / 4)):
            now = time.monotonic()
            late = [c for c in list(self._calls.values()) if now - c.start > self.seconds]
            if not late:
                continue
            call = late[0]
            if self._expired is not call:
                self._expired = call
                if main is not None:
                    signal.pthread_kill(main, signal.SIGALRM)
            elif now - call.start > self.seconds + self.grace:
                sys.stderr.write(f"error: {self.message(call)} (it cannot be interrupted)\n")
                sys.stderr.flush()
                os._exit(2)


class _Watch:
    """One call into user code, registered with its watchdog while it runs (nested calls of one
    thread restore the outer one when they end)."""

    def __init__(self, dog: Watchdog, label: str, what: str) -> None:
        self.dog, self.label, self.what = dog, label, what

    def __enter__(self) -> None:
        call = _Call(self.label, self.what, threading.get_ident(), time.monotonic())
        self.outer = self.dog._calls.get(call.thread)
        self.dog._calls[call.thread] = call

    def __exit__(self, *exc: object) -> None:
        thread = threading.get_ident()
        if self.outer is None:
            self.dog._calls.pop(thread, None)
        else:
            self.dog._calls[thread] = self.outer


_UNWATCHED = nullcontext()


def watched(label: str, what: str) -> AbstractContextManager[None]:
    """The active watchdog's watch over one call (a no-op context when none is active)."""
    dog = _active
    return _UNWATCHED if dog is None else dog.watch(label, what)


def call_timeout(seconds: float | None) -> Watchdog | _NoWatchdog:
    """The watchdog of a command: ``seconds`` > 0 (``None``: :data:`DEFAULT_CALL_TIMEOUT`), or
    none for 0."""
    if seconds is None:
        seconds = DEFAULT_CALL_TIMEOUT
    if seconds == 0:
        return _NoWatchdog()
    return Watchdog(seconds)


class _NoWatchdog:
    def __enter__(self) -> None:
        return None

    def __exit__(self, *exc: object) -> None:
        return None


__all__ = ["DEFAULT_CALL_TIMEOUT", "CallTimeout", "Watchdog", "call_timeout", "watched"]
