"""SIGINT and SIGTERM while a command runs: always end the run, never mid-write.

Python turns SIGINT into ``KeyboardInterrupt``; SIGTERM (``kill``, a batch
system's time limit) would end the process without unwinding, leaving
temporary files behind.  Inside ``sigterm_as_interrupt()`` both signals go
through one handler, which raises ``KeyboardInterrupt`` (``Terminated`` for
SIGTERM, exit 143 = 128 + SIGTERM) so the same clean-up runs.

Two things can still lose a signal, and both are closed here:

- An exception raised while Python runs a destructor (h5py closes its HDF5
  identifiers in ``__dealloc__``, and a Ctrl-C in the first milliseconds of
  writing ``result.h5`` lands there) is printed as "Exception ignored" and
  dropped.  The handler therefore also *records* the signal, and
  :func:`checkpoint` raises a recorded signal that nobody caught; the CLI
  calls it when a command ends, so a swallowed interrupt still ends the run
  with 130/143 instead of 0.
- Writing an output set must not be cut at an arbitrary byte.  Inside
  :func:`deferred` the handler only records the signal; the writers call
  :func:`checkpoint` between data sets and files (plain Python frames, never
  a destructor), and the signal is raised there, or when the outermost
  ``deferred`` block ends.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator


class Terminated(KeyboardInterrupt):
    """The process received SIGTERM."""


class _State:
    """The signal recorded and not yet raised, the ``deferred`` depth, and
    whether the process is the command-line program (:func:`for_process`)."""

    pending: KeyboardInterrupt | None = None
    depth = 0
    process = False


def for_process() -> None:
    """The process runs one command and exits (the console script): a signal
    after the command has ended (its output complete) is ignored instead of
    killing the process in its last milliseconds (by SIGTERM's default action,
    or as a Ctrl-C that click reports as "Aborted!" with exit 1)."""
    _State.process = True


def _exception(signum: int) -> KeyboardInterrupt:
    return Terminated("SIGTERM") if signum == signal.SIGTERM else KeyboardInterrupt()


def _handler(signum, frame):
    exc = _exception(signum)
    _State.pending = exc  # kept until raised where it cannot be swallowed
    if _State.depth == 0:
        raise exc


def _in_main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


@contextlib.contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """Raise ``KeyboardInterrupt``/``Terminated`` on SIGINT/SIGTERM inside the
    block (main thread only); on normal exit, raise a signal that was received
    but swallowed on the way."""
    if not _in_main_thread():
        yield
        return
    _State.pending = None
    previous = _install()
    try:
        yield
        checkpoint()
    finally:
        for sig, handler in previous.items():
            # SIG_IGN, not a Python handler: the interpreter's finalization
            # puts SIG_DFL back in place of Python handlers, not of SIG_IGN
            signal.signal(sig, signal.SIG_IGN if _State.process else handler)


_SIGNALS = (signal.SIGINT, signal.SIGTERM)


def _install() -> dict:
    """Put ``_handler`` on SIGINT and SIGTERM; returns the handlers replaced.
    A signal the process was started with ignored (``nohup``, a background
    job of a script) stays ignored, as Python itself keeps it."""
    previous = {}
    for sig in _SIGNALS:
        if signal.getsignal(sig) is not signal.SIG_IGN:
            previous[sig] = signal.signal(sig, _handler)
    return previous


def checkpoint() -> None:
    """Raise the signal recorded since the last checkpoint, if any."""
    exc, _State.pending = _State.pending, None
    if exc is not None:
        raise exc


def pending() -> KeyboardInterrupt | None:
    """The signal recorded and not yet raised, if any."""
    return _State.pending


def deferring() -> bool:
    """Whether a :func:`deferred` block is running."""
    return _State.depth > 0


@contextlib.contextmanager
def deferred() -> Iterator[None]:
    """Record SIGINT/SIGTERM instead of raising them inside the block; raise a
    recorded one at the next :func:`checkpoint` or when the outermost block
    ends.  Outside ``sigterm_as_interrupt`` (a library caller) the block
    installs the handler itself, main thread only."""
    own = _in_main_thread() and all(
        signal.getsignal(sig) is not _handler for sig in _SIGNALS
    )
    previous = {}
    if own:  # a library caller: nothing was recorded before this block
        _State.pending = None
        previous = _install()
    _State.depth += 1
    try:
        yield
    finally:
        _State.depth -= 1
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        if _State.depth == 0:  # raised over an error of the block: the signal wins
            checkpoint()
