"""A fracture that cannot carry the in-situ stress: the excess is released.

``loading.initial_stress`` puts the body in equilibrium with sigma0 and the
faces with the traction sigma0 . n.  Where that traction is not admissible
(shear above c + f |sigma_n'|, or tension), the first load step releases the
excess: the fracture slips (or opens) by what it drives, as if the same
stress had been applied from zero to the body with the fracture already in
it.  References:

- the closed form of a straight crack in an infinite plane (Phan et al. 2003
  for the frictional slip; Sneddon / Griffith for the opening), the same
  ``closed_form.slip_profile`` as the crack loaded from zero;
- the same crack in the same box loaded from zero (rollers that impose the
  uniform strain of sigma0): the two slips differ by the elastic penalty jump
  of the in-situ traction only (|tau0| / k_t relative to the slip);
- the equilibrium of the whole system with the bulk initial stress included:
  int B^T sigma0 + K u + f_con(u) = the edge forces of the total stress.

Box: the OpenGeoSys peer crack (a = 1 m at 45 degrees, xfemslip.reference.peer), on a
graded mesh of half-width 40 m with cells of h = 0.1 m around the crack.
Measured slip errors (relative L2): 1.169 % released in situ, 1.158 % loaded
from zero through the same rollers, 1.089 % loaded from zero through traction
edges (the rest of the error is the mesh and the finite box: 0.653 / 0.640 /
0.574 % at h = 0.05 m).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import xfemslip
from tests.support.in_situ import NU, SIGMA0, A, E, F, crack_case, rollers
from xfemslip.case import build, load_case
from xfemslip.cli import cli
from xfemslip.conventions import OPEN, SLIP, STICK
from xfemslip.fem.assembly import enriched_part_bbar
from xfemslip.reference import closed_form as cf
from xfemslip.reference import peer
from xfemslip.simulation import build_model, newton_solver, run_case
from xfemslip.studies.depletion import deplete

pytestmark = pytest.mark.verification


def _write(tmp_path, name, doc):
    path = tmp_path / f"{name}.toml"
    path.write_text(build.case_text(doc))
    return load_case(path)


def _steps(out):
    """[(s, slip, opening, state of the final step)] of every step of a
    result.h5."""
    result = xfemslip.read_result(out / "result.h5")
    final = result.fractures[0].state
    return [
        (step.fractures[0].s, step.fractures[0].slip, step.fractures[0].opening, final)
        for step in result.steps
    ]


def _error(s, slip, stress, angle=45.0):
    exact = cf.slip_profile(s, A, E, NU, "plane_strain", stress, angle, F)
    return cf.relative_l2(s, slip, exact)


def test_critically_stressed_crack_slips_as_if_loaded_from_zero(tmp_path):
    """Loaded only through initial_stress (rollers, no further load), the
    crack slips by the closed form to the error of the same crack loaded from
    zero; the two slips differ by the in-situ penalty jump only."""
    released = _write(
        tmp_path, "released", crack_case(0.1, initial=SIGMA0, boundary=rollers())
    )
    loaded = _write(tmp_path, "loaded", crack_case(0.1, boundary=rollers(SIGMA0)))
    run_case(released, tmp_path / "released_out")
    run_case(loaded, tmp_path / "loaded_out")
    ((s, slip_r, _, state),) = _steps(tmp_path / "released_out")
    ((s0, slip_l, _, _),) = _steps(tmp_path / "loaded_out")
    np.testing.assert_array_equal(s, s0)
    err_r, err_l = _error(s, slip_r, SIGMA0), _error(s, slip_l, SIGMA0)
    assert err_r < 0.0125 and err_l < 0.0125  # measured 1.169 % and 1.158 %
    assert abs(err_r - err_l) < 0.0005
    # the in-situ faces start stuck with zero jump under |tau0| = 10 MPa: the
    # released slip lacks the elastic penalty jump tau0 / kt = 2e-6 m
    assert np.abs(slip_r - slip_l).max() < 1.5 * 10.0e6 / peer.PENALTY
    assert np.all(state == SLIP)
    assert np.abs(slip_r).max() > 4.9e-3  # 5.06 mm, not the unreleased 0


def _edge_forces(mesh, boundary_free, stress):
    """Consistent nodal forces (2 n_nodes,) of the uniform traction stress . n
    on the free components of the four edges (rectilinear mesh)."""
    sig = np.array([[stress[0], stress[2]], [stress[2], stress[1]]])
    F = np.zeros(2 * mesh.n_nodes)
    nx, ny = mesh.x.size, mesh.y.size
    node = np.arange(mesh.n_nodes).reshape(ny, nx)
    edges = {
        "bottom": (node[0, :], mesh.x, (0.0, -1.0)),
        "top": (node[-1, :], mesh.x, (0.0, 1.0)),
        "left": (node[:, 0], mesh.y, (-1.0, 0.0)),
        "right": (node[:, -1], mesh.y, (1.0, 0.0)),
    }
    for name, (nodes, coords, n) in edges.items():
        t = sig @ np.array(n)
        half = np.diff(coords) / 2.0
        for comp in boundary_free.get(name, ()):
            np.add.at(F, 2 * nodes[:-1] + comp, t[comp] * half)
            np.add.at(F, 2 * nodes[1:] + comp, t[comp] * half)
    return F


def _initial_stress_force(model, stress):
    """int B^T sigma0 dOmega (n_dofs,) over intact and enriched cells."""
    mesh, bulk, ec = model.mesh, model.bulk, model.ec
    F = np.zeros(bulk.dofmap.n_dofs)
    sxx, syy, sxy = stress
    std = bulk.std_cells
    b = mesh.bounds[std]
    hx, hy = b[:, 1] - b[:, 0], b[:, 3] - b[:, 2]
    xa = np.array([-1.0, 1.0, 1.0, -1.0])  # int dN_a/dx = x_a hy / 2
    ya = np.array([-1.0, -1.0, 1.0, 1.0])  # int dN_a/dy = y_a hx / 2
    dx = xa[None, :] * hy[:, None] / 2.0
    dy = ya[None, :] * hx[:, None] / 2.0
    nodes = mesh.cells[std]
    np.add.at(F, 2 * nodes, sxx * dx + sxy * dy)
    np.add.at(F, 2 * nodes + 1, syy * dy + sxy * dx)
    rows = np.arange(ec.cells.size)
    cell_of_qp = np.repeat(rows, np.diff(ec.qp_offsets))
    area = np.bincount(cell_of_qp, weights=ec.qp_w, minlength=rows.size)
    Bbar = enriched_part_bbar(mesh, ec, rows, ec.qp_w, model.kernels)  # (nc, 3, 8+2S)
    fe = area[:, None] * (sxx * Bbar[:, 0] + syy * Bbar[:, 1] + sxy * Bbar[:, 2])
    dofs = bulk.enr_dofs
    keep = dofs >= 0
    np.add.at(F, dofs[keep], fe[keep])
    return F


@pytest.mark.parametrize(
    "steps, final",
    [(1, SIGMA0), (3, (-16.0e6, -48.0e6, 0.0))],
    ids=["released-only", "three-further-steps"],
)
@pytest.mark.parametrize("tip, tol", [("ramp", 1e-10), ("branch", 2e-4)])
def test_whole_system_is_in_equilibrium_with_the_bulk_initial_stress(
    tmp_path, steps, final, tip, tol
):
    """At every converged step, int B^T sigma0 + K u + f_con(u) balances the
    edge forces of the total stress on the free dofs (bottom and left are
    rollers, top and right carry loading.stress), and every contact patch
    carries an admissible traction.  With the excess subtracted instead of
    released (the clipped in-situ force as reference) this residual is the
    in-situ excess, above 1e-2 of the edge forces.

    With ramp tips the balance holds to round-off.  With branch tips the
    contact force integrates the sqrt(r) jump of the tip functions with Gauss
    points, not exactly, while the bulk integrates their gradients with the
    Duffy rule: the in-situ traction and the bulk initial stress then differ
    by 6e-5 of the edge forces on this 8-cell crack, admissible or not
    (measured), hence the looser bound."""
    doc = crack_case(
        0.25,
        initial=SIGMA0,
        stress=final,
        steps=steps,
        angle=30.0,
        boundary={
            "bottom": {"uy": 0.0},
            "left": {"ux": 0.0},
            "top": "traction",
            "right": "traction",
        },
    )
    # a box of half-width 3 m keeps the check small; equilibrium holds on any box
    coords = [float(v) for v in peer.graded(0.25, half=3.0)]
    doc["mesh"] = {"x": coords, "y": coords}
    doc["fractures"][0]["tip"] = tip
    spec = _write(tmp_path, "equilibrium", doc)
    model = build_model(spec)
    solver = newton_solver(model)
    solver.run(steps)
    p = model.problem
    f0 = _initial_stress_force(model, SIGMA0)
    free = solver.free
    c = model.contact
    for r in solver.completed:
        lam = r.load_factor
        total = tuple(
            s0 + lam * (s1 - s0) for s0, s1 in zip(SIGMA0, final, strict=True)
        )
        F = np.zeros(p.n_dofs)
        # the rollers' free (tangential) components keep the in-situ traction
        F[: 2 * model.mesh.n_nodes] = _edge_forces(
            model.mesh, {"bottom": (0,), "left": (1,)}, SIGMA0
        ) + _edge_forces(model.mesh, {"top": (0, 1), "right": (0, 1)}, total)
        residual = (f0 + p.K @ r.u + r.contact.force - F)[free]
        assert np.linalg.norm(residual) <= tol * np.linalg.norm(F[free])
        res = r.contact
        bound = c.cohesion - c.friction * res.pn
        closed = res.state != OPEN
        assert np.all(res.pn[closed] <= 0.0)
        assert np.all(np.abs(res.pt[closed]) <= bound[closed] * (1 + 1e-12))
        assert np.any(res.state == SLIP)
    # the reference state is not in equilibrium on its own: the excess
    F0 = _edge_forces(
        model.mesh,
        {"bottom": (0,), "left": (1,), "top": (0, 1), "right": (0, 1)},
        SIGMA0,
    )
    F0 = np.pad(F0, (0, p.n_dofs - F0.size))
    excess = (f0 + solver.in_situ.force - F0)[free]
    assert np.linalg.norm(excess) > 1e-2 * np.linalg.norm(F0[free])


def test_further_load_steps_start_from_the_released_state(tmp_path):
    """After the release, three steps that raise the shear (rollers imposing
    the strain of the increment) follow the closed form of the total stress
    sigma0 + lambda dsigma at every step, to the error of the released step."""
    d = (4.0e6, -8.0e6, 0.0)  # more deviatoric: |tau| grows, sigma_n stays
    spec = _write(
        tmp_path,
        "further",
        crack_case(0.1, initial=SIGMA0, stress=SIGMA0, boundary=rollers(d), steps=3),
    )
    run_case(spec, tmp_path / "further_out")
    rows = _steps(tmp_path / "further_out")
    assert len(rows) == 3
    previous = 0.0
    for k, (s, slip, _, state) in enumerate(rows, start=1):
        lam = k / 3
        total = tuple(a + lam * b for a, b in zip(SIGMA0, d, strict=True))
        # measured 1.169 / 1.170 / 1.170 %
        assert _error(s, slip, total) < 0.0125
        assert np.all(state == SLIP)
        assert np.abs(slip).max() > previous
        previous = np.abs(slip).max()


def test_in_situ_tension_opens_the_crack(tmp_path):
    """A horizontal crack with sigma0_yy = +2 MPa across it opens by the
    Griffith profile 4 (1 - nu^2) / E sigma sqrt(a^2 - x^2), carries no
    traction, and does not slip (no shear on it).  The crack lies on the mesh
    line y = 0 (faces along element edges)."""
    sigma0 = (-10.0e6, 2.0e6, 0.0)
    spec = _write(
        tmp_path,
        "tension",
        crack_case(0.1, initial=sigma0, stress=sigma0, boundary=rollers(), angle=0.0),
    )
    run_case(spec, tmp_path / "tension_out")
    ((s, slip, opening, state),) = _steps(tmp_path / "tension_out")
    exact = (
        4.0
        * (1 - NU**2)
        / E
        * sigma0[1]
        * np.sqrt(np.clip(A**2 - (s - A) ** 2, 0, None))
    )
    assert cf.relative_l2(s, opening, exact) < 0.01  # measured 0.62 %
    assert np.all(state == OPEN)
    assert np.abs(slip).max() < 1e-3 * np.abs(opening).max()


def test_admissible_in_situ_traction_is_carried_as_before(tmp_path):
    """With friction 0.5 the same in-situ stress is admissible (|tau| /
    -sigma_n = 1/3): nothing is released, the faces stay stuck with zero
    jump, and the Newton solve takes no iteration."""
    doc = crack_case(0.25, initial=SIGMA0, boundary=rollers())
    doc["fractures"][0]["friction"] = 0.5
    coords = [float(v) for v in peer.graded(0.25, half=3.0)]
    doc["mesh"] = {"x": coords, "y": coords}
    spec = _write(tmp_path, "admissible", doc)
    model = build_model(spec)
    solver = newton_solver(model)
    assert solver._release is None
    np.testing.assert_array_equal(solver.f_c0, solver.in_situ.force)
    solver.run(1)
    r = solver.completed[-1]
    assert r.iterations == 0 and np.all(r.contact.state == STICK)
    assert np.abs(r.u).max() == 0.0


def _reservoir_case(tmp_path, friction):
    """The seed paper's reservoir case with sigma0 = sigma (nothing but the
    in-situ stress) and the fracture's friction replaced."""
    shipped = Path(__file__).parents[2] / "cases" / "reservoir_depletion.toml"
    case = build.file_case(shipped, **{"fractures.0.friction": friction})
    case["loading"]["initial_stress"] = case["loading"]["stress"]
    path = tmp_path / "reservoir.toml"
    path.write_text(build.case_text(case))
    return path


def test_check_prints_the_in_situ_coulomb_margin_and_run_logs_the_release(tmp_path):
    """45 degrees in (-20, -40) MPa: sigma_n = -30 MPa, |tau| = 10 MPa, so the
    margin c + f |sigma_n| - |tau| is -7 MPa with f = 0.1 (released: slips)
    and +5 MPa with f = 0.5 (stable)."""
    runner = CliRunner()
    critical = _reservoir_case(tmp_path, 0.1)
    result = runner.invoke(cli, ["check", str(critical)])
    assert result.exit_code == 0, result.output
    assert "in-situ Coulomb margin -7 MPa (shear above the friction limit" in (
        result.output
    )
    result = runner.invoke(cli, ["run", str(critical), "-o", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    assert (
        "fractures[0]: the initial stress exceeds the friction limit on 0.6 m of "
        "its 0.6 m, by up to 7 MPa of shear" in result.output
    )
    stable = _reservoir_case(tmp_path, 0.5)
    result = runner.invoke(cli, ["check", str(stable)])
    assert "in-situ Coulomb margin 5 MPa (stable)" in result.output
    result = runner.invoke(cli, ["run", str(stable), "-o", str(tmp_path / "o2")])
    assert result.exit_code == 0 and "exceeds the friction limit" not in result.output


def test_deplete_reports_a_fracture_slipping_in_situ_at_zero_change(tmp_path):
    """The shipped depletion case with friction 0.4 on fracture 0 (60 degrees
    in the reservoir: |tau0| = 7.794 MPa > 0.4 x 18.5 MPa): it slips before any
    depletion, so its critical change is 0 at a point of that fracture, found
    without bisection; the other fractures keep their onsets."""
    shipped = Path(__file__).parents[2] / "cases" / "depleting_reservoir.toml"
    case = build.file_case(shipped, **{"fractures.0.friction": 0.4})
    path = tmp_path / "dep.toml"
    path.write_text(build.case_text(case))
    spec = load_case(path)
    assert spec.fractures[0].friction == 0.4 and spec.fractures[1].friction == 0.5
    report = deplete(spec, tmp_path / "out")
    onset = report.onsets[0]
    assert onset.dp_critical == 0.0 and onset.trials == 0
    p = spec.fractures[0].points
    t = (p[-1] - p[0]) / np.linalg.norm(p[-1] - p[0])
    off = (np.array([onset.x, onset.y]) - p[0]) @ np.array([-t[1], t[0]])
    assert abs(off) < 1e-6  # on fracture 0's line
    assert np.isfinite(report.onsets[1].dp_critical)
    assert report.onsets[1].dp_critical < -10.0e6
    assert np.isnan(report.onsets[2].dp_critical)
