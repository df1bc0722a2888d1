"""Poroelastic loading: Biot effective stress in the bulk, Terzaghi on fractures.

Signs: tension positive; the pore pressure p is positive when the fluid pushes.

Bulk (Biot).  The total stress is sigma = sigma' - alpha p I, with the
effective stress sigma' = sigma0' + D eps(u) (D of the cell's material).  The
model starts in equilibrium with the in-situ total stress sigma0
(``loading.initial_stress``) and the initial pore pressure p0 (uniform), so
sigma0' = sigma0 + alpha p0 I.  A load step changes p by lambda * dp (dp =
``pore_pressure.change``, < 0 = depletion) where the pressure changes (the
whole model or the reservoir cells).  Equilibrium of the increment,
int B^T (D eps - alpha lambda dp m) dOmega = lambda F_boundary with
m = [1, 1, 0], moves the pressure term to the right-hand side as the body load

    F_body = lambda * int_region B^T m alpha dp dOmega           (1)

Under depletion (dp < 0) F_body pulls every boundary of the depleting region
inwards: the region contracts.

Uniaxial strain (the check of the sign of (1), docs/depletion.md): a layer
with rollers on its sides (eps_xx = 0) under a constant overburden
(Delta sigma_yy = 0).  With D of plane strain,
Delta sigma_yy = (lambda_L + 2 mu) eps_yy - alpha dp = 0, so
eps_yy = alpha dp / (lambda_L + 2 mu) (< 0 under depletion: compaction) and
Delta sigma_xx = lambda_L eps_yy - alpha dp = -alpha dp (1 - 2 nu) / (1 - nu),
which is > 0 under depletion: the total horizontal stress becomes LESS
compressive by alpha (1 - 2 nu) / (1 - nu) |dp|.  The effective stresses
change by Delta sigma'_yy = alpha dp (more compressive under depletion) and
Delta sigma'_xx = lambda_L eps_yy = nu / (1 - nu) alpha dp, so the effective
horizontal change is nu / (1 - nu) of the vertical one (1/3 at nu = 0.25,
3/7 at nu = 0.3: the paper's "about 1/3").

Out of plane (plane strain, eps_zz = 0): sigma'_zz = nu (sigma'_xx +
sigma'_yy) and sigma_zz = sigma'_zz - alpha p, the in-situ sigma0'_zz taken as
nu (sigma0'_xx + sigma0'_yy) (as without pore pressure).

Fractures (Terzaghi, Biot coefficient 1 on the faces).  The fluid in a
fracture has the pore pressure around it, taken as the MEAN of the pore
pressures on its two faces: at each contact point x with normal n,

    p_f = p0 + lambda dp (c(x + eps n) + c(x - eps n)) / 2        (3)

with c = 1 where the pressure changes (a point of the region) and 0
elsewhere, eps = FACE_OFFSET h_min.  A fracture inside the depleting region
has p_f = p0 + lambda dp, one outside p0, and a fault ON the region's
boundary (a sealing fault between a depleting reservoir and undepleted rock,
the offset-reservoir set-up of Jansen & Meulenbroek 2022) p0 + lambda dp / 2
where one side depletes: the fault-zone fluid is taken at the mean of the
pressures it separates (the pressure is discontinuous across a sealing fault
and the contact law needs one p_f per point).  The contact law (penalty +
Coulomb) acts on the EFFECTIVE normal traction sigma_n' = sigma_n + p_f: its
in-situ value is (sigma0 + p0 I) . n . n, and |tau| <= c - f sigma_n'.  The
faces also carry the fluid pressure -p_f n; its change is the load on the
enriched dofs

    F_frac = lambda * int_Gamma dp_f [[N]]^T n ds                  (2)

(fluid pressure pushes the faces apart: dp_f > 0 opens).  With alpha = 1 and
a uniform dp, (1) and (2) cancel on Gamma by the divergence theorem: a
fracture whose fluid has the surrounding pressure does not perturb a uniform
depletion up to the penalty compliance (checked in
tests/verification/test_depletion.py).

Material regions.  An intact cell belongs to the reservoir when its centre
lies in the ``[reservoir]`` region (its boxes or its polygon,
xfemslip.geometry.regions); its stiffness, its stress and its pore-pressure change
are those of the reservoir.  Region edges that do not fall on mesh lines
are snapped to the cells this way, and the run logs a warning naming the
edge.  Enriched cells (cut, tip and blending cells) are classified
per QUADRATURE POINT of their sub-cell rule instead: the stiffness is
sum_q B_q^T D(x_q) B_q w_q and the Biot load (1) sum_q B_q^T m alpha dp(x_q)
w_q (B_q with the enrichment functions' gradients).  The sub-cell rule is
split along the fracture, so a region edge lying ON a fracture is represented
exactly even when it cuts the cells mid-cell (no warning then): the pressure
and material jump at the fault itself.  An enriched cell reports (stress,
pore pressure) with the material covering most of its area and the
area-weighted mean pressure change.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from xfemslip.fem.assembly import enriched_part_bbar
from xfemslip.fem.boundary import fracture_face_load
from xfemslip.fem.material import elasticity_matrix
from xfemslip.geometry.regions import edges, in_region

logger = logging.getLogger(__name__)

HOST, RESERVOIR = 0, 1
# A box edge closer than this to a mesh line (relative to the local cell size)
# lies on it: no warning.
ALIGN_TOL = 1.0e-9
# The two faces of a fracture are sampled this far off it (relative to the
# smallest cell size) for the fluid pressure (3): far below any cell size, far
# above the round-off of the point coordinates.
FACE_OFFSET = 1.0e-6


@dataclass(frozen=True)
class Materials:
    """Elastic constants per material and the material of every cell."""

    D: np.ndarray  # (k, 3, 3) [Pa]; 0 = host ([material]), 1 = reservoir
    nu: np.ndarray  # (k,) [-]
    E: np.ndarray  # (k,) [Pa]
    cell: np.ndarray  # (n_cells,) int64 material of each cell (by centre;
    # enriched cells: the material covering most of their area)
    model: str
    qp: np.ndarray | None = None  # (nq,) int64 material of each enriched-cell QP


@dataclass(frozen=True)
class PorePressure:
    """Pore pressure of a case: p(lambda) = initial + lambda * change in region."""

    initial: float  # p0 [Pa]
    change: float  # dp at load factor 1 [Pa]
    biot: float  # alpha [-]
    cell_changes: np.ndarray  # (n_cells,) bool: the pressure changes there (centre)
    cell_fraction: np.ndarray  # (n_cells,) float: area fraction where it changes
    qp_changes: np.ndarray  # (nq,) float 1/0 at the enriched cells' QPs
    point_changes: np.ndarray  # (n_ip,) float: mean of the two faces, eq. (3)

    def cell_pressure(self, lam: float) -> np.ndarray:
        """(n_cells,) pore pressure at load factor lam (area mean) [Pa]."""
        return self.initial + lam * self.change * self.cell_fraction


def cell_centres(mesh) -> np.ndarray:
    """(n_cells, 2) cell centres [m]."""
    b = mesh.bounds
    return np.column_stack([0.5 * (b[:, 0] + b[:, 1]), 0.5 * (b[:, 2] + b[:, 3])])


def _on_fracture(fractures, p, q, tol) -> bool:
    """Whether one fracture segment covers the segment p-q (within tol [m])."""
    for fr in fractures:
        for a, b in zip(fr.points[:-1], fr.points[1:], strict=True):
            L = float(np.hypot(*(b - a)))
            t = (b - a) / L
            n = np.array([-t[1], t[0]])
            off = [abs(float((v - a) @ n)) for v in (p, q)]
            s = sorted(float((v - a) @ t) for v in (p, q))
            if max(off) <= tol and s[0] >= -tol and s[1] <= L + tol:
                return True
    return False


def _on_mesh_line(mesh, p, q) -> bool:
    """Whether p-q is an axis-parallel segment on a mesh line (or outside the
    open domain), i.e. needs no snapping."""
    for k, axis in ((0, mesh.x), (1, mesh.y)):
        if p[k] == q[k]:
            v = p[k]
            if v <= axis[0] or v >= axis[-1]:
                return True
            h = float(np.min(np.diff(axis)))
            if np.min(np.abs(axis - v)) <= ALIGN_TOL * h:
                return True
    return False


def _clip_to_domain(mesh, p, q):
    """The part of p-q inside the domain's bounding box, or None."""
    lo = np.array([mesh.x[0], mesh.y[0]])
    hi = np.array([mesh.x[-1], mesh.y[-1]])
    t0, t1 = 0.0, 1.0
    d = q - p
    for k in range(2):
        if d[k] == 0.0:
            if not lo[k] < p[k] < hi[k]:
                return None
            continue
        ta, tb = sorted(((lo[k] - p[k]) / d[k], (hi[k] - p[k]) / d[k]))
        t0, t1 = max(t0, ta), min(t1, tb)
    return None if t0 >= t1 else (p + t0 * d, p + t1 * d)


def _warn_unaligned(mesh, reservoir, fractures=()) -> None:
    """Log a warning for each region edge inside the domain off the mesh
    lines, unless a fracture covers it (its cut cells are split per QP)."""
    tol = ALIGN_TOL * mesh.h_min
    off = []
    for name, p, q in edges(reservoir):
        if _on_mesh_line(mesh, p, q):
            continue
        part = _clip_to_domain(mesh, p, q)
        if part is None or _on_fracture(fractures, *part, tol):
            continue
        off.append(name)
    # a polygon may have thousands of edges: one line names the first few
    subjects = [f"{name} is" for name in off]
    if len(off) > 4:
        subjects = [f"{', '.join(off[:3])} and {len(off) - 3:,} more edges are"]
    for subject in subjects:
        logger.warning(
            "reservoir %s not on a mesh line; the cells whose centre is "
            "inside the region form the reservoir",
            subject,
        )


def _area_majority(ec, qp_material, n_materials) -> np.ndarray:
    """(nc,) material covering most of each enriched cell's area."""
    cell_of_qp = np.repeat(np.arange(ec.cells.size), np.diff(ec.qp_offsets))
    area = np.zeros((ec.cells.size, n_materials))
    np.add.at(area, (cell_of_qp, qp_material), ec.qp_w)
    return np.argmax(area, axis=1).astype(np.int64)


def build_materials(spec, mesh, ec=None, fractures=()) -> Materials:
    """Host ([material]) and, with [reservoir], reservoir constants per cell and,
    given the enriched cells ``ec``, per enriched-cell quadrature point."""
    m = spec.material
    E, nu = [m.E], [m.nu]
    cell = np.zeros(mesh.n_cells, np.int64)
    qp = None
    r = spec.reservoir
    if r is not None:
        E.append(r.E)
        nu.append(r.nu)
        cell[in_region(cell_centres(mesh), r)] = RESERVOIR
        _warn_unaligned(mesh, r, fractures)
        if ec is not None and ec.cells.size:
            qp = np.where(in_region(ec.qp_xy, r), RESERVOIR, HOST)
            cell[ec.cells] = _area_majority(ec, qp, 2)
    D = np.stack([elasticity_matrix(e, v, m.model) for e, v in zip(E, nu, strict=True)])
    return Materials(
        D=D, nu=np.array(nu), E=np.array(E), cell=cell, model=m.model, qp=qp
    )


def build_pore_pressure(
    spec, materials: Materials, ec=None, ip=None, h_min=1.0
) -> PorePressure | None:
    """The case's pore pressure, or None without [pore_pressure].

    ec, ip : enriched cells and interface points (per-QP and per-point regions);
    h_min : smallest cell size [m] (the face offset of eq. 3).
    """
    p = spec.pore_pressure
    if p is None:
        return None
    n_qp = 0 if ec is None else ec.qp_w.size
    if p.region == "reservoir":
        changes = materials.cell == RESERVOIR
        qp = np.zeros(n_qp) if materials.qp is None else materials.qp == RESERVOIR
    else:
        changes = np.ones(materials.cell.size, bool)
        qp = np.ones(n_qp)
    qp = np.asarray(qp, float)
    fraction = changes.astype(float)
    if n_qp:
        cell_of_qp = np.repeat(np.arange(ec.cells.size), np.diff(ec.qp_offsets))
        area = np.bincount(cell_of_qp, weights=ec.qp_w, minlength=ec.cells.size)
        part = np.bincount(cell_of_qp, weights=ec.qp_w * qp, minlength=ec.cells.size)
        fraction[ec.cells] = part / area
    points = np.zeros(0)
    if ip is not None:
        points = _face_mean(spec, ip, FACE_OFFSET * h_min)
    return PorePressure(
        initial=p.initial,
        change=p.change,
        biot=p.biot,
        cell_changes=changes,
        cell_fraction=fraction,
        qp_changes=qp,
        point_changes=points,
    )


def _face_mean(spec, ip, eps) -> np.ndarray:
    """(n_ip,) mean over the two faces of c (1 = the pressure changes), eq. (3)."""
    if spec.pore_pressure.region != "reservoir":
        return np.ones(ip.n)
    plus = in_region(ip.xy + eps * ip.normal, spec.reservoir)
    minus = in_region(ip.xy - eps * ip.normal, spec.reservoir)
    return 0.5 * (plus.astype(float) + minus)


def body_load(mesh, bulk, pore: PorePressure, ec, backend: str) -> np.ndarray:
    """F_body of eq. (1) at load factor 1, (n_dofs,) [N/m].

    Intact rectangle: int dN_a/dx dOmega = x_a hy / 2, int dN_a/dy = y_a hx / 2
    (x_a, y_a = -/+1 the corner signs).  Enriched cell (``ec``, same order as
    ``bulk.enriched_cells``): sum_q w_q B_q^T m alpha dp(x_q) = alpha dp A_c
    Bbar_c^T m, Bbar_c the average strain operator over the part of the cell
    whose QPs lie where the pressure changes (its area A_c), computed by the
    model's kernel ``backend``.
    """
    F = np.zeros(bulk.dofmap.n_dofs)
    q = pore.biot * pore.change * pore.cell_changes  # (n_cells,) [Pa]
    std = bulk.std_cells
    b = mesh.bounds[std]
    hx, hy = b[:, 1] - b[:, 0], b[:, 3] - b[:, 2]
    xa = np.array([-1.0, 1.0, 1.0, -1.0])
    ya = np.array([-1.0, -1.0, 1.0, 1.0])
    fx = q[std, None] * xa[None, :] * hy[:, None] / 2.0
    fy = q[std, None] * ya[None, :] * hx[:, None] / 2.0
    nodes = mesh.cells[std]
    np.add.at(F, 2 * nodes, fx)
    np.add.at(F, 2 * nodes + 1, fy)
    if ec.cells.size:
        w = ec.qp_w * pore.qp_changes
        cell_of_qp = np.repeat(np.arange(ec.cells.size), np.diff(ec.qp_offsets))
        area = np.bincount(cell_of_qp, weights=w, minlength=ec.cells.size)
        rows = np.nonzero(area > 0.0)[0]
        Bbar = enriched_part_bbar(mesh, ec, rows, w, backend)
        # Bbar^T m = rows exx + eyy of the average operator
        fe = (pore.biot * pore.change * area[rows])[:, None] * (Bbar[:, 0] + Bbar[:, 1])
        dofs = bulk.enr_dofs[rows]
        keep = dofs >= 0
        np.add.at(F, dofs[keep], fe[keep])
    return F


def fracture_load(contact, ip, pore: PorePressure) -> np.ndarray:
    """F_frac of eq. (2) at load factor 1, (n_dofs,) [N/m]: the fluid
    pressure change dp_f of eq. (3) on the faces (fracture_face_load), with
    the interface points' own jump operators, sum_p w_p dp_f(p) coef_pk n_p."""
    return fracture_face_load(
        contact, normal=ip.weight * pore.change * pore.point_changes
    )


def make_contact_effective(contact, pore: PorePressure) -> None:
    """Shift the in-situ normal traction of every patch to the effective one,
    sigma_n0' = sigma_n0 + p0 (the initial pressure is uniform)."""
    contact.pn0 = contact.pn0 + pore.initial


def fluid_pressure(ip, pore: PorePressure, lam: float) -> np.ndarray:
    """(n,) fluid pressure in the fractures at the interface points, eq. (3) [Pa]."""
    return pore.initial + lam * pore.change * pore.point_changes
