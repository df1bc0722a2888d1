"""Path following to the loss of equilibrium (xfemslip.solve.continuation).

References: the load factor of the limit point against load control from the
last stable state (just below it Newton converges, just above it there is no
neighbouring equilibrium); the slope of the path by finite differences of
its own points; the two controls against each other; the hand-written
Coulomb bound at the weakened friction of every slipping patch.  The
problem is the Uenishi & Rice fault (tests.support.nucleation) on coarse
cells: the critical length itself is checked in
tests/verification/test_nucleation.py.
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.support import nucleation as ur
from xfemslip.case import build, loads_case
from xfemslip.contact.interface import patch_geometry
from xfemslip.conventions import SLIP
from xfemslip.errors import ConvergenceError
from xfemslip.simulation import build_model, newton_solver
from xfemslip.solve.continuation import ContinuationOptions, follow_to_nucleation

H = 2.0  # cell size along the fault [m]: 10 cells over 2 a_c


@pytest.fixture(scope="module")
def followed():
    model, solver, geometry = ur.model_and_solver(H, "gaussian")
    result = follow_to_nucleation(solver, geometry)
    return model, solver, result


def test_the_limit_point_is_a_maximum_of_the_load(followed):
    """From the last stable state, load control reaches 1e-4 below the
    reported load factor in one Newton iteration and finds no equilibrium
    1e-4 above it."""
    model, solver, result = followed
    n = result.nucleation
    assert n is not None and 0.0 < n.load_factor < 1.0
    last = solver.completed[-1]
    assert last.load_factor == n.load_factor_stable <= n.load_factor
    assert (n.load_factor - n.load_factor_stable) <= 1e-4 * n.load_factor
    c = model.contact
    history = c.history()
    u, res, its = solver.equilibrium(last.u, n.load_factor * (1.0 - 1e-4), 99, 99)
    assert its <= 2
    assert res.accumulated.max() <= n.max_slip
    c.restore(history)
    solver.max_it = 10
    with pytest.raises(ConvergenceError):
        solver.equilibrium(last.u, n.load_factor * (1.0 + 1e-4), 99, 99)
    c.restore(history)


def test_path_rises_with_positive_slope_until_the_limit(followed):
    """Along the control stage the load factor rises, the slip and the
    slipping length grow, and the reported slope matches the finite
    difference of the path's own points (the problem is linear between
    changes of the slipping set, so within a set they agree closely)."""
    _, _, result = followed
    control = [p for p in result.path if np.isfinite(p.slope)]
    assert len(control) >= 2
    lam = np.array([p.load_factor for p in control])
    assert np.all(np.diff(lam) > 0.0)
    assert np.all(np.diff([p.max_slip for p in control]) > 0.0)
    assert np.all(np.diff([p.slipping_length for p in control]) >= 0.0)
    assert all(p.slope > 0.0 for p in control)
    for p, q in zip(control[:-1], control[1:], strict=True):
        if p.slipping_length == q.slipping_length:  # same set: linear
            fd = (q.load_factor - p.load_factor) / (q.control - p.control)
            assert fd == pytest.approx(q.slope, rel=1e-3)
    # the approach ends just past first slip: D_c / 50 of slip at most
    approach = [p for p in result.path if not np.isfinite(p.slope)]
    assert approach[-1].max_slip <= 0.02 * ur.DC


def test_slipping_patches_sit_on_the_weakened_bound(followed):
    """Every slipping patch of the final state carries |p_T| = f(delta)
    |p_N| with f(delta) = f_s - (f_s - f_d) delta / D_c (delta < D_c here),
    and the accumulated slip of result.h5's point field is the patch's."""
    model, solver, result = followed
    res = solver.completed[-1].contact
    slip = res.state == SLIP
    assert slip.sum() >= 4
    delta = res.accumulated[slip]
    assert np.all((delta > 0.0) & (delta < ur.DC))
    f = ur.FS - (ur.FS - ur.FD) * delta / ur.DC
    np.testing.assert_allclose(
        np.abs(res.pt[slip]), f * np.abs(res.pn[slip]), rtol=1e-9
    )
    np.testing.assert_allclose(res.pn[slip], ur.SIGMA_N, rtol=1e-6)
    assert np.array_equal(res.point_accumulated, res.accumulated[model.contact.patch])


def test_nucleation_report(followed):
    """The nucleation point is the patch of largest slip, at the peak of the
    load (x = 0 within a patch), on the fault (index 0); the length lies
    between the stable and the unstable slipping sets."""
    model, solver, result = followed
    n = result.nucleation
    assert n.fracture == 0
    assert abs(n.x) <= 1.5 * H and n.y == pytest.approx(0.0, abs=1e-9)
    res = solver.completed[-1].contact
    assert n.max_slip == res.accumulated.max()
    assert n.slipping_length <= n.length <= n.slipping_length + 2 * 2 * H
    assert n.max_slip < ur.DC


def test_both_controls_find_the_same_limit(followed):
    _, _, potency = followed
    _, solver, geometry = ur.model_and_solver(H, "gaussian")
    peak = follow_to_nucleation(
        solver, geometry, ContinuationOptions(control="max_slip")
    )
    a, b = potency.nucleation, peak.nucleation
    assert b.load_factor == pytest.approx(a.load_factor, rel=1e-4)
    assert b.slipping_length == a.slipping_length
    assert b.length == pytest.approx(a.length, rel=0.02)


def test_a_load_below_the_limit_ends_at_max_load_without_nucleation(followed):
    _, _, result = followed
    stop = 0.97 * result.nucleation.load_factor
    _, solver, geometry = ur.model_and_solver(H, "gaussian")
    out = follow_to_nucleation(solver, geometry, ContinuationOptions(max_load=stop))
    assert out.nucleation is None
    assert solver.completed[-1].load_factor == stop
    assert out.path[-1].load_factor == stop
    assert np.any(solver.completed[-1].contact.state == SLIP)
    # going on from there (a committed slipping state) finds the same limit
    more = follow_to_nucleation(solver, geometry).nucleation
    assert more.load_factor == pytest.approx(result.nucleation.load_factor, rel=1e-4)
    assert more.slipping_length == result.nucleation.slipping_length


def test_no_convergence_at_the_smallest_step_is_one_line_and_keeps_steps():
    _, solver, geometry = ur.model_and_solver(H, "gaussian")
    first = 0.9 * 0.2835  # below the limit (test above: 0.2834 on these cells)
    follow_to_nucleation(solver, geometry, ContinuationOptions(max_load=first))
    kept = len(solver.completed)
    solver.max_it = 0  # no Newton iteration may be taken
    with pytest.raises(ConvergenceError) as info:
        follow_to_nucleation(solver, geometry)
    text = str(info.value)
    assert "\n" not in text
    assert text.startswith(f"continuation step {kept + 1} did not converge: ")
    assert "iteration 0, residual eta = " in text
    assert f"{kept} converged step(s) kept" in text
    assert len(solver.completed) == kept


def test_constant_friction_has_nothing_to_follow(tmp_path):
    table = build.with_keys(ur.case_table(4.0), **{"fractures.0.friction": 0.6})
    model = build_model(loads_case(build.case_text(table)))
    solver = newton_solver(model)
    geometry = patch_geometry(model.contact, model.ip, [0])
    with pytest.raises(ConvergenceError) as info:
        follow_to_nucleation(solver, geometry)
    assert not info.value.retryable
    assert "no fracture has a slip-weakening friction" in str(info.value)


def test_options_are_checked():
    with pytest.raises(ValueError):
        ContinuationOptions(control="arc")
    with pytest.raises(ValueError):
        ContinuationOptions(slip_step=1.0, max_slip_step=0.5)


def _injection_case(change):
    """A fault across a box, a pressurized stretch |x| < 10 m of it (the
    reservoir region, same rock): raising the pore pressure lowers the
    effective normal stress there, so the strength, until the weakening
    stretch loses stability."""
    a = ur.critical_half_length()
    table = ur.case_table(2.0)
    table["loading"]["initial_stress"] = build.stress_table((-20e6, -20e6, 6.5e6))
    table["pore_pressure"] = {"initial": 8e6, "change": change, "region": "reservoir"}
    table["reservoir"] = {
        "box": [-1.0 * a, -4.0, 1.0 * a, 4.0],
        "E": ur.E,
        "nu": ur.NU,
    }
    return loads_case(build.case_text(table))


def test_injection_nucleates_inside_the_pressurized_stretch():
    """A positive pressure change (injection) is followed the same way: the
    weakening patch nucleates inside the pressurized stretch, where the
    effective normal traction fell, at a load factor within the change."""
    model = build_model(_injection_case(6e6))
    solver = newton_solver(model)
    geometry = patch_geometry(model.contact, model.ip, [0])
    result = follow_to_nucleation(solver, geometry)
    n = result.nucleation
    assert n is not None and 0.0 < n.load_factor < 1.0
    assert abs(n.x) < ur.critical_half_length()
    res = solver.completed[-1].contact
    slipping = res.state == SLIP
    # effective normal traction of the slipping patches: raised by the fluid
    assert np.all(res.pn[slipping] > -20e6 + 8e6)
    # and a load 1e-4 above the onset has no equilibrium near the path
    history = model.contact.history()
    solver.max_it = 10
    with pytest.raises(ConvergenceError):
        solver.equilibrium(solver.completed[-1].u, n.load_factor * (1 + 1e-4), 99, 99)
    model.contact.restore(history)


def test_a_small_control_step_on_a_large_displacement_converges():
    """The bordered update meets the linear constraint a . (u - u0) = dc
    exactly, so what is left of it is the round-off of the difference of
    two large displacements: a control step many orders below the
    displacement must still count as met (the path near a patch about to
    slip takes such steps)."""
    from xfemslip.solve.continuation import _constraint_tolerance

    rng = np.random.default_rng(7)
    for dc in (1e-3, 1e-7, 1e-10, 1e-13):
        a = rng.uniform(-20.0, 20.0, 500) * (rng.random(500) < 0.1)
        u0 = rng.uniform(-0.5, 0.5, 500)
        step = rng.normal(size=500)
        u = u0 + step * (dc / float(a @ step))
        g = dc - float(a @ (u - u0))
        assert abs(g) <= _constraint_tolerance(a, u, u0, dc)
        # and it is of the order of that round-off: a control missed by a
        # millionth of a step of 1e-3 m^2 is not met
        assert _constraint_tolerance(a, u, u0, dc) < 1e-9
