"""Key scalars of a run, shared by ``test_cases.py`` and ``regen.py``.

Everything is read from the documented ``result.h5`` (output-format.md,
through ``xfemslip.read_result``); nothing from xfemslip's internals.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from xfemslip import read_result
from xfemslip.case import load_case
from xfemslip.conventions import SLIP
from xfemslip.simulation import run_case

ROOT = Path(__file__).resolve().parents[2]
CASES_DIR = ROOT / "cases"
GOLDEN_DIR = ROOT / "tests" / "regression" / "golden"


def case_files() -> list[Path]:
    return sorted(CASES_DIR.glob("*.toml"))


def golden_path(case: Path) -> Path:
    return GOLDEN_DIR / f"{case.stem}.json"


def run(case: Path, out_dir: Path):
    """``xfemslip run CASE -o OUT_DIR`` in-process; returns its Result."""
    return run_case(load_case(case), out_dir)


def key_scalars(out_dir: Path) -> dict:
    """The pinned scalars of the run written to ``out_dir`` (floats, ints and
    a list of ints)."""
    result = read_result(out_dir / "result.h5")
    points, u, stress = result.points, result.displacement, result.stress
    slips = [f.slip for f in result.fractures]
    states = [f.state for f in result.fractures]
    slip = np.concatenate(slips) if slips else np.zeros(0)
    state = np.concatenate(states) if states else np.zeros(0, np.int8)
    x_mid = 0.5 * (points[:, 0].min() + points[:, 0].max())
    top = points[:, 1] == points[:, 1].max()
    top_centre = np.nonzero(top)[0][np.argmin(np.abs(points[top, 0] - x_mid))]
    scalars = {
        "max_abs_slip": float(np.max(np.abs(slip))) if slip.size else 0.0,
        "min_slip": float(np.min(slip)) if slip.size else 0.0,
        "n_contact_points": int(slip.size),
        "n_slip_points": int(np.sum(state == SLIP)),
        "iterations_per_step": result.iterations_per_step,
        # the reaction is not in the output; the mean vertical stress stands in
        "mean_stress_yy": float(np.mean(stress[:, 1])),
        "top_centre_point": [float(v) for v in points[top_centre]],
        "top_centre_displacement": [float(v) for v in u[top_centre]],
    }
    if result.permeability is not None:  # k_xx, k_yy over in situ, final step
        scalars["permeability_ratio"] = [float(v) for v in result.permeability.ratio()]
    return scalars


def write_golden(case: Path, scalars: dict) -> Path:
    path = golden_path(case)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(
        json.dumps({"case": f"cases/{case.name}", "scalars": scalars}, indent=2) + "\n"
    )
    return path


def read_golden(case: Path) -> dict:
    return json.loads(golden_path(case).read_text())["scalars"]
