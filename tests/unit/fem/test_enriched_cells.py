"""enrichment.build_enriched_cells (group-wise evaluation) against a
cell-by-cell evaluation of every slot, one candidate at a time."""

from __future__ import annotations

import numpy as np

from tests.support.casegen import fracture_spec
from xfemslip.fem.enrichment import (
    HEAVISIDE,
    build_enriched_cells,
    find_candidates,
    group_values,
)
from xfemslip.fem.mesh import build_mesh
from xfemslip.geometry.fracture import GEOMETRY_TOL
from xfemslip.geometry.junctions import build_fractures


def candidate_values(fractures, cand, k, pts, side, tol, probe=None):
    """F (n,) and grad F (n, 2) of candidate k at points with fracture side (n,).

    probe : (n, 2) points deciding the side of junction lines (default pts).
    """
    F, grad = group_values(
        fractures, cand.fracture[k], cand.tip[k], pts, side, tol, probe
    )
    j = 0 if cand.func[k] == HEAVISIDE else cand.func[k] - 1
    return F[:, j], grad[:, j]


def _network(n=24):
    grid = np.linspace(0.0, 1.0, n + 1)
    mesh = build_mesh(grid, grid)
    lines = [
        ([[0.13, 0.31], [0.82, 0.74]], "branch"),  # crossed by the next (X): its arms
        ([[0.21, 0.77], [0.71, 0.18]], "branch"),
        ([[0.52, 0.12], [0.93, 0.33]], "ramp"),
        ([[0.27, 0.90], [0.62, 0.95]], "branch"),  # second branch-tipped one
    ]
    specs = [fracture_spec(p, i, tip) for i, (p, tip) in enumerate(lines)]
    return mesh, build_fractures(mesh, specs, np.array([0.0, 1.0, 0.0, 1.0]))


def test_every_slot_matches_a_cell_by_cell_evaluation():
    mesh, fractures = _network()
    cand = find_candidates(mesh, fractures)
    ec = build_enriched_cells(mesh, fractures, cand)
    tol = GEOMETRY_TOL * mesh.h_min
    assert ec.slot_cand.shape[1] > 8  # several groups meet in some cell
    checked = 0
    for e, c in enumerate(ec.cells):
        q = slice(ec.qp_offsets[e], ec.qp_offsets[e + 1])
        t = slice(ec.tri_offsets[e], ec.tri_offsets[e + 1])
        tris = ec.tris[t]
        per = (q.stop - q.start) // tris.shape[0]
        cent = tris.mean(axis=1)
        F_e, g_e = ec.qp_values(np.arange(q.start, q.stop))
        for s, k in enumerate(ec.slot_cand[e]):
            if k < 0:
                assert not F_e[:, s].any() and not ec.tri_F[t, :, s].any()
                continue
            fr = fractures[cand.fracture[k]]
            side = fr.side(cent)
            cq = np.repeat(cent, per, axis=0)
            F, g = candidate_values(
                fractures, cand, k, ec.qp_xy[q], np.repeat(side, per), tol, cq
            )
            np.testing.assert_allclose(F_e[:, s], F, rtol=1e-14, atol=1e-14)
            np.testing.assert_allclose(g_e[:, s], g, rtol=1e-14, atol=1e-12)
            Fv, _ = candidate_values(
                fractures,
                cand,
                k,
                tris.reshape(-1, 2),
                np.repeat(side, 3),
                tol,
                np.repeat(cent, 3, axis=0),
            )
            np.testing.assert_allclose(
                ec.tri_F[t, :, s], Fv.reshape(-1, 3), rtol=1e-14, atol=1e-14
            )
            # the slot's node is the candidate's node, its shift F at that node
            assert mesh.cells[c, ec.slot_node[e, s]] == cand.node[k]
            checked += 1
    # every (candidate, cell around its node) pair is a slot, exactly once
    pairs = {
        (int(k), int(c))
        for e, c in enumerate(ec.cells)
        for k in ec.slot_cand[e]
        if k >= 0
    }
    expected = {
        (k, int(c))
        for k, node in enumerate(cand.node)
        for c in np.nonzero((mesh.cells == node).any(axis=1))[0]
    }
    assert pairs == expected and checked == len(expected)


def test_without_point_values_keeps_the_rest_and_refuses_their_use():
    """The copy a solved-only model keeps: no values at the points (their
    arrays emptied), every other array the same objects, and the two
    readers of the values raise instead of reading empty arrays."""
    import pytest

    mesh, fractures = _network()
    ec = build_enriched_cells(mesh, fractures, find_candidates(mesh, fractures))
    assert ec.column_F.size > 0 and not ec.values_released
    bare = ec.without_point_values()
    assert bare.values_released and bare.column_F.size == bare.column_gradF.size == 0
    for name in ("cells", "slot_cand", "qp_xy", "qp_w", "tris", "tri_F"):
        assert getattr(bare, name) is getattr(ec, name)
    with pytest.raises(RuntimeError, match="released"):
        bare.qp_values(np.arange(3))
    with pytest.raises(RuntimeError, match="released"):
        bare.part(slice(0, 2))
    F, _ = ec.qp_values(np.arange(3))  # the original keeps them
    assert F.shape == (3, ec.slot_cand.shape[1])
