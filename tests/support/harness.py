"""Helpers of the verification tests: write a case, run it in-process, read result.h5.

Only the public surface of xfemslip is used: ``load_case`` / ``loads_case``,
``run_case`` and the documented ``result.h5`` layout (output-format.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import xfemslip
from xfemslip.case import build, load_case
from xfemslip.conventions import OPEN, SLIP, STICK  # noqa: F401 (re-exported)
from xfemslip.io.read import FRACTURE_ARRAYS
from xfemslip.simulation import run_case
from xfemslip.verify.problems import box_edges, write_edge_csv  # noqa: F401 (re-exported)


@dataclass
class Result:
    """The datasets of one result.h5 (final step) plus the run summary."""

    summary: object
    attrs: dict
    points: np.ndarray
    cells: np.ndarray
    displacement: np.ndarray
    stress: np.ndarray
    fractures: list = field(default_factory=list)  # one dict per fracture

    @property
    def fr(self) -> dict:
        return self.fractures[0]


def case_text(
    *,
    size=(1.0, 1.0),
    origin=(0.0, 0.0),
    elements=(10, 10),
    E=5.0e9,
    nu=0.3,
    model="plane_strain",
    fractures=(),
    stress=None,
    initial_stress=None,
    steps=1,
    boundary=None,
    tolerance=1e-8,
    max_iterations=30,
    formats=("h5",),
) -> str:
    """TOML text of a case; ``fractures`` is a list of dicts of fracture keys,
    ``boundary`` a dict edge -> "traction" | "free" | dict of edge keys."""
    return build.case_text(
        {
            "name": "verification",
            "domain": {"size": size, "origin": origin},
            "mesh": {"elements": elements},
            "material": {"E": E, "nu": nu, "model": model},
            "fractures": list(fractures) or None,
            "loading": {
                "stress": build.stress_table(stress),
                "initial_stress": build.stress_table(initial_stress),
                "steps": steps,
            },
            "boundary": dict(boundary or {}),
            "solver": {"tolerance": tolerance, "max_iterations": max_iterations},
            "output": {"formats": formats},
        }
    )


def read_result(path: Path, summary=None) -> Result:
    """The final step of a result.h5 (read by xfemslip.read_result)."""
    read = xfemslip.read_result(path)
    return Result(
        summary=summary,
        attrs=read.attrs,
        points=read.points,
        cells=read.cells,
        displacement=read.displacement,
        stress=read.stress,
        fractures=[{k: getattr(f, k) for k in FRACTURE_ARRAYS} for f in read.fractures],
    )


def run_text(text: str, folder: Path, name: str = "case") -> Result:
    """Write folder/name.toml, run it into folder/name_out, read the result."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.toml"
    path.write_text(text)
    out = folder / f"{name}_out"
    summary = run_case(load_case(path), out)
    return read_result(out / "result.h5", summary)


def segment(center, length, angle_deg):
    """End points of a straight fracture (case-format.md: center, length, angle)."""
    c = np.asarray(center, float)
    d = (
        0.5
        * length
        * np.array(
            [math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))]
        )
    )
    return [list(c - d), list(c + d)]
