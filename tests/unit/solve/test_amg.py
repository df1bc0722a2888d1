"""The multigrid hierarchies (xfemslip.solve.amg): the grid's geometric one
(its interpolation against linear fields, its coarse dofs against the fixed
ones, as a preconditioner against a direct solve and against smoothed
aggregation, on uniform, graded and layered grids), and pyamg's smoothed
aggregation with the spectral radius of its prolongation smoother from
Lanczos, against a dense eigenvalue solve, pyamg's own hierarchy and a
direct solve."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from xfemslip.case import build, loads_case
from xfemslip.simulation import build_model
from xfemslip.solve.amg import (
    geometric,
    grid_interpolation,
    jacobi_spectral_radius,
    smoothed_aggregation,
    v_cycle,
)
from xfemslip.solve.linear import rigid_body_modes

pyamg = pytest.importorskip("pyamg")

ROOT = Path(__file__).resolve().parents[3]
CASE = ROOT / "cases" / "reservoir_depletion.toml"
# graded cells (10 m growing by 1.2 to 100 m) and three rock units
FIELD = ROOT / "cases" / "field_section.toml"
# coarsest level of the hierarchies here: 3 levels on the 40 x 40 mesh, the
# coarse ones in 3 x 3 blocks (nodes) as on the large meshes of the AMG path
COARSE = 50


def _problem(case=CASE, **keys):
    """K on the free standard dofs of the case (uncracked where the case
    allows; a fracture enriches other dofs), those dofs and the node
    coordinates."""
    table = build.file_case(case, **keys)
    if case == CASE:
        table = build.with_keys(table, fractures=None)
    problem = build_model(loads_case(build.case_text(table), case)).problem
    free = np.zeros(problem.n_dofs, bool)
    free[: 2 * problem.node_xy.shape[0]] = True
    free[problem.fixed] = False
    dof = np.nonzero(free)[0]
    return problem.K[dof][:, dof].tocsr(), dof, problem.node_xy


def _elasticity(n):
    """K of the uncracked reservoir case on n x n cells on its free dofs,
    and the rigid-body modes of those dofs."""
    K, dof, xy = _problem(**{"mesh.elements": [n, n]})
    return K, rigid_body_modes(xy[dof // 2], dof % 2)


@pytest.fixture(scope="module")
def elasticity():
    return _elasticity(40)  # 3,320 free dofs


def test_spectral_radius_against_a_dense_eigenvalue_solve(elasticity):
    """The Lanczos estimate of rho(D^-1 K) is a Ritz value: at most the
    largest eigenvalue of D^-1/2 K D^-1/2 (dense eigvalsh), within 2 %
    of it after the default steps, and exact once the steps span the space."""
    K, _ = elasticity
    s = 1.0 / np.sqrt(K.diagonal())
    exact = sla.eigvalsh((K.multiply(s[:, None]).multiply(s[None, :])).toarray())[-1]
    estimate = jacobi_spectral_radius(K)
    assert 0.98 * exact <= estimate <= exact * (1.0 + 1e-12)
    small = sp.csr_matrix(np.array([[4.0, 1.0, 0.0], [1.0, 3.0, 1.0], [0.0, 1.0, 2.0]]))
    d = 1.0 / np.sqrt(small.diagonal())
    want = np.linalg.eigvalsh(small.toarray() * np.outer(d, d))[-1]
    assert jacobi_spectral_radius(small) == pytest.approx(want, rel=1e-12)


def test_the_hierarchy_is_pyamgs(elasticity):
    """The same levels as pyamg.smoothed_aggregation_solver with the AMG
    path's options (sizes, formats, non-zeros), prolongators within the
    difference of the two spectral radius estimates (1 %), and as good a
    preconditioner (CG iterations to 1e-10)."""
    K, B = elasticity
    ours = smoothed_aggregation(K, B, COARSE)
    theirs = pyamg.smoothed_aggregation_solver(
        K, B=B, max_coarse=COARSE, coarse_solver="splu", improve_candidates=None
    )
    assert len(ours.levels) == len(theirs.levels) >= 3
    for a, b in zip(ours.levels, theirs.levels, strict=True):
        assert a.A.shape == b.A.shape and a.A.format == b.A.format
        assert a.A.nnz == b.A.nnz
    for a, b in zip(ours.levels[:-1], theirs.levels[:-1], strict=True):
        assert spla.norm(a.P - b.P) <= 0.01 * spla.norm(b.P)
    b = np.random.default_rng(1).random(K.shape[0])
    its = {}
    for name, ml in (("ours", ours), ("theirs", theirs)):
        res: list = []
        ml.solve(b, tol=1e-10, accel="cg", residuals=res, maxiter=100)
        its[name] = len(res) - 1
    assert its["ours"] <= its["theirs"] + 1


def test_a_preconditioned_solve_is_the_direct_solve(elasticity):
    """CG with one V-cycle of the hierarchy per step, to a relative residual
    of 1e-10, gives the direct solution to 1e-8."""
    K, B = elasticity
    M = smoothed_aggregation(K, B, COARSE).aspreconditioner(cycle="V")
    b = np.random.default_rng(2).random(K.shape[0])
    x, info = spla.cg(K, b, M=M, rtol=1e-10, atol=0.0, maxiter=200)
    assert info == 0
    direct = spla.spsolve(K.tocsc(), b)
    assert np.abs(x - direct).max() <= 1e-8 * np.abs(direct).max()


def test_the_hierarchy_does_not_depend_on_numpys_random_state(elasticity):
    """The estimate starts from a vector of its own seed: two set-ups after
    different global seeds give the same prolongators, to the bit."""
    K, B = elasticity
    state = np.random.get_state()  # noqa: NPY002 (the state pyamg draws from)
    try:
        np.random.seed(1)  # noqa: NPY002
        a = smoothed_aggregation(K, B, COARSE)
        np.random.seed(2)  # noqa: NPY002
        b = smoothed_aggregation(K, B, COARSE)
    finally:
        np.random.set_state(state)  # noqa: NPY002
    for la, lb in zip(a.levels[:-1], b.levels[:-1], strict=True):
        assert (la.P != lb.P).nnz == 0


# ------------------------------------------------------------ geometric


@pytest.mark.parametrize("m", [1, 2, 5, 8], ids=lambda m: f"{m}-cells")
def test_grid_interpolation_is_linear_between_the_coarse_nodes(m):
    """Every other node and the last are the coarse grid; the interpolation
    is the identity on them and reproduces a linear function exactly on
    a graded grid (weights by the coordinates), each row summing to 1."""
    x = np.cumsum(np.r_[0.0, 1.3 ** np.arange(m)])
    keep, P = grid_interpolation(x)
    want = list(range(0, m + 1, 2))
    assert keep.tolist() == (want if want[-1] == m else [*want, m])
    assert P.shape == (m + 1, keep.size)
    np.testing.assert_allclose(P[keep].toarray(), np.eye(keep.size))
    np.testing.assert_allclose(P @ (2.0 - 3.0 * x[keep]), 2.0 - 3.0 * x, rtol=1e-14)
    np.testing.assert_allclose(P.sum(axis=1).A1, 1.0, rtol=1e-14)


def test_the_coarse_grids_leave_out_the_fixed_dofs():
    """On 11 x 7 cells (odd in both directions): the first coarse level is
    the nodes of every other grid line and the last, with both components
    except where the fine dof is fixed (u_y along the bottom, the pinned
    u_x); it interpolates a linear displacement field exactly wherever its
    stencil holds no fixed dof."""
    K, dof, xy = _problem(**{"mesh.elements": [11, 7]})
    ml = geometric(K, xy, dof, max_coarse=4)
    assert ml is not None and len(ml.levels) >= 3
    P = ml.levels[0].P
    xs, ys = np.unique(xy[:, 0]), np.unique(xy[:, 1])
    coarse = [(i, j) for j in (0, 2, 4, 6, 7) for i in (0, 2, 4, 6, 8, 10, 11)]
    fixed = set(range(2 * xy.shape[0])) - set(dof.tolist())
    node = {(float(x), float(y)): k for k, (x, y) in enumerate(xy)}
    want = [
        2 * node[(float(xs[i]), float(ys[j]))] + c
        for i, j in coarse
        for c in (0, 1)
        if 2 * node[(float(xs[i]), float(ys[j]))] + c not in fixed
    ]
    assert P.shape == (dof.size, len(want))
    # the coarse dofs in the order of their fine dofs on the grid
    order = sorted(want, key=lambda d: (xy[d // 2, 1], xy[d // 2, 0], d % 2))
    cx, cy = xy[np.array(order) // 2].T
    comp = np.array(order) % 2
    u_c = np.where(comp == 0, 1.0 + 2.0 * cx - cy, -0.5 + cx + 3.0 * cy)
    fx, fy = xy[dof // 2].T
    u_f = np.where(dof % 2 == 0, 1.0 + 2.0 * fx - fy, -0.5 + fx + 3.0 * fy)
    full = np.abs(P).sum(axis=1).A1
    rows = np.isclose(P.sum(axis=1).A1, 1.0) & np.isclose(full, 1.0)
    assert rows.mean() > 0.8
    np.testing.assert_allclose((P @ u_c)[rows], u_f[rows], rtol=1e-12, atol=1e-12)


def test_elongated_cells_are_coarsened_across_their_short_side_only():
    """Cells of 1/120 x 1/10 (12:1): the coarse grids halve the 121 columns
    of nodes (61, 31, 16) and keep the 11 rows until the cells are within
    2:1, then halve both (9 x 6).  Each level's dofs: two per node, less
    u_y along the bottom and the pinned u_x where it is a coarse node (the
    middle of the bottom edge, column 60, is one down to 31 columns)."""
    K, dof, xy = _problem(**{"mesh.elements": [120, 10]})
    ml = geometric(K, xy, dof, max_coarse=4)
    dofs = [level.A.shape[0] for level in ml.levels]
    want = [2 * 121 * 11 - 122, 2 * 61 * 11 - 62, 2 * 31 * 11 - 32]
    assert dofs[:5] == [*want, 2 * 16 * 11 - 16, 2 * 9 * 6 - 9]


def test_nodes_that_are_not_a_whole_grid_have_no_geometric_hierarchy():
    """A node missing from the grid, or one off its lines: None (the AMG
    path then takes smoothed aggregation)."""
    K, dof, xy = _problem(**{"mesh.elements": [6, 6]})
    assert geometric(K, xy, dof, 4) is not None
    moved = xy.copy()
    moved[10, 0] += 1e-3
    assert geometric(K, moved, dof, 4) is None
    assert geometric(K, xy[:-1], dof, 4) is None


@pytest.mark.parametrize(
    ("case", "keys"),
    [
        (CASE, {"mesh.elements": [40, 40]}),
        (CASE, {"mesh.elements": [33, 47]}),
        (CASE, {"mesh.elements": [120, 10]}),
        (FIELD, {"mesh.size": 25.0, "mesh.max_size": 200.0}),
    ],
    ids=["uniform", "odd", "elongated", "graded-layered"],
)
def test_geometric_preconditioner_is_the_direct_solve(case, keys):
    """CG with one geometric V-cycle per step, to a relative residual of
    1e-10, gives the direct solution to 1e-8 on a uniform grid, one with
    odd cell counts, one of 12:1 cells and the field section's graded grid
    with three rock units; in at most one iteration more than smoothed
    aggregation needs (measured: 11 against 14, 14 against 15, 24 against
    68 and 26 against 27)."""
    K, dof, xy = _problem(case, **keys)
    b = np.random.default_rng(3).random(K.shape[0])
    direct = spla.spsolve(K.tocsc(), b)
    its = {}
    for name, ml in (
        ("geometric", geometric(K, xy, dof, COARSE)),
        (
            "aggregation",
            smoothed_aggregation(K, rigid_body_modes(xy[dof // 2], dof % 2), COARSE),
        ),
    ):
        count = [0]
        x, info = spla.cg(
            K,
            b,
            M=ml.aspreconditioner(cycle="V"),
            rtol=1e-10,
            atol=0.0,
            maxiter=300,
            callback=lambda _, c=count: c.__setitem__(0, c[0] + 1),
        )
        assert info == 0
        assert np.abs(x - direct).max() <= 1e-8 * np.abs(direct).max()
        its[name] = count[0]
    assert its["geometric"] <= its["aggregation"] + 1


def test_the_v_cycle_is_pyamgs(elasticity):
    """v_cycle (one V-cycle from zero, without pyamg's residual norms) gives
    pyamg's preconditioner's answer to round-off, on both hierarchies."""
    K, B = elasticity
    _, dof, nodes = _problem(**{"mesh.elements": [40, 40]})
    b = np.random.default_rng(4).random(K.shape[0])
    for ml in (geometric(K, nodes, dof, COARSE), smoothed_aggregation(K, B, COARSE)):
        want = ml.aspreconditioner(cycle="V") @ b
        got = v_cycle(ml)(b)
        assert np.abs(got - want).max() <= 1e-12 * np.abs(want).max()
        assert np.abs(want).max() > 0.0
