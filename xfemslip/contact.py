"""Contact driver: interface-point operators, history, and the kernel call.

Each interface point carries the jump operator of eq. 14 with the tip ramp,
[[u]] = sum_a 2 R(x) N_a(x) a_a over the enriched nodes a of its cell, as up to
four coefficients and their dofs.  The history (committed plastic slip and
state) is carried from load step to load step; within a step every Newton
iteration restarts the return map from the committed values.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from xfemslip import kernels
from xfemslip.assembly import coo_block, scatter_vector
from xfemslip.branch import b1_jump
from xfemslip.enrichment import HEAVISIDE

logger = logging.getLogger(__name__)

OPEN, STICK, SLIP = kernels.OPEN, kernels.STICK, kernels.SLIP


@dataclass
class ContactResult:
    """Response of all interface points at one displacement."""

    force: np.ndarray  # (n_dofs,) contact internal force [N/m]
    blocks: np.ndarray  # (n, 2J, 2J) tangent blocks
    gn: np.ndarray
    gt: np.ndarray
    pn: np.ndarray
    pt: np.ndarray
    state: np.ndarray  # (n,) int8
    slip_plastic: np.ndarray


@dataclass
class ContactSet:
    """Interface points with their operators, parameters and history."""

    dofs: np.ndarray  # (n, 2J) int64
    coef: np.ndarray  # (n, J)
    normal: np.ndarray  # (n, 2)
    tangent: np.ndarray  # (n, 2)
    weight: np.ndarray  # (n,) [m]
    pn0: np.ndarray  # (n,) in-situ normal traction [Pa]
    kn: np.ndarray
    kt: np.ndarray
    friction: np.ndarray
    cohesion: np.ndarray
    n_dofs: int
    slip_committed: np.ndarray = field(default=None)  # (n,) [m]
    state_committed: np.ndarray = field(default=None)  # (n,) int8
    gt_committed: np.ndarray = field(default=None)
    pt_committed: np.ndarray = field(default=None)

    @property
    def n(self) -> int:
        return self.weight.size

    def evaluate(self, u, tangent_mode, pt_prev, gt_prev) -> ContactResult:
        """Contact force and tangent at u from the committed history."""
        n = self.n
        J2 = self.dofs.shape[1]
        out_f = np.zeros((n, J2))
        out_K = np.zeros((n, J2, J2))
        gn, gt, pn, pt, slip = (np.zeros(n) for _ in range(5))
        state = np.zeros(n, np.int8)
        kernels.contact_response(
            np.ascontiguousarray(u, dtype=np.float64),
            self.dofs,
            self.coef,
            self.normal,
            self.tangent,
            self.weight,
            self.pn0,
            self.slip_committed,
            self.kn,
            self.kt,
            self.friction,
            self.cohesion,
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
        )
        return ContactResult(
            force=scatter_vector(self.dofs, out_f, self.n_dofs),
            blocks=out_K,
            gn=gn,
            gt=gt,
            pn=pn,
            pt=pt,
            state=state,
            slip_plastic=slip,
        )

    def tangent_matrix(self, result: ContactResult):
        return coo_block(self.dofs, result.blocks, self.n_dofs)

    def commit(self, result: ContactResult) -> None:
        self.slip_committed = result.slip_plastic.copy()
        self.state_committed = result.state.copy()
        self.gt_committed = result.gt.copy()
        self.pt_committed = result.pt.copy()


def _jump_operators(mesh, fractures, ip, ec, cand, dofmap):
    """Coefficients (n, J) and dofs (n, 2J) of [[u]] at the interface points.

    Heaviside slot: [[H R]] N_a = 2 R N_a (eq. 14); branch slot B1:
    [[B1]] N_a = 2 sqrt(r) (n_d . n) N_a; B2..B4 are continuous (no entry).
    """
    n = ip.n
    if n == 0 or ec.slot_cand.shape[1] == 0:
        return np.zeros((n, 0)), np.zeros((n, 0), np.int64)
    pos = np.searchsorted(ec.cells, ip.cell)
    N = mesh.shape_at(ip.cell, ip.xy)  # (n, 4)
    K = ec.slot_cand[pos]  # (n, S) candidate of each slot of the point's cell
    Kc = np.maximum(K, 0)
    func = cand.func[Kc]
    valid = (
        (K >= 0)
        & (cand.fracture[Kc] == ip.fracture[:, None])
        & (dofmap.cand_dof[Kc] >= 0)
        & ((func == HEAVISIDE) | (func == 1))
    )
    jump = np.where(func == HEAVISIDE, 2.0 * ip.ramp[:, None], 0.0)
    for fi, fr in enumerate(fractures):
        for ti, tip in enumerate(fr.tips):
            m = valid & (func == 1) & (cand.fracture[Kc] == fi) & (cand.tip[Kc] == ti)
            rows = np.nonzero(m)[0]
            jump[m] = b1_jump(tip, ip.xy[rows])
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


def build_contact(mesh, fractures, ip, ec, cand, dofmap, initial_stress) -> ContactSet:
    """Interface operators from the interface points and the enriched cells.

    initial_stress : (xx, yy, xy) or None; the faces start closed and stuck
    with traction sigma0 . n (the committed plastic slip is set so that the
    stick traction at zero jump is the in-situ shear traction).
    """
    n = ip.n
    coef, dofs = _jump_operators(mesh, fractures, ip, ec, cand, dofmap)
    par = {
        name: np.array([getattr(fractures[f], name) for f in ip.fracture], dtype=float)
        for name in ("kn", "kt", "friction", "cohesion")
    }
    if n == 0:
        par = {name: np.zeros(0) for name in ("kn", "kt", "friction", "cohesion")}
    pn0 = np.zeros(n)
    slip0 = np.zeros(n)
    if initial_stress is not None and n:
        sxx, syy, sxy = initial_stress
        sig = np.array([[sxx, sxy], [sxy, syy]])
        trac = ip.normal @ sig
        pn0 = np.einsum("nk,nk->n", trac, ip.normal)
        pt0 = np.einsum("nk,nk->n", trac, ip.tangent)
        slip0 = -pt0 / par["kt"]
    cs = ContactSet(
        dofs=dofs,
        coef=coef,
        normal=np.ascontiguousarray(ip.normal),
        tangent=np.ascontiguousarray(ip.tangent),
        weight=ip.weight.copy(),
        pn0=pn0,
        n_dofs=dofmap.n_dofs,
        **par,
    )
    cs.slip_committed = slip0
    cs.state_committed = np.full(n, STICK, np.int8)
    cs.gt_committed = np.zeros(n)
    cs.pt_committed = -par["kt"] * slip0 if n else np.zeros(0)
    return cs
