"""SuperLU's elimination order: the nested dissection of the grid
(xfemslip.solve.ordering), where the whole-matrix SuperLU path takes it, and
that it changes the time of a run, not its answer."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from xfemslip.case import build, loads_case
from xfemslip.simulation import build_model
from xfemslip.solve import linear as linsolve
from xfemslip.solve import ordering
from xfemslip.solve.linear import LinearSolver
from xfemslip.solve.newton import NewtonSolver

CASE = Path(__file__).resolve().parents[3] / "cases" / "reservoir_depletion.toml"


def _grid_laplacian(nx, ny):
    """The 9-point pattern of a Q4 grid's nodes (j (nx + 1) + i), SPD."""
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="xy")
    n0 = (j * (nx + 1) + i).ravel()
    cells = np.stack([n0, n0 + 1, n0 + nx + 2, n0 + nx + 1], axis=1)
    rows = np.repeat(cells, 4, axis=1).ravel()
    cols = np.tile(cells, (1, 4)).ravel()
    vals = np.where(rows == cols, 3.0, -1.0)
    N = (nx + 1) * (ny + 1)
    return sp.csc_matrix((vals, (rows, cols)), shape=(N, N)) + sp.identity(N)


def _xy(nx, ny):
    X, Y = np.meshgrid(np.linspace(0, 2.0, nx + 1), np.linspace(0, 1.0, ny + 1))
    return np.column_stack([X.ravel(), Y.ravel()])


@pytest.mark.parametrize("shape", [(0, 0), (1, 0), (3, 7), (8, 4), (17, 5), (40, 40)])
def test_dissection_is_a_permutation(shape):
    rank = ordering.grid_dissection(*shape)
    assert np.array_equal(np.sort(rank), np.arange((shape[0] + 1) * (shape[1] + 1)))


def test_the_middle_line_comes_last_and_separates_the_halves():
    """9 x 5 nodes: the longer side (x) is cut at its middle column i = 4;
    its 5 nodes take the last 5 ranks, every node left of it comes before
    every node right of it, and within each half the same holds again (the
    2 x 2 and 2 x 2 ... boxes down to 4 x 4 nodes)."""
    nx, ny = 8, 4
    rank = ordering.grid_dissection(nx, ny).reshape(ny + 1, nx + 1)  # [j, i]
    assert sorted(rank[:, 4]) == list(range(40, 45))
    assert rank[:, :4].max() < rank[:, 5:].min()
    # the left half (4 x 5 nodes, taller than wide) is cut at its row j = 2
    left = rank[:, :4]
    assert left[2].min() > max(left[:2].max(), left[3:].max())
    assert left[:2].max() < left[3:].min()


def test_dissection_fills_less_than_minimum_degree_and_bands():
    """The factor of a 2-dof-per-node grid matrix in this order has fewer
    entries than in SuperLU's minimum-degree order of A^T + A and than row
    by row (a band); 60 x 60 cells: 0.75M against 0.82M and 1.84M (at
    200 x 200 cells of the elastic stiffness: 12.2M against 17.3M for
    minimum degree)."""
    nx = ny = 60
    A = sp.kron(_grid_laplacian(nx, ny), np.array([[2.0, 1.0], [1.0, 2.0]])).tocsc()
    settings = {"diag_pivot_thresh": 0.0, "options": {"SymmetricMode": True}}
    dof_node = np.repeat(np.arange(A.shape[0] // 2), 2)
    order = ordering.grid_order(dof_node, _xy(nx, ny))
    nd = spla.splu(ordering.permuted(A, order), permc_spec="NATURAL", **settings)
    mmd = spla.splu(A, permc_spec="MMD_AT_PLUS_A", **settings)
    band = spla.splu(A, permc_spec="NATURAL", **settings)
    assert nd.nnz < mmd.nnz
    assert nd.nnz < 0.5 * band.nnz


def test_grid_order_keeps_a_nodes_dofs_together():
    """Two standard dofs per node and enriched dofs of some nodes numbered
    after them: a node's dofs are consecutive, in their own order, the nodes
    in grid_dissection's order; the grid is found from the coordinates
    (graded, shuffled node numbering of the same grid gives the same order
    of the same nodes)."""
    nx, ny = 6, 3
    xy = _xy(nx, ny) ** [2.0, 1.0]  # graded in x
    n_nodes = xy.shape[0]
    enriched = np.array([5, 9, 9, 20])  # node 9 carries two functions
    dof_node = np.concatenate(
        [np.repeat(np.arange(n_nodes), 2), np.repeat(enriched, 2)]
    )
    order = ordering.grid_order(dof_node, xy)
    assert np.array_equal(np.sort(order), np.arange(dof_node.size))
    nodes = dof_node[order]
    starts = np.r_[0, np.nonzero(np.diff(nodes))[0] + 1]
    assert np.unique(nodes[starts]).size == starts.size  # each node in one run
    for s, e in zip(starts, np.r_[starts[1:], nodes.size], strict=True):
        assert np.all(np.diff(order[s:e]) > 0)  # in their own order
    rank = ordering.grid_dissection(nx, ny)
    assert np.all(np.diff(rank[nodes[starts]]) > 0)
    # the same grid with its nodes numbered in another order
    perm = np.random.default_rng(1).permutation(n_nodes)
    moved = np.empty(n_nodes, np.int64)
    moved[perm] = np.arange(n_nodes)  # node k is now moved[k]
    again = ordering.grid_order(moved[dof_node], xy[perm])
    assert np.array_equal(again, order)


def test_permuted_is_the_symmetric_permutation():
    A = sp.random(40, 40, density=0.2, random_state=3, format="csr")
    order = np.random.default_rng(0).permutation(40)
    B = ordering.permuted(A, order)
    assert B.format == "csc" and B.has_sorted_indices
    assert abs(B - A[order][:, order]).max() == 0.0


def test_ordered_lu_solves_the_original_system():
    nx, ny = 20, 12
    A = _grid_laplacian(nx, ny)
    order = ordering.grid_order(np.arange(A.shape[0]), _xy(nx, ny))
    lu, solve = linsolve.lu_factor(A, order=order)
    rng = np.random.default_rng(2)
    b = rng.standard_normal(A.shape[0])
    x = spla.spsolve(A, b)
    for got in (lu.solve(b), solve(b)):
        assert np.linalg.norm(got - x) <= 1e-12 * np.linalg.norm(x)
    B = rng.standard_normal((A.shape[0], 3))
    X = spla.spsolve(A, B)
    assert np.linalg.norm(lu.solve(B) - X) <= 1e-12 * np.linalg.norm(X)


def _model(n):
    text = build.case_text(build.file_case(CASE, **{"mesh.elements": [n, n]}))
    return build_model(loads_case(text, CASE))


def test_the_order_applies_by_the_share_of_enriched_dofs(monkeypatch):
    """The grid's order is taken when the enriched dofs are at most
    GRID_ORDER_MAX_ENRICHED of the free dofs (the limit set just above and
    just below the reservoir case's share on a coarse mesh), never without
    the dofs' nodes."""
    model = _model(20)
    solver = NewtonSolver(model.problem, 1e-8, 30, "consistent", "superlu")
    share = solver.linear.enriched_share
    assert 0.0 < share < 1.0
    K, free = solver.linear.K, solver.linear.free
    for limit, applies in ((share, True), (np.nextafter(share, 0.0), False)):
        monkeypatch.setattr(linsolve, "GRID_ORDER_MAX_ENRICHED", limit)
        lin = NewtonSolver(model.problem, 1e-8, 30, "consistent", "superlu").linear
        order = lin.elimination_order()
        assert (order is not None) == applies
        if applies:
            assert np.array_equal(np.sort(order), np.arange(K.shape[0]))
    monkeypatch.setattr(linsolve, "GRID_ORDER_MAX_ENRICHED", 1.0)
    bare = LinearSolver(K, "superlu", free, model.mesh.nodes)
    assert bare.enriched_share is None and bare.elimination_order() is None


def test_a_run_gives_the_same_answer_in_either_order(monkeypatch):
    """Two load steps of the reservoir case with SuperLU, in the grid's
    order and in minimum degree: the same Newton iterations and slips to
    the solver's backward error."""
    out = []
    for limit in (1.0, -1.0):
        monkeypatch.setattr(linsolve, "GRID_ORDER_MAX_ENRICHED", limit)
        model = _model(30)
        newton = NewtonSolver(model.problem, 1e-10, 30, "consistent", "superlu")
        steps = newton.run(2)
        ordered = newton.linear.elimination_order() is not None
        out.append((ordered, [s.iterations for s in steps], steps[-1].contact.gt))
    (o1, its1, gt1), (o2, its2, gt2) = out
    assert o1 and not o2
    assert its1 == its2
    assert np.max(np.abs(gt1)) > 1e-4  # it slips
    assert np.max(np.abs(gt1 - gt2)) <= 1e-9 * np.max(np.abs(gt1))
