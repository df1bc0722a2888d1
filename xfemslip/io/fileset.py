"""Sets of single files: written beside their final names, renamed in together.

For outputs that are a few loose files rather than a folder of their own:
``summary.csv`` with ``dfn_summary.csv`` of a sweep, the figures of ``xfemslip
plot`` and ``screen --plot``, ``verify --csv`` with ``--plot``.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable, Mapping
from pathlib import Path

from xfemslip import interrupt
from xfemslip.errors import OutputError
from xfemslip.io.lock import folder_lock, reason, remove_tree, sibling


def replace_files(writes: Mapping[Path, Callable[[Path], object] | None]) -> list[Path]:
    """Write a set of single files that may lie in different folders.

    Parameters
    ----------
    writes : mapping of final path -> ``write(tmp_path)`` or None
        Each function writes its file completely to the path it is given.  A
        path mapped to None is no longer part of the set and is deleted.

    Returns the paths written.  Each path is locked (``.NAME.lock``, as a
    folder) while the set is written; every file is first written to a
    temporary sibling, and only when all are complete are the earlier files of
    the set deleted and the new ones renamed in.  So the names never show files
    of two runs; a process killed in the microseconds between the first and
    the last rename leaves part of the new set and none of the earlier one,
    and no temporary file survives the next write of the set.

    Raises
    ------
    UsageError
        Another process is writing one of the paths.
    OutputError
        A file cannot be written; no file of the set has changed then.
    """
    finals = sorted(Path(path) for path in writes)
    temps: dict[Path, Path] = {}
    current = finals[0] if finals else None
    try:
        with contextlib.ExitStack() as stack:
            for current in finals:
                current.parent.mkdir(parents=True, exist_ok=True)
                stack.enter_context(folder_lock(current, current))
            with interrupt.deferred():
                for current in finals:
                    write = writes[current]
                    if write is not None:
                        temps[current] = sibling(current, "tmp", os.getpid())
                        write(temps[current])
                        interrupt.checkpoint()
                for current in finals:
                    with contextlib.suppress(FileNotFoundError):
                        os.unlink(current)
                for current, tmp in temps.items():
                    os.replace(tmp, current)
    except OSError as err:
        raise OutputError(f"cannot write {current}: {reason(err)}") from None
    except OutputError as err:  # from a writer that names its temporary file
        staged = temps.get(current) if current is not None else None
        err.args = (str(err).replace(str(staged), str(current)),)
        raise
    finally:
        for tmp in temps.values():
            remove_tree(tmp)
    return list(temps)
