"""CSV and text files: the one writer of the tables xfemslip produces.

``write_csv`` and ``write_text`` write a file atomically (complete under its
final name, or not at all; :mod:`xfemslip.io.atomic`); ``write_rows`` writes
straight to the path it is given, for a file of a set that
:func:`xfemslip.io.fileset.replace_files` or an output folder renames in
together.  Rows are text cells, written by :mod:`csv` with its default
``\\r\\n`` line ends, UTF-8.
"""

from __future__ import annotations

import csv
import itertools
from collections.abc import Iterable, Sequence
from pathlib import Path

from xfemslip import interrupt
from xfemslip.io.atomic import atomic_path

__all__ = ["write_csv", "write_rows", "write_text"]


# Rows written between two checkpoints of a deferred signal: a table of a
# million rows takes a minute, and Ctrl-C must not wait for it.
ROWS_PER_CHECKPOINT = 10_000


def write_rows(path: Path | str, header: Sequence, rows: Iterable[Sequence]) -> None:
    """Write ``header`` and ``rows`` as CSV to ``path`` (not atomically); a
    signal held back while a set is written (:func:`xfemslip.interrupt.deferred`)
    is acted on every ROWS_PER_CHECKPOINT rows."""
    rows = iter(rows)
    with open(path, "w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh)
        writer.writerow(header)
        while chunk := list(itertools.islice(rows, ROWS_PER_CHECKPOINT)):
            writer.writerows(chunk)
            interrupt.checkpoint()


def write_csv(path: Path | str, header: Sequence, rows: Iterable[Sequence]) -> None:
    """Write a CSV file atomically (OutputError when it cannot be written)."""
    with atomic_path(path) as tmp:
        write_rows(tmp, header, rows)


def write_text(path: Path | str, text: str) -> None:
    """Write a text file atomically (OutputError when it cannot be written)."""
    with atomic_path(path) as tmp:
        Path(tmp).write_text(text, encoding="utf-8")
