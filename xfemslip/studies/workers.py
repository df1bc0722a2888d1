"""Worker processes of a sweep: started for it, stopped with it.

:func:`run_local` runs the tasks of a sweep (or of an uncertainty study) on
``jobs`` local worker processes; :func:`run_in_child` runs one task in a child
process of the calling one (a Dask worker's thread, see
:mod:`xfemslip.studies.run`).  Both promise the same thing: when the sweep
stops, its workers stop with it, and nothing they leave half-written is
taken for a result.

- A worker is a fresh interpreter (``spawn``: no forked Numba or BLAS state)
  that runs one task at a time, sent over its own pipe, so the sweep knows
  which task each worker holds.  A worker that dies (killed, out of memory)
  fails that task alone, and a new worker takes the next one.
- **The sweep ends early** (Ctrl-C, SIGTERM, an error): every worker gets
  SIGTERM.  A busy worker unwinds its task as a command does (the member's
  staging folder is removed, its folder keeps its earlier content,
  :mod:`xfemslip.io.folder`), an idle one exits at once; a worker still alive
  ``GRACE_S`` later (inside a long call into compiled code) gets SIGKILL, and
  the next run of that member removes what it left.  Members that had
  finished are whole in their folders, and a rerun skips them.
- **The sweep process dies** (SIGKILL, a crash): each worker watches it.
  On Linux the kernel sends the worker SIGTERM when its parent dies
  (``prctl(PR_SET_PDEATHSIG)``); everywhere, a thread of the worker compares
  ``os.getppid()`` with the sweep's pid every ``WATCH_S`` and, once the
  sweep is gone, sends itself SIGTERM and exits ``GRACE_S`` later at the
  latest.  So no worker outlives its sweep holding an output folder open.

A signal a worker's sweep was started with ignored (``nohup``) stays ignored
in the workers too; SIGTERM always stops them.
"""

from __future__ import annotations

import collections
import ctypes
import os
import pickle
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Generator, Iterable
from multiprocessing import get_context
from multiprocessing.connection import wait
from typing import Any

from xfemslip import interrupt
from xfemslip.kernels.threads import share_cores

# A worker that has not unwound its task this long after SIGTERM is killed.
GRACE_S = 1.0
# How often a worker checks that its sweep process is still there.
WATCH_S = 0.25
# How often a task run in a child process checks whether it is still wanted.
POLL_S = 0.2
_PR_SET_PDEATHSIG = 1  # linux/prctl.h


# --------------------------------------------------------------------------- #
# Inside a worker
# --------------------------------------------------------------------------- #


_SIGNALS = (signal.SIGTERM, signal.SIGINT)
_watched: list[int] = []  # the signals a worker acts on (an ignored SIGINT not)


def _exit_now(signum, frame) -> None:
    """The handler of an idle worker: nothing to unwind."""
    os._exit(128 + signum)


def _unwind(signum, frame) -> None:
    """The handler of a busy worker: unwind the task once.  A second signal
    (a terminal's Ctrl-C reaches the worker, then its sweep's SIGTERM) must
    not cut the unwinding short, which removes the member's staging folder;
    the sweep kills a worker that takes longer than GRACE_S."""
    _handle(_noted)  # a Python handler: SIG_IGN would make Python raise
    # "signal ignored due to race condition" for a signal already arriving
    if signum == signal.SIGTERM:
        raise interrupt.Terminated("SIGTERM")
    raise KeyboardInterrupt


def _noted(signum, frame) -> None:
    """The handler while a task unwinds: the signal is already being acted on."""


def _handle(handler) -> None:
    for sig in _watched:
        signal.signal(sig, handler)


def _stop_with_signals() -> None:
    """SIGTERM and SIGINT end an idle worker at once (a busy one unwinds its
    task first, inside :func:`_run_guarded`); an ignored SIGINT stays so."""
    _watched[:] = [
        sig for sig in _SIGNALS if signal.getsignal(sig) is not signal.SIG_IGN
    ]
    _handle(_exit_now)


def _watch_parent(parent: int) -> None:
    """Stop this process once ``parent`` is no longer its parent (module doc)."""
    if sys.platform.startswith("linux"):
        try:
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGTERM), 0, 0, 0)
        except (OSError, AttributeError):  # no prctl: the thread below does it
            pass

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(WATCH_S)
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(GRACE_S)  # the task did not unwind in time
        os._exit(128 + signal.SIGTERM)

    threading.Thread(target=watch, name="xfemslip-parent-watch", daemon=True).start()


def _run_guarded(fn: Callable, task):
    """``fn(task)`` with SIGINT and SIGTERM raised as KeyboardInterrupt /
    Terminated inside it (so the task's folders are unwound); the process
    then exits with the signal's code instead of returning."""
    try:
        _handle(_unwind)
        result = fn(task)
        _handle(_exit_now)
        return result
    except KeyboardInterrupt as exc:
        term = isinstance(exc, interrupt.Terminated)
        os._exit(128 + (signal.SIGTERM if term else signal.SIGINT))


def _worker_main(conn, parent: int, fn: Callable, jobs: int = 1) -> None:
    """A worker of :func:`run_local`: tasks in, results out, until told to
    stop (None), its pipe closes, or a signal or its parent's death ends it.
    Its kernels take 1/``jobs`` of the cores (the pool's workers run at
    once: two workers each building a model on every core of 2 would run
    four threads on them)."""
    share_cores(jobs)
    _stop_with_signals()
    _watch_parent(parent)
    while True:
        try:
            task = conn.recv()
        except (EOFError, OSError):
            break
        if task is None:
            break
        result = _run_guarded(fn, task)
        try:
            conn.send(result)
        except (BrokenPipeError, OSError):
            break
    os._exit(0)


# --------------------------------------------------------------------------- #
# The pool
# --------------------------------------------------------------------------- #


def _ended(exitcode: int | None) -> str:
    """How a worker process ended, for a case's error column."""
    if exitcode is None:
        return "the worker process was lost"
    if exitcode < 0:
        try:
            name = signal.Signals(-exitcode).name
        except ValueError:
            name = f"signal {-exitcode}"
        return f"the worker process was killed by {name}"
    return f"the worker process ended with exit code {exitcode}"


class _Worker:
    """One worker process and the task it holds."""

    def __init__(self, context, fn: Callable, jobs: int = 1) -> None:
        self.conn, child = context.Pipe()
        self.process = context.Process(
            target=_worker_main,
            args=(child, os.getpid(), fn, jobs),
            name="xfemslip-sweep-worker",
            daemon=True,
        )
        self.process.start()
        child.close()
        self.task = None

    @property
    def pid(self) -> int | None:
        return self.process.pid


class LocalPool:
    """``jobs`` worker processes (module doc); use as a context manager:
    leaving the block early stops the workers (:meth:`abort`), leaving it
    normally lets them exit (:meth:`close`)."""

    def __init__(self, jobs: int, fn: Callable, lost: Callable) -> None:
        self.context = get_context("spawn")
        self.fn = fn
        self.lost = lost  # lost(task, reason) -> the task's outcome
        self.jobs = jobs
        self.workers: list[_Worker] = []

    @property
    def pids(self) -> list[int]:
        """Pids of the workers now running (for tests and logs)."""
        return [w.pid for w in self.workers if w.pid is not None]

    def __enter__(self) -> LocalPool:
        return self

    def __exit__(self, kind, value, tb) -> None:
        if kind is None:
            self.close()
        else:
            self.abort()

    def _start(self) -> _Worker:
        worker = _Worker(self.context, self.fn, self.jobs)
        self.workers.append(worker)
        return worker

    def _drop(self, worker: _Worker) -> None:
        worker.conn.close()
        worker.process.join(timeout=GRACE_S)
        if worker.process.is_alive():
            worker.process.kill()
            worker.process.join()
        self.workers.remove(worker)

    def run(self, tasks: Iterable) -> Iterable:
        """The outcome of every task, in completion order."""
        pending = collections.deque(tasks)
        idle = [self._start() for _ in range(min(self.jobs, len(pending)))]
        busy: list[_Worker] = []
        while pending or busy:
            while pending and idle:
                worker = idle.pop()
                task = pending.popleft()
                try:
                    worker.conn.send(task)
                except (BrokenPipeError, OSError):  # died before it got a task
                    self._drop(worker)
                    idle.append(self._start())
                    pending.appendleft(task)
                    continue
                worker.task = task
                busy.append(worker)
            ready = set(
                wait(
                    [w.conn for w in busy] + [w.process.sentinel for w in busy],
                    timeout=1.0,
                )
            )
            for worker in list(busy):
                if worker.conn in ready:
                    try:
                        outcome = worker.conn.recv()
                    except (EOFError, OSError):
                        outcome = None
                    if outcome is not None:
                        busy.remove(worker)
                        task, worker.task = worker.task, None
                        idle.append(worker)
                        yield outcome
                        continue
                if worker.conn in ready or worker.process.sentinel in ready:
                    busy.remove(worker)
                    worker.process.join(timeout=GRACE_S)
                    reason = _ended(worker.process.exitcode)
                    task = worker.task
                    self._drop(worker)
                    if pending:
                        idle.append(self._start())
                    yield self.lost(task, reason)

    def close(self) -> None:
        """Let every worker exit (all tasks done)."""
        for worker in self.workers:
            try:
                worker.conn.send(None)
            except (BrokenPipeError, OSError):
                pass
        for worker in list(self.workers):
            self._drop(worker)

    def abort(self) -> None:
        """Stop every worker now (module doc): SIGTERM, then SIGKILL after
        GRACE_S."""
        for worker in self.workers:
            if worker.process.is_alive():
                worker.process.terminate()
        deadline = time.monotonic() + GRACE_S
        for worker in self.workers:
            worker.process.join(timeout=max(0.0, deadline - time.monotonic()))
        for worker in self.workers:
            if worker.process.is_alive():
                worker.process.kill()
        for worker in self.workers:
            worker.process.join()
            worker.conn.close()
        self.workers.clear()


def run_local(
    tasks: list, jobs: int, fn: Callable, lost: Callable
) -> Generator[Any, None, None]:
    """``fn(task)`` of every task, in completion order: in this process
    (``jobs`` 1), or on worker processes (module doc).  ``fn`` must be
    importable by the workers and never raise; ``lost(task, reason)`` is the
    outcome of a task whose worker died."""
    jobs = min(jobs, len(tasks))  # no idle workers to start
    if jobs <= 1:
        for task in tasks:
            yield fn(task)
        return
    with LocalPool(jobs, fn, lost) as pool:
        yield from pool.run(tasks)


# --------------------------------------------------------------------------- #
# One task in a child process (the tasks of a Dask cluster)
# --------------------------------------------------------------------------- #


def run_in_child(fn: Callable, task, wanted: Callable[[], bool]):
    """``fn(task)`` run in a child process of this one (``python -m
    xfemslip.studies.workers``), which is stopped as :func:`run_local`'s
    workers are once ``wanted()`` turns False (the sweep was interrupted or
    its process died) or this process dies.  Returns fn's result, or None
    when the task was stopped; raises RuntimeError when the child fails."""
    payload = pickle.dumps((fn, task))
    proc = subprocess.Popen(
        [sys.executable, "-m", "xfemslip.studies.workers", str(os.getpid())],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    box: dict = {}

    def talk() -> None:
        box["out"], box["err"] = proc.communicate(payload)

    reader = threading.Thread(target=talk, name="xfemslip-task-io", daemon=True)
    reader.start()
    try:
        while reader.is_alive():
            reader.join(timeout=POLL_S)
            if reader.is_alive() and not wanted():
                _stop_child(proc)
                reader.join()
                return None
    except BaseException:
        _stop_child(proc)
        raise
    if proc.returncode != 0 or not box.get("out"):
        tail = box.get("err", b"").decode(errors="replace").strip().splitlines()
        raise RuntimeError(_ended(proc.returncode) + (f": {tail[-1]}" if tail else ""))
    return pickle.loads(box["out"])


def _stop_child(proc: subprocess.Popen) -> None:
    """SIGTERM, then SIGKILL after GRACE_S."""
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout=GRACE_S)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def _child_main(parent: int) -> None:
    """``python -m xfemslip.studies.workers PARENT``: read a pickled (fn,
    task) from stdin, write the pickled fn(task) to stdout."""
    out = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)  # whatever prints goes to stderr, not into the result
    _stop_with_signals()
    _watch_parent(parent)
    fn, task = pickle.loads(sys.stdin.buffer.read())
    result = _run_guarded(fn, task)
    out.write(pickle.dumps(result))
    out.flush()
    os._exit(0)


if __name__ == "__main__":
    _child_main(int(sys.argv[1]))
