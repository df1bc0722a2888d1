"""Linear solvers of the Newton systems: every path of xfemslip.solve.linear gives
the direct solution (scipy spsolve) of the same systems, and a whole run gives
the same answer with each."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from tests.support.newton_systems import recorded_systems
from xfemslip.case import build, loads_case
from xfemslip.errors import CaseError
from xfemslip.fem.assembly import coo_block
from xfemslip.simulation import build_model
from xfemslip.solve import linear as linsolve
from xfemslip.solve.linear import LinearSolver, choose, rigid_body_modes
from xfemslip.solve.newton import NewtonSolver

CASE = Path(__file__).resolve().parents[3] / "cases" / "reservoir_depletion.toml"
pytest.importorskip("pyamg")


def _text(n, steps=1, fracture=True):
    keys = {"mesh.elements": [n, n], "loading.steps": steps}
    if not fracture:
        keys["fractures"] = None
    return build.case_text(build.file_case(CASE, **keys))


def _newton_systems(n=30, steps=3):
    """Every Newton system (K_ff + K_c, r) of the reservoir case, in order."""
    model = build_model(loads_case(_text(n, steps), CASE))
    # without the stick/slip predictor: the stick, then the slip systems
    solver = NewtonSolver(
        model.problem, 1e-10, 30, "consistent", "superlu", predictor=False
    )
    systems = []
    solve = solver._solve

    def record(res, r, k, it, eta):
        Kc = coo_block(solver.c_dofs, res.blocks, solver.free.size, res.contact.kernels)
        systems.append((Kc, r.copy()))
        return solve(res, r, k, it, eta)

    solver._solve = record
    solver.run(steps)
    return model, solver, systems


@pytest.fixture(scope="module")
def systems():
    return _newton_systems()


@pytest.mark.parametrize("method", ["superlu", "amg"])
def test_every_path_matches_the_direct_solve(systems, method, monkeypatch):
    """The sequence of Newton systems of a 3-step run (stick, then slip with
    the non-symmetric consistent tangent) solved with one LinearSolver, as a
    run does: agreement with spsolve to 1e-8 relative.  The band limits are
    lifted so that the kept-factorization path (Schwarz-GMRES) runs on this
    small mesh, where the band is most of it."""
    monkeypatch.setattr(linsolve, "LU_BAND_LAYERS", 2)
    monkeypatch.setattr(linsolve, "LU_BAND_MAX_FRACTION", 1.0)
    model, newton, seq = systems
    ls = LinearSolver(newton.K_ff, method, newton.free, model.mesh.nodes)
    asym = []
    for Kc, r in seq:
        A = (newton.K_ff + Kc).tocsc()
        asym.append(abs(A - A.T).max() / abs(A).max())
        x_ref = spla.spsolve(A, r)
        x = ls.solve(Kc, r)
        assert np.linalg.norm(x - x_ref) <= 1e-8 * np.linalg.norm(x_ref)
    assert max(asym) > 1e-6  # the slip tangent is not symmetric
    st = ls.stats
    assert st["method"] == method
    if method == "superlu":  # one factorization, the rest through the kept one
        assert st["factorizations"] == 1
        assert st["krylov_iterations"] > 0
    else:
        assert st["factorizations"] == 0
        assert st["krylov_iterations"] >= len(seq)


@pytest.mark.parametrize("method", ["superlu", "amg"])
def test_unchanged_contact_tangent_and_no_fracture(method):
    """Without a fracture: superlu factorizes once and back-solves the second
    system; amg solves the SPD system by CG.  Both match spsolve."""
    model = build_model(loads_case(_text(24, fracture=False), CASE))
    newton = NewtonSolver(model.problem, 1e-10, 30, "consistent", method)
    rng = np.random.default_rng(1)
    ls = newton.linear
    for _ in range(2):
        r = rng.standard_normal(newton.free.size)
        x = ls.solve(None, r)
        x_ref = spla.spsolve(newton.K_ff.tocsc(), r)
        assert np.linalg.norm(x - x_ref) <= 1e-8 * np.linalg.norm(x_ref)
    if method == "superlu":
        assert ls.stats["factorizations"] == 1
        assert ls.stats["krylov_iterations"] == 0


def test_whole_run_agrees_between_linear_solvers(monkeypatch):
    """Same iterations and slip (1e-9 relative) whatever the linear solver."""
    monkeypatch.setattr(linsolve, "LU_BAND_LAYERS", 2)
    monkeypatch.setattr(linsolve, "LU_BAND_MAX_FRACTION", 1.0)
    out = {}
    for method in ("superlu", "amg", "auto"):
        model = build_model(loads_case(_text(30, steps=2), CASE))
        newton = NewtonSolver(model.problem, 1e-10, 30, "consistent", method)
        steps = newton.run(2)
        out[method] = ([s.iterations for s in steps], steps[-1].contact.gt)
    its, gt = out["superlu"]
    assert np.max(np.abs(gt)) > 1e-4  # it slips
    for method in ("amg", "auto"):
        assert out[method][0] == its
        assert np.max(np.abs(out[method][1] - gt)) <= 1e-9 * np.max(np.abs(gt))


def test_auto_choice(monkeypatch):
    monkeypatch.setattr(linsolve.pardiso, "available", lambda: False)
    g = np.linspace(0.0, 1.0, 11)
    square = np.column_stack([np.repeat(g, 11), np.tile(g, 11)])
    stretched = square * [1.0, 5.0]  # cells 0.1 x 0.5
    assert linsolve.cell_aspect_ratio(square) == pytest.approx(1.0)
    assert linsolve.cell_aspect_ratio(stretched) == pytest.approx(5.0)
    n = linsolve.AUTO_AMG_MIN_DOFS
    assert choose("auto", n - 1, square) == "superlu"
    assert choose("auto", n, square) == "amg"
    assert choose("auto", n, stretched) == "superlu"  # AMG fails on such meshes
    assert choose("auto", 10**7, None) == "superlu"  # no coordinates
    assert choose("superlu", 10**7, square) == "superlu"
    assert choose("amg", 10, None) == "amg"


def test_rigid_body_modes_are_the_nullspace_of_an_unconstrained_mesh():
    model = build_model(loads_case(_text(6, fracture=False), CASE))
    n_std = 2 * model.mesh.n_nodes
    K = model.problem.K[:n_std][:, :n_std]
    dof = np.arange(n_std)
    B = rigid_body_modes(model.mesh.nodes[dof // 2], dof % 2)
    assert np.linalg.matrix_rank(B) == 3
    assert np.abs(K @ B).max() <= 1e-9 * abs(K).max()


def test_singular_matrix_is_reported_by_both_paths():
    """A matrix with a zero-energy mode: RuntimeError (the solver turns it into
    the 'tangent matrix is singular' ConvergenceError)."""
    model = build_model(loads_case(_text(8, fracture=False), CASE))
    n_std = 2 * model.mesh.n_nodes
    K = sp.csr_matrix(model.problem.K[:n_std][:, :n_std])  # nothing fixed
    r = np.zeros(n_std)
    r[-1] = 1.0
    for method in ("superlu", "amg"):
        ls = LinearSolver(K, method, np.arange(n_std), model.mesh.nodes)
        with pytest.raises(RuntimeError):
            x = ls.solve(None, r)
            if np.linalg.norm(K @ x - r) > 1e-6:  # a least-squares answer
                raise RuntimeError("no solution")


def test_case_option(tmp_path):
    text = CASE.read_text()
    assert loads_case(text, CASE).solver.linear_solver == "auto"

    # the shipped [solver] table with linear_solver in place of max_iterations
    def solver_is(name):
        keys = {"solver.max_iterations": None, "solver.linear_solver": name}
        return build.case_text(build.file_case(CASE, **keys))

    spec = loads_case(solver_is("amg"))
    assert spec.solver.linear_solver == "amg"
    with pytest.raises(CaseError, match="solver.linear_solver: must be one of"):
        loads_case(solver_is("lu"), "c")


@pytest.mark.slow
def test_default_solver_at_the_amg_size_agrees_with_superlu(monkeypatch):
    """160 x 160 (53k free dofs): "auto" picks AMG with the default band and
    limits (without the mkl extra); the slip and the Newton iterations
    equal those of SuperLU."""
    monkeypatch.setattr(linsolve.pardiso, "available", lambda: False)
    out = {}
    for method in ("auto", "superlu"):
        model = build_model(loads_case(_text(160), CASE))
        newton = NewtonSolver(model.problem, 1e-8, 30, "consistent", method)
        steps = newton.run(1)
        out[method] = (newton.linear.stats, steps[-1].iterations, steps[-1].contact.gt)
    (st_a, it_a, gt_a), (st_s, it_s, gt_s) = out["auto"], out["superlu"]
    assert st_a["method"] == "amg" and st_a["factorizations"] == 0
    # the stick/slip predictor: one Newton system (the slip tangent), so
    # SuperLU factors it once and needs no Krylov steps
    assert st_s["factorizations"] == 1 and st_s["krylov_iterations"] == 0
    assert it_a == it_s == 1
    assert np.max(np.abs(gt_a - gt_s)) <= 1e-8 * np.max(np.abs(gt_s))


def test_backward_error_closed_form():
    # r = A x - b = (0, -0.5): 0.5 / (||A|| ||x|| + ||b||) = 0.5 / (2 * 1 + 2)
    A = sp.csr_matrix(np.array([[2.0, 0.0], [0.0, 1.0]]))
    x, b = np.array([1.0, 1.0]), np.array([2.0, 1.5])
    assert linsolve.backward_error(A, x, b) == pytest.approx(0.125, rel=1e-15)
    assert linsolve.backward_error(A, np.array([np.nan, 1.0]), b) == np.inf


class _Inexact:
    """A factorization whose solves are off by a relative `error` (or zero)."""

    def __init__(self, A, error):
        self.A, self.error = A.toarray(), error

    def solve(self, b):
        if self.error is None:
            return np.zeros_like(b)
        return np.linalg.solve(self.A, b) * (1.0 + self.error)


@pytest.mark.parametrize(
    ("error", "refined", "fallen_back"), [(1e-6, 1, 0), (None, 1, 1)]
)
def test_refinement_then_fallback(monkeypatch, error, refined, fallen_back):
    """A slightly wrong fast solve is fixed by one refinement step (no new
    factorization); a useless one goes to the safe settings."""
    real = linsolve._splu

    def fake(A, settings):
        return _Inexact(A, error) if settings is linsolve.LU_FAST else real(A, settings)

    monkeypatch.setattr(linsolve, "_splu", fake)
    rng = np.random.default_rng(3)
    M = rng.standard_normal((30, 30)) + 30.0 * np.eye(30)
    b = rng.standard_normal(30)
    stats = {}
    x = linsolve.lu_factor(sp.csc_matrix(M), stats)[1](b)
    np.testing.assert_allclose(x, np.linalg.solve(M, b), rtol=1e-11)
    assert stats.get("refinements", 0) == refined
    assert stats.get("fallbacks", 0) == fallen_back


def test_kept_factorization_takes_small_contact_changes(monkeypatch):
    """Where the band is too large for the Schwarz sweep (here: all of it),
    a system whose contact tangent differs from the factored one in a few
    patches is solved by GMRES on the kept factorization, within the rank
    bound of the change (2 per changed patch, + KEPT_GMRES_EXTRA): the
    Newton systems of a 3-step run, in order, agree with spsolve to 1e-8,
    with fewer factorizations than changed tangents."""
    monkeypatch.setattr(linsolve, "LU_BAND_MAX_FRACTION", 0.0)
    newton, seq = recorded_systems(_text(30, 3), CASE, 3)
    ls = LinearSolver(
        newton.K_ff,
        "superlu",
        newton.free,
        newton.p.node_xy,
        newton.c_dofs,
        kernels=newton.p.contact.kernels,
    )
    changed, ranks = 0, []
    last = None
    for blocks, r in seq:
        if last is not None and not np.array_equal(blocks, last):
            changed += 1
        last = blocks
        ls._blocks_now = blocks
        ranks.append(ls._change_rank())
        ls._blocks_now = None
        x = ls.solve_contact(blocks, r)
        Kc = coo_block(
            newton.c_dofs, blocks, newton.free.size, newton.p.contact.kernels
        )
        x_ref = spla.spsolve((newton.K_ff + Kc).tocsc(), r)
        assert np.linalg.norm(x - x_ref) <= 1e-8 * np.linalg.norm(x_ref)
    st = ls.stats
    small = [
        k
        for k in ranks[1:]
        if k is not None
        and 0 < k <= linsolve.KEPT_GMRES_MAX - 1 - linsolve.KEPT_GMRES_EXTRA
    ]
    assert small, ranks  # the run has small changes to take
    assert (
        0
        < st["krylov_iterations"]
        <= sum(k + 1 + linsolve.KEPT_GMRES_EXTRA for k in small)
    )
    assert st["factorizations"] < 1 + changed


def test_change_rank_counts_two_per_changed_patch():
    """The rank bound of a contact tangent change: 2 per patch whose block
    differs from the factored one; unknown without blocks."""
    ls = LinearSolver(sp.identity(8, format="csr"), "superlu")
    ref = np.arange(5 * 4 * 4, dtype=float).reshape(5, 4, 4)
    ls._lu_blocks = ref
    now = ref.copy()
    now[1, 0, 3] += 1.0
    now[4] *= 2.0
    ls._blocks_now = now
    assert ls._change_rank() == 4
    ls._blocks_now = ref[:3]
    assert ls._change_rank() is None
    ls._blocks_now = None
    assert ls._change_rank() is None
