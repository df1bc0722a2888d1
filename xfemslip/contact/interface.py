"""Contact driver: interface-point operators, history, and the kernel call.

Each interface point carries the jump operator of eq. 14 with the tip ramp,
[[u]] = sum_a 2 R(x) N_a(x) a_a over the enriched nodes a of its cell, as up to
four coefficients and their dofs.  The history (committed plastic slip and
state) is carried from load step to load step; within a step every Newton
iteration restarts the return map from the committed values.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from xfemslip import kernels
from xfemslip.contact.defaults import AUTO_PENALTY, CONTACT_PATCH_CELLS
from xfemslip.conventions import OPEN, STICK
from xfemslip.fem.assembly import coo_block, scatter_vector
from xfemslip.fem.enrichment import HEAVISIDE, group_values
from xfemslip.geometry.fracture import GEOMETRY_TOL

logger = logging.getLogger(__name__)


# The history a ContactSet commits after a converged step: what a caller that
# steps back (a bisection) saves and restores.
COMMITTED = (
    "slip_committed",
    "slip_reference",
    "state_committed",
    "gt_committed",
    "pt_committed",
    "accumulated_committed",
)


@dataclass
class ContactResult:
    """Response of all contact patches at one displacement.

    The contact law is evaluated once per patch (see ``ContactSet``): ``gn``
    ... ``slip_plastic`` and ``blocks`` are per patch; ``point_*`` are the same
    quantities at every interface point (jumps evaluated at the point itself,
    tractions and state those of its patch), which is what the output reports.
    They are computed on first access only, so Newton iterations and line-search
    trials do not pay for them.
    """

    force: np.ndarray  # (n_dofs,) contact internal force [N/m]
    blocks: np.ndarray | None  # (m, 2J, 2J) tangent blocks; None: not kept
    gn: np.ndarray  # (m,) [m]
    gt: np.ndarray  # (m,) [m]
    pn: np.ndarray  # (m,) [Pa]
    pt: np.ndarray  # (m,) [Pa]
    state: np.ndarray  # (m,) int8
    slip_plastic: np.ndarray  # (m,) [m]
    # ContactSet.slip_reference when it was evaluated (m,) [m]
    slip_reference: np.ndarray = field(repr=False)
    # accumulated frictional slip delta = int |d g_T^p| (kernels.contact)
    accumulated: np.ndarray = field(repr=False)  # (m,) [m]
    # the displacement it was evaluated at (a reference, not a copy: the solver
    # never changes an array in place once it has been evaluated)
    u: np.ndarray = field(repr=False)  # (n_dofs,) [m]
    contact: ContactSet = field(repr=False)

    @cached_property
    def _point_jump(self) -> np.ndarray:
        c = self.contact
        return _point_jumps(self.u, c.point_dofs, c.point_coef)

    @property
    def point_gn(self) -> np.ndarray:  # (n,) [m]
        return np.einsum("nk,nk->n", self._point_jump, self.contact.point_normal)

    @property
    def point_gt(self) -> np.ndarray:  # (n,) [m]
        return np.einsum("nk,nk->n", self._point_jump, self.contact.point_tangent)

    @property
    def point_pn(self) -> np.ndarray:  # (n,) [Pa]
        return self.pn[self.contact.patch]

    @property
    def point_pt(self) -> np.ndarray:  # (n,) [Pa]
        return self.pt[self.contact.patch]

    @property
    def point_state(self) -> np.ndarray:  # (n,) int8
        return self.state[self.contact.patch]

    @property
    def plastic_slip(self) -> np.ndarray:  # (m,) [m]
        """The slip that slid, per patch: g_T^p less its value in the in-situ
        state, where the patch is in contact; the whole tangential jump where
        it is open (no shear, nothing elastic: the kernel returns g_T^p = g_T).

        In contact g_T = (p_T - p_T0) / k_T + (g_T^p - g_T0^p): the first
        term is the elastic give of the penalty, the second what slid.  A stuck
        patch that never slipped has 0; a slipping one g_T - (p_T - p_T0) / k_T
        (the return map, eq. 27).
        """
        return np.where(
            self.state == OPEN,
            self.slip_plastic,
            self.slip_plastic - self.slip_reference,
        )

    @property
    def point_plastic_slip(self) -> np.ndarray:  # (n,) [m]
        return self.plastic_slip[self.contact.patch]

    @property
    def point_accumulated(self) -> np.ndarray:  # (n,) [m]
        return self.accumulated[self.contact.patch]

    @property
    def point_friction(self) -> np.ndarray:  # (n,) [-]
        """The friction coefficient f(delta) of each point's patch after this
        evaluation's slip (the static one where it has not slipped)."""
        c = self.contact
        return c.friction_at(self.accumulated)[c.patch]


@dataclass
class ContactSet:
    """Contact patches with their operators, parameters and history.

    The penalty law is applied to the jump averaged over a *patch* of
    interface points (an L2 projection of the jump onto piecewise constants on
    the patches), not point by point.  Pointwise penalty on a Heaviside-enriched
    crack over-constrains the jump (several Gauss points per cut cell against
    about one jump dof per node) and the tractions oscillate from point to point
    (the LBB problem of XFEM contact; Bechet, Moes & Wohlmuth 2009, IJNME 78).
    One traction per patch of about one cell length removes it.  With
    ``[solver] contact_patch = 0`` every interface point is its own patch.
    """

    dofs: np.ndarray  # (m, 2J) int64, m patches
    coef: np.ndarray  # (m, J)
    normal: np.ndarray  # (m, 2)
    tangent: np.ndarray  # (m, 2)
    weight: np.ndarray  # (m,) patch length [m]
    pn0: np.ndarray  # (m,) in-situ normal traction [Pa]
    kn: np.ndarray
    kt: np.ndarray
    friction: np.ndarray  # static f_s [-]
    cohesion: np.ndarray  # static c_s [Pa]
    n_dofs: int
    fracture: np.ndarray  # (m,) fracture of each patch
    patch: np.ndarray  # (n,) patch of each interface point
    point_dofs: np.ndarray  # (n, 2Jp) jump of each point
    point_coef: np.ndarray  # (n, Jp)
    point_normal: np.ndarray  # (n, 2)
    point_tangent: np.ndarray  # (n, 2)
    slip_committed: np.ndarray  # (m,) [m]
    # g_T^p of a patch that has slid nothing (m,) [m]: -p_T0 / k_T, which lets
    # the penalty carry the in-situ shear p_T0 at zero jump; 0 once the patch
    # has opened (its faces separated and shed that shear)
    slip_reference: np.ndarray
    state_committed: np.ndarray  # (m,) int8
    gt_committed: np.ndarray
    pt_committed: np.ndarray
    # kernel backend of the model ("numba" | "numpy", kernels.choose)
    kernels: str = field(kw_only=True)
    # slip weakening (kernels.contact): dynamic friction f_d [-] and cohesion
    # c_d [Pa], reached after slip_distance D_c [m] of accumulated slip; for
    # constant friction f_d = f_s, c_d = c_s and D_c = inf (_weakening_arrays)
    friction_dynamic: np.ndarray = field(kw_only=True)
    cohesion_dynamic: np.ndarray = field(kw_only=True)
    slip_distance: np.ndarray = field(kw_only=True)
    # committed accumulated slip delta of each patch [m], like slip_committed
    accumulated_committed: np.ndarray = field(kw_only=True)

    @property
    def n(self) -> int:
        return self.weight.size

    @property
    def weakens(self) -> np.ndarray:
        """(m,) bool: patches whose friction or cohesion weakens with slip."""
        return (self.friction != self.friction_dynamic) | (
            self.cohesion != self.cohesion_dynamic
        )

    def friction_at(self, accumulated) -> np.ndarray:
        """(m,) friction coefficient f(delta) of every patch at the
        accumulated slip ``accumulated`` (m,) [m] (kernels.contact.weakened)."""
        return kernels.backend("numpy").weakened(
            self.friction, self.friction_dynamic, accumulated, self.slip_distance
        )

    def cohesion_at(self, accumulated) -> np.ndarray:
        """(m,) cohesion c(delta) [Pa] of every patch at the accumulated slip
        ``accumulated`` (m,) [m]."""
        return kernels.backend("numpy").weakened(
            self.cohesion, self.cohesion_dynamic, accumulated, self.slip_distance
        )

    def shear_bound(self, pn, accumulated=None) -> np.ndarray:
        """(m,) Coulomb's bound on |p_T| [Pa] at the normal traction ``pn``
        (m,) [Pa], c - f p_N, with the friction and cohesion weakened at the
        accumulated slip ``accumulated`` (None: the static values)."""
        if accumulated is None:
            return self.cohesion - self.friction * pn
        return self.cohesion_at(accumulated) - self.friction_at(accumulated) * pn

    def history(self) -> tuple:
        """Copy of the committed history (what ``restore`` takes back)."""
        return tuple(getattr(self, name).copy() for name in COMMITTED)

    def restore(self, history: tuple) -> None:
        """Set the committed history to ``history`` (from ``history()``)."""
        for name, value in zip(COMMITTED, history, strict=True):
            setattr(self, name, value.copy())

    def evaluate(
        self, u, tangent_mode, pt_prev, gt_prev, scratch=None
    ) -> ContactResult:
        """Contact force and tangent at u from the committed history.

        scratch : None, or an (n, 2J, 2J) float64 array the kernel writes the
        tangent blocks into (overwritten entirely); the result then has
        ``blocks = None``.  For an evaluation whose tangent is not used (a
        line-search trial, a look at the states): a fresh (n, 2J, 2J) array
        per evaluation, 10.7 MB on a crowded network, is allocated and
        faulted in for nothing.
        """
        n = self.n
        J2 = self.dofs.shape[1]
        out_f = np.zeros((n, J2))
        out_K = np.zeros((n, J2, J2)) if scratch is None else scratch
        gn, gt, pn, pt, slip, accumulated = (np.zeros(n) for _ in range(6))
        state = np.zeros(n, np.int8)
        kernels.backend(self.kernels).contact_response(
            np.ascontiguousarray(u, dtype=np.float64),
            self.dofs,
            self.coef,
            self.normal,
            self.tangent,
            self.weight,
            self.pn0,
            self.slip_committed,
            self.accumulated_committed,
            self.kn,
            self.kt,
            self.friction,
            self.cohesion,
            self.friction_dynamic,
            self.cohesion_dynamic,
            self.slip_distance,
            int(tangent_mode),
            pt_prev,
            gt_prev,
            out_f,
            out_K,
            gn,
            gt,
            pn,
            pt,
            state,
            slip,
            accumulated,
        )
        return ContactResult(
            force=scatter_vector(self.dofs, out_f, self.n_dofs),
            blocks=out_K if scratch is None else None,
            gn=gn,
            gt=gt,
            pn=pn,
            pt=pt,
            state=state,
            slip_plastic=slip,
            slip_reference=self.slip_reference,
            accumulated=accumulated,
            u=u,
            contact=self,
        )

    def tangent_matrix(self, result: ContactResult):
        assert result.blocks is not None  # evaluated with its tangent kept
        return coo_block(self.dofs, result.blocks, self.n_dofs, self.kernels)

    def in_situ_force(self, zero: ContactResult) -> np.ndarray:
        """Contact force (n_dofs,) [N/m] of the in-situ traction sigma0 . n
        carried at zero jump, whether or not the contact law admits it.

        The bulk starts in equilibrium with the initial stress, and so do the
        faces with the traction sigma0 . n: this force is the reference state
        that the Newton residual subtracts.  ``zero`` is the law at zero
        jump.  Where the in-situ traction is admissible the law carries it
        (STICK) and this is ``zero.force`` itself, bit for bit.  Where it is
        not (shear above c - f p_N, or tension across the fracture) the law
        carries less, and the difference, ``in_situ_force - zero.force``, is
        the excess that the first load step releases: the fracture slips or
        opens by what it drives, as if the same stress had been applied from
        zero to the body with the fracture already in it.
        """
        bad = zero.state != STICK
        if not bad.any():
            return zero.force
        # the stick traction at zero jump, as the kernel forms it:
        # p_T = k_T (g_T - g_T^p) with g_T = 0, p_N = k_N g_N + p_N0 = p_N0
        pt = self.kt[bad] * (0.0 - self.slip_committed[bad])
        dpn = self.pn0[bad] - zero.pn[bad]
        dpt = pt - zero.pt[bad]
        excess = (
            dpn[:, None] * self.normal[bad] + dpt[:, None] * self.tangent[bad]
        )  # (b, 2) [Pa]
        w = self.weight[bad][:, None] * self.coef[bad]  # (b, J) [m]
        f = np.empty((w.shape[0], 2 * w.shape[1]))
        f[:, 0::2] = w * excess[:, 0:1]
        f[:, 1::2] = w * excess[:, 1:2]
        return zero.force + scatter_vector(self.dofs[bad], f, self.n_dofs)

    def commit(self, result: ContactResult) -> None:
        self.slip_committed = result.slip_plastic.copy()
        # a new array, not in place: results evaluated before keep theirs
        self.slip_reference = np.where(result.state == OPEN, 0.0, self.slip_reference)
        self.state_committed = result.state.copy()
        self.gt_committed = result.gt.copy()
        self.pt_committed = result.pt.copy()
        self.accumulated_committed = result.accumulated.copy()


@dataclass(frozen=True)
class PatchGeometry:
    """Where the contact patches of a ContactSet lie: what path following
    (xfemslip.solve.continuation) reports a nucleation with."""

    centre: np.ndarray  # (m, 2) length-weighted centre of each patch [m]
    s: np.ndarray  # (m,) arc length of that centre along its fracture [m]
    fracture: np.ndarray  # (m,) case-file index of each patch's fracture


def patch_geometry(contact: ContactSet, ip, fracture_ids) -> PatchGeometry:
    """The PatchGeometry of ``contact`` built on the interface points ``ip``;
    ``fracture_ids`` gives the case-file index of each fracture position
    (``[fr.index for fr in model.fractures]``)."""
    m = contact.n
    W = np.bincount(contact.patch, weights=ip.weight, minlength=m)

    def mean(values):
        return np.bincount(contact.patch, weights=ip.weight * values, minlength=m) / W

    return PatchGeometry(
        centre=np.column_stack([mean(ip.xy[:, 0]), mean(ip.xy[:, 1])]),
        s=mean(ip.s),
        fracture=np.asarray(fracture_ids, np.int64)[contact.fracture],
    )


def _point_jumps(u, dofs, coef) -> np.ndarray:
    """[[u]] (n, 2) at the interface points from their jump operators."""
    if dofs.shape[1] == 0:
        return np.zeros((dofs.shape[0], 2))
    ux = np.where(dofs[:, 0::2] >= 0, u[np.maximum(dofs[:, 0::2], 0)], 0.0)
    uy = np.where(dofs[:, 1::2] >= 0, u[np.maximum(dofs[:, 1::2], 0)], 0.0)
    return np.column_stack([(coef * ux).sum(axis=1), (coef * uy).sum(axis=1)])


def _cell_size(mesh, cells) -> np.ndarray:
    """sqrt of the area of each cell [m]: the local h of patches and penalty."""
    b = mesh.bounds[cells]
    return np.sqrt((b[:, 1] - b[:, 0]) * (b[:, 3] - b[:, 2]))


# A patch holds at most this many pieces (cells) per unit of its target
# length, whatever their length.  On square-ish cells a patch of 1.5 cells
# holds 2 to 5 pieces (5 next to junctions, where pieces are short); on cells
# much longer across the fracture than along it (a strip of 100,000 x 1
# cells), the sqrt(area) size would gather hundreds of pieces into one patch,
# whose dense tangent block grows like their square.
PATCH_PIECES_PER_CELL = 4


def _symmetric_groups(lengths, target, max_items=None):
    """Consecutive items (lengths in cell units) in groups at least ``target``
    long (or of ``max_items`` items): greedy from both ends toward the
    middle, so the reversed list gets the mirrored partition (and a rotated
    or reflected fracture the same one).

    The two leftovers and an item centred exactly on the middle form a middle
    group; one shorter than target joins the shorter of its neighbours (on an
    exact tie the front one: the only case where reversing the list can give
    another partition).
    """
    k = len(lengths)
    total = float(np.sum(lengths))
    centre = np.cumsum(lengths) - 0.5 * np.asarray(lengths)
    tol = 1e-9 * total
    front = [i for i in range(k) if centre[i] < 0.5 * total - tol]
    back = [i for i in range(k) if centre[i] > 0.5 * total + tol]
    mid = [i for i in range(k) if abs(centre[i] - 0.5 * total) <= tol]

    def greedy(items):
        acc, members, groups = 0.0, [], []
        for i in items:
            members.append(i)
            acc += lengths[i]
            if acc >= target or len(members) == max_items:
                groups.append(members)
                acc, members = 0.0, []
        return groups, members

    front_groups, front_left = greedy(front)
    back_groups, back_left = greedy(back[::-1])
    back_groups = [g[::-1] for g in back_groups[::-1]]
    middle = front_left + mid + back_left[::-1]

    def size(g):
        return sum(lengths[i] for i in g)

    if middle and size(middle) < target and (front_groups or back_groups):
        # too short: it joins the shorter neighbour (the front one on a tie)
        if front_groups and (
            not back_groups or size(front_groups[-1]) <= size(back_groups[0])
        ):
            middle = front_groups.pop() + middle
        else:
            middle = middle + back_groups.pop(0)
    return front_groups + ([middle] if middle else []) + back_groups


def contact_patches(
    mesh, fractures, ip, length_cells: float, breaks=None
) -> np.ndarray:
    """Patch index (n,) of every interface point.

    Along each straight segment of each fracture, the pieces of the cut cells
    (in order along the segment) are gathered into patches at least
    ``length_cells`` local cell sizes long (cell size = sqrt of its area, so
    graded meshes get graded patches), greedily from both ends of the segment
    toward its middle (``_symmetric_groups``: the patches do not depend on the
    fracture's point order).  A patch never spans a kink of the polyline, so
    its normal is one, nor a junction with another fracture (each branch has
    its own tractions), nor a point of ``breaks[f]`` (arc lengths [m] of
    fracture f where its loading jumps: a reservoir corner on a fault; the
    interface points are split there too).  ``length_cells = 0`` gives one
    patch per point.
    """
    n = ip.n
    if n == 0 or length_cells <= 0.0:
        return np.arange(n, dtype=np.int64)
    size = _cell_size(mesh, ip.cell)
    seg = np.zeros(n, np.int64)
    part = np.zeros(n, np.int64)  # stretch between junctions
    for fi, fr in enumerate(fractures):
        m = ip.fracture == fi
        ends = fr.s_start + fr.length
        seg[m] = np.minimum(np.searchsorted(ends, ip.s[m], side="right"), ends.size - 1)
        splits = np.asarray(fr.junction_s, float)
        if breaks is not None and len(breaks[fi]):
            splits = np.sort(np.concatenate([splits, breaks[fi]]))
        part[m] = np.searchsorted(splits, ip.s[m])
    patch = np.empty(n, np.int64)
    next_id = 0
    order = np.lexsort((ip.s, part, seg, ip.fracture))
    # consecutive runs of one (fracture, segment, junction part); within a
    # run, pieces by cell
    key = (ip.fracture[order] * (seg.max() + 1) + seg[order]) * (part.max() + 1) + part[
        order
    ]
    runs = np.flatnonzero(np.diff(key)) + 1
    for run in np.split(order, runs):
        cells, first = np.unique(ip.cell[run], return_index=True)
        cells = cells[np.argsort(first)]  # cells in order along the segment
        piece: dict[int, list[int]] = {c: [] for c in cells}
        for i in run:
            piece[ip.cell[i]].append(i)
        lengths = [ip.weight[piece[c]].sum() / size[piece[c][0]] for c in cells]
        cap = PATCH_PIECES_PER_CELL * math.ceil(length_cells)
        for g in _symmetric_groups(lengths, length_cells, cap):
            patch[[i for c in g for i in piece[cells[c]]]] = next_id
            next_id += 1
    return patch


def _patch_operators(patch, weight, coef, dofs):
    """Weighted mean of the point jump operators over each patch.

    [[u]]_P = sum_{p in P} (w_p / W_P) [[u]]_p: the coefficients of the
    points of a patch are merged by dof.  Returns (coef (m, J), dofs (m, 2J),
    W (m,)).
    """
    m = int(patch.max()) + 1 if patch.size else 0
    W = np.bincount(patch, weights=weight, minlength=m)
    J = coef.shape[1]
    if m == 0 or J == 0:
        return np.zeros((m, 0)), np.zeros((m, 0), np.int64), W
    rows = np.repeat(patch, J)
    xdof = dofs[:, 0::2].ravel()
    val = (coef * (weight / W[patch])[:, None]).ravel()
    keep = xdof >= 0
    rows, xdof, val = rows[keep], xdof[keep], val[keep]
    stride = int(xdof.max()) + 1
    uniq, inv = np.unique(rows * stride + xdof, return_inverse=True)
    vsum = np.bincount(inv, weights=val)
    urow, udof = np.divmod(uniq, stride)
    count = np.bincount(urow, minlength=m)
    Jm = int(count.max())
    start = np.concatenate([[0], np.cumsum(count)[:-1]])
    slot = np.arange(urow.size) - start[urow]
    out_coef = np.zeros((m, Jm))
    out_dofs = -np.ones((m, 2 * Jm), np.int64)
    out_coef[urow, slot] = vsum
    out_dofs[urow, 2 * slot] = udof
    out_dofs[urow, 2 * slot + 1] = udof + 1
    return out_coef, out_dofs, W


# Offset of the two probe points x +/- eps n that decide, at an interface
# point x, the side of every discontinuity of the enrichment functions
# (relative to the smallest cell size).
JUMP_PROBE = 1.0e-7
# |F(x+) - F(x-)| below this is no jump (B2..B4 on their own fracture: cos(pi/2)).
JUMP_ZERO = 1.0e-10


def _jump_operators(mesh, fractures, ip, ec, cand, dofmap):
    """Coefficients (n, J) and dofs (n, 2J) of [[u]] at the interface points.

    Every enrichment of the point's cell enters with its jump across the
    point's fracture, [[F]] N_a = (F(x+) - F(x-)) N_a, F evaluated with the
    sides of x+/- = x +/- eps n: the own Heaviside gives 2 R N_a (eq. 14), the
    own B1 gives 2 sqrt(r) (n_d . n) N_a (xfemslip.fem.branch), B2..B4 nothing; a
    junction function of another fracture (Daux et al. 2000) jumps across
    this fracture next to the junction and is continuous elsewhere.
    """
    n = ip.n
    if n == 0 or ec.slot_cand.shape[1] == 0:
        return np.zeros((n, 0)), np.zeros((n, 0), np.int64)
    pos = np.searchsorted(ec.cells, ip.cell)
    N = mesh.shape_at(ip.cell, ip.xy)  # (n, 4)
    K = ec.slot_cand[pos]  # (n, S) candidate of each slot of the point's cell
    Kc = np.maximum(K, 0)
    live = (K >= 0) & (dofmap.cand_dof[Kc] >= 0)
    jump = np.zeros(K.shape)
    eps = JUMP_PROBE * mesh.h_min
    tol = GEOMETRY_TOL * mesh.h_min
    group = np.where(live, cand.fracture[Kc] * 100003 + cand.tip[Kc] + 50000, -1)
    # the live slots of each group as one slice of a stable sort, in the
    # order np.nonzero(group == g) gives (a mask per group over all the
    # slots was 0.4 s of 300 groups on a 100-fracture network)
    flat = np.flatnonzero(live)
    by_group = np.argsort(group.ravel()[flat], kind="stable")
    flat = flat[by_group]
    groups, starts = np.unique(group.ravel()[flat], return_index=True)
    ends = np.append(starts[1:], flat.size)
    for g, lo, hi in zip(groups.tolist(), starts.tolist(), ends.tolist(), strict=True):
        fi, tip = divmod(int(g), 100003)
        tip -= 50000
        fr = fractures[fi]
        rows, cols = np.divmod(flat[lo:hi], K.shape[1])
        pts = ip.xy[rows]
        off = eps * ip.normal[rows]
        vals = []
        for probe in (pts + off, pts - off):
            side = fr.side(probe)
            vals.append(group_values(fractures, fi, tip, pts, side, tol, probe)[0])
        k = Kc[rows, cols]
        j = np.where(cand.func[k] == HEAVISIDE, 0, cand.func[k] - 1)
        d = (vals[0] - vals[1])[np.arange(rows.size), j]
        jump[rows, cols] = np.where(np.abs(d) > JUMP_ZERO, d, 0.0)
    valid = live & (jump != 0.0)
    a = np.maximum(ec.slot_node[pos], 0)
    coef_all = np.where(valid, jump * np.take_along_axis(N, a, axis=1), 0.0)
    J = int(valid.sum(axis=1).max())
    order = np.argsort(~valid, axis=1, kind="stable")[:, :J]  # valid slots first
    kept = np.take_along_axis(valid, order, axis=1)
    first = np.take_along_axis(dofmap.cand_dof[Kc], order, axis=1)
    coef = np.where(kept, np.take_along_axis(coef_all, order, axis=1), 0.0)
    dofs = np.empty((n, 2 * J), np.int64)
    dofs[:, 0::2] = np.where(kept, first, -1)
    dofs[:, 1::2] = np.where(kept, first + 1, -1)
    return np.ascontiguousarray(coef), dofs


def _or_nan(value):
    return np.nan if value is None else value


def _weakening_arrays(fractures, frac, friction, cohesion) -> dict:
    """friction_dynamic, cohesion_dynamic and slip_distance (m,) of the
    patches (fractures[frac[p]] each): the fracture's slip-weakening law, or
    the static values and D_c = inf for constant friction."""
    out = {
        "friction_dynamic": friction.copy(),
        "cohesion_dynamic": cohesion.copy(),
        "slip_distance": np.full(frac.size, np.inf),
    }
    for fi, fr in enumerate(fractures):
        law = getattr(fr, "weakening", None)
        if law is None:
            continue
        mine = frac == fi
        out["friction_dynamic"][mine] = law.dynamic_friction
        out["cohesion_dynamic"][mine] = law.dynamic_cohesion
        out["slip_distance"][mine] = law.slip_distance
    return out


def build_contact(
    mesh,
    fractures,
    ip,
    ec,
    cand,
    dofmap,
    initial_stress,
    E=None,
    patch_cells=None,
    *,
    kernels: str,
    breaks=None,
) -> ContactSet:
    """Interface operators from the interface points and the enriched cells.

    initial_stress : (xx, yy, xy), or (n_ip, 3) per interface point (an
    in-situ stress varying with depth: the patch takes its points' weighted
    mean), or None; the faces start closed and stuck with traction sigma0 . n
    (the committed plastic slip is set so that the stick traction at zero
    jump is the in-situ shear traction).
    breaks : per fracture, the arc lengths where patches must end
    (contact_patches).
    E : Young's modulus [Pa], for the automatic penalty of fractures without
    kn / kt (AUTO_PENALTY * E / h, h = sqrt of the area of the patch's cells).
    patch_cells : length of a contact patch in local cell sizes (0: pointwise;
    None: CONTACT_PATCH_CELLS).
    kernels : the model's kernel backend ("numba" | "numpy"), which
    evaluates the contact law.
    """
    coef, dofs = _jump_operators(mesh, fractures, ip, ec, cand, dofmap)
    if patch_cells is None:
        patch_cells = CONTACT_PATCH_CELLS
    patch = contact_patches(mesh, fractures, ip, patch_cells, breaks)
    p_coef, p_dofs, W = _patch_operators(patch, ip.weight, coef, dofs)
    n = W.size
    _, first = np.unique(patch, return_index=True)  # one point of each patch
    frac = ip.fracture[first]
    normal = np.ascontiguousarray(ip.normal[first])
    tangent = np.ascontiguousarray(ip.tangent[first])
    par = {
        name: np.array([_or_nan(getattr(fractures[f], name)) for f in frac], float)
        for name in ("kn", "kt", "friction", "cohesion")
    }
    par |= _weakening_arrays(fractures, frac, par["friction"], par["cohesion"])
    # mean cell size over each patch, for the automatic penalty
    h = np.bincount(patch, weights=ip.weight * _cell_size(mesh, ip.cell)) / W
    for name in ("kn", "kt"):
        auto = np.isnan(par[name])
        if auto.any():
            if E is None:
                raise ValueError("automatic penalty needs E")
            par[name][auto] = AUTO_PENALTY * E / h[auto]
    pn0 = np.zeros(n)
    slip0 = np.zeros(n)
    if initial_stress is not None and np.ndim(initial_stress) == 2:
        S = (
            np.column_stack(
                [
                    np.bincount(patch, weights=ip.weight * c, minlength=n)
                    for c in np.asarray(initial_stress, float).T
                ]
            )
            / W[:, None]
        )  # (n, 3) patch means
        tx = normal[:, 0] * S[:, 0] + normal[:, 1] * S[:, 2]
        ty = normal[:, 0] * S[:, 2] + normal[:, 1] * S[:, 1]
        pn0 = tx * normal[:, 0] + ty * normal[:, 1]
        pt0 = tx * tangent[:, 0] + ty * tangent[:, 1]
        slip0 = -pt0 / par["kt"]
    elif initial_stress is not None:
        sxx, syy, sxy = initial_stress
        sig = np.array([[sxx, sxy], [sxy, syy]])
        trac = normal @ sig
        pn0 = np.einsum("nk,nk->n", trac, normal)
        pt0 = np.einsum("nk,nk->n", trac, tangent)
        slip0 = -pt0 / par["kt"]
    cs = ContactSet(
        dofs=p_dofs,
        coef=p_coef,
        normal=normal,
        tangent=tangent,
        weight=W,
        pn0=pn0,
        n_dofs=dofmap.n_dofs,
        fracture=frac,
        patch=patch,
        point_dofs=dofs,
        point_coef=coef,
        point_normal=np.ascontiguousarray(ip.normal),
        point_tangent=np.ascontiguousarray(ip.tangent),
        slip_committed=slip0,
        slip_reference=slip0.copy(),
        state_committed=np.full(n, STICK, np.int8),
        gt_committed=np.zeros(n),
        pt_committed=-par["kt"] * slip0,
        accumulated_committed=np.zeros(n),
        kernels=kernels,
        **par,
    )
    return cs
