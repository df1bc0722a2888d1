"""Slip-weakening friction in whole solves: the constant law bit for bit when
static = dynamic, a stable weakening path against constant friction at the
friction it has reached, the history and the output datasets, and the
predictor and Newton remedies with weakening patches.

References: the constant-friction solver (the same code with a number
friction), the friction f(delta) = f_s - (f_s - f_d) delta / D_c written out
here, and the solve without the predictor.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tests.support.casegen import fracture_case
from xfemslip import run_case
from xfemslip.contact import branches
from xfemslip.contact.predictor import predicted_law
from xfemslip.conventions import SLIP, STICK, TANGENT_CONSISTENT
from xfemslip.io.read import read_result
from xfemslip.simulation import build_model
from xfemslip.solve import remedies
from xfemslip.solve.newton import NewtonSolver

POINTS = [[1.0, 1.5], [5.0, 4.0]]  # an interior crack that slips at f = 0.3
FS, FD, DC = 0.3, 0.2, 0.05


def _law(static=FS, dynamic=FD, distance=DC):
    return {
        "law": "slip_weakening",
        "static": static,
        "dynamic": dynamic,
        "slip_distance": distance,
    }


def _spec(friction, patch=None, steps=None, kernels=None):
    spec = fracture_case(POINTS, n=12, friction=friction)
    solver = spec.solver
    if patch is not None:
        solver = dataclasses.replace(solver, contact_patch=patch)
    if kernels is not None:
        solver = dataclasses.replace(solver, kernels=kernels)
    loading = spec.loading
    if steps is not None:
        loading = dataclasses.replace(loading, steps=steps)
    return dataclasses.replace(spec, solver=solver, loading=loading)


@pytest.mark.parametrize("kernels", ["numpy", "numba"])
def test_equal_static_and_dynamic_friction_is_coulomb_bit_for_bit(kernels, tmp_path):
    """The same case with friction = 0.3 and with { static = dynamic = 0.3 }:
    every field of every step, written and read back, is the same bytes;
    the law's run adds accumulated_slip and friction_coefficient."""
    plain = run_case(_spec(0.3, steps=3, kernels=kernels), tmp_path / "a")
    law = run_case(_spec(_law(0.3, 0.3), steps=3, kernels=kernels), tmp_path / "b")
    a, b = read_result(tmp_path / "a"), read_result(tmp_path / "b")
    assert len(a.steps) == len(b.steps) == 3
    for x, y in zip(a.steps + plain.steps, b.steps + law.steps, strict=True):
        np.testing.assert_array_equal(x.displacement, y.displacement)
        for fx, fy in zip(x.fractures, y.fractures, strict=True):
            assert np.any(fx.state == SLIP)
            for name in ("slip", "opening", "normal_traction", "shear_traction"):
                np.testing.assert_array_equal(getattr(fx, name), getattr(fy, name))
            np.testing.assert_array_equal(fx.state, fy.state)
            assert fx.accumulated_slip is None and fx.friction_coefficient is None
            assert np.all(fy.friction_coefficient == 0.3)
            assert np.all(fy.accumulated_slip[fy.state == SLIP] > 0.0)
    np.testing.assert_array_equal(a.stress, b.stress)


def _weakening_path(patch):
    model = build_model(_spec(_law(), patch=patch))
    solver = NewtonSolver(model.problem, 1e-10, 60, "consistent")
    solver.run(4)
    return model, solver


def _constant_at(patch, friction, lam):
    """One load step to lam with constant friction ``friction`` (m,) per
    patch."""
    model = build_model(_spec(FS, patch=patch))
    c = model.contact
    c.friction = friction.copy()
    c.friction_dynamic = friction.copy()
    solver = NewtonSolver(model.problem, 1e-10, 60, "consistent")
    solver.run_path([lam])
    return solver.completed[-1]


def test_one_patch_weakens_by_hand_and_matches_constant_friction():
    """The whole crack as one contact patch (contact_patch = 100 cells): at
    every step its traction sits on the bound of f(delta) = 0.3 - 0.1 delta /
    0.05 at its accumulated slip delta, delta grows with the slip, and a
    single load step with constant friction f(delta) to the same load gives
    the same jump (the path is stable and the slip monotone)."""
    model, solver = _weakening_path(100.0)
    assert model.contact.n == 1
    previous = 0.0
    for step in solver.completed:
        c = step.contact
        assert c.state[0] == SLIP
        delta = float(c.accumulated[0])
        assert previous < delta < DC
        f = FS - (FS - FD) * delta / DC
        assert abs(c.pt[0]) == pytest.approx(f * abs(c.pn[0]), rel=1e-12)
        # the accumulated slip is the plastic slip (monotone, from zero: the
        # case has no initial stress)
        assert delta == pytest.approx(abs(c.slip_plastic[0]), rel=1e-9)
        same = _constant_at(100.0, np.array([f]), step.load_factor).contact
        assert same.gt[0] == pytest.approx(c.gt[0], rel=1e-9)
        assert same.pt[0] == pytest.approx(c.pt[0], rel=1e-9)
        previous = delta


def test_patches_match_constant_friction_at_their_own_friction():
    """With 1.5-cell patches each patch has its own accumulated slip; the
    constant-friction solve with the friction f(delta_p) of every patch p
    reaches the same state at every step."""
    model, solver = _weakening_path(1.5)
    assert model.contact.n >= 5
    for step in solver.completed:
        c = step.contact
        assert np.all(c.state == SLIP)
        f = FS - (FS - FD) * c.accumulated / DC
        np.testing.assert_allclose(c.point_friction, f[model.contact.patch])
        same = _constant_at(1.5, f, step.load_factor).contact
        np.testing.assert_allclose(same.gt, c.gt, rtol=1e-8)
        np.testing.assert_allclose(same.pt, c.pt, rtol=1e-8)


def test_history_is_committed_and_restored():
    model, solver = _weakening_path(1.5)
    c = model.contact
    np.testing.assert_array_equal(
        c.accumulated_committed, solver.completed[-1].contact.accumulated
    )
    saved = c.history()
    c.accumulated_committed = np.zeros(c.n)
    c.restore(saved)
    np.testing.assert_array_equal(
        c.accumulated_committed, solver.completed[-1].contact.accumulated
    )


def test_predictor_gives_the_same_answer_with_weakening():
    """Newton with and without the stick/slip predictor: the same states and
    fields to the solver tolerance (the predictor leaves weakening patches
    to the true law)."""
    runs = []
    for predictor in (False, True):
        model = build_model(_spec(_law(), patch=1.5))
        s = NewtonSolver(model.problem, 1e-10, 60, "consistent", predictor=predictor)
        s.run(4)
        runs.append(s)
    for x, y in zip(runs[0].completed, runs[1].completed, strict=True):
        np.testing.assert_array_equal(x.contact.state, y.contact.state)
        for name in ("pt", "gt", "accumulated"):
            p, q = getattr(x.contact, name), getattr(y.contact, name)
            np.testing.assert_allclose(p, q, rtol=1e-8)


def _weakened_set():
    """A contact set with slip history: half its patches weaken."""
    model, solver = _weakening_path(1.5)
    c = model.contact
    weak = np.arange(c.n) % 2 == 0
    c.friction_dynamic = np.where(weak, FD, FS)
    c.friction = np.full(c.n, FS)
    return c, solver.completed[-1].u, weak


def test_predicted_law_leaves_weakening_patches_to_the_true_law():
    c, u, weak = _weakened_set()
    state = np.full(c.n, SLIP, np.int8)
    sign = np.ones(c.n)
    law = predicted_law(c, state, sign)
    # the constant patches are forced (committed slip -inf), the others not
    assert np.all(np.isneginf(law.slip_committed[~weak]))
    np.testing.assert_array_equal(law.slip_committed[weak], c.slip_committed[weak])


def test_stick_hold_of_a_weakening_patch_is_finite():
    """force_branches(stick_at) makes the cohesion infinite; on a weakening
    patch with accumulated slip within D_c the dynamic cohesion must be too
    (inf - inf would be NaN): the held patches stick with the trial
    traction."""
    c, u, weak = _weakened_set()
    assert np.all((c.accumulated_committed > 0.0) & (c.accumulated_committed < DC))
    held = branches.force_branches(c, stick_at=np.ones(c.n, bool))
    res = held.evaluate(u * 1.1, TANGENT_CONSISTENT, c.pt_committed, c.gt_committed)
    assert np.all(res.state == STICK)
    assert np.all(np.isfinite(res.pt)) and np.all(np.isfinite(res.force))


def test_local_search_skips_weakening_patches():
    c, u, weak = _weakened_set()
    stubborn = weak.copy()
    out = remedies.local_search(
        c, c, u, None, None, stubborn, None, None, None, TANGENT_CONSISTENT
    )
    assert out is None


def test_mixed_fractures_all_carry_the_history_in_every_output(tmp_path):
    """One weakening and one constant fracture: both carry accumulated_slip
    and friction_coefficient in result.h5 (the constant one its friction)
    and in fractures.vtu, read back as written."""
    import meshio

    from xfemslip.case import build, loads_case

    table = {
        "domain": {"size": [6.0, 6.0]},
        "mesh": {"elements": [12, 12]},
        "material": {"E": 10.0e9, "nu": 0.3},
        "fractures": [
            {"points": POINTS, "friction": _law(), "tip": "ramp"},
            {"points": [[0.5, 5.0], [2.5, 5.5]], "friction": 0.25, "tip": "ramp"},
        ],
        "loading": {"stress": build.stress_table((-20.0e6, -40.0e6, 0.0))},
        "boundary": {"bottom": {"ux": 0.0, "uy": 0.0}, "top": "traction"},
        "output": {"formats": ["h5", "vtu"]},
    }
    run_case(loads_case(build.case_text(table)), tmp_path)
    weak, plain = read_result(tmp_path).fractures
    assert np.all(plain.friction_coefficient == 0.25)
    assert np.all(weak.friction_coefficient <= FS)
    assert np.any(weak.friction_coefficient < FS)
    np.testing.assert_allclose(
        weak.friction_coefficient,
        FS - (FS - FD) * np.minimum(weak.accumulated_slip / DC, 1.0),
    )
    vtu = meshio.read(tmp_path / "fractures.vtu")
    both = np.concatenate([weak.accumulated_slip, plain.accumulated_slip])
    np.testing.assert_allclose(
        np.sort(vtu.point_data["accumulated_slip"]), np.sort(both)
    )
