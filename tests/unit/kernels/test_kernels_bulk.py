"""Tests of xfemslip.kernels.bulk against NumPy references written here.

- rectangle_stiffness: an isoparametric Q4 with 2x2 Gauss (Jacobian from the
  node coordinates) plus Wilson's incompatible modes, condensed; rigid-body
  modes, the closed-form nodal forces of a uniform stress and of pure bending
  (where the plain Q4 is too stiff);
- enriched_cell_matrices: a per-point NumPy loop on the inputs of a built
  model, and the strain energy of a piecewise-linear field cut by the fracture
  (closed form A_+ eps^T D eps).
"""

from __future__ import annotations

import numpy as np
import pytest

from tests.support.bulk_reference import ETA, XI, compact_slots, enriched_reference
from tests.support.casegen import fracture_case
from xfemslip.fem.enrichment import HEAVISIDE, find_candidates
from xfemslip.fem.material import elasticity_matrix
from xfemslip.kernels.bulk import enriched_cell_matrices, rectangle_stiffness
from xfemslip.kernels.shape import q4_shape
from xfemslip.simulation import build_model

D_STRAIN = elasticity_matrix(10.0e9, 0.3, "plane_strain")
D_STRESS = elasticity_matrix(5.0e9, 0.25, "plane_stress")


_case = fracture_case


MODELS = {
    "ramp-generic": ([[1.3, 1.7], [4.6, 3.9]], "ramp"),
    "branch-generic": ([[1.3, 1.7], [4.6, 3.9]], "branch"),
    "ramp-crossing": ([[0.0, 1.3], [6.0, 4.1]], "ramp"),
    "branch-tip-on-node": ([[1.0, 2.0], [4.3, 3.7]], "branch"),
}
_BUILT = {}


def _model(key):
    if key not in _BUILT:
        pts, tip = MODELS[key]
        _BUILT[key] = build_model(_case(pts, tip))
    return _BUILT[key]


# ------------------------------------------------------------------ NumPy references


def q4_reference(coords, D):
    """8x8 stiffness of a Q4 with nodes coords (4, 2), isoparametric, 2x2 Gauss."""
    g = 1.0 / np.sqrt(3.0)
    K = np.zeros((8, 8))
    for xi in (-g, g):
        for eta in (-g, g):
            dN_dnat = 0.25 * np.array(
                [XI * (1.0 + eta * ETA), ETA * (1.0 + xi * XI)]
            )  # (2, 4)
            J = dN_dnat @ coords  # (2, 2): d(x, y)/d(xi, eta)
            dN = np.linalg.solve(J, dN_dnat)  # (2, 4) d/dx, d/dy
            B = np.zeros((3, 8))
            B[0, 0::2] = dN[0]
            B[1, 1::2] = dN[1]
            B[2, 0::2] = dN[1]
            B[2, 1::2] = dN[0]
            K += B.T @ D @ B * np.linalg.det(J)
    return K


def qm6_reference(coords, D):
    """8x8 condensed stiffness of the isoparametric Q4 plus the incompatible
    modes 1 - xi^2, 1 - eta^2 on each component (Wilson et al. 1973), 2x2 Gauss."""
    g = 1.0 / np.sqrt(3.0)
    K = np.zeros((12, 12))
    for xi in (-g, g):
        for eta in (-g, g):
            dN_dnat = 0.25 * np.array([XI * (1.0 + eta * ETA), ETA * (1.0 + xi * XI)])
            dP_dnat = np.array([[-2.0 * xi, 0.0], [0.0, -2.0 * eta]])  # (2, 2)
            J = dN_dnat @ coords
            dN = np.linalg.solve(J, np.hstack([dN_dnat, dP_dnat]))  # (2, 6)
            B = np.zeros((3, 12))
            B[0, 0::2] = dN[0]
            B[1, 1::2] = dN[1]
            B[2, 0::2] = dN[1]
            B[2, 1::2] = dN[0]
            K += B.T @ D @ B * np.linalg.det(J)
    return K[:8, :8] - K[:8, 8:] @ np.linalg.solve(K[8:, 8:], K[8:, :8])


def test_q4_reference_on_a_unit_square():
    """Known entries of the plane-stress unit-square Q4 with nu = 0 and E = 1."""
    K = q4_reference(
        np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]),
        elasticity_matrix(1.0, 0.0, "plane_stress"),
    )
    # K_00 = int (dN0/dx)^2 + 1/2 (dN0/dy)^2 = 1/3 + 1/6
    # K_01 = 1/2 int dN0/dy dN0/dx = 1/8
    assert K[0, 0] == pytest.approx(0.5, rel=1e-14)
    assert K[0, 1] == pytest.approx(0.125, rel=1e-14)


# ------------------------------------------------------------------ rectangle_stiffness

SIZES = (
    np.array([1.0, 0.5, 2.0, 0.125, 3.0e-3]),
    np.array([1.0, 2.0, 0.25, 0.125, 7.0e-3]),
)


@pytest.mark.parametrize(
    "D", [D_STRAIN, D_STRESS], ids=["plane-strain", "plane-stress"]
)
def test_rectangle_stiffness_equals_the_isoparametric_reference(D):
    hx, hy = SIZES
    K = rectangle_stiffness(hx, hy, D)
    assert K.shape == (hx.size, 8, 8)
    for e in range(hx.size):
        coords = (
            np.array([[0.0, 0.0], [hx[e], 0.0], [hx[e], hy[e]], [0.0, hy[e]]]) + 4.2
        )
        ref = qm6_reference(coords, D)
        # the shifted coordinates cost the reference a few digits on the 3 mm cell
        np.testing.assert_allclose(K[e], ref, rtol=0, atol=1e-11 * np.abs(ref).max())


def test_rectangle_stiffness_is_symmetric_psd_with_three_rigid_modes():
    hx, hy = SIZES
    K = rectangle_stiffness(hx, hy, D_STRAIN)
    for e in range(hx.size):
        Ke = K[e]
        np.testing.assert_allclose(Ke, Ke.T, rtol=0, atol=1e-15 * np.abs(Ke).max())
        ev = np.linalg.eigvalsh(Ke)
        assert ev.min() > -1e-12 * ev.max()
        assert np.count_nonzero(ev < 1e-10 * ev.max()) == 3
        # the three rigid modes are in the null space
        x = np.array([0.0, hx[e], hx[e], 0.0]) - 0.3
        y = np.array([0.0, 0.0, hy[e], hy[e]]) + 0.7
        for ux, uy in ((np.ones(4), np.zeros(4)), (np.zeros(4), np.ones(4)), (-y, x)):
            u = np.column_stack([ux, uy]).ravel()
            np.testing.assert_allclose(Ke @ u, 0.0, atol=1e-12 * np.abs(Ke).max())


def test_rectangle_stiffness_uniform_strain_gives_boundary_tractions():
    """K u for u = eps . x is the nodal force of the uniform stress sigma = D eps:
    each node gets half of sigma . n_out times the length of each adjacent edge."""
    hx, hy = 0.5, 0.2
    K = rectangle_stiffness(np.array([hx]), np.array([hy]), D_STRAIN)[0]
    exx, eyy, gxy = 1e-3, -2e-3, 4e-4
    x = np.array([0.0, hx, hx, 0.0])
    y = np.array([0.0, 0.0, hy, hy])
    u = np.column_stack([exx * x + 0.5 * gxy * y, eyy * y + 0.5 * gxy * x]).ravel()
    sxx, syy, sxy = D_STRAIN @ np.array([exx, eyy, gxy])
    S = np.array([[sxx, sxy], [sxy, syy]])
    tl, tr = S @ [-1.0, 0.0], S @ [1.0, 0.0]
    tb, tt = S @ [0.0, -1.0], S @ [0.0, 1.0]
    f = np.concatenate(
        [
            0.5 * (hy * tl + hx * tb),
            0.5 * (hy * tr + hx * tb),
            0.5 * (hy * tr + hx * tt),
            0.5 * (hy * tl + hx * tt),
        ]
    )
    np.testing.assert_allclose(K @ u, f, rtol=1e-12, atol=1e-9 * np.abs(f).max())


def _bending(x, y, c, D):
    """Nodal values (8,) of the pure-bending field sigma_xx = c y, sigma_yy =
    sigma_xy = 0: u = s11 c x y, v = -s11 c x^2 / 2 + s12 c y^2 / 2 (S = D^-1)."""
    S = np.linalg.inv(D)
    return np.column_stack(
        [S[0, 0] * c * x * y, -0.5 * S[0, 0] * c * x**2 + 0.5 * S[1, 0] * c * y**2]
    ).ravel()


@pytest.mark.parametrize("hx, hy", [(0.5, 0.2), (2.0, 0.05), (0.1, 0.3)])
def test_rectangle_stiffness_is_exact_in_pure_bending(hx, hy):
    """K times the nodal values of pure bending (anywhere in the plane) is the
    nodal force of the linear edge traction -+c y on the two vertical edges."""
    c = 3.0e6
    x0, y0 = -0.7, 0.4
    x = np.array([x0, x0 + hx, x0 + hx, x0])
    y = np.array([y0, y0, y0 + hy, y0 + hy])
    u = _bending(x, y, c, D_STRAIN)
    y1 = y0 + hy
    low, high = c * hy * (2 * y0 + y1) / 6.0, c * hy * (y0 + 2 * y1) / 6.0
    f = np.zeros(8)
    f[[0, 2, 4, 6]] = [-low, low, high, -high]  # x forces at nodes 0..3
    K = rectangle_stiffness(np.array([hx]), np.array([hy]), D_STRAIN)[0]
    np.testing.assert_allclose(K @ u, f, rtol=0, atol=1e-10 * np.abs(f).max())


@pytest.mark.parametrize("hx, hy", [(0.5, 0.2), (2.0, 0.05), (0.1, 0.3)])
def test_plain_q4_bending_energy_has_the_parasitic_shear_term(hx, hy):
    """On a centred cell the bilinear interpolant of pure bending is u = s11 c x y,
    v = const: shear strain s11 c x, so the Q4 stores 2U = s11^2 c^2 (D11 hx hy^3
    + D33 hy hx^3) / 12 against the exact s11 c^2 hx hy^3 / 12 (too stiff by a
    term growing with (hx / hy)^2).  The incompatible modes store the exact one."""
    D = D_STRAIN
    c = 3.0e6
    x = 0.5 * hx * XI
    y = 0.5 * hy * ETA
    u = _bending(x, y, c, D)
    s11 = np.linalg.inv(D)[0, 0]
    exact = s11 * c**2 * hx * hy**3 / 12.0
    q4 = s11**2 * c**2 * (D[0, 0] * hx * hy**3 + D[2, 2] * hy * hx**3) / 12.0
    e_q4 = u @ q4_reference(np.column_stack([x, y]), D) @ u
    e_im = u @ rectangle_stiffness(np.array([hx]), np.array([hy]), D)[0] @ u
    assert e_q4 == pytest.approx(q4, rel=1e-12)
    assert e_im == pytest.approx(exact, rel=1e-9)  # condensation round-off
    assert e_q4 > 1.05 * e_im


# ------------------------------------------------------------- enriched_cell_matrices


def _kernel_inputs(m, cells):
    ec = m.ec
    rows = []
    for e in cells:
        q0, q1 = ec.qp_offsets[e], ec.qp_offsets[e + 1]
        rows.append(
            (
                m.mesh.bounds[ec.cells[e]],
                ec.qp_xy[q0:q1],
                ec.qp_w[q0:q1],
                *ec.qp_values(np.arange(q0, q1)),
                ec.slot_node[e],
                ec.slot_fnode[e],
            )
        )
    return rows


def _run_kernel(rows, D):
    bounds = np.array([r[0] for r in rows])
    offsets = np.concatenate([[0], np.cumsum([r[1].shape[0] for r in rows])]).astype(
        np.int64
    )
    xy, w, F, gradF = (
        np.ascontiguousarray(np.concatenate([r[k] for r in rows])) for k in (1, 2, 3, 4)
    )
    slot_node = np.ascontiguousarray(np.array([r[5] for r in rows]))
    slot_fnode = np.ascontiguousarray(np.array([r[6] for r in rows]))
    slots = compact_slots(offsets, F, gradF, slot_node)
    return enriched_cell_matrices(
        bounds, offsets, xy, w, *slots, slot_node, slot_fnode, D
    )


@pytest.mark.parametrize("key", sorted(MODELS))
def test_enriched_cell_matrices_equal_the_numpy_reference(key):
    m = _model(key)
    ec = m.ec
    n = ec.cells.size
    # a few cells: cut ones (most qp), blending ones (fewest slots), and the tip cells
    n_qp = np.diff(ec.qp_offsets)
    n_slots = (ec.slot_node >= 0).sum(axis=1)
    tip_cells = [
        int(np.nonzero(ec.cells == m.fractures[0].piece_cell[k])[0][0]) for k in (0, -1)
    ]
    pick = sorted(
        {int(np.argmax(n_qp)), int(np.argmin(n_slots)), int(n // 2), *tip_cells}
    )
    rows = _kernel_inputs(m, pick)
    K, Bbar = _run_kernel(rows, m.D)
    for i, r in enumerate(rows):
        K_ref, B_ref = enriched_reference(*r, m.D)
        scale = np.abs(K_ref).max()
        np.testing.assert_allclose(K[i], K_ref, rtol=0, atol=1e-12 * scale)
        np.testing.assert_allclose(
            Bbar[i], B_ref, rtol=0, atol=1e-12 * np.abs(B_ref).max()
        )
        np.testing.assert_allclose(K[i], K[i].T, rtol=0, atol=1e-14 * scale)
        assert np.linalg.eigvalsh(K[i]).min() > -1e-10 * scale


@pytest.mark.parametrize("backend", ["numba", "numpy"])
@pytest.mark.parametrize("key", ["branch-generic", "branch-tip-on-node"])
def test_shared_columns_give_the_matrices_of_one_column_per_slot(key, backend):
    """The built cells store each (group, function) of a cell once, shared by
    the slots of its nodes; the same values with a column per slot give the
    same K and Bbar bit for bit, and the sharing stores fewer values."""
    from xfemslip import kernels

    m = _model(key)
    ec = m.ec
    used = ec.slot_column >= 0
    assert np.array_equal(used, ec.slot_node >= 0)
    # tip cells: four nodes share each of the tip's four functions
    assert ec.column_F.size < np.sum(np.diff(ec.qp_offsets) * used.sum(axis=1))
    assert (used.sum(axis=1) > ec.slot_column.max(axis=1) + 1).any()
    F, gradF = ec.qp_values(np.arange(ec.qp_w.size))
    per_slot = compact_slots(ec.qp_offsets, F, gradF, ec.slot_node)
    args = (
        np.ascontiguousarray(m.mesh.bounds[ec.cells]),
        ec.qp_offsets,
        ec.qp_xy,
        ec.qp_w,
    )
    tail = (ec.slot_node, ec.slot_fnode, m.D)
    kernel = kernels.backend(backend).enriched_cell_matrices
    K_shared, B_shared = kernel(
        *args, ec.column_offsets, ec.column_F, ec.column_gradF, ec.slot_column, *tail
    )
    K_slot, B_slot = kernel(*args, *per_slot, *tail)
    np.testing.assert_array_equal(K_shared, K_slot)
    np.testing.assert_array_equal(B_shared, B_slot)


def test_a_cell_without_slots_in_a_batch_of_enriched_ones():
    """NumPy's batches gather each cell's columns; a cell with no slot (no
    column, the last of the stored values) beside enriched cells with the
    same rule gives the plain Q4 block and leaves the others' matrices as
    the Numba kernel's."""
    from xfemslip import kernels

    m = _model("branch-generic")
    ec = m.ec
    e = int(np.argmax(np.diff(ec.qp_offsets)))  # a tip cell, several columns
    q = slice(ec.qp_offsets[e], ec.qp_offsets[e + 1])
    n = q.stop - q.start
    v = slice(ec.column_offsets[e], ec.column_offsets[e + 1])
    S = ec.slot_node.shape[1]
    empty = -np.ones((1, S), np.int64)
    args = (
        np.repeat(m.mesh.bounds[ec.cells[[e]]], 2, axis=0),
        np.array([0, n, 2 * n], np.int64),
        np.concatenate([ec.qp_xy[q]] * 2),
        np.concatenate([ec.qp_w[q]] * 2),
        np.array([0, v.stop - v.start, v.stop - v.start], np.int64),
        ec.column_F[v],
        ec.column_gradF[v],
        np.concatenate([ec.slot_column[[e]], empty]),
        np.concatenate([ec.slot_node[[e]], empty]),
        np.concatenate([ec.slot_fnode[[e]], np.zeros((1, S))]),
        m.D,
    )
    K, Bbar = kernels.backend("numpy").enriched_cell_matrices(*args)
    K_ref, B_ref = kernels.backend("numba").enriched_cell_matrices(*args)
    scale = np.abs(K_ref).max()
    np.testing.assert_allclose(K, K_ref, rtol=0, atol=1e-13 * scale)
    np.testing.assert_allclose(Bbar, B_ref, rtol=0, atol=1e-13 * np.abs(B_ref).max())
    assert np.abs(K[0, 8:, 8:]).max() > 0.0
    np.testing.assert_array_equal(K[1, 8:, :], 0.0)
    np.testing.assert_allclose(K[1, :8, :8], K_ref[1, :8, :8], rtol=1e-13)


@pytest.mark.parametrize("n_slots", [0, 2])
def test_uncut_cell_without_slots_reproduces_the_q4(n_slots):
    """A cell integrated with the sub-cell machinery (two triangles, degree-5 rule,
    which is exact for the degree-2 integrand) and empty slots is the plain Q4
    (enriched cells have no incompatible modes, unlike rectangle_stiffness)."""
    from xfemslip.fem.quadrature import triangle_rule

    b = np.array([[1.5, 2.0, -0.5, -0.25]])
    x0, x1, y0, y1 = b[0]
    tris = np.array([[[x0, y0], [x1, y0], [x1, y1]], [[x0, y0], [x1, y1], [x0, y1]]])
    xy, w = triangle_rule(tris)
    nq = xy.shape[0]
    K, Bbar = enriched_cell_matrices(
        b,
        np.array([0, nq], np.int64),
        xy,
        w,
        np.zeros(2, np.int64),
        np.zeros(0),
        np.zeros((0, 2)),
        -np.ones((1, n_slots), np.int64),
        -np.ones((1, n_slots), np.int64),
        np.zeros((1, n_slots)),
        D_STRAIN,
    )
    K_rect = q4_reference(np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]), D_STRAIN)
    assert K.shape == (1, 8 + 2 * n_slots, 8 + 2 * n_slots)
    np.testing.assert_allclose(
        K[0, :8, :8], K_rect, rtol=0, atol=1e-13 * np.abs(K_rect).max()
    )
    np.testing.assert_array_equal(K[0, 8:, :], 0.0)
    np.testing.assert_array_equal(K[0, :, 8:], 0.0)
    # the cell-average strain of a bilinear field is its gradient at the centre
    np.testing.assert_allclose(Bbar[0, :, :8].sum(), 0.0, atol=1e-12)
    dNx = XI / (2 * (x1 - x0))
    np.testing.assert_allclose(Bbar[0, 0, 0:8:2], dNx, rtol=1e-13)
    np.testing.assert_array_equal(Bbar[0, :, 8:], 0.0)


def test_heaviside_cell_energy_of_a_field_that_jumps_across_the_fracture():
    """u = w(x) on the + side and 0 on the - side, w linear, is represented exactly
    by u_a = w(x_a) [H_a = +1] and a_a = w(x_a) / 2 on every node of a cut cell
    (R = 1, no tip).  Its energy is A_+ eps(w)^T D eps(w) (0 for a rigid w)."""
    m = _model("ramp-crossing")
    ec, mesh, fr = m.ec, m.mesh, m.fractures[0]
    cand = find_candidates(mesh, m.fractures)
    cut = np.unique(fr.piece_cell)
    checked = 0
    rows_all = _kernel_inputs(m, range(ec.cells.size))
    K_all, _ = _run_kernel(rows_all, m.D)
    for e, c in enumerate(ec.cells):
        if c not in cut:
            continue
        slots = np.nonzero(ec.slot_cand[e] >= 0)[0]
        assert sorted(ec.slot_node[e, slots]) == [0, 1, 2, 3]
        assert np.all(cand.func[ec.slot_cand[e, slots]] == HEAVISIDE)
        nodes = mesh.nodes[mesh.cells[c]]
        H = np.where(fr.signed_distance(nodes) >= 0.0, 1.0, -1.0)
        q0, q1 = ec.qp_offsets[e], ec.qp_offsets[e + 1]
        plus = fr.signed_distance(ec.qp_xy[q0:q1]) > 0.0
        area_plus = ec.qp_w[q0:q1][plus].sum()
        for grad_w, rigid in (
            (np.array([[0.0, 0.0], [0.0, 0.0]]), True),  # translation
            (np.array([[0.0, -1.0], [1.0, 0.0]]), True),  # rotation
            (np.array([[1e-3, 2e-4], [-3e-4, -5e-4]]), False),  # strain + rotation
        ):
            # a translation only with the rigid modes: with the strained field it
            # would cost ~6 digits to cancellation in v^T K v
            shift = np.array([0.3, -0.7]) if rigid else np.zeros(2)
            wv = (nodes - nodes.mean(axis=0)) @ grad_w.T + shift
            v = np.zeros(K_all.shape[1])
            v[:8] = (wv * (H > 0)[:, None]).ravel()
            for s in slots:
                a = ec.slot_node[e, s]
                v[8 + 2 * s : 10 + 2 * s] = 0.5 * wv[a]
            energy = v @ K_all[e] @ v
            if rigid:
                scale = np.abs(K_all[e]).max() * np.abs(v).max() ** 2
                assert abs(energy) < 1e-12 * scale
            else:
                eps = np.array(
                    [grad_w[0, 0], grad_w[1, 1], grad_w[0, 1] + grad_w[1, 0]]
                )
                assert energy == pytest.approx(area_plus * eps @ m.D @ eps, rel=1e-10)
        checked += 1
    assert checked == cut.size >= 6


@pytest.mark.parametrize("key", sorted(MODELS))
def test_sub_cell_weights_sum_to_the_cell_area(key):
    m = _model(key)
    ec = m.ec
    b = m.mesh.bounds[ec.cells]
    area = (b[:, 1] - b[:, 0]) * (b[:, 3] - b[:, 2])
    w_sum = np.add.reduceat(ec.qp_w, ec.qp_offsets[:-1])
    np.testing.assert_allclose(w_sum, area, rtol=1e-12)
    e1 = ec.tris[:, 1] - ec.tris[:, 0]
    e2 = ec.tris[:, 2] - ec.tris[:, 0]
    tri_area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    np.testing.assert_allclose(
        np.add.reduceat(tri_area, ec.tri_offsets[:-1]), area, rtol=1e-12
    )
    # every quadrature point lies in its cell
    cell_of_qp = np.repeat(np.arange(ec.cells.size), np.diff(ec.qp_offsets))
    bq = b[cell_of_qp]
    x, y = ec.qp_xy[:, 0], ec.qp_xy[:, 1]
    assert np.all((x >= bq[:, 0]) & (x <= bq[:, 1]) & (y >= bq[:, 2]) & (y <= bq[:, 3]))


def test_q4_shape_kernel_matches_the_closed_form():
    N = np.empty(4)
    dN = np.empty((4, 2))
    x0, x1, y0, y1 = 0.5, 1.25, -1.0, 0.5
    x, y = 0.7, 0.1
    q4_shape(x, y, x0, x1, y0, y1, N, dN)
    hx, hy = x1 - x0, y1 - y0
    # N_0 = (x1 - x)(y1 - y)/(hx hy), etc.
    ref = np.array(
        [
            (x1 - x) * (y1 - y),
            (x - x0) * (y1 - y),
            (x - x0) * (y - y0),
            (x1 - x) * (y - y0),
        ]
    ) / (hx * hy)
    np.testing.assert_allclose(N, ref, rtol=1e-14)
    ref_dx = np.array([-(y1 - y), (y1 - y), (y - y0), -(y - y0)]) / (hx * hy)
    ref_dy = np.array([-(x1 - x), -(x - x0), (x - x0), (x1 - x)]) / (hx * hy)
    np.testing.assert_allclose(dN[:, 0], ref_dx, rtol=1e-14)
    np.testing.assert_allclose(dN[:, 1], ref_dy, rtol=1e-14)
