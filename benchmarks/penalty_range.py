#!/usr/bin/env python3
"""Range of penalty stiffness over which the shipped cases converge.

Every fracture of each shipped case gets kn = kt = 10^k E/h (E of
[material], h the smallest cell size), k = 3..9; each run is one `xfemslip
run` process with a time bound.  The table gives, per case and k, "ok" with
the Newton iterations of all steps, or the exit code and the start of the
failure message.

    python benchmarks/penalty_range.py [--exponents=-1,0,...] [--only NAME,...]
                                       [--tangent secant]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import tomllib
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # tests.support
from tests.support.hardcases import measure  # noqa: E402
from xfemslip.case import build  # noqa: E402

CASES = [
    "reservoir_depletion",
    "liu_borja_plate",
    "fracture_network",
    "depleting_reservoir",
]


def with_penalty(name: str, exponent: int, tangent=None) -> tuple[str, float]:
    """Case text with kn = kt = 10^exponent E/h on every fracture (and the
    given [solver] tangent), and that kn."""
    doc = tomllib.loads((ROOT / "cases" / f"{name}.toml").read_text())
    if tangent:
        doc.setdefault("solver", {})["tangent"] = tangent
    mesh, domain = doc["mesh"], doc.get("domain", {})
    if "elements" in mesh:
        h = min(s / n for s, n in zip(domain["size"], mesh["elements"], strict=True))
    else:
        h = float(min(np.diff(mesh["x"]).min(), np.diff(mesh["y"]).min()))
    kn = 10.0**exponent * doc["material"]["E"] / h
    for fracture in doc.get("fractures", []):
        fracture["kn"] = fracture["kt"] = kn
    doc.pop("output", None)
    return build.case_text(doc), kn


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--exponents", default="3,4,5,6,7,8,9")
    parser.add_argument("--only", default=",".join(CASES))
    parser.add_argument("--timeout", type=float, default=600.0)
    parser.add_argument("--tangent", choices=["consistent", "secant"])
    opt = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        for name in opt.only.split(","):
            for k in (int(e) for e in opt.exponents.split(",")):
                text, kn = with_penalty(name, k, opt.tangent)
                case = Path(tmp) / f"{name}-{k}.toml"
                case.write_text(text)
                argv = [sys.executable, "-m", "xfemslip", "run", str(case)]
                argv += ["-o", str(Path(tmp) / f"out-{name}-{k}")]
                code, wall, _, lines = measure(argv, opt.timeout, f"{case}.log")
                if code == 0:
                    iters = [ln for ln in lines if "Newton iterations per" in ln]
                    what = "ok " + (iters[-1].split(":")[-1].strip() if iters else "")
                else:
                    errors = [ln for ln in lines if ln.startswith("Error:")]
                    what = (errors[-1] if errors else lines[-1] if lines else "")[:160]
                print(f"{name:20s} 1e{k} E/h ({kn:.2e} Pa/m) exit {code!s:>7s} "
                      f"{wall:6.1f} s  {what}", flush=True)  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
