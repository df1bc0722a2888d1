#!/usr/bin/env python3
"""Time and peak memory of the inputs whose cost must follow the mesh, not
the number of vertices: a 1,000-point zigzag inside one cell, a smooth
2,000-point arc (a digitised fault trace), a 5,000-vertex reservoir polygon,
and `deplete --tolerance 1e-10` (below what the load steps can resolve).

Each input is one `xfemslip` process with a time bound; the table gives its
exit code, wall time, peak resident memory (ru_maxrss of that child alone,
from os.wait4) and the last line it printed.

    python benchmarks/hard_inputs.py [--timeout 60] [--only zigzag,arc,...]
        [--markdown docs/performance/hard_inputs.md]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import mdtable

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # tests.support
from tests.support.hardcases import arc, depletion, measure, polygon, zigzag  # noqa: E402

INPUTS = {
    "zigzag": (zigzag, ["run"]),
    "arc": (arc, ["run"]),
    "polygon": (polygon, ["run"]),
    # ten times the vertices: the cost must stay that of the mesh
    "zigzag-10k": (lambda: zigzag(10_000), ["run"]),
    "arc-20k": (lambda: arc(20_000), ["run"]),
    "polygon-50k": (lambda: polygon(50_000), ["run"]),
    "deplete-1e-10": (depletion, ["deplete", "--tolerance", "1e-10"]),
}

LABELS = {
    "zigzag": "1,000-point zigzag inside one cell",
    "arc": "smooth 2,000-point arc (a digitised fault trace)",
    "polygon": "5,000-vertex reservoir polygon",
    "zigzag-10k": "zigzag of 10,000 points",
    "arc-20k": "arc of 20,000 points",
    "polygon-50k": "polygon of 50,000 vertices",
    "deplete-1e-10": "`deplete --tolerance 1e-10`",
}


def markdown(
    rows: list[tuple[str, object, float, float]], timeout: float, loads
) -> str:
    """The table of docs/performance/hard_inputs.md: per input, the exit code,
    wall time and peak resident memory of its process."""
    text = mdtable.table(
        ["input", "exit", "wall [s]", "peak [MB]"],
        [
            [LABELS[n], code, f"{wall:.2f}", f"{peak:.0f}"]
            for n, code, wall, peak in rows
        ],
    )
    return text + mdtable.note(
        f"Each input one `xfemslip` process with a {timeout:g} s bound", loads
    )


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--timeout", type=float, default=60.0)
    parser.add_argument("--only", default=",".join(INPUTS))
    mdtable.add_option(parser, "docs/performance/hard_inputs.md")
    opt = parser.parse_args()
    rows, loads = [], [mdtable.load()]
    print(f"{'input':14s} {'exit':>7s} {'wall [s]':>9s} {'peak [MB]':>10s}  last line")
    with tempfile.TemporaryDirectory() as tmp:
        for name in opt.only.split(","):
            make, command = INPUTS[name]
            case = Path(tmp) / f"{name}.toml"
            case.write_text(make())
            argv = [sys.executable, "-m", "xfemslip", *command, str(case)]
            argv += ["-o", str(Path(tmp) / f"out-{name}"), "--overwrite"]
            code, wall, peak, lines = measure(
                argv, opt.timeout, Path(tmp) / f"{name}.log"
            )
            last = lines[-1][:100] if lines else ""
            print(f"{name:14s} {code!s:>7s} {wall:9.2f} {peak:10.0f}  {last}")
            rows.append((name, code, wall, peak))
            loads.append(mdtable.load())
    mdtable.write(opt.markdown, markdown(rows, opt.timeout, loads))
    return 0


if __name__ == "__main__":
    sys.exit(main())
