"""SIGTERM handled like Ctrl-C (SIGINT) while a command runs.

Python turns SIGINT into ``KeyboardInterrupt``; SIGTERM (``kill``, a batch
system's time limit) would end the process without unwinding, leaving the
temporary files of :mod:`xfemslip.writers.atomic` behind.  Inside
``sigterm_as_interrupt()`` SIGTERM raises ``Terminated`` (a
``KeyboardInterrupt``), so the same clean-up runs: a file being written is
removed, no file under a final name is ever truncated, and the CLI reports
the interruption (exit 143 = 128 + SIGTERM).
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator


class Terminated(KeyboardInterrupt):
    """The process received SIGTERM."""


def _raise_terminated(signum, frame):
    raise Terminated("SIGTERM")


@contextlib.contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """Raise ``Terminated`` on SIGTERM inside the block (main thread only)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
