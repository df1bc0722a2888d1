"""Enrichment: which nodes carry shifted-Heaviside dofs, and the dof map.

Enrichment function of fracture f (paper eqs. 11-12, with a tip ramp):

    F(x) = H(phi(x)) * R(x),   H = +1 where phi >= 0 else -1,

and each enriched node a contributes N_a(x) (F(x) - F(x_a)) a_a (shifted, so
the nodal dofs stay the displacement at the node).  The jump across the
fracture is [[u]] = 2 R sum_a N_a a_a (eq. 14 with the ramp).  R = 1 except in
the tip cell, where it falls linearly to 0 at the geometric tip (geometry.py):
the modelled discontinuity ends exactly at the tip, wherever the tip lies.
A node x_a exactly on the fracture takes H = +1 (eq. 12).

Junctions (Daux, Moes, Dolbow, Sukumar & Belytschko 2000, IJNME 48): a
fracture ending on another, or each of the two arms into which the other
fracture of an X cuts it, is enriched with its own junction function
J = H(phi) on its side of the main fracture's line and a constant beyond
(geometry.Cut), one candidate group per arm; nodes enriched by several
fractures or arms keep independent dofs.  Enriched cells are also cut along
those lines, so each wedge of a junction cell is integrated on its own.

Candidate nodes: every node of a cell that holds a piece of the fracture (of
the arm).
A Heaviside candidate is kept only if its shape function is non-zero somewhere
on the fracture (``carries_jump``): a node whose support the fracture only
touches on its boundary is not enriched.
Sliver rule (conditioning): a candidate is dropped when the diagonal of its
enriched stiffness is below ``ENRICHMENT_DIAG_RATIO`` times the diagonal of
its standard dofs (minimum over x and y).  For a node whose support the
fracture cuts into a sliver of area fraction eps the ratio is O(eps); for a
fracture running along element edges it is exactly 0 for the nodes off the
fracture, whose enrichment vanishes identically.  Dropping such a node changes
the represented jump by O(eps) while keeping the matrix well conditioned.

Dof numbering: standard ``2*node + c``; kept enrichments appended in candidate
order as ``n_std + 2*k + c``.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from xfemslip.fem.branch import branch_functions
from xfemslip.fem.quadrature import cell_subtriangles, duffy_rule, triangle_rule
from xfemslip.geometry.fracture import GEOMETRY_TOL

logger = logging.getLogger(__name__)

ENRICHMENT_DIAG_RATIO = 1.0e-4
# A Heaviside enrichment whose shape function is below this on the whole
# fracture (in units of the jump, 2 R N_a) carries no jump (see carries_jump).
JUMP_TOL = 1.0e-9

HEAVISIDE = 0  # candidate function codes: 0 = F = H R, 1..4 = branch B1..B4


@dataclass(frozen=True)
class EnrichedCells:
    """Cells with at least one enriched node, with their sub-cell quadrature.

    S is the largest number of enrichment slots of a cell; unused slots are -1.
    """

    cells: np.ndarray  # (nc,) int64 cell ids
    slot_cand: np.ndarray  # (nc, S) int64 candidate id of each slot, -1 empty
    slot_node: np.ndarray  # (nc, S) int64 local node 0..3 of each slot, -1 empty
    slot_fnode: np.ndarray  # (nc, S) float64 F at the slot's node (the shift)
    qp_offsets: np.ndarray  # (nc+1,) int64
    qp_xy: np.ndarray  # (nq, 2) [m]
    qp_w: np.ndarray  # (nq,) [m^2]
    qp_F: np.ndarray  # (nq, S)
    qp_gradF: np.ndarray  # (nq, S, 2) [1/m]
    tri_offsets: np.ndarray  # (nc+1,) int64 sub-triangles of each cell
    tris: np.ndarray  # (nt, 3, 2) [m]
    tri_F: np.ndarray  # (nt, 3, S) F at the triangle's vertices, from its own side


@dataclass(frozen=True)
class Candidates:
    """Node enrichments before the sliver rule: one row per (node, function)."""

    fracture: np.ndarray  # (k,) int64 fracture position
    node: np.ndarray  # (k,) int64 global node
    func: np.ndarray  # (k,) int64: HEAVISIDE or 1..4 (branch B1..B4)
    tip: np.ndarray  # (k,) int64 index in fracture.tips for branch functions,
    # else -1 - arm (Heaviside of that arm, geometry.Fracture.arms)


@dataclass(frozen=True)
class DofMap:
    n_std: int
    n_dofs: int
    cand_dof: np.ndarray  # (k,) int64 first dof of each candidate, -1 if dropped

    @property
    def n_enriched_functions(self) -> int:
        """Kept (node, function) enrichments, each with 2 dofs."""
        return int(np.count_nonzero(self.cand_dof >= 0))


def find_candidates(mesh, fractures) -> Candidates:
    """Heaviside candidates on the nodes of cut cells; branch candidates within
    ``tip_radius`` of each tip (and always on the tip cell's nodes) when the
    fracture's tip mode is "branch".  A branch-enriched node gets no Heaviside."""
    rows = []
    for fi, fr in enumerate(fractures):
        cut_nodes = np.unique(mesh.cells[np.unique(fr.piece_cell)].ravel())
        branch = set()
        if fr.tip_mode == "branch":
            for ti, tip in enumerate(fr.tips):
                dist = np.linalg.norm(mesh.nodes - tip.point, axis=1)
                near = set(np.nonzero(dist <= fr.tip_radius)[0].tolist())
                k = 0 if tip.end == 0 else -1
                near |= set(mesh.cells[fr.piece_cell[k]].tolist())
                branch |= near
                rows += [(fi, n, j, ti) for n in sorted(near) for j in (1, 2, 3, 4)]
        # one Heaviside per arm (geometry.Fracture.arms): code tip = -1 - arm
        if len(fr.arms) == 1:
            arm_nodes = [cut_nodes]
        else:
            mid = fr.arc_length(fr.piece_seg, fr.piece_t.mean(axis=1))
            arm = fr.arm_of(mid)
            arm_nodes = [
                np.unique(mesh.cells[np.unique(fr.piece_cell[arm == a])].ravel())
                for a in range(len(fr.arms))
            ]
        for a, nodes in enumerate(arm_nodes):
            rows += [
                (fi, int(n), HEAVISIDE, -1 - a) for n in nodes if int(n) not in branch
            ]
    arr = np.array(rows, dtype=np.int64).reshape(-1, 4)
    return Candidates(*(np.ascontiguousarray(arr[:, i]) for i in range(4)))


def group_values(fractures, fi, tip, pts, side, tol, probe=None):
    """All functions of one (fracture, tip) group: (n, 1) Heaviside or (n, 4) branch.

    Heaviside of arm a (tip = -1 - a): F = J R with J the junction function of
    Daux et al. (2000): H(phi) on the arm's side of each junction line, a
    constant beyond (Fracture.junction_factor, evaluated at probe).
    """
    fr = fractures[fi]
    if tip < 0:
        R, gR = fr.ramp(pts)
        J = fr.junction_factor(-1 - tip, pts if probe is None else probe, side, tol)
        return (J * R)[:, None], (J[:, None] * gR)[:, None, :]
    return branch_functions(fr.tips[tip], pts, side, tol)


def _cell_lines(fr, b, tol):
    """Kink lines of fracture fr that can cross the cell with bounds b."""
    lo = np.minimum(fr.points[:-1], fr.points[1:]) - tol
    hi = np.maximum(fr.points[:-1], fr.points[1:]) + tol
    near = (
        (lo[:, 0] <= b[1])
        & (hi[:, 0] >= b[0])
        & (lo[:, 1] <= b[3])
        & (hi[:, 1] >= b[2])
    )
    out = [(fr.points[k], fr.normal[k]) for k in np.nonzero(near)[0]]
    for tip in fr.tips:
        # the ramp's kink lines are infinite: they cross every cell of the strip
        # -l <= psi <= 0, not only the cells near the tip
        for point in (tip.point, tip.point - tip.ramp_length * tip.direction):
            psi = (
                np.array([[b[0], b[2]], [b[1], b[2]], [b[1], b[3]], [b[0], b[3]]])
                - point
            ) @ tip.direction
            if psi.min() < -tol and psi.max() > tol:
                out.append((point, tip.direction))
    corners = np.array([[b[0], b[2]], [b[1], b[2]], [b[1], b[3]], [b[0], b[3]]])
    for point, normal in fr.cut_lines():
        d = (corners - point) @ normal
        if d.min() < -tol and d.max() > tol:
            out.append((point, normal))
    return out


def _listing_free_key(fr):
    """Key of a fracture that depends neither on its position in the case file
    nor on its point order: its two end points, sorted."""
    ends = sorted([tuple(fr.points[0]), tuple(fr.points[-1])])
    return ends[0] + ends[1]


def _candidate_node_values(fractures, mesh, cand, tol):
    """F(x_a) of every candidate at its own node (the shift of eq. 11), (k,).

    A node on the fracture takes H = +1 (eq. 12).
    """
    out = np.zeros(cand.node.size)
    for fi, fr in enumerate(fractures):
        for tip in np.unique(cand.tip[cand.fracture == fi]):
            rows = np.nonzero((cand.fracture == fi) & (cand.tip == tip))[0]
            pts = mesh.nodes[cand.node[rows]]
            side = np.where(fr.signed_distance(pts) >= -tol, 1.0, -1.0)
            F = group_values(fractures, fi, int(tip), pts, side, tol, pts)[0]
            j = np.where(cand.func[rows] == HEAVISIDE, 0, cand.func[rows] - 1)
            out[rows] = F[np.arange(rows.size), j]
    return out


def _cell_rule(mesh, c, fractures, frs, has_branch, tol):
    """Sub-triangles, quadrature points and weights of one enriched cell."""
    b = mesh.bounds[c]
    # the fractures of the cell in a listing-free order, each with its own
    # lines in its own order: the sub-cells do not depend on the order the
    # fractures are listed in (and a single fracture's are as before)
    frs = sorted(frs, key=lambda fi: _listing_free_key(fractures[fi]))
    lines = [ln for fi in frs for ln in _cell_lines(fractures[fi], b, tol)]
    if not has_branch:
        tris = cell_subtriangles(b, lines, tol)
        return (tris, *triangle_rule(tris))
    apexes = [t.point for fi in frs for t in fractures[fi].tips]
    tris = cell_subtriangles(b, lines, tol, apexes=apexes)
    return (tris, *duffy_rule(tris))


def build_enriched_cells(mesh, fractures, cand: Candidates) -> EnrichedCells:
    """Slots, sub-cell quadrature and enrichment values of every enriched cell.

    Two passes: the sub-cells of each cell (its own cut lines), then the
    enrichment functions of each (fracture, tip or arm) group evaluated once
    on the quadrature points and sub-triangle vertices of all the cells the
    group reaches (the functions are point-wise, so the values are those of a
    cell-by-cell evaluation; measured in docs/performance.md, "Fracture
    networks").  The fracture side of a point is that of its sub-cell's centroid.
    """
    tol = GEOMETRY_TOL * mesh.h_min
    cand_fnode = _candidate_node_values(fractures, mesh, cand, tol)
    # (candidate, cell) pairs of every cell around each candidate's node,
    # grouped by cell, candidates in increasing order within a cell
    k_all = c_all = np.zeros(0, np.int64)
    if cand.node.size:
        order = np.argsort(mesh.cells.ravel(), kind="stable")
        split = np.searchsorted(mesh.cells.ravel()[order], np.arange(mesh.n_nodes + 1))
        count = np.diff(split)[cand.node]
        k_all = np.repeat(np.arange(cand.node.size), count)
        c_all = order[_ranges(split[cand.node], count)] // 4
    pair = np.lexsort((k_all, c_all))
    k_all, c_all = k_all[pair], c_all[pair]
    cand_cells, first, n_slots = np.unique(c_all, return_index=True, return_counts=True)
    cand_cells = cand_cells.astype(np.int64)
    nc = cand_cells.size
    S = int(n_slots.max(initial=0))
    slot_cand = -np.ones((nc, S), np.int64)
    slot_cand[
        np.repeat(np.arange(nc), n_slots), _ranges(np.zeros(nc, np.int64), n_slots)
    ] = k_all
    used = slot_cand >= 0
    k_used = slot_cand[used]
    slot_node = -np.ones((nc, S), np.int64)
    slot_fnode = np.zeros((nc, S))
    local = (
        mesh.cells[np.repeat(cand_cells, used.sum(axis=1))]
        == (cand.node[k_used][:, None])
    )
    slot_node[used] = np.argmax(local, axis=1)
    slot_fnode[used] = cand_fnode[k_used]

    # pass 1: sub-cells and quadrature of each cell
    parts: dict[str, list[np.ndarray]] = {key: [] for key in ("xy", "w", "tris")}
    per_cell: list[np.ndarray] = []  # quadrature points of each sub-triangle
    frac_of, func_of = cand.fracture.tolist(), cand.func.tolist()
    for e, c in enumerate(cand_cells):
        ks = slot_cand[e, : n_slots[e]].tolist()
        frs = sorted({frac_of[k] for k in ks})
        has_branch = any(func_of[k] != HEAVISIDE for k in ks)
        tris, xy, w = _cell_rule(mesh, c, fractures, frs, has_branch, tol)
        parts["xy"].append(xy)
        parts["w"].append(w)
        parts["tris"].append(tris)
        per_cell.append(np.full(tris.shape[0], xy.shape[0] // tris.shape[0]))

    def cat(key, shape):
        p = parts[key]
        return np.ascontiguousarray(np.concatenate(p)) if p else np.zeros(shape)

    qp_xy, qp_w, tris = cat("xy", (0, 2)), cat("w", (0,)), cat("tris", (0, 3, 2))
    qp_off = np.zeros(nc + 1, np.int64)
    tri_off = np.zeros(nc + 1, np.int64)
    qp_off[1:] = np.cumsum([x.shape[0] for x in parts["xy"]])
    tri_off[1:] = np.cumsum([t.shape[0] for t in parts["tris"]])
    per_tri = np.concatenate(per_cell) if per_cell else np.zeros(0, np.int64)
    centroids = tris.mean(axis=1)

    # pass 2: each enrichment group on every cell it reaches
    F = np.zeros((qp_xy.shape[0], S))
    gF = np.zeros((qp_xy.shape[0], S, 2))
    Fv = np.zeros((tris.shape[0], 3, S))
    e_used, s_used = np.nonzero(used)
    group = cand.fracture[k_used] * (1 << 32) + (cand.tip[k_used] + (1 << 31))
    # the slots of each group as one slice of a stable sort (in the order a
    # mask `group == g` gives) rather than a mask over all slots per group:
    # 1,733 groups x 130k slots on a 100-fracture network
    by_group = np.argsort(group, kind="stable")
    _, starts = np.unique(group[by_group], return_index=True)
    bounds = np.append(starts, group.size).tolist()
    for lo, hi in zip(bounds[:-1], bounds[1:], strict=True):
        mine = by_group[lo:hi]
        k0 = k_used[mine][0]
        fi, tip = int(cand.fracture[k0]), int(cand.tip[k0])
        cells = np.unique(e_used[mine])  # rows of the cells the group reaches
        ti = _ranges(tri_off[cells], np.diff(tri_off)[cells])
        qi = _ranges(qp_off[cells], np.diff(qp_off)[cells])
        st = fractures[fi].side(centroids[ti])
        Fq, gq = group_values(
            fractures,
            fi,
            tip,
            qp_xy[qi],
            np.repeat(st, per_tri[ti]),
            tol,
            np.repeat(centroids[ti], per_tri[ti], axis=0),
        )
        Fvert = group_values(
            fractures,
            fi,
            tip,
            tris[ti].reshape(-1, 2),
            np.repeat(st, 3),
            tol,
            np.repeat(centroids[ti], 3, axis=0),
        )[0].reshape(ti.size, 3, -1)
        # every slot of the group: its cell's rows in the group's arrays
        es, ss = e_used[mine], s_used[mine]
        func = cand.func[slot_cand[es, ss]]
        js = np.where(func == HEAVISIDE, 0, func - 1)
        pos = np.searchsorted(cells, es)
        g_qp = np.concatenate([[0], np.cumsum(np.diff(qp_off)[cells])])
        g_tri = np.concatenate([[0], np.cumsum(np.diff(tri_off)[cells])])
        nq_s = np.diff(qp_off)[es]
        rows_q = _ranges(qp_off[es], nq_s)
        rows_g = _ranges(g_qp[pos], nq_s)
        cols = np.repeat(ss, nq_s)
        jj = np.repeat(js, nq_s)
        F[rows_q, cols] = Fq[rows_g, jj]
        gF[rows_q, cols] = gq[rows_g, jj]
        nt_s = np.diff(tri_off)[es]
        rows_t = _ranges(tri_off[es], nt_s)
        rows_gt = _ranges(g_tri[pos], nt_s)
        Fv[rows_t, :, np.repeat(ss, nt_s)] = Fvert[rows_gt, :, np.repeat(js, nt_s)]

    return EnrichedCells(
        cells=cand_cells,
        slot_cand=slot_cand,
        slot_node=slot_node,
        slot_fnode=slot_fnode,
        qp_offsets=qp_off,
        qp_xy=qp_xy,
        qp_w=qp_w,
        qp_F=F,
        qp_gradF=gF,
        tri_offsets=tri_off,
        tris=tris,
        tri_F=Fv,
    )


def _ranges(starts, counts):
    """Concatenation of arange(s, s + n) for each (s, n), int64."""
    starts = np.asarray(starts, np.int64)
    counts = np.asarray(counts, np.int64)
    total = int(counts.sum())
    if total == 0:
        return np.zeros(0, np.int64)
    first = np.cumsum(counts) - counts
    return np.repeat(starts - first, counts) + np.arange(total, dtype=np.int64)


def carries_jump(mesh, cand: Candidates, ip) -> np.ndarray:
    """Whether each candidate's function jumps somewhere on its fracture (k,) bool.

    A Heaviside candidate carries the jump 2 R N_a on the fracture; it carries
    none when the fracture only touches its support's boundary (a fracture
    along element edges, seen from a node off it), where N_a = 0.  Such an
    enrichment is smooth, adds nothing to the crack, and can be linearly
    dependent on its neighbours (the ramp), so it is never kept.  Branch
    candidates are kept (B2..B4 carry no jump by design).
    """
    jump = np.zeros(cand.node.size)
    if ip.n and cand.node.size:
        N = mesh.shape_at(ip.cell, ip.xy)  # (n_ip, 4)
        n_nodes = mesh.n_nodes
        n_frac = int(max(ip.fracture.max(), cand.fracture.max())) + 1
        key = ip.fracture[:, None] * n_nodes + mesh.cells[ip.cell]  # (n_ip, 4)
        best = np.zeros(n_nodes * n_frac)
        np.maximum.at(best, key.ravel(), (np.abs(2.0 * ip.ramp)[:, None] * N).ravel())
        jump = best[cand.fracture * n_nodes + cand.node]
    return (cand.func != HEAVISIDE) | (jump > JUMP_TOL)


def select_enrichment(
    mesh,
    cand: Candidates,
    ec: EnrichedCells,
    K_enr: np.ndarray,
    std_diag: np.ndarray,
    jumps: np.ndarray | None = None,
) -> DofMap:
    """Apply the jump and sliver rules and number the kept enriched dofs.

    K_enr : (nc, 8+2S, 8+2S) enriched-cell stiffness with every candidate slot.
    std_diag : (n_std,) diagonal of the standard-dof bulk stiffness.
    jumps : (k,) bool from ``carries_jump`` (None: not applied).
    """
    n_std = 2 * mesh.n_nodes
    k = cand.node.size
    diag = np.zeros((k, 2))
    S = ec.slot_cand.shape[1]
    for s in range(S):
        m = ec.slot_cand[:, s] >= 0
        for comp in range(2):
            np.add.at(
                diag[:, comp],
                ec.slot_cand[m, s],
                K_enr[m, 8 + 2 * s + comp, 8 + 2 * s + comp],
            )
    ref = np.stack([std_diag[2 * cand.node], std_diag[2 * cand.node + 1]], axis=1)
    ratio = (diag / ref).min(axis=1) if k else np.zeros(0)
    keep = ratio >= ENRICHMENT_DIAG_RATIO
    if jumps is not None:
        keep &= jumps
    cand_dof = -np.ones(k, np.int64)
    cand_dof[keep] = n_std + 2 * np.arange(np.count_nonzero(keep))
    if k and not keep.all():
        logger.info(
            "enrichment: dropped %d of %d node enrichments whose support the fracture "
            "cuts into a sliver (stiffness ratio < %.0e)",
            k - keep.sum(),
            k,
            ENRICHMENT_DIAG_RATIO,
        )
    return DofMap(n_std=n_std, n_dofs=n_std + 2 * int(keep.sum()), cand_dof=cand_dof)
