"""Tests of xfemslip.fem.boundary: edge tractions, prescribed displacements, pins.

References: closed-form edge loads (sigma . n_out times the edge length, split
evenly between the two nodes of each element edge), the work of the load on a
field that jumps across a fracture (t . w times the loaded length on the + side),
and hand-picked dofs for corners and rigid-body pins.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from xfemslip.case import BoundarySpec, EdgeSpec, build, loads_case
from xfemslip.errors import GeometryError
from xfemslip.fem.assembly import assemble_bulk
from xfemslip.fem.boundary import dirichlet, rigid_body_pins, traction_load
from xfemslip.fem.enrichment import HEAVISIDE, build_enriched_cells, find_candidates
from xfemslip.fem.material import elasticity_matrix
from xfemslip.fem.mesh import build_mesh
from xfemslip.geometry.junctions import build_fractures
from xfemslip.simulation import build_model

N = 8  # 8 x 8 cells on the unit square, h = 0.125
H = 1.0 / N


STRESS = (-20.0e6, -40.0e6, 0.0)
FIXED_BOTTOM = {"bottom": {"ux": 0.0, "uy": 0.0}, "top": "traction"}
ROLLER_BOTTOM = {
    "bottom": {"uy": 0.0},
    "top": "traction",
    "left": "traction",
    "right": "traction",
}


def _model(boundary, stress=STRESS, fracture=None, initial=None):
    return build_model(_spec(boundary, stress, fracture, initial))


def _spec(boundary, stress=STRESS, fracture=None, initial=None):
    """The square on N x N cells with the edges ``boundary``, the far field
    (xx, yy, xy) ``stress`` [Pa], optionally a fracture table and an initial
    stress."""
    text = build.case_text(
        {
            "domain": {"size": [1.0, 1.0]},
            "mesh": {"elements": [N, N]},
            "material": {"E": 10.0e9, "nu": 0.3, "model": "plane_strain"},
            "fractures": None if fracture is None else [fracture],
            "loading": {
                "stress": build.stress_table(stress),
                "initial_stress": build.stress_table(initial),
            },
            "boundary": boundary,
        }
    )
    return loads_case(text)


def _load_stage(spec):
    """The stages up to traction_load only (simulation.build_model's order), so the
    edge load is tested in isolation from the rest of the model."""
    mesh = build_mesh(spec.mesh.x, spec.mesh.y)
    D = elasticity_matrix(spec.material.E, spec.material.nu, spec.material.model)
    box = np.array([mesh.x[0], mesh.x[-1], mesh.y[0], mesh.y[-1]])
    fractures = build_fractures(mesh, spec.fractures, box)
    cand = find_candidates(mesh, fractures)
    ec = build_enriched_cells(mesh, fractures, cand)
    bulk = assemble_bulk(mesh, D, cand, ec, backend="numba")
    F = traction_load(
        mesh, spec.boundary, spec.loading, ec, cand, bulk.dofmap, fractures
    )
    return SimpleNamespace(mesh=mesh, fractures=fractures, cand=cand, bulk=bulk, F=F)


def _edge_forces(m, edge):
    nodes = m.mesh.edge_nodes(edge)
    F = m.problem.F_unit
    return np.column_stack([F[2 * nodes], F[2 * nodes + 1]])


def _uniform_edge(total):
    """Nodal forces (N+1, 2) of a uniform traction whose resultant is total (2,)."""
    w = np.full(N + 1, H)
    w[[0, -1]] = 0.5 * H
    return w[:, None] * np.asarray(total, float)[None, :]


# ------------------------------------------------------------------ traction_load


def test_top_traction_on_an_uncracked_mesh():
    m = _model(FIXED_BOTTOM)
    assert m.problem.n_dofs == 2 * (N + 1) ** 2  # no fracture, no enriched dof
    top = _edge_forces(m, "top")
    # t = sigma . (0, 1) = (xy, yy) = (0, -40e6) on a width of 1 m
    assert top[:, 1].sum() == pytest.approx(-40e6, rel=1e-14)
    assert np.all(top[:, 0] == 0.0)
    np.testing.assert_allclose(top, _uniform_edge([0.0, -40e6]), rtol=1e-14)
    # nothing anywhere else
    F = m.problem.F_unit.copy()
    nodes = m.mesh.edge_nodes("top")
    F[2 * nodes] = 0.0
    F[2 * nodes + 1] = 0.0
    assert np.all(F == 0.0)


def test_traction_on_every_edge_is_self_equilibrated():
    sxx, syy, sxy = -20e6, -40e6, 5e6
    # xfemslip.case refuses a case without any prescribed displacement, so the
    # all-traction boundary is handed to traction_load directly
    m = _model(ROLLER_BOTTOM, stress=(sxx, syy, sxy))
    all_traction = BoundarySpec(
        **{e: EdgeSpec(kind="traction") for e in ("bottom", "top", "left", "right")}
    )
    F_all = traction_load(
        m.mesh,
        all_traction,
        m.spec.loading,
        m.ec,
        find_candidates(m.mesh, m.fractures),
        m.bulk.dofmap,
        m.fractures,
    )
    # the model's own load: the bottom (uy prescribed, no traction = true) is not loaded
    np.testing.assert_array_equal(_edge_forces(m, "bottom")[1:-1], 0.0)
    m.problem.F_unit = F_all
    S = np.array([[sxx, sxy], [sxy, syy]])
    # the corner nodes get a share from both of their edges: compare per edge
    # on the interior nodes, and the resultants over all nodes
    for edge, n_out in (
        ("bottom", (0, -1)),
        ("top", (0, 1)),
        ("left", (-1, 0)),
        ("right", (1, 0)),
    ):
        f = _edge_forces(m, edge)
        expected = _uniform_edge(S @ np.array(n_out, float))
        np.testing.assert_allclose(f[1:-1], expected[1:-1], rtol=1e-14)
    F = m.problem.F_unit.reshape(-1, 2)
    np.testing.assert_allclose(F.sum(axis=0), 0.0, atol=1e-7)  # zero resultant
    x, y = m.mesh.nodes[:, 0], m.mesh.nodes[:, 1]
    assert np.sum(x * F[:, 1] - y * F[:, 0]) == pytest.approx(
        0.0, abs=1e-7
    )  # zero moment
    # corner (0, 0): half an element edge of the bottom and of the left traction
    corner = 0.5 * H * (S @ [0.0, -1.0] + S @ [-1.0, 0.0])
    np.testing.assert_allclose(F[0], corner, rtol=1e-14)


def test_initial_stress_applies_only_the_increment():
    m = _model(
        {**FIXED_BOTTOM, "right": "traction"},
        stress=(-20.0e6, -40.0e6, 3.0e6),
        initial=(-12.0e6, -30.0e6, 1.0e6),
    )
    # increment: xx = -8e6, yy = -10e6, xy = 2e6
    top = _edge_forces(m, "top")
    np.testing.assert_allclose(top[:-1], _uniform_edge([2e6, -10e6])[:-1], rtol=1e-14)
    right = _edge_forces(m, "right")
    np.testing.assert_allclose(
        right[1:-1], _uniform_edge([-8e6, 2e6])[1:-1], rtol=1e-14
    )
    # top-right corner gets both edges' halves
    np.testing.assert_allclose(
        top[-1],
        0.5 * H * np.array([2e6, -10e6]) + 0.5 * H * np.array([-8e6, 2e6]),
        rtol=1e-14,
    )


def test_traction_in_the_free_component_of_a_displacement_edge():
    m = _model(
        {"bottom": {"uy": 0.0, "traction": True}, "left": {"ux": 0.0}},
        stress=(-20.0e6, -40.0e6, 6.0e6),
    )
    bottom = _edge_forces(m, "bottom")
    # t = sigma . (0, -1) = (-xy, -yy); only the free x component is loaded
    np.testing.assert_allclose(
        bottom[:, 0], _uniform_edge([-6e6, 0.0])[:, 0], rtol=1e-14
    )
    assert np.all(bottom[:, 1] == 0.0)
    assert np.all(_edge_forces(m, "left")[1:] == 0.0)


@pytest.mark.parametrize(
    "points, tip",
    [
        pytest.param([[0.3, 0.0], [0.66, 1.0]], "ramp", id="crossing"),
        pytest.param([[0.39, 0.35], [0.66, 1.0]], "ramp", id="reaching-the-top"),
    ],
)
def test_enriched_traction_load_does_the_work_of_a_jumping_field(points, tip):
    """u = w on the + side of the fracture and 0 on the other, w a constant vector,
    is represented by u_a = w [H_a = +1] and a_a = w / 2 on the Heaviside nodes
    (R = 1 at the top edge).  The top traction t = (xy, yy) then does the work
    t . w * (length of the top edge on the + side) = t . w * 0.66."""
    sxy, syy = 7e6, -40e6
    m = _load_stage(
        _spec(
            FIXED_BOTTOM,
            stress=(-20.0e6, syy, sxy),
            fracture=_fracture_table(points, tip),
        )
    )
    fr = m.fractures[0]
    cand = m.cand
    dm = m.bulk.dofmap
    assert np.all(cand.func == HEAVISIDE)
    top_nodes = m.mesh.edge_nodes("top")
    top_cells = np.nonzero(np.isin(m.mesh.cells, top_nodes).any(axis=1))[0]
    top_cell_nodes = np.unique(m.mesh.cells[top_cells])
    near_top = np.isin(cand.node, top_cell_nodes)
    assert np.all(dm.cand_dof[near_top] >= 0)  # nothing dropped where it matters
    # the enriched edge load is really there
    assert np.abs(m.F[dm.n_std :]).max() > 1e3
    w = np.array([2.0e-3, -3.0e-3])
    Hn = np.where(fr.signed_distance(m.mesh.nodes) >= 0.0, 1.0, -1.0)
    v = np.zeros(dm.n_dofs)
    v[: dm.n_std] = (w[None, :] * (Hn > 0)[:, None]).ravel()
    for k in np.nonzero(dm.cand_dof >= 0)[0]:
        v[dm.cand_dof[k] : dm.cand_dof[k] + 2] = 0.5 * w
    work = m.F @ v
    assert work == pytest.approx((sxy * w[0] + syy * w[1]) * 0.66, rel=1e-12)
    # the standard part alone would interpolate the jump linearly across a cell
    std_only = m.F[: dm.n_std] @ v[: dm.n_std]
    assert abs(std_only - work) > 1e-3 * abs(work)


def _fracture_table(points, tip):
    return {"points": points, "friction": 0.5, "kn": 1.0e12, "kt": 1.0e12, "tip": tip}


def test_build_model_with_a_crossing_fracture_reaching_a_fixed_edge():
    m = _model(
        FIXED_BOTTOM, fracture=_fracture_table([[0.3, 0.0], [0.66, 1.0]], "ramp")
    )
    assert m.problem.fixed.max() < m.problem.n_dofs
    # both parts touch the fixed bottom: none floats
    assert not m.problem.floating


# ---------------------------------------------------------------------- dirichlet


def _mesh4():
    g = np.linspace(0.0, 1.0, 5)
    return build_mesh(g, g)


def _edge(ux=None, uy=None, n=5):
    v = np.full((n, 2), np.nan)
    if ux is not None:
        v[:, 0] = ux
    if uy is not None:
        v[:, 1] = uy
    return EdgeSpec(kind="displacement", values=v, source="table")


FREE = EdgeSpec(kind="free")


def _bc(**edges):
    return BoundarySpec(
        **{e: edges.get(e, FREE) for e in ("bottom", "top", "left", "right")}
    )


def test_dirichlet_merges_agreeing_corners():
    mesh = _mesh4()
    bc = dirichlet(
        mesh, _bc(bottom=_edge(0.0, 0.0), left=_edge(ux=0.0), top=_edge(uy=-0.1))
    )
    bottom, left, top = (mesh.edge_nodes(e) for e in ("bottom", "left", "top"))
    expected = set(
        (2 * bottom).tolist()
        + (2 * bottom + 1).tolist()
        + (2 * left).tolist()
        + (2 * top + 1).tolist()
    )
    assert bc.dofs.tolist() == sorted(expected)  # sorted, each dof once
    vals = dict(zip(bc.dofs.tolist(), bc.values.tolist(), strict=True))
    assert all(vals[2 * n + 1] == -0.1 for n in top)
    assert vals[2 * left[-1]] == 0.0  # top-left corner: ux from left, uy from top
    assert vals[2 * left[-1] + 1] == -0.1
    assert bc.pinned.size == 0


def test_dirichlet_accepts_corner_values_equal_within_tolerance():
    mesh = _mesh4()
    bc = dirichlet(
        mesh, _bc(bottom=_edge(0.01, 0.0), left=_edge(ux=0.01 * (1 + 1e-13)))
    )
    assert np.count_nonzero(bc.dofs == 0) == 1


def test_dirichlet_raises_on_conflicting_corner_values():
    mesh = _mesh4()
    with pytest.raises(GeometryError, match=r"boundary\.bottom and boundary\.left.*ux"):
        dirichlet(mesh, _bc(bottom=_edge(0.0, 0.0), left=_edge(ux=0.1)))
    with pytest.raises(GeometryError, match=r"boundary\.top and boundary\.right.*uy"):
        dirichlet(mesh, _bc(top=_edge(uy=-0.1), right=_edge(ux=0.0, uy=0.0)))


def test_only_uy_on_the_bottom_gives_one_pin_at_the_bottom_middle():
    mesh = _mesh4()
    bc = dirichlet(mesh, _bc(bottom=_edge(uy=0.0)))
    middle = mesh.edge_nodes("bottom")[2]  # node (0.5, 0)
    np.testing.assert_array_equal(mesh.nodes[middle], [0.5, 0.0])
    assert bc.pinned.tolist() == [2 * middle]  # ux there
    assert 2 * middle in bc.dofs.tolist()
    assert bc.values[bc.dofs.tolist().index(2 * middle)] == 0.0
    assert bc.dofs.size == 5 + 1


def test_fully_fixed_bottom_needs_no_pin():
    mesh = _mesh4()
    assert dirichlet(mesh, _bc(bottom=_edge(0.0, 0.0))).pinned.size == 0
    # two uy-edges still leave the x translation free
    assert (
        dirichlet(mesh, _bc(bottom=_edge(uy=0.0), top=_edge(uy=-0.1))).pinned.size == 1
    )


def test_pins_for_other_free_modes():
    mesh = _mesh4()
    mid_bottom = mesh.edge_nodes("bottom")[2]
    mid_top = mesh.edge_nodes("top")[2]
    # nothing fixed: both translations at the bottom middle, rotation by ux at the top
    assert rigid_body_pins(mesh, np.zeros(0, np.int64)).tolist() == [
        2 * mid_bottom,
        2 * mid_bottom + 1,
        2 * mid_top,
    ]
    # ux = 0 on the left fixes the x translation and the rotation: one uy pin
    bc = dirichlet(mesh, _bc(left=_edge(ux=0.0)))
    assert bc.pinned.tolist() == [2 * mid_bottom + 1]
    # a single fixed corner (0, 0) leaves the rotation; ux at the bottom middle
    # cannot stop it (same y as the corner), uy there can
    assert rigid_body_pins(mesh, np.array([0, 1])).tolist() == [2 * mid_bottom + 1]


def test_reservoir_style_case_pins_ux_at_the_bottom_middle():
    m = _model(ROLLER_BOTTOM)
    middle = m.mesh.edge_nodes("bottom")[N // 2]
    fixed = set(m.problem.fixed.tolist())
    assert 2 * middle in fixed
    assert fixed == {2 * n + 1 for n in m.mesh.edge_nodes("bottom")} | {2 * middle}
