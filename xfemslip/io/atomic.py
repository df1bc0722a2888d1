"""Atomic file writes: write to a temporary name, rename when complete.

A failed or interrupted run never leaves a truncated file under the final
name (``output-format.md``).  The temporary file lives in the same directory
as the final one, so the rename is atomic on POSIX and Windows
(:func:`os.replace`).
"""

from __future__ import annotations

import contextlib
import logging
import os
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

from xfemslip.errors import OutputError

logger = logging.getLogger(__name__)


def temp_path_for(final: Path) -> Path:
    """Return the temporary sibling of ``final``: ``.<name>.tmp-<pid>``."""
    return final.with_name(f".{final.name}.tmp-{os.getpid()}")


def _remove_quietly(path: Path) -> None:
    """Delete ``path`` if it exists; ignore errors (used while unwinding)."""
    with contextlib.suppress(OSError):
        path.unlink(missing_ok=True)


def _one_line(err: OSError) -> str:
    """``err`` as a short one-line reason, without the file name."""
    reason = err.strerror or str(err) or type(err).__name__
    return " ".join(str(reason).split())


@contextlib.contextmanager
def atomic_path(final: Path | str) -> Iterator[Path]:
    """Yield a temporary path next to ``final``; rename it onto ``final`` on success.

    Parameters
    ----------
    final : Path
        The file that should exist only once it is complete.

    Yields
    ------
    Path
        Where the body writes.  On normal exit it is renamed onto ``final``
        (replacing an existing file); if the body raises, it is deleted and the
        exception propagates.

    Raises
    ------
    OutputError
        When the file cannot be written or renamed (``OSError`` from the body
        or the rename: permission denied, disk full, missing directory, ...).
        The message is one line naming ``final``.
    """
    final = Path(final)
    tmp = temp_path_for(final)
    try:
        yield tmp
        os.replace(tmp, final)
    except OSError as err:
        _remove_quietly(tmp)
        raise OutputError(f"cannot write {final}: {_one_line(err)}") from err
    except BaseException:
        _remove_quietly(tmp)
        raise
    logger.debug("wrote %s", final)


def refuse_non_finite(value, name: str | Callable[[], str]) -> None:
    """Never write NaN or inf: raise OutputError naming the array (``name``,
    or a function giving it, called only then: an HDF5 object's path is a
    library call, 10 us of each of the thousands of datasets of a network's
    result).

    The last line of defence; ``simulation`` turns a non-finite solution into a
    ConvergenceError before any writer is called.
    """
    array = np.asarray(value)
    if array.dtype.kind in "fc" and not np.all(np.isfinite(array)):
        bad = int(np.count_nonzero(~np.isfinite(array)))
        label = name() if callable(name) else name
        raise OutputError(
            f"refusing to write {label}: {bad} non-finite value(s) (NaN or inf)"
        )
