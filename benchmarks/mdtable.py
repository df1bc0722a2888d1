"""The markdown tables the benchmarks write into docs/performance/, written
in one place so that every table has the same shape: a header row, the rows,
and a line saying how and where it was measured.

    import mdtable                      # benchmarks/ is first on sys.path
    text = mdtable.table(["case", "wall [s]"], [["reservoir", "0.61"]])
    text += mdtable.note("Medians of 5 whole processes", loads)
    mdtable.write(args.markdown, text)  # prints it; writes it if a path is given

Each benchmark keeps a function that turns its measurements into that text
(``markdown(...)``), separate from the measuring, so that
tests/unit/test_benchmark_tables.py can check it on a synthetic result.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from collections.abc import Iterable, Sequence
from pathlib import Path


def add_option(parser: argparse.ArgumentParser, default_path: str) -> None:
    """The ``--markdown PATH`` option: where the benchmark writes its table."""
    parser.add_argument(
        "--markdown",
        type=Path,
        metavar="PATH",
        default=None,
        help=f"also write the table to PATH (the docs keep it in {default_path})",
    )


def table(header: Sequence[str], rows: Iterable[Sequence[object]]) -> str:
    """A markdown table; every cell is printed as str(cell)."""
    lines = [
        "| " + " | ".join(header) + " |",
        "| " + " | ".join("---" for _ in header) + " |",
    ]
    for row in rows:
        cells = [str(c) for c in row]
        if len(cells) != len(header):
            raise ValueError(
                f"row {cells} has {len(cells)} cells, header {len(header)}"
            )
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def machine(loads: Sequence[float] = ()) -> str:
    """ "x86_64, 2 cores, 2026-11-28, load average 0.9-1.1" (the load part only
    when loads were sampled)."""
    text = f"{platform.machine()}, {os.cpu_count()} cores, {time.strftime('%Y-%m-%d')}"
    if loads:
        low, high = f"{min(loads):.1f}", f"{max(loads):.1f}"
        text += f", load average {low}" + (f"-{high}" if high != low else "")
    return text


def note(how: str, loads: Sequence[float] = ()) -> str:
    """The line under a table: how it was measured, then the machine."""
    return f"\n{how}; {machine(loads)}.\n"


def load() -> float:
    """The one-minute load average now (sampled around each measurement)."""
    return os.getloadavg()[0]


def write(path: Path | None, text: str) -> None:
    """Print the table; write it to ``path`` too when one is given."""
    print(text, flush=True)
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
