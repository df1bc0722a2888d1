"""The samples of a study share their mesh, enrichment, bulk stiffness and
its factorization (xfemslip.solve.shared): the shared path gives each sample
what the plain build and solve give it, and the same probabilities."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from xfemslip.case import loads_case
from xfemslip.solve import shared
from xfemslip.studies.depletion import deplete
from xfemslip.studies.reactivation import (
    aggregate,
    evaluate_xfem,
    read_sample,
    sample_cases,
)
from xfemslip.studies.uncertainty import loads_uncertainty

# the seed paper's reservoir case (1 m box, a 0.6 m fracture at 45 degrees)
# on 16 x 16 cells, with a pore pressure depleted by 30 MPa in 5 steps
BASE = """
name = "reservoir"
[domain]
size = [1.0, 1.0]
[mesh]
elements = [16, 16]
[material]
E = 5.0e9
nu = 0.3
[[fractures]]
center = [0.5, 0.5]
length = 0.6
angle = 45.0
friction = 0.1
kn = 5.0e12
kt = 5.0e12
[pore_pressure]
initial = 10.0e6
change = -30.0e6
[loading]
initial_stress = { xx = -30.0e6, yy = -40.0e6, xy = 0.0 }
stress = { xx = -30.0e6, yy = -40.0e6, xy = 0.0 }
steps = 5
[boundary]
left = { ux = 0.0 }
right = { ux = 0.0 }
bottom = { uy = 0.0 }
top = "traction"
"""

STUDY = """
name = "study"
base = "base.toml"
[uncertainty]
samples = 6
seed = 7
evaluate = "xfem"
levels = { start = 0.0, stop = -30.0e6, num = 16 }
[uncertainty.inputs]
"fractures[0].friction" = { distribution = "uniform", low = 0.2, high = 0.35 }
"loading.initial_stress.xx" = { distribution = "normal", mean = -30e6, std = 1e6 }
"pore_pressure.initial" = { distribution = "uniform", low = 8e6, high = 12e6 }
"""


@pytest.fixture
def spec(tmp_path):
    (tmp_path / "base.toml").write_text(BASE)
    path = tmp_path / "study.toml"
    path.write_text(STUDY)
    return loads_uncertainty(path.read_text(), path)


def test_shared_samples_give_the_plain_answers(spec, tmp_path):
    """Every sample solved on its own (its own mesh, assembly and SuperLU
    factorizations, outside shared.sharing) against the study, whose
    samples share them: the same bisection brackets, slips to the Newton
    tolerance, the same counts and probabilities."""
    shared.forget()
    plain = {}
    for cid, _text, case, reason in sample_cases(spec):
        assert not reason and case is not None
        assert not shared.active()
        deplete(case, tmp_path / "plain" / cid, overwrite=True)
        plain[cid] = read_sample(tmp_path / "plain" / cid)
    result = evaluate_xfem(spec, tmp_path / "study", jobs=1, force=True)
    assert list(result.status) == ["ok"] * 6
    dp = np.array([plain[cid]["dp_critical"] for cid in result.ids])
    slip = np.array([plain[cid]["max_slip"] for cid in result.ids])
    # the bisection of each sample takes the same decisions: its bracket, to
    # the 30 kPa tolerance, is the plain one to the last digit written
    assert np.isfinite(dp).sum() >= 3  # some samples slip, on both paths
    np.testing.assert_array_equal(np.isnan(result.dp_critical), np.isnan(dp))
    np.testing.assert_allclose(result.dp_critical, dp, rtol=1e-9, atol=0.0)
    # the slip at the last step, to the Newton tolerance (1e-8 relative)
    np.testing.assert_allclose(result.max_slip, slip, rtol=1e-6, atol=1e-12)
    again = aggregate(dataclasses.replace(result, dp_critical=dp))
    np.testing.assert_array_equal(result.slipped, again.slipped)
    np.testing.assert_array_equal(result.probability, again.probability)


def test_a_sample_is_built_from_its_own_case(spec, tmp_path):
    """Kept pieces are the geometry's: each sample's fractures carry its own
    friction (the drawn value), and the second sample's bulk matrix is the
    first one's (the same object: not assembled again)."""
    from xfemslip.simulation import build_model

    shared.forget()
    cases = [c for _, _, c, _ in sample_cases(spec)]
    with shared.sharing():
        a = build_model(cases[0])
        b = build_model(cases[1])
    assert b.bulk is a.bulk and b.mesh is a.mesh
    assert b.fractures[0].friction == cases[1].fractures[0].friction
    assert a.fractures[0].friction == cases[0].fractures[0].friction
    assert a.fractures[0].friction != b.fractures[0].friction
    np.testing.assert_array_equal(
        b.contact.friction, np.full(b.contact.n, cases[1].fractures[0].friction)
    )
    alone = build_model(cases[1])  # outside sharing: built anew
    assert alone.bulk is not b.bulk
    assert (alone.bulk.K != b.bulk.K).nnz == 0
    np.testing.assert_array_equal(alone.problem.F_unit, b.problem.F_unit)


def test_samples_write_no_vtu(spec):
    """A sample's case asks for result.h5 only (the study reads its tables)."""
    for _, text, case, _ in sample_cases(spec):
        assert case.output.formats == ("h5",) or list(case.output.formats) == ["h5"]
        assert loads_case(text, Path("x.toml")).output.formats == case.output.formats


def test_a_run_drops_the_point_values_a_study_keeps(tmp_path):
    """solve_and_write outside sharing drops the enrichment values at the
    points once the model is assembled (the run's answer is that of the
    model that keeps them); within sharing the model keeps them for the
    next sample."""
    from xfemslip.simulation import build_model, newton_solver, solve_and_write

    case = loads_case(BASE, tmp_path / "base.toml")

    def drive(solver, model):
        return solver.run(model.spec.loading.steps)

    plain = solve_and_write(case, None, False, drive)
    assert plain.model.ec.values_released
    model = build_model(case)
    kept = newton_solver(model).run(case.loading.steps)
    assert not model.ec.values_released
    np.testing.assert_array_equal(plain.results[-1].u, kept[-1].u)
    with shared.sharing():
        inside = solve_and_write(case, None, False, drive)
    assert not inside.model.ec.values_released
    shared.forget()
