"""Refined DFN failure (docs/performance.md, "Fracture networks", refined
meshes): at the first Newton step that the line search can only make
worse, the 2x2 compliance (g_N, g_T) of the rest of the model seen by the
patch that the full step reverses (a Schur complement through one sparse LU),
and the determinant of the patch's stick / slip-forward / slip-backward
tangent relative to the rest; then the same with the n-t coupling of the slip
tangent dropped on all other slipping patches, and on each slipping patch
within 4 cells alone.  Run it on the code before the local branch search
(e.g. a checkout of 2e0d672: with the search the bad step does not happen):

    PYTHONPATH=<old tree> python benchmarks/refined_dfn_diagnosis.py CASE.toml

CASE: seed 1 of cases/sweeps/dfn_realizations.toml with elements = [100, 100].
"""

import dataclasses
import logging
import sys

import numpy as np
import scipy.sparse.linalg as spla

from xfemslip.case import load_case
from xfemslip.conventions import SLIP
from xfemslip.fem.assembly import coo_block
from xfemslip.simulation import build_model, newton_solver
from xfemslip.solve import newton as S
from xfemslip.solve import remedies

spec = load_case(sys.argv[1])
m = build_model(spec)
ip, c = m.ip, m.contact
h = m.mesh.h_min
cen = np.zeros((c.n, 2))
w = np.zeros(c.n)
np.add.at(cen, c.patch, ip.xy * ip.weight[:, None])
np.add.at(w, c.patch, ip.weight)
cen /= w[:, None]
done = [0]


def jump_rows(self, i):
    B = np.zeros((2, self.free.size))
    for k in range(c.coef.shape[1]):
        for d in range(2):
            dof = self.c_dofs[i, 2 * k + d]
            if dof >= 0:
                B[0, dof] += c.coef[i, k] * c.normal[i, d]
                B[1, dof] += c.coef[i, k] * c.tangent[i, d]
    return B


def compliance(self, blocks, B):
    K_c = coo_block(self.c_dofs, blocks, self.free.size, self.p.contact.kernels)
    A = (self.K_ff + K_c).tocsc()
    return B @ spla.splu(A).solve(B.T.copy())


def analyse(self, u, res, law, i):
    B = jump_rows(self, i)
    base = res.blocks.copy()
    base[i] = 0

    def report(tag, blocks):
        Cm = compliance(self, blocks, B)
        k = c.kn[i] * c.weight[i]
        dets = {
            s: np.linalg.det(
                np.eye(2)
                + Cm
                @ (
                    c.weight[i]
                    * np.array([[c.kn[i], 0], [-s * c.friction[i] * c.kn[i], 0]])
                )
            )
            for s in (1, -1)
        }
        dst = np.linalg.det(
            np.eye(2) + Cm @ (c.weight[i] * np.diag([c.kn[i], c.kt[i]]))
        )
        print(
            f"  {tag}: C_nn={Cm[0, 0] * k:+.3e} C_nt={Cm[0, 1] * k:+.3e} "
            f"C_tn={Cm[1, 0] * k:+.3e} C_tt={Cm[1, 1] * k:+.3e} (x kn w)  "
            f"det: stick {dst:+.2e} slip+ {dets[1]:+.2e} slip- "
            f"{dets[-1]:+.2e}",
            flush=True,
        )

    print(
        f"patch {i}: fracture {c.fracture[i]} at ({cen[i, 0]:.4f}, "
        f"{cen[i, 1]:.4f}), length {c.weight[i] / h:.2f} h, state "
        f"{res.state[i]}, pn {res.pn[i]:.3e} pt {res.pt[i]:.3e}"
    )
    report("bulk only (no other contact)", np.zeros_like(base))
    report("rest, consistent tangents", base)
    slip = res.state == SLIP
    slip[i] = False
    f = law.friction.copy()
    coh = law.cohesion.copy()
    f[slip] = 0
    coh[slip] = 0
    alt = dataclasses.replace(law, friction=f, cohesion=coh).evaluate(
        u, self.mode, law.pt_committed, law.gt_committed
    )
    dec = base.copy()
    dec[slip] = alt.blocks[slip]
    report("rest, slip tangents without the n-t coupling", dec)
    near = np.nonzero(slip & (np.linalg.norm(cen - cen[i], axis=1) < 4 * h))[0]
    for j in near:
        one = base.copy()
        one[j] = alt.blocks[j]
        d = np.linalg.norm(cen[j] - cen[i]) / h
        report(
            f"rest, coupling dropped at patch {j} only (fracture "
            f"{c.fracture[j]}, {d:.2f} h away, pt {res.pt[j]:+.2e})",
            one,
        )


orig_ls = S.NewtonSolver._line_search


def ls(self, u, du, lam, eta0, pt_prev, gt_prev, law=None):
    out = orig_ls(self, u, du, lam, eta0, pt_prev, gt_prev, law)
    law_ = self.p.contact if law is None else law
    if out[3] > eta0 and done[0] < 1:
        r0 = law_.evaluate(u, self.mode, pt_prev, gt_prev)
        trial = u.copy()
        trial[self.free] -= du
        r1 = law_.evaluate(trial, self.mode, pt_prev, gt_prev)
        ch = np.nonzero(
            remedies.regimes(r0.state, r0.pt) != remedies.regimes(r1.state, r1.pt)
        )[0]
        print(
            f"line search raised eta {eta0:.3e} -> {out[3]:.3e}; patches "
            f"reversed by the full step: {list(ch)}",
            flush=True,
        )
        for i in ch[:2]:
            analyse(self, u, r0, law_, int(i))
        done[0] += 1
    return out


S.NewtonSolver._line_search = ls
sol = newton_solver(m)
sol.max_cuts = 0
logging.basicConfig(level=logging.WARNING, format="%(message)s")
try:
    sol.run(spec.loading.steps)
    print("CONVERGED", sol.completed[-1].iterations)
except Exception as e:
    print("FAIL", str(e)[:200])
