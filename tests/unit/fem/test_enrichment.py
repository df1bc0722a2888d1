"""Tests of xfemslip.fem.enrichment (and the assembled bulk matrix it leads to).

Dof map: counts, order, no duplicates.  Candidates: cut-cell nodes (ramp),
tip-radius nodes (branch).  Sliver rule: exactly the enrichments whose
stiffness is zero are dropped.  Matrix: symmetric, and non-singular with a
moderate (Jacobi-scaled) condition number once the contact stick stiffness is
added and the Dirichlet dofs are removed, on every hard geometry of the case
format (tips on nodes and edges, fractures through nodes and along edges, ...).

The 6 x 6 meshes use a 6 m square so that every node has integer coordinates:
fractures "through nodes" or "along edges" are exactly there.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from tests.support.casegen import fracture_case
from xfemslip import conventions
from xfemslip.case import build, loads_case
from xfemslip.fem.assembly import _enriched_matrices
from xfemslip.fem.enrichment import ENRICHMENT_DIAG_RATIO, HEAVISIDE, find_candidates
from xfemslip.simulation import build_model

_case = fracture_case


_CACHE = {}


def _model(points, tip="ramp", n=6, size=6.0):
    key = (repr(points), tip, n, size)
    if key not in _CACHE:
        _CACHE[key] = build_model(_case(points, tip, n, size))
    return _CACHE[key]


# 8 x 8 on the unit square, the interior fracture of the geometry tests
SMALL = ([[0.2, 0.3], [0.8, 0.6]], 8, 1.0)


def _small(tip):
    pts, n, size = SMALL
    return _model(pts, tip, n, size)


# ------------------------------------------------------------------------ dof map


@pytest.mark.parametrize("tip", ["ramp", "branch"])
def test_dof_map_numbers_enriched_dofs_after_the_standard_ones(tip):
    m = _small(tip)
    dm = m.bulk.dofmap
    n_nodes = m.mesh.n_nodes
    assert dm.n_std == 2 * n_nodes == 2 * 81
    kept = dm.cand_dof[dm.cand_dof >= 0]
    assert kept.size > 0
    # contiguous pairs right after the standard dofs, in candidate order, no duplicates
    np.testing.assert_array_equal(kept, dm.n_std + 2 * np.arange(kept.size))
    assert dm.n_dofs == dm.n_std + 2 * kept.size
    assert m.bulk.K.shape == (dm.n_dofs, dm.n_dofs)
    assert m.problem.n_dofs == dm.n_dofs
    # the cell dof tables use exactly the dofs [0, n_dofs)
    enr = m.bulk.enr_dofs
    assert enr.max() < dm.n_dofs
    used = np.unique(np.concatenate([enr[enr >= 0], np.arange(dm.n_std)]))
    np.testing.assert_array_equal(used, np.arange(dm.n_dofs))
    # no dof without stiffness
    assert np.all(m.bulk.K.diagonal() > 0.0)
    # within a cell, no dof appears twice
    for row in enr:
        r = row[row >= 0]
        assert np.unique(r).size == r.size


def test_ramp_candidates_are_the_nodes_of_the_cut_cells():
    m = _small("ramp")
    fr = m.fractures[0]
    cand = find_candidates(m.mesh, m.fractures)
    assert np.all(cand.func == HEAVISIDE) and np.all(cand.tip == -1)
    cut_nodes = np.unique(m.mesh.cells[np.unique(fr.piece_cell)])
    np.testing.assert_array_equal(np.sort(cand.node), cut_nodes)  # each once
    # by hand: the fracture crosses 8 cells, (0.2, 0.3) -> (0.8, 0.6) with slope 1/2
    assert np.unique(fr.piece_cell).size == 8


def test_branch_candidates_near_the_tips():
    pts, _, size = SMALL
    m = _model(pts, "branch", 20, size)  # h = 0.05: room for the default radius
    fr = m.fractures[0]
    cand = find_candidates(m.mesh, m.fractures)
    nodes = m.mesh.nodes
    branch_nodes = set()
    for ti, tip in enumerate(fr.tips):
        near = np.nonzero(np.linalg.norm(nodes - tip.point, axis=1) <= fr.tip_radius)[0]
        tip_cell = fr.piece_cell[0 if tip.end == 0 else -1]
        expected = set(near.tolist()) | set(m.mesh.cells[tip_cell].tolist())
        for node in expected:
            rows = np.nonzero((cand.node == node) & (cand.tip == ti))[0]
            assert sorted(cand.func[rows].tolist()) == [1, 2, 3, 4]
        got = set(cand.node[(cand.tip == ti)].tolist())
        assert got == expected
        branch_nodes |= expected
    # default radius: 4 tip-cell sizes
    assert fr.tip_mode == "branch"
    assert fr.tip_radius == pytest.approx(4 * 0.05)
    heaviside = cand.node[cand.func == HEAVISIDE]
    assert not set(heaviside.tolist()) & branch_nodes
    cut_nodes = set(np.unique(m.mesh.cells[np.unique(fr.piece_cell)]).tolist())
    assert set(heaviside.tolist()) == cut_nodes - branch_nodes


def test_branch_radius_is_capped_so_supports_stay_on_the_tip_segment():
    """16 x 16: the default 4 h = 0.25 m would let B1's ray (radius + one cell
    diagonal) reach past the middle of the 0.67 m fracture: capped to
    L/2 - diagonal."""
    pts, _, size = SMALL
    m = _model(pts, "branch", 16, size)
    fr = m.fractures[0]
    L = float(np.linalg.norm(np.subtract(pts[1], pts[0])))
    assert fr.tip_mode == "branch"
    assert fr.tip_radius == pytest.approx(L / 2 - np.sqrt(2.0) / 16)


def test_too_short_for_branch_falls_back_to_ramp(caplog):
    """8 x 8: half the fracture (2.7 cells) is less than two cell diagonals."""
    pts, n, size = SMALL
    with caplog.at_level("WARNING", logger="xfemslip.geometry.fracture"):
        m = build_model(_case(pts, "branch", n, size))
    assert m.fractures[0].tip_mode == "ramp"
    assert any('uses tip = "ramp"' in r.getMessage() for r in caplog.records)
    assert np.all(find_candidates(m.mesh, m.fractures).func == HEAVISIDE)


# -------------------------------------------------------------------- sliver rule


def _enriched_diagonal(m):
    """Per candidate: its enriched stiffness diagonal (min over x, y) over the
    diagonal of its node's standard dofs, recomputed from the enriched cells."""
    ec = m.ec
    K, _ = _enriched_matrices(m.mesh, ec, m.D, None, backend=m.kernels)
    cand = find_candidates(m.mesh, m.fractures)
    diag = np.zeros((cand.node.size, 2))
    for e in range(ec.cells.size):
        for s in np.nonzero(ec.slot_cand[e] >= 0)[0]:
            diag[ec.slot_cand[e, s]] += K[
                e, 8 + 2 * s : 10 + 2 * s, 8 + 2 * s : 10 + 2 * s
            ].diagonal()
    std = m.bulk.K.diagonal()
    ref = np.column_stack([std[2 * cand.node], std[2 * cand.node + 1]])
    return cand, (diag / ref).min(axis=1)


@pytest.mark.parametrize(
    "points, dropped_nodes",
    [
        # crossing along y = 3: the nodes of the cut cells below the line (y = 2)
        # see H = -1 and R = 1 over their whole support, so N_a (F - F_a) = 0
        pytest.param(
            [[0.0, 3.0], [6.0, 3.0]], [(x, 2.0) for x in range(7)], id="crossing"
        ),
        # interior, tips at mid-edge (1.5, 3) and (4.5, 3): the cut cells below
        # the line have the nodes (1..5, 2); none of them touches the fracture
        # (N_a = 0 on y = 3), so none carries a jump.  Only (3, 2) has an
        # identically zero enrichment (R = 1 over its support); the others are
        # non-zero but smooth, and (1, 2)+(2, 2), (4, 2)+(5, 2) cancel pairwise
        # (the singular matrix the jump rule prevents).
        pytest.param(
            [[1.5, 3.0], [4.5, 3.0]], [(x, 2.0) for x in range(1, 6)], id="interior"
        ),
    ],
)
def test_sliver_rule_drops_the_zero_enrichments_along_a_grid_line(
    points, dropped_nodes
):
    m = _model(points, "ramp")
    cand, ratio = _enriched_diagonal(m)
    dropped = m.bulk.dofmap.cand_dof < 0
    got = sorted(map(tuple, m.mesh.nodes[cand.node[dropped]].tolist()))
    assert got == sorted(dropped_nodes)
    # every dropped one is off the line (no jump); the kept ones are far from
    # zero stiffness
    assert np.all(~np.isclose(m.mesh.nodes[cand.node[dropped], 1], 3.0))
    assert ratio[~dropped].min() > 1e-2
    # nodes on the line are all kept
    on_line = np.isclose(m.mesh.nodes[cand.node, 1], 3.0)
    assert np.all(~dropped[on_line])


@pytest.mark.parametrize("tip", ["ramp", "branch"])
def test_sliver_rule_keeps_everything_for_a_generic_fracture(tip):
    m = _model([[1.3, 1.7], [4.6, 3.9]], tip)
    _, ratio = _enriched_diagonal(m)
    assert np.all(m.bulk.dofmap.cand_dof >= 0)
    # no enrichment is anywhere near zero stiffness (smallest: ~6e-4 for B1..B4
    # on the nodes furthest from the tip, ~1e-2 for the Heaviside ones)
    assert ratio.min() > 2.0 * ENRICHMENT_DIAG_RATIO


# ------------------------------------------------------------- assembled matrix


GEOMETRIES = {
    "generic": [[1.3, 1.7], [4.6, 3.9]],
    "diagonal-through-nodes": [[1.0, 1.0], [5.0, 5.0]],
    "along-edges": [[1.5, 3.0], [4.5, 3.0]],
    "tip-on-node": [[1.0, 2.0], [4.3, 3.7]],
    "tips-on-edges": [[1.5, 2.0], [4.0, 3.3]],
    "crossing": [[0.0, 1.3], [6.0, 4.1]],
    "reaching-one-edge": [[0.0, 2.2], [3.7, 4.1]],
    "kinked-on-a-node": [[1.2, 1.4], [3.0, 3.0], [4.7, 1.9]],
}
# Jacobi-scaled condition numbers seen: ~5e2 with the ramp; with branch functions
# on every node within 4 tip-cell sizes (here most of the 6 x 6 mesh) ~1e6-1e8,
# the known growth of geometric tip enrichment (Bechet et al. 2005).
COND_LIMIT = {"ramp": 1e4, "branch": 1e10}


def _reduced_tangent(m):
    """K_bulk + K_contact(stick, u = 0) on the free dofs, Jacobi-scaled (sparse)."""
    c = m.contact
    res = c.evaluate(
        np.zeros(m.problem.n_dofs),
        conventions.TANGENT_CONSISTENT,
        c.pt_committed,
        c.gt_committed,
    )
    assert np.all(res.state == conventions.STICK)
    K = (m.bulk.K + c.tangent_matrix(res)).tocsr()
    free = np.setdiff1d(np.arange(K.shape[0]), m.problem.fixed)
    A = K[free][:, free]
    d = sp.diags(1.0 / np.sqrt(A.diagonal()))
    return (d @ A @ d).tocsc()


def _extreme_eigenvalues(A):
    """Smallest and largest eigenvalue of the symmetric A.  Sparse (ARPACK; the
    smallest by shift-invert with SuperLU): a dense eigvalsh of ~700 dofs is
    slow when the BLAS threads compete with other processes for the cores."""
    A = 0.5 * (A + A.T)
    lam_max = spla.eigsh(A, k=1, which="LA", tol=1e-6, return_eigenvectors=False)[0]
    try:
        lam_min = spla.eigsh(
            A, k=1, sigma=0.0, which="LM", tol=1e-8, return_eigenvectors=False
        )[0]
    except RuntimeError:  # SuperLU: "Factor is exactly singular"
        lam_min = 0.0
    return lam_min, lam_max


def _check_matrix(m, tip):
    K = m.bulk.K
    scale = abs(K).max()
    assert abs(K - K.T).max() <= 1e-14 * scale
    lam_min, lam_max = _extreme_eigenvalues(_reduced_tangent(m))
    assert lam_min > 0.0, f"singular: smallest eigenvalue {lam_min:.3e}"
    assert lam_max / lam_min < COND_LIMIT[tip]


def test_condition_estimate_agrees_with_a_dense_one():
    m = _model(GEOMETRIES["generic"], "ramp")
    A = _reduced_tangent(m)
    ev = np.linalg.eigvalsh(A.toarray())
    lam_min, lam_max = _extreme_eigenvalues(A)
    assert lam_min == pytest.approx(ev[0], rel=1e-6)
    assert lam_max == pytest.approx(ev[-1], rel=1e-6)


@pytest.mark.parametrize("tip", ["ramp", "branch"])
@pytest.mark.parametrize("name", sorted(GEOMETRIES))
def test_bulk_matrix_symmetric_and_well_conditioned(name, tip):
    _check_matrix(_model(GEOMETRIES[name], tip), tip)


def test_bulk_matrix_along_edges_with_tips_on_nodes_ramp():
    _check_matrix(_model([[1.0, 3.0], [5.0, 3.0]], "ramp"), "ramp")


def test_bulk_matrix_along_edges_with_tips_on_nodes_branch():
    _check_matrix(_model([[1.0, 3.0], [5.0, 3.0]], "branch"), "branch")


# ------------------------------------------------- sub-cells and kink lines of F


def _straddling(tris, point, normal, tol=1e-9):
    d = (tris - point) @ normal
    return (d.min(axis=1) < -tol) & (d.max(axis=1) > tol)


def test_sub_cells_respect_the_fracture_line():
    """Crossing fracture (no tip, R = 1): F = H jumps only across the fracture."""
    m = _model(GEOMETRIES["crossing"], "ramp")
    fr = m.fractures[0]
    assert fr.tips == ()
    assert not _straddling(m.ec.tris, fr.points[0], fr.normal[0]).any()


# the interior fracture of the rotation property test: 2 m long on 8 x 8 cells of 1 m
SHORT = [[1.9599609375, 1.658203125], [3.0400390625, 3.341796875]]


def test_sub_cells_respect_the_ramp_kink_lines():
    """R = clip(-psi/l) kinks along the whole lines psi = 0 and psi = -l, so every
    enriched cell they cross must be cut along them (at HEAD 6d64142 only the
    cells whose centre lay within l + diagonal of the tip were, which made the
    stiffness inexact and orientation-dependent)."""
    m = _model(SHORT, "ramp", n=8, size=8.0)
    ec, fr = m.ec, m.fractures[0]
    bad = set()
    for e in range(ec.cells.size):
        tris = ec.tris[ec.tri_offsets[e] : ec.tri_offsets[e + 1]]
        for tip in fr.tips:
            for point in (tip.point, tip.point - tip.ramp_length * tip.direction):
                if _straddling(tris, point, tip.direction).any():
                    bad.add(int(ec.cells[e]))
    assert not bad, f"cells {sorted(bad)} straddle a ramp kink line"


# -------------------------------------------- closed fracture under hydrostatic load


def _hydrostatic_model(tip, sigma=-5.0e6):
    fracture = {
        "points": SHORT,
        "friction": 0.4,
        "kn": 1.0e12,
        "kt": 1.0e12,
        "tip": tip,
    }
    text = build.case_text(
        {
            "domain": {"size": [8.0, 8.0]},
            "mesh": {"elements": [8, 8]},
            "material": {"E": 10.0e9, "nu": 0.25, "model": "plane_strain"},
            "fractures": [fracture],
            "loading": {"stress": {"xx": sigma, "yy": sigma, "xy": 0.0}},
            "boundary": {
                "bottom": {"uy": 0.0, "traction": True},
                "top": "traction",
                "left": "traction",
                "right": "traction",
            },
        }
    )
    return build_model(loads_case(text))


def _stick_solution(m):
    """Linear solve with every point stuck: u and the contact response at u."""
    p, c = m.problem, m.contact
    res = c.evaluate(
        np.zeros(p.n_dofs),
        conventions.TANGENT_CONSISTENT,
        c.pt_committed,
        c.gt_committed,
    )
    K = (p.K + c.tangent_matrix(res)).tocsr()
    free = np.setdiff1d(np.arange(p.n_dofs), p.fixed)
    u = np.zeros(p.n_dofs)
    u[free] = spla.spsolve(K[free][:, free].tocsc(), p.F_unit[free])
    return c.evaluate(u, conventions.TANGENT_CONSISTENT, c.pt_committed, c.gt_committed)


def _assert_closed_under_hydrostatic_compression(tip):
    """sigma = -5 MPa in every direction: the fracture carries sigma_n = -5 MPa and no
    shear in the continuum.  On 8 x 8 cells the penalty solution is rough, but every
    point must stay closed with |p_N| of the order of 5 MPa."""
    res = _stick_solution(_hydrostatic_model(tip))
    assert np.all(res.state != conventions.OPEN)
    assert np.all(res.pn < 0.0)
    assert np.all(res.pn > -2.0 * 5.0e6)


@pytest.mark.parametrize("tip", ["ramp", {"kind": "branch", "radius": 1.5}])
def test_hydrostatic_compression_keeps_a_short_fracture_closed(tip):
    _assert_closed_under_hydrostatic_compression(tip)


def test_hydrostatic_compression_keeps_a_short_fracture_closed_default_branch():
    _assert_closed_under_hydrostatic_compression("branch")
