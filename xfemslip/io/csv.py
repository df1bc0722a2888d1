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
from collections.abc import Iterable, Sequence
from pathlib import Path

from xfemslip.io.atomic import atomic_path

__all__ = ["write_csv", "write_rows", "write_text"]


def write_rows(path: Path | str, header: Sequence, rows: Iterable[Sequence]) -> None:
    """Write ``header`` and ``rows`` as CSV to ``path`` (not atomically)."""
    with open(path, "w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh)
        writer.writerow(header)
        writer.writerows(rows)


def write_csv(path: Path | str, header: Sequence, rows: Iterable[Sequence]) -> None:
    """Write a CSV file atomically (OutputError when it cannot be written)."""
    with atomic_path(path) as tmp:
        write_rows(tmp, header, rows)


def write_text(path: Path | str, text: str) -> None:
    """Write a text file atomically (OutputError when it cannot be written)."""
    with atomic_path(path) as tmp:
        Path(tmp).write_text(text, encoding="utf-8")
