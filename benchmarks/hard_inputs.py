#!/usr/bin/env python3
"""Time and peak memory of the inputs whose cost must follow the mesh, not
the number of vertices: a 1,000-point zigzag inside one cell, a smooth
2,000-point arc (a digitised fault trace), a 5,000-vertex reservoir polygon,
and `deplete --tolerance 1e-10` (below what the load steps can resolve).

Each input is one `xfemslip` process with a time bound; the table gives its
exit code, wall time, peak resident memory (ru_maxrss of that child alone,
from os.wait4) and the last line it printed.

    python benchmarks/hard_inputs.py [--timeout 60] [--only zigzag,arc,...]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

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


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--timeout", type=float, default=60.0)
    parser.add_argument("--only", default=",".join(INPUTS))
    opt = parser.parse_args()
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
    return 0


if __name__ == "__main__":
    sys.exit(main())
