"""Enrichment: which nodes carry shifted-Heaviside dofs, and the dof map.

Enrichment function of fracture f (paper eqs. 11-12, with a tip ramp):

    F(x) = H(phi(x)) * R(x),   H = +1 where phi >= 0 else -1,

and each enriched node a contributes N_a(x) (F(x) - F(x_a)) a_a (shifted, so
the nodal dofs stay the displacement at the node).  The jump across the
fracture is [[u]] = 2 R sum_a N_a a_a (eq. 14 with the ramp).  R = 1 except in
the tip cell, where it falls linearly to 0 at the geometric tip
(xfemslip/geometry/fracture.py, ``Fracture.ramp``):
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

import dataclasses
import logging
from dataclasses import dataclass
from typing import Any

import numpy as np

from xfemslip import kernels
from xfemslip.fem.branch import branch_functions
from xfemslip.fem.quadrature import DUFFY_POINTS, TRI_BARY, duffy_rule, triangle_rule
from xfemslip.geometry.fracture import GEOMETRY_TOL
from xfemslip.kernels.threads import backend_threads, map_in_threads, map_kernels
from xfemslip.kernels.vectorized import ranges

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
    # F and grad F at the points, once per column: the slots of a cell that
    # take the same function of the same group (a fracture's H R, or one of
    # a tip's B1..B4, from each of the cell's nodes) share one column, their
    # values differing only by the node's shift slot_fnode.  Cell e's value
    # of slot s at its point q (q0 = qp_offsets[e], nq its points) is at
    # column_offsets[e] + slot_column[e, s] * nq + (q - q0).  Stored per slot
    # they would be 3.1 times as many on a 100-fracture network: 27M points
    # x slots against 8.7M points x columns, 640 MB against 210 MB.
    slot_column: np.ndarray  # (nc, S) int64 column of each slot, -1 empty
    column_offsets: np.ndarray  # (nc+1,) int64
    column_F: np.ndarray  # (nv,) [-]
    column_gradF: np.ndarray  # (nv, 2) [1/m]
    tri_offsets: np.ndarray  # (nc+1,) int64 sub-triangles of each cell
    tris: np.ndarray  # (nt, 3, 2) [m]
    tri_F: np.ndarray  # (nt, 3, S) F at the triangle's vertices, from its own side
    # column_F and column_gradF dropped (without_point_values)
    values_released: bool = False

    def without_point_values(self) -> EnrichedCells:
        """These cells without the enrichment values at their quadrature
        points (column_F, column_gradF: 210 MB on a 100-fracture network at
        200 x 200 cells), for a model assembled and
        loaded, which is only solved and written from here on (the
        sub-triangles and their vertex values stay for the output);
        qp_values and part raise on the copy."""
        return dataclasses.replace(
            self,
            column_F=np.zeros(0),
            column_gradF=np.zeros((0, 2)),
            values_released=True,
        )

    def _check_values(self) -> None:
        if self.values_released:
            raise RuntimeError(
                "the enrichment values at the quadrature points were released "
                "after the model was assembled"
            )

    def qp_values(self, q) -> tuple[np.ndarray, np.ndarray]:
        """F (n, S) and grad F (n, S, 2) [1/m] at the points q (n,) int,
        each slot in its column (0 in empty slots)."""
        self._check_values()
        q = np.asarray(q, dtype=np.int64)
        S = self.slot_cand.shape[1]
        e = np.searchsorted(self.qp_offsets, q, side="right") - 1
        nq = np.diff(self.qp_offsets)[e]
        col = self.slot_column[e]  # (n, S)
        used = col >= 0
        v = (
            self.column_offsets[e][:, None]
            + col * nq[:, None]
            + (q - self.qp_offsets[e])[:, None]
        )
        F = np.zeros((q.size, S))
        gF = np.zeros((q.size, S, 2))
        F[used] = self.column_F[v[used]]
        gF[used] = self.column_gradF[v[used]]
        return F, gF

    def part(self, rows) -> tuple[Any, ...]:
        """The points and slot values of the cells ``rows`` (indices into
        cells, or a slice of them: then views, no copy), as the cell kernels
        take them: (qp_offsets, points (index array or slice),
        column_offsets, column_F, column_gradF), offsets from 0."""
        self._check_values()
        if isinstance(rows, slice):
            lo, hi, _ = rows.indices(self.cells.size)
            q0, v0 = self.qp_offsets[lo], self.column_offsets[lo]
            v1 = self.column_offsets[hi]
            return (
                self.qp_offsets[lo : hi + 1] - q0,
                slice(q0, self.qp_offsets[hi]),
                self.column_offsets[lo : hi + 1] - v0,
                self.column_F[v0:v1],
                self.column_gradF[v0:v1],
            )
        rows = np.asarray(rows, dtype=np.int64)
        counts = np.diff(self.qp_offsets)[rows]
        q_off = np.zeros(rows.size + 1, np.int64)
        np.cumsum(counts, out=q_off[1:])
        q_idx = ranges(self.qp_offsets[rows], counts)
        v_counts = np.diff(self.column_offsets)[rows]
        v_off = np.zeros(rows.size + 1, np.int64)
        np.cumsum(v_counts, out=v_off[1:])
        v_idx = ranges(self.column_offsets[rows], v_counts)
        return q_off, q_idx, v_off, self.column_F[v_idx], self.column_gradF[v_idx]


@dataclass(frozen=True)
class Candidates:
    """Node enrichments before the sliver rule: one row per (node, function)."""

    fracture: np.ndarray  # (k,) int64 fracture position
    node: np.ndarray  # (k,) int64 global node
    func: np.ndarray  # (k,) int64: HEAVISIDE or 1..4 (branch B1..B4)
    tip: np.ndarray  # (k,) int64 index in fracture.tips for branch functions,
    # else -1 - arm (Heaviside of that arm, geometry.Fracture.arms)

    def groups(self) -> np.ndarray:
        """(k,) int64: each candidate's group (its fracture and tip or arm) as
        one number; a group's functions are evaluated together
        (group_values)."""
        return self.fracture * (1 << 32) + (self.tip + (1 << 31))

    def function_index(self) -> np.ndarray:
        """(k,) int64: the column of each candidate's function among its
        group's values (H R: 0; B1..B4: 0..3)."""
        return np.where(self.func == HEAVISIDE, 0, self.func - 1)


@dataclass(frozen=True)
class DofMap:
    n_std: int
    n_dofs: int
    cand_dof: np.ndarray  # (k,) int64 first dof of each candidate, -1 if dropped

    @property
    def n_enriched_functions(self) -> int:
        """Kept (node, function) enrichments, each with 2 dofs."""
        return int(np.count_nonzero(self.cand_dof >= 0))

    def dof_node(self, cand_node: np.ndarray) -> np.ndarray:
        """(n_dofs,) the node each dof belongs to: node d // 2 for a
        standard dof d, the enriched node (cand_node, Candidates.node) for
        the two dofs of a kept enrichment."""
        node = np.empty(self.n_dofs, np.int64)
        node[: self.n_std] = np.arange(self.n_std) // 2
        kept = self.cand_dof >= 0
        first = self.cand_dof[kept]
        node[first] = cand_node[kept]
        node[first + 1] = cand_node[kept]
        return node


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
                near = set(mesh.nodes_within(tip.point, fr.tip_radius).tolist())
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


def _cell_lines_table(mesh, fractures, cells, pair_cell, pair_frac, branch, tol):
    """The cut lines and apexes of every enriched cell, as the sub-cell
    kernel takes them (kernels.cell_subtriangles).

    cells : (nc,) enriched cell ids; (pair_cell, pair_frac) : the (row in
    cells, fracture) pairs of the fractures with a slot in each cell;
    branch : (nc,) bool, cells with a branch slot (their apexes are the tips
    of their fractures).  A cell's lines are those of its fractures in a
    listing-free order (the sub-cells do not depend on the order the
    fractures are listed in), each fracture's in its own order: the segments
    whose box (grown by tol) meets the cell, the two ramp kink lines of each
    tip and its junction lines wherever they cross the cell (the ramp's kink
    lines are infinite: they cross every cell of the strip -l <= psi <= 0).
    Returns (line_offsets, line_point, line_normal, apex_offsets, apex_xy).
    """
    order = sorted(range(len(fractures)), key=lambda f: _listing_free_key(fractures[f]))
    rank = np.empty(len(fractures), np.int64)
    rank[order] = np.arange(len(fractures))
    b = mesh.bounds[cells]  # (nc, 4)
    corners = np.stack(
        [b[:, [0, 2]], b[:, [1, 2]], b[:, [1, 3]], b[:, [0, 3]]], axis=1
    )  # (nc, 4, 2)
    keys, pts, nrms, akeys, axy = [], [], [], [], []
    for fi, fr in enumerate(fractures):
        rows = pair_cell[pair_frac == fi]
        if rows.size == 0:
            continue
        lines = [(fr.points[k], fr.normal[k]) for k in range(fr.normal.shape[0])]
        n_seg = len(lines)
        for tip in fr.tips:
            lines.append((tip.point, tip.direction))
            lines.append((tip.point - tip.ramp_length * tip.direction, tip.direction))
        lines += list(fr.cut_lines())
        P = np.array([p for p, _ in lines], float)
        N = np.array([n for _, n in lines], float)
        lo = np.minimum(fr.points[:-1], fr.points[1:]) - tol
        hi = np.maximum(fr.points[:-1], fr.points[1:]) + tol
        br = b[rows]
        seg = (
            (lo[None, :, 0] <= br[:, 1:2])
            & (hi[None, :, 0] >= br[:, 0:1])
            & (lo[None, :, 1] <= br[:, 3:4])
            & (hi[None, :, 1] >= br[:, 2:3])
        )
        d = (corners[rows][:, None, :, :] - P[None, n_seg:, None, :]) @ N[
            n_seg:, :, None
        ]
        d = d[..., 0]  # (r, lines after the segments, 4)
        cross = (d.min(axis=2) < -tol) & (d.max(axis=2) > tol)
        use = np.concatenate([seg, cross], axis=1)  # (r, lines)
        r_i, l_i = np.nonzero(use)
        keys.append(np.column_stack([rows[r_i], np.full(r_i.size, rank[fi]), l_i]))
        pts.append(P[l_i])
        nrms.append(N[l_i])
        tips = np.array([t.point for t in fr.tips], float).reshape(-1, 2)
        brows = rows[branch[rows]]
        if tips.size and brows.size:
            t_i = np.tile(np.arange(tips.shape[0]), brows.size)
            akeys.append(
                np.column_stack(
                    [
                        np.repeat(brows, tips.shape[0]),
                        np.full(t_i.size, rank[fi]),
                        t_i,
                    ]
                )
            )
            axy.append(tips[t_i])

    def table(keys, values):
        nc = cells.size
        if not keys:
            return np.zeros(nc + 1, np.int64), np.zeros((0, 2)), np.zeros((0, 2))
        k = np.concatenate(keys)
        o = np.lexsort((k[:, 2], k[:, 1], k[:, 0]))
        offsets = np.zeros(nc + 1, np.int64)
        offsets[1:] = np.cumsum(np.bincount(k[:, 0], minlength=nc))
        return offsets, *(np.ascontiguousarray(np.concatenate(v)[o]) for v in values)

    line_off, line_pt, line_n = table(keys, (pts, nrms))
    apex_off, apex_xy, _ = table(akeys, (axy, axy))
    return line_off, line_pt, line_n, apex_off, apex_xy


def _cell_rules(tri_off, tris, branch):
    """Quadrature points (nq, 2), weights (nq,) and offsets (nc + 1,) of the
    sub-triangles of each cell, and the points per triangle (nt,): the Duffy
    rule on the triangles of cells with a branch slot (the tip is vertex 0),
    the 7-point rule elsewhere; points in the order of the triangles."""
    tri_cell = np.repeat(np.arange(branch.size), np.diff(tri_off))
    on = branch[tri_cell]
    per_tri = np.where(on, DUFFY_POINTS**2, TRI_BARY.shape[0]).astype(np.int64)
    start = np.cumsum(per_tri) - per_tri
    xy = np.empty((int(per_tri.sum()), 2))
    w = np.empty(xy.shape[0])
    for mask, rule in ((on, duffy_rule), (~on, triangle_rule)):
        if mask.any():
            pxy, pw = rule(tris[mask])
            dest = ranges(start[mask], per_tri[mask])
            xy[dest] = pxy
            w[dest] = pw
    qp_off = np.zeros(branch.size + 1, np.int64)
    qp_off[1:] = np.cumsum(
        np.bincount(tri_cell, weights=per_tri, minlength=branch.size)
    )
    return xy, w, qp_off, per_tri


# Cells per thread below which the sub-cells are cut on one thread
SUBCELL_THREAD_CELLS = 2000


def _subtriangles(backend: str, bounds, lines, tol: float):
    """kernels.cell_subtriangles of the cells ``bounds`` with their ``lines``
    (line_offsets, line_point, line_normal, apex_offsets, apex_xy): the
    compiled kernel on every core in contiguous runs of cells (it releases
    the GIL; each cell is cut on its own, so the result is the one-call
    result to the bit), the NumPy one in one call."""
    cut = kernels.backend(backend).cell_subtriangles
    nc = bounds.shape[0]
    parts = max(1, min(backend_threads(backend), nc // SUBCELL_THREAD_CELLS))
    if parts == 1:
        return cut(bounds, *lines, tol)
    line_off, line_point, line_normal, apex_off, apex_xy = lines
    edges = np.linspace(0, nc, parts + 1).astype(np.int64)

    def run(k: int):
        a, b = edges[k], edges[k + 1]
        l0, l1, p0, p1 = line_off[a], line_off[b], apex_off[a], apex_off[b]
        return cut(
            bounds[a:b],
            line_off[a : b + 1] - l0,
            line_point[l0:l1],
            line_normal[l0:l1],
            apex_off[a : b + 1] - p0,
            apex_xy[p0:p1],
            tol,
        )

    pieces = map_in_threads(run, range(parts), parts)
    tri_off = np.zeros(nc + 1, np.int64)
    shift = 0
    for k, (off, _) in enumerate(pieces):
        tri_off[edges[k] + 1 : edges[k + 1] + 1] = off[1:] + shift
        shift += off[-1]
    return tri_off, np.concatenate([t for _, t in pieces])


def build_enriched_cells(
    mesh, fractures, cand: Candidates, backend: str = "numpy"
) -> EnrichedCells:
    """Slots, sub-cell quadrature and enrichment values of every enriched cell.

    Two passes: the sub-cells of every cell (its own cut lines, all cells in
    one call of the kernel ``backend``'s cell_subtriangles, "numba" or
    "numpy"), then the enrichment functions of each (fracture, tip or arm)
    group evaluated once on the quadrature points and sub-triangle vertices
    of all the cells the group reaches (the functions are point-wise, so
    the values are those of a cell-by-cell evaluation; measured in
    docs/performance.md, "Fracture networks").  The fracture side of a point
    is that of its sub-cell's centroid.
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
        c_all = order[ranges(split[cand.node], count)] // 4
    pair = np.lexsort((k_all, c_all))
    k_all, c_all = k_all[pair], c_all[pair]
    cand_cells, first, n_slots = np.unique(c_all, return_index=True, return_counts=True)
    cand_cells = cand_cells.astype(np.int64)
    nc = cand_cells.size
    S = int(n_slots.max(initial=0))
    slot_cand = -np.ones((nc, S), np.int64)
    slot_cand[
        np.repeat(np.arange(nc), n_slots), ranges(np.zeros(nc, np.int64), n_slots)
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

    # pass 1: sub-cells and quadrature of every cell (one kernel call)
    e_used, s_used = np.nonzero(used)
    # the (cell row, fracture) pairs in lexicographic order, as one key each
    # (np.unique of the rows, axis=0, took 0.09 s on a 100-fracture network)
    n_frac = max(len(fractures), 1)
    key = np.unique(e_used * n_frac + cand.fracture[k_used])
    pair = np.column_stack([key // n_frac, key % n_frac])
    branch = np.zeros(nc, bool)
    branch[e_used[cand.func[k_used] != HEAVISIDE]] = True
    lines = _cell_lines_table(
        mesh, fractures, cand_cells, pair[:, 0], pair[:, 1], branch, tol
    )
    tri_off, tris = _subtriangles(
        backend, np.ascontiguousarray(mesh.bounds[cand_cells]), lines, float(tol)
    )
    qp_xy, qp_w, qp_off, per_tri = _cell_rules(tri_off, tris, branch)
    centroids = tris.mean(axis=1)

    # pass 2: each enrichment group on every cell it reaches; a cell's slots
    # that take the same function of the same group share a column
    nq_cell = np.diff(qp_off)
    nt_cell = np.diff(tri_off)
    group = cand.groups()[k_used]
    _, group_rank = np.unique(group, return_inverse=True)
    width = 4 * (int(group_rank.max(initial=0)) + 1)
    # (cell, group, function index into the group's values) of every slot
    key = e_used * width + group_rank.ravel() * 4 + cand.function_index()[k_used]
    col_key, slot_key = np.unique(key, return_inverse=True)
    slot_key = slot_key.ravel()
    col_cell = col_key // width
    col_in_cell = np.arange(col_key.size) - np.searchsorted(col_cell, col_cell)
    slot_column = -np.ones((nc, S), np.int64)
    slot_column[e_used, s_used] = col_in_cell[slot_key]
    n_cols = np.bincount(col_cell, minlength=nc)
    col_off = np.zeros(nc + 1, np.int64)
    np.cumsum(nq_cell * n_cols, out=col_off[1:])
    F = np.zeros(col_off[-1])
    gF = np.zeros((col_off[-1], 2))
    Fv_col = np.zeros((tris.shape[0], 3, int(n_cols.max(initial=0))))
    scatter = kernels.backend(backend).scatter_column_values
    # the slots of each group as one slice of a stable sort (in the order a
    # mask `group == g` gives) rather than a mask over all slots per group:
    # 1,733 groups x 130k slots on a 100-fracture network
    by_group = np.argsort(group, kind="stable")
    _, starts = np.unique(group[by_group], return_index=True)
    bounds = np.append(starts, group.size).tolist()

    def evaluate(span: tuple[int, int]) -> None:
        lo, hi = span
        mine = by_group[lo:hi]
        k0 = k_used[mine][0]
        fi, tip = int(cand.fracture[k0]), int(cand.tip[k0])
        cells = np.unique(e_used[mine])  # rows of the cells the group reaches
        ti = ranges(tri_off[cells], nt_cell[cells])
        qi = ranges(qp_off[cells], nq_cell[cells])
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
        # every column of the group, with its cell's first rows in the
        # group's arrays
        cols = np.unique(slot_key[mine])
        es = col_cell[cols]
        scatter(
            F,
            gF,
            Fv_col,
            np.ascontiguousarray(Fq),
            np.ascontiguousarray(gq),
            np.ascontiguousarray(Fvert),
            es,
            col_in_cell[cols],
            col_key[cols] % 4,
            np.searchsorted(cells, es),
            col_off,
            nq_cell,
            np.concatenate([[0], np.cumsum(nq_cell[cells])]),
            tri_off,
            nt_cell,
            np.concatenate([[0], np.cumsum(nt_cell[cells])]),
        )

    # the groups write disjoint columns; with the compiled kernels (a large
    # model) they run on every core: NumPy's functions of many points and
    # the scatter kernel release the GIL
    map_kernels(backend, evaluate, zip(bounds[:-1], bounds[1:], strict=True))
    # the vertex values (for the output) per slot, each its column's
    tri_slot = slot_column[np.repeat(np.arange(nc), nt_cell)]  # (nt, S)
    Fv = np.zeros((tris.shape[0], 3, S))
    t_used, s_of = np.nonzero(tri_slot >= 0)
    Fv[t_used, :, s_of] = Fv_col[t_used, :, tri_slot[t_used, s_of]]

    return EnrichedCells(
        cells=cand_cells,
        slot_cand=slot_cand,
        slot_node=slot_node,
        slot_fnode=slot_fnode,
        qp_offsets=qp_off,
        qp_xy=qp_xy,
        qp_w=qp_w,
        slot_column=slot_column,
        column_offsets=col_off,
        column_F=F,
        column_gradF=gF,
        tri_offsets=tri_off,
        tris=tris,
        tri_F=Fv,
    )


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
    enr_diag: np.ndarray,
    std_diag: np.ndarray,
    jumps: np.ndarray | None = None,
) -> DofMap:
    """Apply the jump and sliver rules and number the kept enriched dofs.

    enr_diag : (nc, 8+2S) diagonal of the enriched-cell stiffness with every
    candidate slot.
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
                enr_diag[m, 8 + 2 * s + comp],
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
