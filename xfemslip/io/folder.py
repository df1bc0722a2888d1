"""Output folders: a set of files appears whole, or the earlier set stays.

The rule (``output-format.md``, *Output folders*), for every command that
writes a set of files into a folder ``DIR`` (``run``, ``deplete``, a sweep
member); sets of single files are :mod:`xfemslip.io.fileset`:

1. **Lock.** The process takes an exclusive ``flock`` on ``.DIR.lock`` beside
   ``DIR`` (the file holds its pid) and keeps it until the set is in place.  A
   second process is refused at once (``UsageError``, exit 2) naming that pid.
   The kernel drops the lock of a process that dies, so a stale lock file
   never blocks; the holder deletes it when it is done
   (:mod:`xfemslip.io.lock`).
2. **Leftovers.** A lock file found with the lock free names a killed
   process; holding the lock, the process deletes what that one left beside
   ``DIR`` (``.DIR.tmp-<pid>``, ``.DIR.old-<pid>``) and logs a warning naming
   each (the lock file names the pids, so no folder is searched).
3. **Staging.** The new set is written into the fresh hidden sibling
   ``.DIR.tmp-<pid>``.
4. **Swap.** Once every file of the set is complete, entries of ``DIR`` that
   no xfemslip command writes (notes, a sweep member's ``case.toml``) are
   carried into the staging folder as hard links (copies where a link is not
   possible), the staging folder and ``DIR`` are exchanged in one atomic
   ``renameat2(RENAME_EXCHANGE)``, and the earlier set is deleted.  At every
   instant, also for a process killed with SIGKILL, ``DIR`` is the complete
   earlier folder or the complete new one.  Where the file system cannot
   exchange (not Linux, some network file systems), ``DIR`` is renamed to
   ``.DIR.old-<pid>`` and the staging folder to ``DIR``; a process killed
   between the two renames leaves no ``DIR`` for a moment, and the next one
   finishes the swap (step 2).

Earlier xfemslip outputs in ``DIR`` (``OWNED``, e.g. figures drawn from the
earlier result) are never carried: they describe the earlier run.

A failure or an interrupt before the swap deletes the staging folder and
leaves ``DIR`` as it was (and removes the folders the process created for
it).  ``DIR`` itself is never written into, so a folder the user cannot
write is refused before any work, and a mount point (which cannot be
renamed) is refused too.

Test hook: with ``XFEMSLIP_TEST_PAUSE=<point>`` in the environment the process
prints ``xfemslip: test pause at <point>`` to stderr and waits there until a
signal arrives (which is then handled as anywhere else) at the named point:
``locked`` (lock taken, before any work), ``staged`` (the new set complete in
the staging folder), ``swapped`` (after the exchange, before the earlier set
is deleted), ``half-swapped`` (between the two renames of the fallback). The
fault tests use it to kill a process exactly between two renames.
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import logging
import os
import re
import shutil
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from xfemslip import interrupt
from xfemslip.errors import OutputError, UsageError
from xfemslip.io.lock import folder_lock, reason, remove_tree, sibling

logger = logging.getLogger(__name__)

PAUSE_ENV = "XFEMSLIP_TEST_PAUSE"
PAUSE_LIMIT_S = 600.0  # a paused process that nobody signals goes on after this

# The files a run writes into its folder (an earlier set of them is refused
# without --overwrite).
RUN_FILES = (
    "result.h5",
    "result.vtu",
    "fractures.vtu",
    "result.pvd",
    "fractures.pvd",
    "result.xdmf",
    "result_steps.xdmf",
    "profile.csv",
)
# Every name an xfemslip command writes into a result folder: an earlier one is
# never carried into a new set, whichever command wrote it.
OWNED = frozenset(
    {
        *RUN_FILES,
        "steps",
        "figures",
        "critical_depletion.csv",
        "slip_vs_depletion.csv",
        "slip_vs_depletion.png",
        "depletion_field.png",
    }
)
# Temporary files of a single-file write (writers.atomic) in an earlier folder.
_TEMP_FILE = re.compile(r"\..+\.tmp-\d+")
_EXCHANGE_UNSUPPORTED = {errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP, errno.ENOTSUP}


@dataclass
class Staging:
    """Where a set is written before it is swapped into ``final``."""

    display: Path  # the folder as the user named it (for messages)
    final: Path  # the same, resolved (symlinks followed)
    path: Path | None  # the staging folder: write every file of the set here
    committed: bool = False  # the swap has happened


def pause_for_test(point: str) -> None:
    """The test hook of the module docstring (no effect without the variable)."""
    if os.environ.get(PAUSE_ENV) != point:
        return
    sys.stderr.write(f"xfemslip: test pause at {point} (pid {os.getpid()})\n")
    sys.stderr.flush()
    deadline = time.monotonic() + PAUSE_LIMIT_S
    while interrupt.pending() is None and time.monotonic() < deadline:
        time.sleep(0.01)
    if interrupt.deferring():  # a deferred signal is honoured when the block ends
        return
    interrupt.checkpoint()


# --------------------------------------------------------------------------- #
# The output folder
# --------------------------------------------------------------------------- #


@contextlib.contextmanager
def output_folder(
    folder: Path | str,
    *,
    overwrite: bool = True,
    results: tuple[str, ...] = (),
    owned: frozenset[str] = OWNED,
) -> Iterator[Staging]:
    """Write a set of files into ``folder`` as the module docstring says.

    Parameters
    ----------
    folder : Path
        The output folder ``DIR``; created (with its parents) when missing.
    overwrite : bool
        When False, a ``DIR`` that holds any of ``results`` is refused.
    results : tuple of str
        Names whose presence means ``DIR`` holds results.
    owned : set of str
        Top-level names of earlier xfemslip outputs, never carried over.

    Yields
    ------
    Staging
        Write every file into ``staging.path``; on normal exit of the block the
        set is swapped into ``DIR``.  If the block raises, nothing is swapped.

    Raises
    ------
    UsageError
        ``DIR`` is a file or a mount point, holds results and ``overwrite``
        is False, or is being written by another process (exit 2).
    OutputError
        ``DIR`` or its parent cannot be written (exit 1).
    """
    display = Path(folder)
    final = _resolve(display)
    created = _make_parents(final, display)
    stage = Staging(display, final, None)
    try:
        with folder_lock(final, display):
            try:
                pause_for_test("locked")
                _check_target(final, display, overwrite, results)
                stage.path = _make_staging(final, display)
                yield stage
                with interrupt.deferred():
                    _commit(stage, owned)
            except BaseException as exc:
                _unwind(stage, created, exc)
                raise
    finally:
        if not stage.committed:
            _remove_created(created)


def _unwind(stage: Staging, created: list[Path], exc: BaseException) -> None:
    """Delete the staging folder of a set that was not swapped in; let the
    error say what the folder holds, in the user's name for it."""
    if stage.path is not None and not stage.committed:
        remove_tree(stage.path)
    if isinstance(exc, KeyboardInterrupt):
        exc.add_note(_interrupted_note(stage, created))
    if isinstance(exc, OutputError) and stage.path is not None:
        exc.args = (str(exc).replace(str(stage.path), str(stage.display)),)


def _interrupted_note(stage: Staging, created: list[Path]) -> str:
    """What an interrupted command leaves in its folder (for the CLI's line)."""
    if stage.committed:
        return f"{stage.display} holds the complete new result"
    if created or not stage.final.is_dir():
        return f"nothing was written to {stage.display}"
    return f"{stage.display} keeps its earlier content"


def _resolve(display: Path) -> Path:
    """The folder with symlinks resolved (a symlinked DIR keeps its link)."""
    try:
        return Path(os.path.realpath(display))
    except ValueError as err:  # an embedded NUL byte
        raise UsageError(f"{str(display)!r}: not a valid folder name ({err})") from None


def _make_parents(final: Path, display: Path) -> list[Path]:
    """Create the missing parents of ``final``; returns them, outermost first."""
    missing = []
    parent = final.parent
    while not os.path.lexists(parent):
        missing.append(parent)
        parent = parent.parent
    missing.reverse()
    try:
        for path in missing:
            os.mkdir(path)
        if not final.parent.is_dir():
            raise NotADirectoryError(errno.ENOTDIR, os.strerror(errno.ENOTDIR))
    except OSError as err:
        _remove_created(missing)
        if err.errno == errno.ENAMETOOLONG:
            raise UsageError(f"{display}: {reason(err)}") from None
        raise OutputError(
            f"cannot create output directory {display}: {reason(err)}"
        ) from None
    return missing


def _remove_created(created: list[Path]) -> None:
    """Remove the folders a failed command created, innermost first, if empty."""
    for path in reversed(created):
        with contextlib.suppress(OSError):
            os.rmdir(path)


def _check_target(final: Path, display: Path, overwrite: bool, results) -> None:
    """Refuse a DIR that cannot be replaced, or holds results without overwrite."""
    if not os.path.lexists(final):
        return
    if not final.is_dir():
        raise UsageError(f"{display} exists and is not a directory")
    if _holds_cwd(final):
        raise UsageError(
            f"{display} is (or holds) the current directory; an output folder "
            "is replaced whole, so choose a folder of its own, e.g. -o "
            f"{display / 'out'}"
        )
    if os.path.ismount(final):
        raise UsageError(
            f"{display} is a mount point, which cannot be replaced; "
            "write into a folder inside it"
        )
    if not os.access(final, os.W_OK):
        readonly = os.statvfs(final).f_flag & os.ST_RDONLY
        why = errno.EROFS if readonly else errno.EACCES
        raise OutputError(f"cannot write {display}: {os.strerror(why)}")
    existing = [name for name in results if os.path.lexists(final / name)]
    if existing and not overwrite:
        raise UsageError(
            f"{display} already holds {', '.join(existing)}; "
            "use --overwrite to replace it or -o to choose another directory"
        )


def _holds_cwd(final: Path) -> bool:
    """Whether the current directory is ``final`` or inside it (swapping it
    would leave this process in the deleted earlier folder)."""
    try:
        cwd = Path(os.getcwd())
    except OSError:
        return False
    return cwd == final or final in cwd.parents


def _make_staging(final: Path, display: Path) -> Path:
    staging = sibling(final, "tmp", os.getpid())
    try:
        os.mkdir(staging)
    except OSError as err:
        if err.errno == errno.ENAMETOOLONG:
            raise UsageError(f"{display}: {reason(err)}") from None
        raise OutputError(f"cannot write {display}: {reason(err)}") from None
    return staging


# --------------------------------------------------------------------------- #
# The swap
# --------------------------------------------------------------------------- #


def _commit(stage: Staging, owned: frozenset[str]) -> None:
    """Swap the complete staging folder into place; delete the earlier set."""
    pause_for_test("staged")
    interrupt.checkpoint()  # a signal before the swap keeps the earlier set
    final, staging = stage.final, stage.path
    assert staging is not None  # only a staged set is committed
    try:
        if not final.is_dir():
            os.rename(staging, final)
            stage.committed = True
            return
        # the new set's names and earlier xfemslip outputs are not carried
        replaced = owned | frozenset(os.listdir(staging))
        carried = _carry_over(final, staging, replaced)
        old = _swap(staging, final)
        stage.committed = True
    except OSError as err:
        raise OutputError(f"cannot write {stage.display}: {reason(err)}") from None
    pause_for_test("swapped")
    _remove_old(old, final, carried, replaced)


def _replaced(name: str, replaced: frozenset[str]) -> bool:
    """Whether the top-level entry ``name`` of DIR goes with the earlier set."""
    return name in replaced or _TEMP_FILE.fullmatch(name) is not None


def _carry_over(final: Path, staging: Path, replaced: frozenset[str]) -> dict:
    """Link the foreign entries of ``final`` into ``staging``.

    Returns {relative path: (st_dev, st_ino)} of every file carried, so that
    only those are deleted with the earlier set.
    """
    carried: dict = {}
    with os.scandir(final) as entries:
        for entry in entries:
            if _replaced(entry.name, replaced):
                continue
            _link_tree(Path(entry.path), staging / entry.name, carried, final)
    return carried


def _link_tree(src: Path, dst: Path, carried: dict, root: Path) -> None:
    """Recreate ``src`` at ``dst``: folders anew, files as hard links."""
    if src.is_dir() and not src.is_symlink():
        if os.path.ismount(src):
            raise OSError(errno.EBUSY, f"{src} is a mount point")
        os.mkdir(dst)
        with os.scandir(src) as entries:
            for entry in entries:
                _link_tree(Path(entry.path), dst / entry.name, carried, root)
        shutil.copystat(src, dst, follow_symlinks=False)
        return
    try:
        os.link(src, dst, follow_symlinks=False)
    except OSError:  # no hard links here (another device, FAT, ...): copy
        shutil.copy2(src, dst, follow_symlinks=False)
    info = os.lstat(src)
    carried[src.relative_to(root)] = (info.st_dev, info.st_ino)


def _swap(staging: Path, final: Path) -> Path:
    """Exchange ``staging`` and ``final``; returns where the earlier set is now."""
    try:
        _rename_exchange(staging, final)
        return staging
    except OSError as err:
        if err.errno not in _EXCHANGE_UNSUPPORTED:
            raise
    old = sibling(final, "old", os.getpid())
    os.rename(final, old)
    pause_for_test("half-swapped")
    try:
        os.rename(staging, final)
    except OSError:
        os.rename(old, final)  # put the earlier set back
        raise
    return old


_LIBC: list[ctypes.CDLL] = []


def _rename_exchange(a: Path, b: Path) -> None:
    """``renameat2(a, b, RENAME_EXCHANGE)``: swap two paths atomically (Linux)."""
    if not _LIBC:
        _LIBC.append(ctypes.CDLL(None, use_errno=True))
    function = getattr(_LIBC[0], "renameat2", None)
    if function is None:
        raise OSError(errno.ENOSYS, "renameat2 is not available")
    at_fdcwd, rename_exchange = -100, 2  # <fcntl.h>, <linux/fs.h>
    if function(at_fdcwd, os.fsencode(a), at_fdcwd, os.fsencode(b), rename_exchange):
        code = ctypes.get_errno()
        raise OSError(code, os.strerror(code))


def _remove_old(old: Path, new: Path, carried: dict, replaced) -> None:
    """Delete the earlier set at ``old``.  An entry that is neither an xfemslip
    output nor carried over (written into DIR while the swap ran) is moved
    into the new folder, never deleted."""
    stack = [(old, new)]
    while stack:
        src, dst = stack.pop()
        with os.scandir(src) as entries:
            for entry in entries:
                path = Path(entry.path)
                if src == old and _replaced(entry.name, replaced):
                    remove_tree(path)
                elif entry.is_dir(follow_symlinks=False):
                    stack.append((path, dst / entry.name))
                elif carried.get(path.relative_to(old)) == _identity(path):
                    path.unlink()
                else:
                    _rescue(path, dst / entry.name)
    remove_tree(old)


def _identity(path: Path) -> tuple[int, int]:
    info = os.lstat(path)
    return info.st_dev, info.st_ino


def _rescue(path: Path, target: Path) -> None:
    """Move a file that appeared in DIR during the swap into the new DIR."""
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        os.replace(path, target)
        logger.warning("kept %s, written into the folder while it was replaced", target)
    except OSError as err:
        logger.warning("could not keep %s: %s", path, reason(err))
