"""Poroelastic loading: Biot effective stress in the bulk, Terzaghi on fractures.

Signs: tension positive; the pore pressure p is positive when the fluid pushes.

Bulk (Biot).  The total stress is sigma = sigma' - alpha p I, with the
effective stress sigma' = sigma0' + D eps(u) (D and alpha of the zone at the
point, :mod:`xfemslip.fem.zones`).  The model starts in equilibrium with the
in-situ total stress sigma0 (``loading.initial_stress``, uniform or growing
with depth) and the initial pore pressure p0 (uniform, or with a gradient and
the units' overpressures), so sigma0' = sigma0 + alpha p0 I.  A load step
changes p by lambda * dp, dp the pore-pressure change of the zone
(``pore_pressure.change`` in its region, or the unit's own ``change``; < 0 =
depletion).  Equilibrium of the increment, int B^T (D eps - alpha lambda dp
m) dOmega = lambda F_boundary with m = [1, 1, 0], moves the pressure term to
the right-hand side as the body load

    F_body = lambda * int B^T m alpha dp dOmega                  (1)

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
fracture takes its pressure from the pore pressures p(x + eps n) and
p(x - eps n) on its two faces at each contact point x (eps = FACE_OFFSET
h_min), by the fracture's ``fluid_pressure`` rule
(:func:`xfemslip.fem.zones.fluid_value`):

    p_f = mean | higher | lower of the two, or a fixed value      (3)

A fracture inside a depleting region has p_f = p0 + lambda dp, one outside
p0; a fault ON a region's boundary (between a depleting reservoir and
undepleted rock, the offset-reservoir set-up of Jansen & Meulenbroek 2022)
takes by default the mean, p0 + lambda dp / 2 where one side depletes (the
pressure is discontinuous across a sealing fault and the contact law needs
one p_f per point); "higher" or "lower" take one side's, a number holds the
fault's own pressure (sealed).  The rule is applied to the face pressures at
the start and at the end of loading and p_f follows the straight line
between (exact when the same face stays the higher one, as with equal
initial pressures).  The contact law (penalty + Coulomb) acts on the
EFFECTIVE normal traction sigma_n' = sigma_n + p_f: its in-situ value is
sigma0 . n . n + p_f(0), and |tau| <= c - f sigma_n'.  The
faces also carry the fluid pressure -p_f n; its change is the load on the
enriched dofs

    F_frac = lambda * int_Gamma dp_f [[N]]^T n ds                  (2)

(fluid pressure pushes the faces apart: dp_f > 0 opens).  With alpha = 1 and
a uniform dp, (1) and (2) cancel on Gamma by the divergence theorem: a
fracture whose fluid has the surrounding pressure does not perturb a uniform
depletion up to the penalty compliance (checked in
tests/verification/test_depletion.py).

Material regions.  An intact cell belongs to the zone its centre lies in
(:meth:`xfemslip.fem.zones.Zones.at`); its stiffness, its stress and its
pore-pressure change are those of the zone.  Region edges that do not fall on mesh lines
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

Changes are kept as ratios to a scale (``pore_pressure.change``, or 1 Pa
when that is 0): a case whose zones all change by that one value or not at
all gives ratios of exactly 1 and 0, so its loads come out of the same
floating-point operations whatever the number of zones.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace

import numpy as np

from xfemslip.fem.assembly import enriched_part_bbar
from xfemslip.fem.boundary import fracture_face_load
from xfemslip.fem.material import elasticity_matrix
from xfemslip.fem.zones import (
    HOST,
    Zones,
    build_zones,
    fluid_value,
    initial_pressure,
)
from xfemslip.geometry.regions import edges

logger = logging.getLogger(__name__)

# A box edge closer than this to a mesh line (relative to the local cell size)
# lies on it: no warning.
ALIGN_TOL = 1.0e-9
# The two faces of a fracture are sampled this far off it (relative to the
# smallest cell size) for the fluid pressure (3): far below any cell size, far
# above the round-off of the point coordinates.
FACE_OFFSET = 1.0e-6
# Enriched cells' Biot load (1) by groups of quadrature points with one
# (alpha, dp) each, at most this many groups; more distinct values (a field)
# are integrated by sign, each with weights w |alpha dp|.
MAX_LOAD_GROUPS = 16


@dataclass(frozen=True)
class Materials:
    """Elastic constants per zone and the zone of every cell."""

    D: np.ndarray  # (k, 3, 3) [Pa]; zone 0 = host ([material])
    nu: np.ndarray  # (k,) [-]
    E: np.ndarray  # (k,) [Pa]
    cell: np.ndarray  # (n_cells,) int64 zone of each cell (by centre;
    # enriched cells: the zone covering most of their area)
    model: str
    zones: Zones
    qp: np.ndarray | None = None  # (nq,) int64 zone of each enriched-cell QP

    @property
    def several(self) -> bool:
        """Whether the model has more than the host's constants."""
        return self.D.shape[0] > 1


@dataclass(frozen=True)
class PorePressure:
    """Pore pressure of a case: p(lambda) = p0 + lambda * scale * ratio.

    ``scale`` is ``pore_pressure.change`` (1 Pa when it is 0); the ratios
    carry each zone's change relative to it.
    """

    initial: float  # [pore_pressure] initial [Pa] (at its datum)
    change: float  # [pore_pressure] change at load factor 1 [Pa]
    biot: float  # [pore_pressure] biot, the host's alpha [-]
    scale: float  # [Pa]
    cell_p0: np.ndarray  # (n_cells,) initial pore pressure [Pa]
    cell_biot: np.ndarray  # (n_cells,) alpha of each cell's zone [-]
    cell_load: np.ndarray  # (n_cells,) alpha dp / scale of intact cells [-]
    cell_fraction: np.ndarray  # (n_cells,) area mean of dp / scale [-]
    qp_alpha: np.ndarray  # (nq,) alpha at the enriched cells' QPs [-]
    qp_ratio: np.ndarray  # (nq,) dp / scale there [-]
    point_p0: np.ndarray  # (n_ip,) fluid pressure at load factor 0, eq. (3) [Pa]
    point_ratio: np.ndarray  # (n_ip,) its change / scale at load factor 1 [-]
    uniform_p0: float | None = None  # p0 where it is one value (else None)
    # a change from a file (field_changes): alpha dp / scale at the 2 x 2
    # Gauss points of every cell (the intact cells' Biot load), and the
    # fields after the first, each reached at its own load factor
    cell_gauss: np.ndarray | None = None  # (n_cells, 4) [-]
    later: tuple = ()  # PorePressure of fields 2..m

    @property
    def n_fields(self) -> int:
        return 1 + len(self.later)

    def weights(self, lam: float) -> np.ndarray:
        """(m,) share of each field at load factor lam: the change follows
        the fields in turn, field j reached at lam = j / m (from none at 0),
        linearly between; with one field, lam itself."""
        m = self.n_fields
        if m == 1:
            return np.array([lam])
        knots = np.arange(m + 1) / m
        return np.array(
            [np.interp(lam, knots, np.eye(m + 1)[j]) for j in range(1, m + 1)]
        )

    def _sum(self, name: str, lam: float) -> np.ndarray:
        if not self.later:
            return lam * self.scale * getattr(self, name)
        parts = (self, *self.later)
        return sum(
            w * p.scale * getattr(p, name)
            for w, p in zip(self.weights(lam), parts, strict=True)
        )

    def cell_pressure(self, lam: float) -> np.ndarray:
        """(n_cells,) pore pressure at load factor lam (area mean) [Pa]."""
        return self.cell_p0 + self._sum("cell_fraction", lam)

    def fluid(self, lam: float) -> np.ndarray:
        """(n_ip,) fluid pressure in the fractures, eq. (3) [Pa]."""
        return self.point_p0 + self._sum("point_ratio", lam)


def cell_centres(mesh) -> np.ndarray:
    """(n_cells, 2) cell centres [m]."""
    b = mesh.bounds
    return np.column_stack([0.5 * (b[:, 0] + b[:, 1]), 0.5 * (b[:, 2] + b[:, 3])])


def _on_fracture(fractures, p: np.ndarray, q: np.ndarray, tol: float) -> bool:
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


def _clip_to_domain(
    mesh, p: np.ndarray, q: np.ndarray
) -> tuple[np.ndarray, np.ndarray] | None:
    """The part of p-q inside the domain's bounding box, or None."""
    lo, hi = mesh.box.lo, mesh.box.hi
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


def _warn_unaligned(mesh, unit, fractures=()) -> None:
    """Log a warning for each edge of a unit inside the domain off the mesh
    lines, unless a fracture covers it (its cut cells are split per QP)."""
    tol = ALIGN_TOL * mesh.h_min
    off = []
    for name, p, q in edges(unit.region, mesh.box):
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
    label = "reservoir" if unit.name == "reservoir" else f"unit {unit.name!r}:"
    for subject in subjects:
        logger.warning(
            "%s %s not on a mesh line; the cells whose centre is inside the "
            "region form the %s",
            label,
            subject,
            "reservoir" if unit.name == "reservoir" else "unit",
        )


def face_zones(zones: Zones, ip, eps) -> tuple[np.ndarray, np.ndarray]:
    """(n_ip,) zone of the + and of the - face of every interface point:
    :meth:`Zones.at` the points x + eps n and x - eps n (eps [m], normally
    FACE_OFFSET h_min).  A fracture inside one unit has it on both faces; a
    fault bounding the reservoir has the reservoir on one face only."""
    return zones.at(ip.xy + eps * ip.normal), zones.at(ip.xy - eps * ip.normal)


def _area_majority(ec, qp_material, n_materials) -> np.ndarray:
    """(nc,) material covering most of each enriched cell's area."""
    cell_of_qp = np.repeat(np.arange(ec.cells.size), np.diff(ec.qp_offsets))
    area = np.zeros((ec.cells.size, n_materials))
    np.add.at(area, (cell_of_qp, qp_material), ec.qp_w)
    return np.argmax(area, axis=1).astype(np.int64)


def build_materials(spec, mesh, ec=None, fractures=()) -> Materials:
    """The zones' constants, the zone of every cell and, given the enriched
    cells ``ec``, of every enriched-cell quadrature point."""
    zones = build_zones(spec)
    cell = np.full(mesh.n_cells, HOST, np.int64)
    qp = None
    if spec.units:
        cell = zones.at(cell_centres(mesh))
        for unit in spec.units:
            _warn_unaligned(mesh, unit, fractures)
        if ec is not None and ec.cells.size:
            qp = zones.at(ec.qp_xy)
            cell[ec.cells] = _area_majority(ec, qp, zones.n)
    D = np.stack(
        [
            elasticity_matrix(e, v, spec.material.model)
            for e, v in zip(zones.E, zones.nu, strict=True)
        ]
    )
    return Materials(
        D=D,
        nu=zones.nu.copy(),
        E=zones.E.copy(),
        cell=cell,
        model=spec.material.model,
        qp=qp,
        zones=zones,
    )


def build_pore_pressure(
    spec, materials: Materials, mesh, ec=None, ip=None, fractures=()
) -> PorePressure | None:
    """The case's pore pressure, or None without [pore_pressure].

    ec, ip : enriched cells and interface points (per-QP and per-point
    zones); fractures : the FractureSpecs of the case, by interface point
    ``ip.fracture`` (their fluid_pressure rule).
    """
    p = spec.pore_pressure
    if p is None:
        return None
    if p.field is not None:
        return _field_pressure(spec, materials, mesh, ec, ip, fractures)
    zones = materials.zones
    scale = p.change if p.change != 0.0 else 1.0
    ratio = zones.change / scale  # (k,): exactly 1.0 or 0.0 where it is
    alpha = zones.biot
    n_qp = 0 if ec is None else ec.qp_w.size
    qp_zone = materials.qp if materials.qp is not None else np.zeros(n_qp, np.int64)
    fraction = ratio[materials.cell]
    if n_qp:
        cell_of_qp = np.repeat(np.arange(ec.cells.size), np.diff(ec.qp_offsets))
        area = np.bincount(cell_of_qp, weights=ec.qp_w, minlength=ec.cells.size)
        part = np.bincount(
            cell_of_qp, weights=ec.qp_w * ratio[qp_zone], minlength=ec.cells.size
        )
        fraction[ec.cells] = part / area
    uniform = p.gradient == 0.0 and not np.any(zones.overpressure)
    if uniform:
        cell_p0 = np.full(materials.cell.size, p.initial)
    else:
        cell_p0 = initial_pressure(spec, zones, cell_centres(mesh), materials.cell)
    point_p0, point_ratio = np.zeros(0), np.zeros(0)
    if ip is not None:
        eps = FACE_OFFSET * mesh.h_min
        point_p0, point_ratio = _fluid(spec, zones, ip, eps, ratio, uniform, fractures)
    return PorePressure(
        initial=p.initial,
        change=p.change,
        biot=p.biot,
        scale=scale,
        cell_p0=cell_p0,
        cell_biot=alpha[materials.cell],
        cell_load=(alpha * ratio)[materials.cell],
        cell_fraction=fraction,
        qp_alpha=alpha[qp_zone],
        qp_ratio=ratio[qp_zone],
        point_p0=point_p0,
        point_ratio=point_ratio,
        uniform_p0=p.initial if uniform else None,
    )


# 2 x 2 Gauss points of a cell in its reference square, and the corners' signs
GAUSS = np.array([-1.0, 1.0]) / np.sqrt(3.0)
CORNER_X = np.array([-1.0, 1.0, 1.0, -1.0])
CORNER_Y = np.array([-1.0, -1.0, 1.0, 1.0])


def gauss_points(mesh) -> np.ndarray:
    """(n_cells, 4, 2) the 2 x 2 Gauss points of every cell [m], in the order
    (xi, eta) = (-, -), (+, -), (-, +), (+, +)."""
    b = mesh.bounds
    xc, yc = 0.5 * (b[:, 0] + b[:, 1]), 0.5 * (b[:, 2] + b[:, 3])
    hx, hy = b[:, 1] - b[:, 0], b[:, 3] - b[:, 2]
    xi = np.array([GAUSS[0], GAUSS[1], GAUSS[0], GAUSS[1]])
    eta = np.array([GAUSS[0], GAUSS[0], GAUSS[1], GAUSS[1]])
    x = xc[:, None] + 0.5 * hx[:, None] * xi[None, :]
    y = yc[:, None] + 0.5 * hy[:, None] * eta[None, :]
    return np.stack([x, y], axis=-1)


def _field_pressure(spec, materials, mesh, ec, ip, fractures) -> PorePressure:
    """The pore pressure of a change read from a file ([pore_pressure.field],
    xfemslip.case.pressure_field): each field interpolated to the 2 x 2 Gauss
    points of every cell, the enriched cells' quadrature points and the
    fractures' contact points; one PorePressure per field (scale 1 Pa)."""
    p = spec.pore_pressure
    zones = materials.zones
    field = p.field.field
    alpha = zones.biot
    n_qp = 0 if ec is None else ec.qp_w.size
    qp_zone = materials.qp if materials.qp is not None else np.zeros(n_qp, np.int64)
    gauss = field.values(gauss_points(mesh).reshape(-1, 2))  # (m, 4 n_cells)
    qp = field.values(ec.qp_xy) if n_qp else np.zeros((field.n_fields, 0))
    points = field.values(ip.xy) if ip is not None else np.zeros((field.n_fields, 0))
    uniform = p.gradient == 0.0 and not np.any(zones.overpressure)
    centres = cell_centres(mesh)
    cell_p0 = (
        np.full(mesh.n_cells, p.initial)
        if uniform
        else initial_pressure(spec, zones, centres, materials.cell)
    )
    eps = FACE_OFFSET * mesh.h_min
    out = []
    for j in range(field.n_fields):
        g = gauss[j].reshape(mesh.n_cells, 4)
        fraction = g.mean(axis=1)  # the cell mean: exact for a bilinear field
        if n_qp:
            cell_of_qp = np.repeat(np.arange(ec.cells.size), np.diff(ec.qp_offsets))
            area = np.bincount(cell_of_qp, weights=ec.qp_w, minlength=ec.cells.size)
            part = np.bincount(
                cell_of_qp, weights=ec.qp_w * qp[j], minlength=ec.cells.size
            )
            fraction[ec.cells] = part / area
        point_p0, point_ratio = np.zeros(0), np.zeros(0)
        if ip is not None:
            point_p0, point_ratio = _fluid(
                spec, zones, ip, eps, None, uniform, fractures, points[j]
            )
        out.append(
            PorePressure(
                initial=p.initial,
                change=0.0,
                biot=p.biot,
                scale=1.0,
                cell_p0=cell_p0,
                cell_biot=alpha[materials.cell],
                cell_load=np.zeros(mesh.n_cells),
                cell_fraction=fraction,
                qp_alpha=alpha[qp_zone],
                qp_ratio=qp[j].copy(),
                point_p0=point_p0,
                point_ratio=point_ratio,
                uniform_p0=p.initial if uniform else None,
                cell_gauss=alpha[materials.cell][:, None] * g,
            )
        )
    first = out[0]
    return replace(first, later=tuple(out[1:]))


def _fluid(spec, zones, ip, eps, ratio, uniform, fractures, values=None):
    """(p_f at load factor 0 [Pa], its change / scale at 1) at every
    interface point, eq. (3): each fracture's rule on its two faces."""
    sides = []
    for zone in face_zones(zones, ip, eps):
        # the depth term at the point itself (it is continuous), the face's
        # unit for its overpressure
        p0 = (
            np.full(ip.n, spec.pore_pressure.initial)
            if uniform
            else initial_pressure(spec, zones, ip.xy, zone)
        )
        # a field from a file is continuous: both faces take its value
        sides.append((p0, ratio[zone] if values is None else values))
    (p0_plus, r_plus), (p0_minus, r_minus) = sides
    rules = [getattr(f, "fluid_pressure", "mean") for f in fractures]
    if not rules or all(r == "mean" for r in rules):
        return 0.5 * (p0_plus + p0_minus), 0.5 * (r_plus + r_minus)
    scale = (spec.pore_pressure.change or 1.0) if values is None else 1.0
    start = np.empty(ip.n)
    end = np.empty(ip.n)
    for fi, rule in enumerate(rules):
        m = ip.fracture == fi
        start[m] = fluid_value(rule, p0_plus[m], p0_minus[m])
        end[m] = fluid_value(
            rule, p0_plus[m] + scale * r_plus[m], p0_minus[m] + scale * r_minus[m]
        )
    return start, (end - start) / scale


def body_load(
    mesh, bulk, pore: PorePressure, ec, backend: str, kept: dict | None = None
) -> np.ndarray:
    """F_body of eq. (1) at load factor 1, (n_dofs,) [N/m].

    Intact rectangle: int dN_a/dx dOmega = x_a hy / 2, int dN_a/dy = y_a hx / 2
    (x_a, y_a = -/+1 the corner signs).  Enriched cell (``ec``, same order as
    ``bulk.enriched_cells``): sum_q w_q B_q^T m alpha dp(x_q), by groups of
    QPs with one (alpha, dp): alpha dp A_g Bbar_g^T m, Bbar_g the average
    strain operator over the group's part of the cell (its area A_g),
    computed by the model's kernel ``backend``.  ``kept``: a dict in which
    those operators are kept for the next call on the same mesh and enriched
    cells (the samples of a study, xfemslip.simulation), keyed by the QP
    weights of their group.
    """
    F = np.zeros(bulk.dofmap.n_dofs)
    std = bulk.std_cells
    b = mesh.bounds[std]
    hx, hy = b[:, 1] - b[:, 0], b[:, 3] - b[:, 2]
    xa = np.array([-1.0, 1.0, 1.0, -1.0])
    ya = np.array([-1.0, -1.0, 1.0, 1.0])
    if pore.cell_gauss is None:
        q = pore.scale * pore.cell_load  # (n_cells,) alpha dp [Pa]
        fx = q[std, None] * xa[None, :] * hy[:, None] / 2.0
        fy = q[std, None] * ya[None, :] * hx[:, None] / 2.0
    else:  # alpha dp at the 2 x 2 Gauss points: sum_q w_q q_q grad N_a
        fx, fy = _gauss_biot(pore.scale * pore.cell_gauss[std], hx, hy)
    nodes = mesh.cells[std]
    np.add.at(F, 2 * nodes, fx)
    np.add.at(F, 2 * nodes + 1, fy)
    if ec.cells.size:
        for w, factor in _load_groups(ec, pore):
            _add_enriched_load(F, mesh, bulk, ec, w, factor, pore.scale, backend, kept)
    return F


def _gauss_biot(q, hx, hy):
    """(fx, fy) (n, 4) int grad N_a q dOmega of rectangles hx x hy with q
    (n, 4) at the 2 x 2 Gauss points (order of :func:`gauss_points`):
    weights hx hy / 4, dN_a/dx = x_a (1 + y_a eta) / (2 hx) and
    dN_a/dy = y_a (1 + x_a xi) / (2 hy)."""
    xi = np.array([GAUSS[0], GAUSS[1], GAUSS[0], GAUSS[1]])
    eta = np.array([GAUSS[0], GAUSS[0], GAUSS[1], GAUSS[1]])
    dx = CORNER_X[None, :] * (1.0 + CORNER_Y[None, :] * eta[:, None]) / 2.0  # (q, a)
    dy = CORNER_Y[None, :] * (1.0 + CORNER_X[None, :] * xi[:, None]) / 2.0
    fx = (q @ dx) * (hy / 4.0)[:, None]  # hx hy / 4 * 1 / hx
    fy = (q @ dy) * (hx / 4.0)[:, None]
    return fx, fy


def _load_groups(ec, pore: PorePressure):
    """(QP weights, factor) of each group of enriched-cell QPs whose Biot load
    is factor * sum_q w_q B_q^T m: one group per distinct (alpha, dp / scale)
    (factor alpha scale and the ratio), or, with many distinct values, one per
    sign of alpha dp (weights w |alpha dp / scale|, factor +-scale)."""
    pairs = np.column_stack([pore.qp_alpha, pore.qp_ratio])
    loaded = pairs[pairs[:, 1] != 0.0]
    if loaded.size and np.all(loaded == loaded[0]):  # one rock, one change
        values = loaded[:1]
    else:
        values = np.unique(loaded, axis=0)
    if len(values) <= MAX_LOAD_GROUPS:
        for a, r in values:
            mine = (pore.qp_alpha == a) & (pore.qp_ratio == r)
            w = ec.qp_w * mine
            yield w, (a, r)
        return
    v = pore.qp_alpha * pore.qp_ratio
    for sign in (1.0, -1.0):
        w = ec.qp_w * np.where(sign * v > 0.0, np.abs(v), 0.0)
        if w.any():
            yield w, (sign, 1.0)


# Biot-load operators body_load keeps for the next case (``kept``)
MAX_KEPT_LOADS = 8


def _add_enriched_load(F, mesh, bulk, ec, w, factor, scale, backend, kept=None) -> None:
    """F += (alpha scale A) r Bbar^T m over the enriched cells holding weight
    w, (alpha, r) = ``factor``."""
    a, r = factor
    cell_of_qp = np.repeat(np.arange(ec.cells.size), np.diff(ec.qp_offsets))
    area = np.bincount(cell_of_qp, weights=w, minlength=ec.cells.size)
    rows = np.nonzero(area > 0.0)[0]
    if rows.size == 0:
        return
    key = (backend, w.tobytes()) if kept is not None else None
    if key is not None and key in kept:
        Bbar = kept[key]
    else:
        Bbar = enriched_part_bbar(mesh, ec, rows, w, backend)
        if key is not None:
            if len(kept) >= MAX_KEPT_LOADS:  # loads that change with every case
                kept.clear()
            kept[key] = Bbar
    # Bbar^T m = rows exx + eyy of the average operator
    fe = ((a * scale * area[rows]) * r)[:, None] * (Bbar[:, 0] + Bbar[:, 1])
    dofs = bulk.enr_dofs[rows]
    keep = dofs >= 0
    np.add.at(F, dofs[keep], fe[keep])


def fracture_load(contact, ip, pore: PorePressure) -> np.ndarray:
    """F_frac of eq. (2) at load factor 1, (n_dofs,) [N/m]: the fluid
    pressure change dp_f of eq. (3) on the faces (fracture_face_load), with
    the interface points' own jump operators, sum_p w_p dp_f(p) coef_pk n_p."""
    return fracture_face_load(contact, normal=ip.weight * pore.scale * pore.point_ratio)


def make_contact_effective(contact, pore: PorePressure, ip) -> None:
    """Shift the in-situ normal traction of every patch to the effective one,
    sigma_n0' = sigma_n0 + p_f(0), p_f(0) of eq. (3) averaged over the patch."""
    if pore.uniform_p0 is not None and np.all(pore.point_p0 == pore.uniform_p0):
        contact.pn0 = contact.pn0 + pore.uniform_p0
        return
    W = np.bincount(contact.patch, weights=ip.weight, minlength=contact.n)
    p0 = np.bincount(
        contact.patch, weights=ip.weight * pore.point_p0, minlength=contact.n
    )
    contact.pn0 = contact.pn0 + p0 / W
