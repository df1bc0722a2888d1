"""The lock of an output folder or file, and the leftovers of killed writers.

``folder_lock(final)`` takes an exclusive ``flock`` on ``.NAME.lock`` beside
``final`` and keeps it while the set is written (rule 1 and 2 of
:mod:`xfemslip.io.folder`).  A second process is refused at once
(``UsageError``, exit 2) naming the holder's pid.  The kernel drops the lock
of a process that dies, so a stale lock file never blocks: it names the
killed process, whose staging folder or temporary files beside ``final``
(``.NAME.tmp-<pid>``, ``.NAME.old-<pid>``) the next holder deletes, saying so.
The holder deletes the lock file before it releases the lock; a waiter that
opened the deleted file sees that and opens the new one.
"""

from __future__ import annotations

import contextlib
import errno
import logging
import os
import shutil
import sys
from collections.abc import Iterator
from pathlib import Path

from xfemslip.errors import OutputError, UsageError

if sys.platform == "win32":
    fcntl = None  # no POSIX file locks: writing an output set is refused
else:
    import fcntl

logger = logging.getLogger(__name__)

# Why a Windows process cannot write an output set (the command line refuses
# to start there, xfemslip.cli.env.check_platform, with the same words).
UNSUPPORTED_PLATFORM = (
    "xfemslip runs on Linux and macOS; on Windows, run it in WSL (Windows "
    "Subsystem for Linux): its output folders are locked with POSIX file "
    "locks (fcntl), which Windows does not have"
)


def sibling(final: Path, kind: str, pid: int | None = None) -> Path:
    """``.NAME.<kind>[-pid]`` beside ``final``."""
    suffix = "" if pid is None else f"-{pid}"
    return final.parent / f".{final.name}.{kind}{suffix}"


def reason(err: OSError) -> str:
    """The one-line reason of an OSError, without the file name."""
    return " ".join(str(err.strerror or err).split())


def remove_tree(path: Path) -> None:
    """Delete a file or folder tree; a failure is logged, never raised."""
    if os.path.isdir(path) and not os.path.islink(path):
        shutil.rmtree(path, ignore_errors=True)
    else:
        with contextlib.suppress(OSError):
            os.unlink(path)
    if os.path.lexists(path):
        logger.warning("could not remove %s", path)


@contextlib.contextmanager
def folder_lock(final: Path, display: Path) -> Iterator[None]:
    """Hold the exclusive lock of ``final`` (``.NAME.lock`` beside it).

    The lock file names its holder's pid, followed by the pids of killed
    holders whose leftovers are not cleaned yet.  A lock file that is there
    when the lock is free was left by a killed process: its leftovers beside
    ``final`` are cleaned first (:func:`_clean_leftovers`).

    Raises
    ------
    UsageError
        Another process holds it (the message names its pid).
    OutputError
        The lock file cannot be created (read-only or missing parent).
    """
    if fcntl is None:
        raise UsageError(f"cannot write {display}: {UNSUPPORTED_PLATFORM}")
    path = sibling(final, "lock")
    while True:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
        except OSError as err:
            if err.errno == errno.ENAMETOOLONG:  # the name is the user's input
                raise UsageError(
                    f"{display}: name too long for the hidden files beside it "
                    f"({path.name!r}, {len(os.fsencode(path.name))} bytes)"
                ) from None
            raise OutputError(f"cannot write {display}: {reason(err)}") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            pids = _pids(fd)
            holder = pids[0] if pids else "unknown"
            os.close(fd)
            raise UsageError(
                f"{display} is being written by another xfemslip process "
                f"(pid {holder}); wait for it to end or choose another "
                "output folder"
            ) from None
        if _same_file(fd, path):
            break
        os.close(fd)  # the holder deleted the file after we opened it: again
    try:
        stale = _pids(fd)
        _write_pids(fd, [os.getpid(), *stale])  # still listed if we are killed
        _clean_leftovers(final, stale)
        _write_pids(fd, [os.getpid()])
        yield
    finally:
        with contextlib.suppress(OSError):
            os.unlink(path)  # still holding the lock: see _same_file
        os.close(fd)


def _pids(fd: int) -> list[int]:
    """The pids a lock file lists (holder first)."""
    text = os.pread(fd, 4096, 0).decode("ascii", "replace")
    return [int(word) for word in text.split() if word.isdigit()]


def _write_pids(fd: int, pids: list[int]) -> None:
    data = (" ".join(str(pid) for pid in dict.fromkeys(pids)) + "\n").encode()
    os.pwrite(fd, data, 0)
    os.ftruncate(fd, len(data))


def _same_file(fd: int, path: Path) -> bool:
    """Whether ``path`` still names the file open as ``fd`` (a holder deletes
    the lock file before it releases the lock, so a waiter that opened the
    deleted file must not count it as taken)."""
    try:
        named = os.stat(path)
    except FileNotFoundError:
        return False
    held = os.fstat(fd)
    return (named.st_dev, named.st_ino) == (held.st_dev, held.st_ino)


def _clean_leftovers(final: Path, pids: list[int]) -> None:
    """Delete (or finish) what the killed processes ``pids`` left beside
    ``final``: staging folders, temporary files, a half-done swap."""
    for pid in pids:
        old, staging = sibling(final, "old", pid), sibling(final, "tmp", pid)
        if os.path.lexists(old) and not os.path.lexists(final):
            # a two-rename swap cut between its renames: the staging folder of
            # that process was complete, so finish its swap
            os.rename(staging if staging.is_dir() else old, final)
            logger.warning(
                "finished the swap of %s that an interrupted xfemslip process "
                "(pid %d) had begun",
                final,
                pid,
            )
        for path in (old, staging):
            if os.path.lexists(path):
                remove_tree(path)
                logger.warning(
                    "removed %s, left by an interrupted xfemslip process (pid %d)",
                    path,
                    pid,
                )
