"""Boundary conditions: prescribed displacements, edge tractions, rigid-body pins.

Tractions on an edge are t = sigma . n_out with the outward normal of the edge;
with an initial stress sigma0 the body starts in equilibrium with it and the
edges receive the increment lambda (sigma - sigma0) . n_out (``loading.stress``
is the final total far-field stress).  The traction is integrated with the
enriched shape functions too, so a fracture reaching a loaded edge is loaded
consistently.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from xfemslip.errors import GeometryError
from xfemslip.fem.enrichment import HEAVISIDE, group_values
from xfemslip.fem.quadrature import LINE_POINTS, LINE_WEIGHTS

logger = logging.getLogger(__name__)

OUTWARD = {
    "bottom": (0.0, -1.0),
    "top": (0.0, 1.0),
    "left": (-1.0, 0.0),
    "right": (1.0, 0.0),
}
# Prescribed values at a corner shared by two edges may differ by this much
# (relative to the largest prescribed magnitude) before it is an error.
CORNER_TOL = 1.0e-9


@dataclass(frozen=True)
class Dirichlet:
    dofs: np.ndarray  # (m,) int64, sorted
    values: np.ndarray  # (m,) final prescribed values [m]
    pinned: np.ndarray  # (p,) int64 dofs pinned to remove rigid-body modes (value 0)


def dirichlet(mesh, boundary) -> Dirichlet:
    """Prescribed dofs and their final values from the four edges, plus pins."""
    values: dict[int, float] = {}  # dof -> prescribed value [m]
    owner: dict[int, str] = {}  # dof -> the edge that prescribes it
    scale = 0.0
    for name in ("bottom", "top", "left", "right"):
        edge = getattr(boundary, name)
        if edge.kind != "displacement":
            continue
        nodes = mesh.edge_nodes(name)
        v = np.asarray(edge.values, dtype=float)
        if v.shape != (nodes.size, 2):
            raise ValueError(
                f"boundary.{name}: values shape {v.shape} != {(nodes.size, 2)}"
            )
        scale = max(scale, float(np.nanmax(np.abs(v), initial=0.0)))
        for node, row in zip(nodes, v, strict=True):
            for c in range(2):
                if np.isnan(row[c]):
                    continue
                dof = 2 * int(node) + c
                if dof in values and abs(values[dof] - row[c]) > CORNER_TOL * max(
                    scale, 1e-300
                ):
                    comp = "xy"[c]
                    raise GeometryError(
                        f"boundary.{owner[dof]} and boundary.{name} prescribe "
                        "different "
                        f"u{comp} at their common corner ({mesh.nodes[node, 0]:g}, "
                        f"{mesh.nodes[node, 1]:g}): {values[dof]:g} and {row[c]:g} m"
                    )
                values[dof] = float(row[c])
                owner[dof] = name
    dofs = np.array(sorted(values), dtype=np.int64)
    vals = np.array([values[d] for d in dofs], dtype=float)
    pinned = rigid_body_pins(mesh, dofs)
    if pinned.size:
        dofs_all = np.concatenate([dofs, pinned])
        order = np.argsort(dofs_all)
        return Dirichlet(
            dofs=dofs_all[order],
            values=np.concatenate([vals, np.zeros(pinned.size)])[order],
            pinned=pinned,
        )
    return Dirichlet(dofs=dofs, values=vals, pinned=pinned)


def hold_enriched(bc: Dirichlet, cand, dofmap) -> Dirichlet:
    """Also fix (to 0) the enrichment dofs of every prescribed node component.

    The prescribed values hold the whole edge, not just its nodes: with the
    enrichment amplitudes of the edge's nodes at zero, the displacement along
    the edge is the linear interpolation of the nodal values, as prescribed.
    (A fracture reaching a fixed edge therefore cannot open or slip there in
    the fixed component; along a roller it still slides.)  Rigid-body pins
    are point constraints and do not fix enrichment dofs.
    """
    prescribed = np.setdiff1d(bc.dofs, bc.pinned)
    node, comp = prescribed // 2, prescribed % 2
    kept = dofmap.cand_dof >= 0
    if not kept.any() or prescribed.size == 0:
        return bc
    by_node: dict[int, list[int]] = {}
    for k in np.nonzero(kept)[0]:
        by_node.setdefault(int(cand.node[k]), []).append(int(dofmap.cand_dof[k]))
    extra = [
        d + int(c)
        for n, c in zip(node, comp, strict=True)
        for d in by_node.get(int(n), ())
    ]
    if not extra:
        return bc
    dofs = np.concatenate([bc.dofs, np.array(extra, np.int64)])
    values = np.concatenate([bc.values, np.zeros(len(extra))])
    order = np.argsort(dofs)
    return Dirichlet(dofs=dofs[order], values=values[order], pinned=bc.pinned)


def _rigid_modes(mesh, dofs):
    """Rigid-body modes (ux, uy, rotation about the centre) at dofs, (m, 3)."""
    centre = mesh.nodes.mean(axis=0)
    node, comp = dofs // 2, dofs % 2
    rel = mesh.nodes[node] - centre
    return np.column_stack(
        [comp == 0, comp == 1, np.where(comp == 0, -rel[:, 1], rel[:, 0])]
    ).astype(float)


def rigid_body_pins(mesh, fixed) -> np.ndarray:
    """The fewest extra dofs that remove the rigid-body modes the boundary leaves free.

    Candidates, in order: ux and uy at the node nearest the middle of the
    bottom edge, then of the top, left and right edges; a candidate is taken
    when it removes a mode (raises the rank of the constrained modes).
    """
    rank = np.linalg.matrix_rank(_rigid_modes(mesh, fixed)) if fixed.size else 0
    if rank == 3:
        return np.zeros(0, np.int64)
    cands = []
    for name in ("bottom", "top", "left", "right"):
        nodes = mesh.edge_nodes(name)
        mid = nodes[np.argmin(np.abs(np.arange(nodes.size) - (nodes.size - 1) / 2.0))]
        cands += [2 * int(mid), 2 * int(mid) + 1]
    pins = []
    current = list(fixed)
    for d in cands:
        if d in current:
            continue
        r = np.linalg.matrix_rank(_rigid_modes(mesh, np.array(current + [d])))
        if r > rank:
            pins.append(d)
            current.append(d)
            rank = r
            node = d // 2
            logger.info(
                "rigid-body mode left free by the boundary: pinned u%s = 0 at node %d "
                "(%g, %g)",
                "xy"[d % 2],
                node,
                mesh.nodes[node, 0],
                mesh.nodes[node, 1],
            )
        if rank == 3:
            break
    return np.array(pins, dtype=np.int64)


def traction_load(mesh, boundary, loading, ec, cand, dofmap, fractures) -> np.ndarray:
    """External force (n_dofs,) [N/m] at load factor 1 from the traction edges."""
    F = np.zeros(dofmap.n_dofs)
    if loading.stress is None:
        return F
    sig = np.array(loading.stress, float)
    if loading.initial_stress is not None:
        sig = sig - np.array(loading.initial_stress, float)
    sxx, syy, sxy = sig
    S = np.array([[sxx, sxy], [sxy, syy]])
    enr_pos = {int(c): e for e, c in enumerate(ec.cells)}
    segments = []  # boundary edges of enriched cells: (cell, e, p, q, t)
    for name in ("bottom", "top", "left", "right"):
        edge = getattr(boundary, name)
        mask = np.ones(2)
        if edge.kind == "displacement":
            if not edge.traction:
                continue
            mask = np.isnan(np.asarray(edge.values, float)[0]).astype(float)
        elif edge.kind != "traction":
            continue
        t = (S @ np.array(OUTWARD[name])) * mask
        nodes = mesh.edge_nodes(name)
        cells = edge_cells(mesh, name)
        for p, q, cell in zip(nodes[:-1], nodes[1:], cells, strict=True):
            length = np.linalg.norm(mesh.nodes[q] - mesh.nodes[p])
            F[2 * p : 2 * p + 2] += 0.5 * length * t
            F[2 * q : 2 * q + 2] += 0.5 * length * t
            if int(cell) in enr_pos:
                segments.append((int(cell), enr_pos[int(cell)], p, q, t))
    if segments:
        _enriched_edge_load(F, mesh, segments, ec, cand, dofmap, fractures)
    return F


def edge_cells(mesh, edge: str) -> np.ndarray:
    """Cells along an edge, in the order of ``mesh.edge_nodes(edge)`` segments."""
    nx, ny = mesh.nx, mesh.ny
    i, j = np.arange(nx), np.arange(ny)
    return {
        "bottom": i,
        "top": (ny - 1) * nx + i,
        "left": j * nx,
        "right": j * nx + nx - 1,
    }[edge].astype(np.int64)


def _edge_points(mesh, segments, fractures):
    """Gauss points of the boundary edges of enriched cells, each edge split
    where it crosses a kink line of an enrichment function.

    Returns per point: the segment index (P,), x (P, 2), the midpoint of its
    piece of edge (P, 2), which decides the side of the fracture, and the
    weight times the length (P,) [m]."""
    lines = [ln for fr in fractures for ln in fr.kink_lines()]
    points = np.array([pt for pt, _ in lines], float).reshape(-1, 2)
    normals = np.array([nm for _, nm in lines], float).reshape(-1, 2)
    seg, xs, mids, coefs = [], [], [], []
    for i, (_, _, p, q, _) in enumerate(segments):
        xp, xq = mesh.nodes[p], mesh.nodes[q]
        # where the edge crosses each kink line, all lines at once
        den = normals[:, 0] * (xq - xp)[0] + normals[:, 1] * (xq - xp)[1]
        off = points - xp
        num = off[:, 0] * normals[:, 0] + off[:, 1] * normals[:, 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.where(den != 0.0, num / den, -1.0)
        cuts = np.sort(np.concatenate([[0.0, 1.0], s[(s > 0.0) & (s < 1.0)]]))
        a0, a1 = cuts[:-1, None], cuts[1:, None]
        s = 0.5 * (a0 + a1) + 0.5 * (a1 - a0) * LINE_POINTS[None, :]  # (m, 4)
        xs.append(xp + s.reshape(-1, 1) * (xq - xp))
        mid = xp + (0.5 * (a0 + a1)) * (xq - xp)  # (m, 2)
        mids.append(np.repeat(mid, LINE_POINTS.size, axis=0))
        length = np.linalg.norm(xq - xp)
        coefs.append((0.5 * (a1 - a0) * length * LINE_WEIGHTS[None, :]).ravel())
        seg.append(np.full(s.size, i))
    return (
        np.concatenate(seg),
        np.concatenate(xs),
        np.concatenate(mids),
        np.concatenate(coefs),
    )


def _enriched_edge_load(F, mesh, segments, ec, cand, dofmap, fractures):
    """int N_a (F - F_a) t ds over the boundary edges of the enriched cells
    (``segments``: (cell, enriched-cell position, node p, node q, traction)),
    every function of a (fracture, tip) group evaluated at all its points at
    once."""
    seg, x, mid, coef = _edge_points(mesh, segments, fractures)
    cell = np.array([g[0] for g in segments], np.int64)[seg]
    e = np.array([g[1] for g in segments], np.int64)[seg]
    t = np.array([g[4] for g in segments], float)[seg]
    N = mesh.shape_at(cell, x)
    k = ec.slot_cand[e]  # (P, S)
    kc = np.maximum(k, 0)
    live = (k >= 0) & (dofmap.cand_dof[kc] >= 0)
    groups = np.where(live, cand.fracture[kc], -1), np.where(live, cand.tip[kc], 0)
    pairs = np.unique(np.column_stack([g[live] for g in groups]), axis=0)
    for fi, tip in pairs:
        rows, cols = np.nonzero(live & (groups[0] == fi) & (groups[1] == tip))
        fr = fractures[fi]
        values = group_values(fractures, fi, tip, x[rows], fr.side(mid[rows]), 0.0)[0]
        kk = kc[rows, cols]
        j = np.where(cand.func[kk] == HEAVISIDE, 0, cand.func[kk] - 1)
        Fx = values[np.arange(rows.size), j]
        er = e[rows]
        phi = N[rows, ec.slot_node[er, cols]] * (Fx - ec.slot_fnode[er, cols])
        contribution = (coef[rows] * phi)[:, None] * t[rows]
        d = dofmap.cand_dof[kk]
        np.add.at(F, d, contribution[:, 0])
        np.add.at(F, d + 1, contribution[:, 1])


def fracture_face_load(contact, normal=None, shear=None) -> np.ndarray:
    """External force (n_dofs,) [N/m] of equal and opposite tractions on the
    two faces of the fractures: sum_p [[N_p]]^T (normal_p n_p + shear_p t_p)
    over the interface points, with the points' own jump operators.

    normal, shear : (n,) [N/m] per interface point: the point's weight times
    the traction on its + face (shear along t, normal along n: a positive
    normal pushes the faces apart, as a fluid pressure does).  Where the faces
    stick this adds the traction to the contact tractions p_N, p_T without
    deforming the body: the load of a stress acting on a locked fault.
    """
    F = np.zeros(contact.n_dofs)
    dofs, coef = contact.point_dofs, contact.point_coef
    if dofs.shape[1] == 0:
        return F
    for c in range(2):
        d = dofs[:, c::2]
        v = np.zeros(coef.shape)
        if normal is not None:
            v = v + coef * (normal * contact.point_normal[:, c])[:, None]
        if shear is not None:
            v = v + coef * (shear * contact.point_tangent[:, c])[:, None]
        keep = d >= 0
        np.add.at(F, d[keep], v[keep])
    return F
