"""The fields of a converged load step, in the output sign convention.

The containers (``StepFields``, ``FractureFields``, ``VisMesh``) hold plain
arrays, tension positive (``output-format.md``); ``step_fields`` fills them
from a model and a converged step, and the writers (:mod:`xfemslip.io`) and
:class:`xfemslip.post.result.Result` carry them.

Stress: sigma = sigma0 + D eps (- alpha (p - p0) I with pore pressure, see
xfemslip.fem.poro), averaged over each element (sub-cells included
for enriched elements).  Out-of-plane stress in plane strain:
sigma_zz = nu (sigma_xx + sigma_yy) (the in-situ sigma_zz is taken as
nu (sigma0_xx + sigma0_yy), consistent with plane strain); zero in plane stress.
Fracture fields: slip = [[u]] . t, opening = [[u]] . n, p_N, p_T and the state
codes of :mod:`xfemslip.conventions`; with a slip-weakening friction also the
accumulated slip and the friction coefficient it leaves.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from xfemslip.contact.interface import JUMP_PROBE
from xfemslip.conventions import STICK
from xfemslip.fem.enrichment import HEAVISIDE, find_candidates, group_values
from xfemslip.fem.material import shear_modulus
from xfemslip.fem.poro import FACE_OFFSET, cell_centres, face_zones
from xfemslip.fem.zones import build_zones, in_situ_stress, loading_breaks
from xfemslip.geometry.fracture import GEOMETRY_TOL


@dataclass
class FractureFields:
    """Contact fields of one fracture at its K integration points, sorted by s."""

    s: np.ndarray  # (K,) arc length from the first point [m]
    points: np.ndarray  # (K, 2) [m]
    slip: np.ndarray  # (K,) [[u]].t [m]
    opening: np.ndarray  # (K,) [[u]].n [m]
    normal_traction: np.ndarray  # (K,) p_N [Pa], compression negative
    shear_traction: np.ndarray  # (K,) p_T along t [Pa]
    state: np.ndarray  # (K,) int8: 0 open, 1 stick, 2 slip
    # the slip that slid, along t (ContactResult.plastic_slip): the committed
    # plastic slip of the point's patch from the in-situ state, the whole jump
    # where open; None in a result written without it
    plastic_slip: np.ndarray | None = None  # (K,) [m]
    # with [pore_pressure] only (xfemslip.fem.poro); normal_traction is then total
    fluid_pressure: np.ndarray | None = None  # (K,) p_f [Pa]
    effective_normal_traction: np.ndarray | None = None  # (K,) p_N + p_f [Pa]
    # with [permeability] only (xfemslip.post.hydraulics)
    aperture: np.ndarray | None = None  # (K,) hydraulic aperture a [m]
    transmissivity: np.ndarray | None = None  # (K,) a^3 / 12 [m^3]
    # |p_T| / (c + f max(0, -p_N')) of a stuck point, 1 where it slips or is
    # open (coulomb_utilisation); None in a result written without it
    utilisation: np.ndarray | None = None  # (K,) [-]

    # with a slip-weakening friction only (kernels.contact)
    accumulated_slip: np.ndarray | None = None  # (K,) delta = int |d g_T^p| [m]
    friction_coefficient: np.ndarray | None = None  # (K,) f(delta) [-]

    @property
    def slid(self) -> np.ndarray:
        """(K,) [m] the slip that slid: ``plastic_slip``, or the tangential
        jump ``slip`` for a result written without it (the elastic give of
        stuck points then counts as slip)."""
        return self.slip if self.plastic_slip is None else self.plastic_slip


@dataclass
class FractureProperties:
    """What the derived quantities of one fracture need of the model, the same
    at every step (``result.h5``: ``/fractures/<i>/shear_modulus``,
    ``poisson_ratio`` and the attribute ``ends``)."""

    ends: tuple[float, float]  # arc-length range of the fracture inside the domain [m]
    shear_modulus: np.ndarray  # (K,) mu at its contact points, sorted by s [Pa]
    poisson_ratio: np.ndarray  # (K,) nu there [-]
    # the in-situ state at the contact points (effective normal and shear
    # traction, utilisation), None in a result written without them
    in_situ_normal_traction: np.ndarray | None = None  # (K,) p_N0' [Pa]
    in_situ_shear_traction: np.ndarray | None = None  # (K,) p_T0 [Pa]
    in_situ_utilisation: np.ndarray | None = None  # (K,) [-]
    # where the rock on a face changes along it (arc lengths [m]) and the
    # units on its + and - faces on each stretch between (len(breaks) + 1)
    breaks: np.ndarray | None = None
    units_plus: tuple[str, ...] = ()
    units_minus: tuple[str, ...] = ()


@dataclass
class StepFields:
    """Fields of one converged load step."""

    step: int  # 1-based
    load_factor: float  # lambda in (0, 1]
    newton_iterations: int
    displacement: np.ndarray  # (N, 2) [m]
    # (None for a step other than the last one read back from result.h5,
    # which stores them for the final step only)
    stress: np.ndarray | None  # (M, 3) [Pa] element average sxx, syy, sxy
    stress_zz: np.ndarray | None  # (M,) [Pa]
    principal_stress: np.ndarray | None  # (M, 2) [Pa] s_max, s_min
    fractures: list[FractureFields] = field(default_factory=list)
    # with [pore_pressure] only (xfemslip.fem.poro)
    effective_stress: np.ndarray | None = None  # (M, 3) sigma + alpha p I [Pa]
    pore_pressure: np.ndarray | None = None  # (M,) [Pa]


@dataclass
class VisMesh:
    """Bulk mesh for ParaView with cut elements split along the fractures.

    Uncut elements are quads on shared points; each cut element is replaced by
    triangles on points of its own, so the displacement can jump across the
    fracture.  ``*_cell`` maps every vis cell to its bulk element (for cell data).
    """

    points: np.ndarray  # (P, 2) [m]
    displacement: np.ndarray  # (P, 2) [m]
    quads: np.ndarray  # (Q, 4) int64
    quad_cell: np.ndarray  # (Q,) int64
    triangles: np.ndarray  # (T, 3) int64
    triangle_cell: np.ndarray  # (T,) int64
    # per fracture (position order): the displacement of its - and + faces at
    # its contact points, each (K, 2) [m], sorted by s (fracture_faces)
    faces: list[tuple[np.ndarray, np.ndarray]] | None = None


def cell_strain(mesh, bulk, u) -> np.ndarray:
    """Element-average strain (M, 3) [exx, eyy, gxy]."""
    eps = np.zeros((mesh.n_cells, 3))
    c = bulk.std_cells
    b = mesh.bounds[c]
    hx, hy = b[:, 1] - b[:, 0], b[:, 3] - b[:, 2]
    U = u[: 2 * mesh.n_nodes].reshape(-1, 2)[mesh.cells[c]]  # (ns, 4, 2)
    xa = np.array([-1.0, 1.0, 1.0, -1.0])
    ya = np.array([-1.0, -1.0, 1.0, 1.0])
    dNdx = xa[None, :] / (2.0 * hx[:, None])  # gradient at the centre = cell average
    dNdy = ya[None, :] / (2.0 * hy[:, None])
    eps[c, 0] = np.sum(dNdx * U[:, :, 0], axis=1)
    eps[c, 1] = np.sum(dNdy * U[:, :, 1], axis=1)
    eps[c, 2] = np.sum(dNdy * U[:, :, 0] + dNdx * U[:, :, 1], axis=1)
    if bulk.enr_dofs.shape[0]:
        ue = np.where(bulk.enr_dofs >= 0, u[np.maximum(bulk.enr_dofs, 0)], 0.0)
        eps[bulk.enriched_cells] = np.einsum("eij,ej->ei", bulk.enr_Bbar, ue)
    return eps


def bulk_fields(
    mesh, bulk, D, u, initial_stress, nu, model, cell_material=None, biot_p=None
):
    """stress (M, 3), stress_zz (M,), principal_stress (M, 2) [Pa] (total).

    With several materials (xfemslip.fem.poro): D (k, 3, 3), nu (k,) and
    ``cell_material`` (M,).  ``initial_stress``: (3,), or (M, 3) varying with
    depth.  With pore pressure, ``biot_p`` = (alpha p0, alpha p) [Pa] (each
    (M,) or a number) at this step: sigma = sigma0 + D eps - alpha (p - p0) m
    and, in plane strain, sigma_zz = nu (sigma'_xx + sigma'_yy) - alpha p with
    sigma' = sigma0 + alpha p0 m + D eps (see xfemslip.fem.poro).
    """
    eps = cell_strain(mesh, bulk, u)
    if cell_material is None:
        stress = eps @ np.asarray(D).reshape(3, 3).T
        nu_c = np.full(mesh.n_cells, float(np.ravel(nu)[0]))
    else:
        stress = np.einsum("mij,mj->mi", np.asarray(D)[cell_material], eps)
        nu_c = np.asarray(nu, float)[cell_material]
    if initial_stress is not None:  # (3,) uniform or (M, 3) per cell
        stress = stress + np.atleast_2d(np.asarray(initial_stress, float))
    a0, a = (0.0, np.zeros(mesh.n_cells)) if biot_p is None else biot_p
    # stress is sigma0 + D eps here, i.e. sigma' - alpha p0 m
    szz = (
        nu_c * (stress[:, 0] + stress[:, 1] + 2.0 * a0) - a
        if model == "plane_strain"
        else np.zeros(len(stress))
    )
    stress = stress - (a - a0)[:, None] * np.array([1.0, 1.0, 0.0])
    centre = 0.5 * (stress[:, 0] + stress[:, 1])
    radius = np.hypot(0.5 * (stress[:, 0] - stress[:, 1]), stress[:, 2])
    principal = np.column_stack([centre + radius, centre - radius])
    return stress, szz, principal


def coulomb_utilisation(pn, pt, state, friction, cohesion) -> np.ndarray:
    """|p_T| / (c + f max(0, -p_N')) [-] of each contact point or patch: how
    much of its Coulomb strength a stuck point uses; 1 where it slips (on the
    bound) or is open (no strength left); 0 for a stuck point without shear
    or strength.  p_N' is the effective normal traction the contact law acts
    on (tension positive)."""
    strength = cohesion + friction * np.maximum(0.0, -np.asarray(pn, float))
    ratio = np.divide(
        np.abs(pt), strength, out=np.zeros(np.shape(strength)), where=strength > 0.0
    )
    return np.where(np.asarray(state) == STICK, np.minimum(ratio, 1.0), 1.0)


def fracture_fields(ip, res, n_fractures, fluid=None) -> list[FractureFields]:
    """Contact fields per fracture, ordered by arc length.

    fluid : (n,) fluid pressure at the interface points [Pa] or None.  The
    contact law gives the effective normal traction sigma_n'; with a fluid,
    ``normal_traction`` is the total sigma_n' - p_f and the effective one and
    p_f are reported too (xfemslip.fem.poro).
    """
    c = getattr(res, "contact", None)
    weakening = _weakening_law(res)
    use = None
    if c is not None:  # against the friction reached (weakened where it slid)
        f, coh = (
            (c.friction_at(res.accumulated), c.cohesion_at(res.accumulated))
            if weakening
            else (c.friction, c.cohesion)
        )
        use = coulomb_utilisation(res.pn, res.pt, res.state, f, coh)[c.patch]
    out = []
    for fi in range(n_fractures):
        m = np.nonzero(ip.fracture == fi)[0]
        m = m[np.argsort(ip.s[m], kind="stable")]
        pn = res.point_pn[m].copy()
        extra = {}
        if fluid is not None:
            pf = np.asarray(fluid, float)[m].copy()
            extra = {"fluid_pressure": pf, "effective_normal_traction": pn}
            pn = pn - pf
        if weakening:
            extra["accumulated_slip"] = res.point_accumulated[m].copy()
            extra["friction_coefficient"] = res.point_friction[m].copy()
        out.append(
            FractureFields(
                s=ip.s[m].copy(),
                points=ip.xy[m].copy(),
                slip=res.point_gt[m].copy(),
                opening=res.point_gn[m].copy(),
                normal_traction=pn,
                shear_traction=res.point_pt[m].copy(),
                state=res.point_state[m].astype(np.int8),
                plastic_slip=res.point_plastic_slip[m].copy(),
                utilisation=None if use is None else use[m].copy(),
                **extra,
            )
        )
    return out


def _weakening_law(res) -> bool:
    """Whether a fracture of the contact set has a slip-weakening friction
    (a finite slip distance; constant Coulomb has D_c = inf): every fracture
    then reports its accumulated slip and friction."""
    c = getattr(res, "contact", None)
    if c is None or res.accumulated is None:
        return False
    return bool(np.isfinite(c.slip_distance).any())


def vis_mesh(mesh, ec, bulk, u) -> VisMesh:
    """Bulk mesh with enriched cells split into sub-triangles, each on its side."""
    n_std = 2 * mesh.n_nodes
    U = u[:n_std].reshape(-1, 2)
    is_enr = np.zeros(mesh.n_cells, bool)
    is_enr[ec.cells] = True
    quads = mesh.cells[~is_enr]
    quad_cell = np.nonzero(~is_enr)[0]
    nt = ec.tris.shape[0]
    if nt == 0:
        return VisMesh(
            points=mesh.nodes.copy(),
            displacement=U.copy(),
            quads=quads,
            quad_cell=quad_cell,
            triangles=np.zeros((0, 3), np.int64),
            triangle_cell=np.zeros(0, np.int64),
        )
    tri_owner = np.repeat(
        np.arange(ec.cells.size), np.diff(ec.tri_offsets)
    )  # enriched index
    cell = ec.cells[tri_owner]
    pts = ec.tris.reshape(-1, 2)
    owner_v = np.repeat(tri_owner, 3)
    N = mesh.shape_at(np.repeat(cell, 3), pts)  # (3nt, 4)
    disp = np.einsum("va,vac->vc", N, U[mesh.cells[np.repeat(cell, 3)]])
    Fv = ec.tri_F.reshape(-1, ec.tri_F.shape[2])  # (3nt, S)
    dofs = bulk.enr_dofs[owner_v]  # (3nt, 8+2S)
    for s in range(ec.slot_cand.shape[1]):
        a = ec.slot_node[owner_v, s]
        d = dofs[:, 8 + 2 * s]
        ok = (a >= 0) & (d >= 0)
        phi = np.where(
            ok,
            N[np.arange(len(a)), np.maximum(a, 0)]
            * (Fv[:, s] - ec.slot_fnode[owner_v, s]),
            0.0,
        )
        amp = np.where(
            ok[:, None], u[np.stack([np.maximum(d, 0), np.maximum(d, 0) + 1], 1)], 0.0
        )
        disp += phi[:, None] * amp
    base = mesh.n_nodes
    triangles = base + np.arange(3 * nt, dtype=np.int64).reshape(nt, 3)
    return VisMesh(
        points=np.vstack([mesh.nodes, pts]),
        displacement=np.vstack([U, disp]),
        quads=quads,
        quad_cell=quad_cell,
        triangles=triangles,
        triangle_cell=cell.astype(np.int64),
    )


def fracture_faces(model, u) -> list[tuple[np.ndarray, np.ndarray]]:
    """Displacement of the two faces of every fracture at its contact points.

    Per fracture (position order), ``(u_minus, u_plus)`` (K, 2) [m] sorted by
    s as in :func:`fracture_fields`: the XFEM field of the point's cell
    evaluated on each side, u(x +/- eps n) = sum_a N_a u_a + sum_s N_a(s)
    (F_s(x +/- eps n) - F_s(x_a(s))) a_s, the functions' sides taken at the
    probes x +/- eps n as for the jump operators of the contact
    (xfemslip.contact.interface), so u_plus - u_minus is the jump [[u]] whose
    t and n components are ``slip`` and ``opening``.
    """
    mesh, ec, ip, fractures = model.mesh, model.ec, model.ip, model.fractures
    n_points = ip.n
    U = u[: 2 * mesh.n_nodes].reshape(-1, 2)
    N = mesh.shape_at(ip.cell, ip.xy) if n_points else np.zeros((0, 4))
    std = np.einsum("na,nac->nc", N, U[mesh.cells[ip.cell]])
    sides = [std.copy(), std.copy()]  # +, -
    n_slots = ec.slot_cand.shape[1]
    if n_points and n_slots:
        cand = find_candidates(mesh, fractures)
        pos = np.searchsorted(ec.cells, ip.cell)
        eps = JUMP_PROBE * mesh.h_min
        tol = GEOMETRY_TOL * mesh.h_min
        probes = (ip.xy + eps * ip.normal, ip.xy - eps * ip.normal)
        K = ec.slot_cand[pos]  # (n, S) candidate of each slot of the point's cell
        node = ec.slot_node[pos]
        dof = model.bulk.enr_dofs[pos, 8::2][:, :n_slots]
        live = (K >= 0) & (node >= 0) & (dof >= 0)
        Kc = np.maximum(K, 0)
        group = np.where(live, cand.fracture[Kc] * 100003 + cand.tip[Kc] + 50000, -1)
        # one evaluation of a (fracture, tip) group's functions per side, for
        # every slot of every point it enriches
        for g in np.unique(group[live]):
            fi, tip = divmod(int(g), 100003)
            tip -= 50000
            rows, cols = np.nonzero(group == g)
            k, d = Kc[rows, cols], dof[rows, cols]
            weight = N[rows, node[rows, cols]]
            amp = np.column_stack([u[d], u[d + 1]])
            column = np.where(cand.func[k] == HEAVISIDE, 0, cand.func[k] - 1)
            shift_node = ec.slot_fnode[pos[rows], cols]
            fr = fractures[fi]
            for side, probe in zip(sides, probes, strict=True):
                values = group_values(
                    fractures,
                    fi,
                    tip,
                    ip.xy[rows],
                    fr.side(probe[rows]),
                    tol,
                    probe[rows],
                )[0]
                F = values[np.arange(rows.size), column]
                np.add.at(side, rows, ((F - shift_node) * weight)[:, None] * amp)
    out = []
    for fi in range(len(fractures)):
        m = np.nonzero(ip.fracture == fi)[0]
        m = m[np.argsort(ip.s[m], kind="stable")]
        out.append((sides[1][m], sides[0][m]))
    return out


def vis_mesh_with_faces(model, u) -> VisMesh:
    """:func:`vis_mesh` of ``model`` at the solution ``u`` with the fractures'
    face displacements (:func:`fracture_faces`), for the ParaView files."""
    vis = vis_mesh(model.mesh, model.ec, model.bulk, u)
    vis.faces = fracture_faces(model, u)
    return vis


def cell_in_situ(model):
    """The in-situ stress of every cell: ``initial_stress`` (3,) when uniform
    (or None), else (M, 3) [Pa] at the cell centres in their zones."""
    spec = model.spec
    if spec.loading.in_situ is None:
        return spec.loading.initial_stress
    mats = model.materials
    p0 = None if model.pore is None else model.pore.cell_p0
    return in_situ_stress(spec, mats.zones, cell_centres(model.mesh), mats.cell, p0)


def step_fields(model, r) -> StepFields:
    """The fields of the converged step ``r`` (a ``StepResult``) of ``model``
    (a :class:`xfemslip.simulation.Model`)."""
    spec = model.spec
    mats, pore = model.materials, model.pore
    hetero = bool(spec.units)
    biot_p = None
    if pore is not None:
        p = pore.cell_pressure(r.load_factor)
        biot_p = (pore.cell_biot * pore.cell_p0, pore.cell_biot * p)
    stress, szz, principal = bulk_fields(
        model.mesh,
        model.bulk,
        mats.D if hetero else model.D,
        r.u,
        cell_in_situ(model),
        mats.nu if hetero else spec.material.nu,
        spec.material.model,
        cell_material=mats.cell if hetero else None,
        biot_p=biot_p,
    )
    extra = {}
    fluid = None
    if pore is not None:
        assert biot_p is not None  # set with the pore pressure above
        extra = {
            "effective_stress": stress + biot_p[1][:, None] * [1.0, 1.0, 0.0],
            "pore_pressure": p,
        }
        fluid = pore.fluid(r.load_factor)
    n_std = 2 * model.mesh.n_nodes
    return StepFields(
        step=r.step,
        load_factor=r.load_factor,
        newton_iterations=r.iterations,
        displacement=r.u[:n_std].reshape(-1, 2).copy(),
        stress=stress,
        stress_zz=szz,
        principal_stress=principal,
        fractures=fracture_fields(model.ip, r.contact, len(model.fractures), fluid),
        **extra,
    )


def fracture_properties(model) -> list[FractureProperties]:
    """What the derived quantities need of each fracture of ``model`` (a
    :class:`xfemslip.simulation.Model`), in position order: the arc-length
    range of its polyline as built (clipped to the domain), and the shear
    modulus and Poisson's ratio at its contact points, sorted by s as in
    :func:`fracture_fields`.

    The elastic constants at a contact point are the mean of those of the
    zones on its two faces (:func:`xfemslip.fem.poro.face_zones`, sampled
    FACE_OFFSET h_min off the fracture as the fluid pressure is): a fracture
    inside one unit has that unit's, a fault bounding the reservoir the mean
    of the reservoir's and the host's.
    """
    spec, ip = model.spec, model.ip
    zones = model.materials.zones if model.materials else build_zones(spec)
    E, nu = np.asarray(zones.E, float), np.asarray(zones.nu, float)
    eps = FACE_OFFSET * model.mesh.h_min
    plus, minus = face_zones(zones, ip, eps)
    mu = shear_modulus(E, nu)
    point_mu = 0.5 * (mu[plus] + mu[minus])
    point_nu = 0.5 * (nu[plus] + nu[minus])
    c = model.contact
    pn0 = c.pn0  # effective where there is pore pressure (make_contact_effective)
    pt0 = -c.kt * c.slip_reference
    state0 = np.full(c.n, STICK, np.int8)
    use0 = coulomb_utilisation(pn0, pt0, state0, c.friction, c.cohesion)
    use0 = np.where(pn0 > 0.0, 1.0, use0)  # in tension in situ: it opens
    breaks = model.breaks
    if breaks is None:
        breaks = loading_breaks(zones, model.fractures, model.mesh.box, eps)
    out = []
    for fi, fr in enumerate(model.fractures):
        m = np.nonzero(ip.fracture == fi)[0]
        m = m[np.argsort(ip.s[m], kind="stable")]
        ends = (float(fr.s_start[0]), float(fr.s_start[-1] + fr.length[-1]))
        cuts = np.asarray(breaks[fi], float)
        mids = np.concatenate([[ends[0]], cuts, [ends[1]]])
        xy, normal = fr.point_at(0.5 * (mids[1:] + mids[:-1]))
        out.append(
            FractureProperties(
                ends=ends,
                shear_modulus=point_mu[m].copy(),
                poisson_ratio=point_nu[m].copy(),
                in_situ_normal_traction=pn0[c.patch[m]].copy(),
                in_situ_shear_traction=pt0[c.patch[m]].copy(),
                in_situ_utilisation=use0[c.patch[m]].copy(),
                breaks=cuts,
                units_plus=tuple(zones.names[z] for z in zones.at(xy + eps * normal)),
                units_minus=tuple(zones.names[z] for z in zones.at(xy - eps * normal)),
            )
        )
    return out


def stress_for_paraview(stress, stress_zz) -> dict[str, np.ndarray]:
    """The element stress as ParaView reads it: ``stress_tensor`` (M, 6) in
    VTK's symmetric-tensor order XX, YY, ZZ, XY, YZ, XZ (so ParaView's tensor
    filters and its component names apply), ``mean_stress`` (M,) = trace / 3
    and ``von_mises`` (M,) = sqrt(3 J2) [Pa], tension positive.

    ``stress`` (M, 3) is sxx, syy, sxy; ``stress_zz`` (M,) the out-of-plane
    stress (zero in plane stress)."""
    sxx, syy, sxy = (np.asarray(stress, float)[:, k] for k in range(3))
    szz = np.asarray(stress_zz, float)
    zero = np.zeros_like(sxx)
    tensor = np.column_stack([sxx, syy, szz, sxy, zero, zero])
    mean = (sxx + syy + szz) / 3.0
    j2 = ((sxx - syy) ** 2 + (syy - szz) ** 2 + (szz - sxx) ** 2) / 6.0 + sxy**2
    return {
        "stress_tensor": tensor,
        "mean_stress": mean,
        "von_mises": np.sqrt(3.0 * j2),
    }


def first_non_finite(steps) -> tuple[int, str] | None:
    """(index, field name) of the first of ``steps`` (StepFields) holding NaN
    or inf, or None: such a step is never written."""
    for index, f in enumerate(steps):
        arrays = {
            "displacement": f.displacement,
            "stress": f.stress,
            "stress_zz": f.stress_zz,
            "principal_stress": f.principal_stress,
        }
        for i, fr in enumerate(f.fractures):
            for name in (
                "slip",
                "opening",
                "normal_traction",
                "shear_traction",
                "plastic_slip",
            ):
                arrays[f"fractures[{i}].{name}"] = getattr(fr, name)
        for name, value in arrays.items():
            if value is not None and not np.all(np.isfinite(value)):
                return index, name
    return None
