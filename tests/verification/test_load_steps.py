"""Proportional monotonic loading: the final answer does not depend on the steps.

Coulomb friction is path dependent, but under proportional, monotonic loading
no point reverses its slip, so 1 step and 5 steps must end in the same state
(case-format.md says so for the shipped cases).  Without cohesion the problem
is moreover positively homogeneous of degree 1 in the load (penalty contact,
Coulomb cone, linear bulk), so every intermediate step must be the final
answer scaled by its load factor k / steps.

Measured: relative slip and displacement differences 1 vs 5 steps 1e-13 to
7e-13 (reservoir, plate, each also with 3 MPa cohesion, where the fracture
sticks in the first steps and slips later).  Newton iterations per step:
reservoir [2] vs [2, 3, 3, 3, 3]; with cohesion [2] vs [1, 1, 3, 4, 3].
(Load-unload hysteresis is not tested: the case format has no unloading.)
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

import xfemslip
from tests.support.harness import SLIP, STICK, read_result
from xfemslip.case import build, load_case
from xfemslip.simulation import run_case

pytestmark = pytest.mark.verification

CASES = Path(__file__).resolve().parents[2] / "cases"


def run_steps(folder: Path, case: str, steps: int, cohesion=None):
    doc = tomllib.loads((CASES / f"{case}.toml").read_text())
    doc["loading"]["steps"] = steps
    doc["output"] = {"formats": ["h5"]}
    if cohesion is not None:
        doc["fractures"][0]["cohesion"] = cohesion
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{case}_{steps}.toml"
    path.write_text(build.case_text(doc))
    out = folder / f"out_{steps}"
    summary = run_case(load_case(path), out)
    return read_result(out / "result.h5", summary), out / "result.h5"


def rel_diff(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(a)))


@pytest.mark.parametrize(
    ("case", "cohesion"),
    [
        ("reservoir_depletion", None),
        ("liu_borja_plate", None),
        ("reservoir_depletion", 3.0e6),
    ],
    ids=["reservoir-tractions", "plate-displacements", "reservoir-cohesion-3MPa"],
)
def test_one_and_five_steps_agree(tmp_path, case, cohesion):
    one, _ = run_steps(tmp_path / "one", case, 1, cohesion)
    five, _ = run_steps(tmp_path / "five", case, 5, cohesion)
    assert np.mean(one.fr["state"] == SLIP) >= 0.8  # premise: the fracture slides
    assert rel_diff(one.fr["slip"], five.fr["slip"]) < 1e-6
    assert rel_diff(one.displacement, five.displacement) < 1e-6
    assert rel_diff(one.fr["normal_traction"], five.fr["normal_traction"]) < 1e-6
    np.testing.assert_array_equal(one.fr["state"], five.fr["state"])
    assert len(five.summary.iterations_per_step) == 5


def test_intermediate_steps_scale_with_the_load(tmp_path):
    """No cohesion: step k of 5 is the final state times k / 5 (homogeneity)."""
    final, h5 = run_steps(tmp_path, "reservoir_depletion", 5)
    steps = xfemslip.read_result(h5).steps
    assert [step.step for step in steps] == [1, 2, 3, 4, 5]
    for k, step in enumerate(steps, start=1):
        lam = k / 5
        np.testing.assert_allclose(
            step.fractures[0].slip,
            lam * final.fr["slip"],
            rtol=0,
            atol=1e-9 * np.max(np.abs(final.fr["slip"])),
        )
        np.testing.assert_allclose(
            step.displacement,
            lam * final.displacement,
            rtol=0,
            atol=1e-9 * np.max(np.abs(final.displacement)),
        )
        np.testing.assert_array_equal(step.fractures[0].state, final.fr["state"])


def test_cohesion_delays_slip(tmp_path):
    """With cohesion c the far-field closed form says the 45-degree fracture sticks
    while |tau| <= c + f |sigma_n|, i.e. up to load factor
    lambda* = c / (|tau| - f |sigma_n|) = 3 / (10 - 0.1 * 30) = 0.43 of the
    reservoir load: steps 1 and 2 (lambda 0.2, 0.4) stick everywhere, the
    last step slides."""
    _, h5 = run_steps(tmp_path, "reservoir_depletion", 5, cohesion=3.0e6)
    steps = xfemslip.read_result(h5).steps
    assert len(steps) == 5
    states = [step.fractures[0].state for step in steps]
    slips = [step.fractures[0].slip for step in steps]
    assert np.all(states[0] == STICK) and np.all(states[1] == STICK)
    # stuck steps are linear in the load: step 2 = 2 x step 1 (elastic penalty jump)
    np.testing.assert_allclose(slips[1], 2 * slips[0], rtol=1e-9)
    assert np.mean(states[4] == SLIP) >= 0.8
    assert np.max(np.abs(slips[4])) > 100 * np.max(np.abs(slips[1]))
