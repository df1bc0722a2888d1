"""Junctions of fractures (geometry.find_junctions, junction functions of
Daux et al. 2000 in enrichment.py, jump operators in contact.py).

Expected numbers are computed by hand (snapped points, arc lengths) or are
exact properties: the four wedges of an X are independent with the junction
functions and are not with two Heavisides; a junction function's jump is zero
beyond the fracture it ends on.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.support.casegen import fracture_spec
from xfemslip.case import build
from xfemslip.errors import GeometryError
from xfemslip.fem.enrichment import HEAVISIDE, build_enriched_cells, find_candidates
from xfemslip.fem.mesh import build_mesh
from xfemslip.geometry.junctions import JUNCTION_SNAP_CELLS, build_fractures

N_CELLS = 10  # h = 0.1
H = 1.0 / N_CELLS
BOX = np.array([0.0, 1.0, 0.0, 1.0])


def _mesh(n=N_CELLS):
    grid = np.linspace(0.0, 1.0, n + 1)
    return build_mesh(grid, grid)


def _spec(points, index, tip="ramp"):
    return fracture_spec(points, index, tip, friction=0.0)


def _build(*polylines, n=N_CELLS):
    mesh = _mesh(n)
    specs = [_spec(p, i) for i, p in enumerate(polylines)]
    return mesh, build_fractures(mesh, specs, BOX)


def _pieces_length(fr):
    return float(
        np.sum((fr.piece_t[:, 1] - fr.piece_t[:, 0]) * fr.length[fr.piece_seg])
    )


# -------------------------------------------------------------- classification

MAIN = [[0.12, 0.53], [0.88, 0.53]]  # horizontal, off the grid lines


def test_x_crossing_cuts_the_shorter_fracture_into_two_arms():
    # the longer one is the main one whatever the order (order independence)
    for order in ((0, 1), (1, 0)):
        polys = [MAIN, [[0.47, 0.21], [0.47, 0.83]]]
        _, fr = _build(*(polys[i] for i in order))
        main = fr[order.index(0)]
        sec = fr[order.index(1)]
        assert len(main.arms) == 1 and main.arms[0] == ()
        assert len(sec.arms) == 2 and len(sec.tips) == 2 and len(main.tips) == 2
        # the split is at the crossing (0.47, 0.53): 0.32 m from the secondary's start
        assert sec.arm_splits == pytest.approx((0.32,), abs=1e-12)
        assert sec.junction_s == pytest.approx((0.32,), abs=1e-12)
        assert main.junction_s == pytest.approx((0.35,), abs=1e-12)
        lower, upper = sec.arms
        for arm, sign in ((lower, -1.0), (upper, 1.0)):
            (cut,) = arm
            np.testing.assert_allclose(cut.point, [0.47, 0.53], atol=1e-15)
            np.testing.assert_allclose(cut.normal, [0.0, 1.0], atol=1e-15)
            assert cut.sign == sign and cut.far == 0.0
        # pieces split at the junction, none straddling it, none lost
        for f in (main, sec):
            s_a = f.arc_length(f.piece_seg, f.piece_t[:, 0])
            s_b = f.arc_length(f.piece_seg, f.piece_t[:, 1])
            (sj,) = f.junction_s
            assert not np.any((s_a < sj - 1e-12) & (s_b > sj + 1e-12))
            assert _pieces_length(f) == pytest.approx(f.length.sum(), rel=1e-12)


@pytest.mark.parametrize(
    ("end", "kind"),
    [
        pytest.param([0.47, 0.53], "exact", id="on-the-main"),
        pytest.param([0.47, 0.53 - 0.3 * H], "overshoot", id="overshoot-0.3h"),
        pytest.param([0.47, 0.53 + 0.3 * H], "gap", id="gap-0.3h"),
    ],
)
def test_t_junction_end_is_snapped_onto_the_main(end, kind):
    _, (main, sec) = _build(MAIN, [end, [0.47, 0.86]])
    np.testing.assert_allclose(sec.points[0], [0.47, 0.53], atol=1e-14)
    assert sec.junction_ends == (0,)
    assert [t.end for t in sec.tips] == [1]  # no tip at the junction
    assert len(main.tips) == 2 and len(main.arms) == 1
    assert len(sec.arms) == 1
    (cut,) = sec.arms[0]
    assert cut.sign == 1.0 and cut.far == 0.0  # the branch lies above the main
    # the arc length stays measured from the case file's first point
    # (trimmed: the first point moves 0.3 h along t; extended: -0.3 h)
    shift = {"exact": 0.0, "overshoot": 0.3 * H, "gap": -0.3 * H}[kind]
    assert sec.s_start[0] == pytest.approx(shift, abs=1e-12)


def test_overshoot_beyond_the_snap_distance_is_an_x():
    over = (JUNCTION_SNAP_CELLS + 0.3) * H
    _, (main, sec) = _build(MAIN, [[0.47, 0.53 - over], [0.47, 0.86]])
    assert sec.junction_ends == () and len(sec.tips) == 2 and len(sec.arms) == 2
    assert main.junction_s == pytest.approx((0.35,), abs=1e-12)


def test_oblique_overshoot_is_measured_along_the_fracture():
    # the end is 0.3 h from the main but 1.19 h past it along the fracture
    _, (main, sec) = _build(MAIN, [[0.40, 0.50], [0.9, 0.63]])
    assert sec.junction_ends == () and len(sec.arms) == 2 and len(sec.tips) == 2
    np.testing.assert_allclose(sec.points[0], [0.40, 0.50], atol=1e-15)


def test_shared_end_point_is_a_v():
    # two fractures from (0.3, 0.3); the longer one keeps its tip at the apex
    long_, short = [[0.3, 0.3], [0.85, 0.4]], [[0.32, 0.31], [0.4, 0.75]]
    for order in ((0, 1), (1, 0)):
        polys = [long_, short]
        _, fr = _build(*(polys[i] for i in order))
        main, sec = fr[order.index(0)], fr[order.index(1)]
        np.testing.assert_allclose(sec.points[0], [0.3, 0.3], atol=1e-15)
        assert sec.junction_ends == (0,) and main.junction_ends == ()
        assert len(main.tips) == 2 and len(sec.tips) == 1
        (cut,) = sec.arms[0]
        # J = indicator of the wedge between the two: beyond the main's line
        # it takes the secondary's outer value, minus its side of the main's body
        nrm = sec.normal[0]
        inner = math.copysign(1.0, main.tangent[0] @ nrm)
        assert cut.far == -inner


def test_junction_on_a_mesh_node():
    # both diagonals through the node (0.5, 0.5): pieces end there, no split needed
    _, (a, b) = _build([[0.2, 0.2], [0.8, 0.8]], [[0.2, 0.8], [0.75, 0.25]])
    for f in (a, b):
        assert _pieces_length(f) == pytest.approx(f.length.sum(), rel=1e-12)
        s_a = f.arc_length(f.piece_seg, f.piece_t[:, 0])
        (sj,) = f.junction_s
        assert np.min(np.abs(s_a - sj)) < 1e-12  # a piece starts at the node
    assert len(a.arms) + len(b.arms) == 3


def test_several_junctions_on_one_fracture():
    # a main crossed by one fracture and ended on by two others
    _, fr = _build(
        MAIN,
        [[0.3, 0.2], [0.3, 0.9]],
        [[0.55, 0.53], [0.6, 0.8]],
        [[0.75, 0.15], [0.75, 0.53]],
    )
    assert fr[0].junction_s == pytest.approx((0.18, 0.43, 0.63), abs=1e-12)
    assert len(fr[1].arms) == 2
    assert fr[2].junction_ends == (0,) and fr[3].junction_ends == (1,)
    assert fr[3].arms[0][0].sign == -1.0  # below the main


def test_overlap_is_refused_with_one_line():
    with pytest.raises(GeometryError) as err:
        _build(MAIN, [[0.5, 0.53], [0.95, 0.53]])
    msg = str(err.value)
    assert "fractures[0] and fractures[1] overlap" in msg and "\n" not in msg


# ---------------------------------------------------------- wedges of an X


def _junction_cell_basis(mesh, fractures, point):
    """Scalar basis of the cell holding ``point``: N_a and N_a (F_s - F_s(x_a))
    at its quadrature points, with the side of each sub-triangle's centroid."""
    cand = find_candidates(mesh, fractures)
    ec = build_enriched_cells(mesh, fractures, cand)
    b = mesh.bounds
    c = int(
        np.nonzero(
            (b[:, 0] < point[0])
            & (point[0] < b[:, 1])
            & (b[:, 2] < point[1])
            & (point[1] < b[:, 3])
        )[0][0]
    )
    e = int(np.searchsorted(ec.cells, c))
    q0, q1 = ec.qp_offsets[e], ec.qp_offsets[e + 1]
    xy = ec.qp_xy[q0:q1]
    N = mesh.shape_at(np.full(xy.shape[0], c), xy)
    cols = [N]
    for s in np.nonzero(ec.slot_cand[e] >= 0)[0]:
        a = ec.slot_node[e, s]
        F = ec.qp_values(np.arange(q0, q1))[0][:, s]
        cols.append((N[:, a] * (F - ec.slot_fnode[e, s]))[:, None])
    tris = ec.tris[ec.tri_offsets[e] : ec.tri_offsets[e + 1]]
    centroid = np.repeat(tris.mean(axis=1), xy.shape[0] // tris.shape[0], axis=0)
    return np.hstack(cols), xy, N, centroid, cand, ec, e


def _residual(basis, target):
    coef, *_ = np.linalg.lstsq(basis, target, rcond=None)
    return float(np.linalg.norm(basis @ coef - target) / np.linalg.norm(target))


def test_x_wedges_move_independently_only_with_junction_functions():
    """Four wedges around an X: {1, H1, J2a, J2b} span every wedge-wise
    constant field (4 dofs), {1, H1, H2} only 3 (H1 H2 is missing)."""
    point = np.array([0.47, 0.53])
    mesh, fr = _build(MAIN, [[0.38, 0.35], [0.6, 0.79]])
    basis, xy, N, cen, cand, ec, e = _junction_cell_basis(mesh, fr, point)
    h1 = fr[0].side(cen)
    h2 = fr[1].side(cen)
    wedges = [(h1 == s1) & (h2 == s2) for s1 in (-1, 1) for s2 in (-1, 1)]
    assert all(w.any() for w in wedges)
    # every node of the junction cell carries H1 and both arms' J
    groups = {(int(cand.fracture[k]), int(cand.tip[k])) for k in ec.slot_cand[e]}
    assert groups == {(0, -1), (1, -1), (1, -2)}
    assert np.all(cand.func[ec.slot_cand[e]] == HEAVISIDE)
    # Heaviside-only basis of the same cell: N_a, N_a (H_f - H_f(x_a))
    c = ec.cells[e]
    nodes = mesh.nodes[mesh.cells[c]]
    two_h = [N]
    for f in fr:
        hn = f.side(nodes)
        two_h.append(N * (f.side(cen)[:, None] - hn[None, :]))
    two_h = np.hstack(two_h)
    for w in wedges:
        target = w.astype(float)
        assert _residual(basis, target) < 1e-10
        assert _residual(two_h, target) > 0.05
    # both bases hold the three wedge-wise fields 1, H1, H2 exactly
    for target in (np.ones(len(xy)), h1, h2):
        assert _residual(basis, target) < 1e-10
        assert _residual(two_h, target) < 1e-10


# ------------------------------------------------- jumps of junction functions


def _case_text(polylines, n=20, tip="ramp", friction=0.0):
    fracture = {"friction": friction, "kn": 5.0e12, "kt": 5.0e12, "tip": tip}
    return build.case_text(
        {
            "domain": {"size": [1.0, 1.0]},
            "mesh": {"elements": [n, n]},
            "material": {"E": 5.0e9, "nu": 0.3},
            "fractures": [dict(fracture, points=p) for p in polylines] or None,
            "loading": {"stress": {"xx": -20.0e6, "yy": -40.0e6, "xy": 5.0e6}},
            "boundary": {
                "bottom": {"uy": 0.0},
                "top": "traction",
                "left": "traction",
                "right": "traction",
            },
        }
    )


def _model(polylines, **kw):
    from xfemslip.case import loads_case
    from xfemslip.simulation import build_model

    return build_model(loads_case(_case_text(polylines, **kw), "junction.toml"))


@pytest.mark.parametrize("kind", ["X", "T"])
def test_junction_function_jumps_only_next_to_its_junction(kind):
    """Only the dofs of one arm's junction function J are non-zero: that arm
    opens; the other arm of an X does not move at all, and the main fracture
    jumps only within one cell of the junction (J is constant beyond it)."""
    from xfemslip.contact.interface import _point_jumps

    sec = [[0.47, 0.2], [0.47, 0.86]] if kind == "X" else [[0.47, 0.53], [0.47, 0.86]]
    m = _model([MAIN, sec])
    dm, c, ip = m.bulk.dofmap, m.contact, m.ip
    cand = find_candidates(m.mesh, m.fractures)
    arm = -2 if kind == "X" else -1  # the upper arm
    k = np.nonzero((cand.fracture == 1) & (cand.tip == arm) & (dm.cand_dof >= 0))[0]
    assert k.size
    rng = np.random.default_rng(6)
    u = np.zeros(dm.n_dofs)
    for d in dm.cand_dof[k]:
        u[d : d + 2] = rng.uniform(-1.0, 1.0, 2)
    jump = np.linalg.norm(_point_jumps(u, c.point_dofs, c.point_coef), axis=1)
    junction = np.array([0.47, 0.53])
    dist = np.linalg.norm(ip.xy - junction, axis=1)
    on_sec, on_main = ip.fracture == 1, ip.fracture == 0
    upper = ip.xy[:, 1] > junction[1]
    assert jump[on_sec & upper].min() > 0.0
    assert np.all(jump[on_sec & ~upper] == 0.0)  # the lower arm (X)
    h = 1.0 / 20
    assert np.all(jump[on_main & (dist > 2.0 * math.sqrt(2.0) * h)] == 0.0)
    # J = H(phi_2) above the main, 0 below: it jumps across the main next to
    # the junction (the fourth wedge of an X)
    assert jump[on_main & (dist < h)].max() > 0.1


def test_network_figure_is_written(tmp_path):
    """plot_results(kinds=["network"]) on a small T-junction run: one PNG,
    with the slip colour scale running up to the largest |slip| that slid in
    the run (its plastic slip, in mm)."""
    from matplotlib.figure import Figure  # noqa: F401  (matplotlib present)

    from xfemslip.case import loads_case
    from xfemslip.plot.data import figure_data
    from xfemslip.plot.figures import figure_network, plot_results
    from xfemslip.simulation import run_case

    text = _case_text([MAIN, [[0.47, 0.53], [0.47, 0.86]]], n=16)
    spec = loads_case(text, tmp_path / "net.toml")
    run_case(spec, tmp_path / "out")
    written = plot_results(
        [tmp_path / "out"], tmp_path / "fig", kinds=["network"], formats=["png"]
    )
    assert [p.name for p in written] == ["network.png"]
    assert written[0].stat().st_size > 10_000
    data = figure_data(tmp_path / "out")
    fig = figure_network(data)
    slip_axes = fig.axes[0]
    top = max(float(np.abs(f.slid).max()) for f in data.fractures)
    lc = [c for c in slip_axes.collections if c.get_array() is not None]
    assert len(lc) == 2 and lc[0].norm.vmax == 1e3 * top
