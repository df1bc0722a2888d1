"""``describe``: the resolved SI summary of a case printed by ``xfemslip check``."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from xfemslip import display
from xfemslip.case.friction import describe_strength
from xfemslip.case.options import SOLVER_OPTIONS
from xfemslip.case.specs import (
    EDGES,
    CaseSpec,
    EdgeSpec,
    FractureSpec,
    HydraulicSpec,
    MeshSpec,
    PermeabilitySpec,
    SolverSpec,
)
from xfemslip.case.tables import fmt
from xfemslip.contact.defaults import AUTO_PENALTY
from xfemslip.fem.zones import build_zones, in_situ_stress, initial_pressure
from xfemslip.reference.screen import coulomb_margin, plane_stresses


def _with_unit(value: Any, unit: str) -> str:
    """A value of a spec with its SI ``unit`` in engineering units (``0.5
    MPa``, ``5000 GPa/m``); no unit for dimensionless ("-") or unitless ("")
    values."""
    if not isinstance(value, int | float) or isinstance(value, bool):
        return str(value)
    if unit == "Pa":
        return display.pressure(value)
    if unit == "Pa/m":  # a penalty stiffness
        return f"{display.number(value / 1e9)} GPa/m"
    if unit == "m":
        return display.length(value)
    return f"{fmt(value)} {unit}" if unit not in ("", "-") else fmt(value)


def _describe_axis(coords: np.ndarray, label: str) -> str:
    """Element sizes along one axis: uniform or graded (min .. max)."""
    h = np.diff(coords)
    unit = MeshSpec.UNITS[label]
    if np.ptp(h) <= 1e-9 * h.max():
        return f"d{label} = {_with_unit(float(h[0]), unit)} (uniform)"
    return (
        f"d{label} = {display.number(float(h.min()))} .. "
        f"{_with_unit(float(h.max()), unit)} "
        "(graded)"
    )


def _describe_network_fracture(spec: FractureSpec) -> list[str]:
    """One line per [network] fracture: where from, ends, length, parameters."""
    p, units = spec.points, FractureSpec.UNITS
    length = float(np.hypot(*np.diff(p, axis=0).T).sum())
    params = ", ".join(
        f"{k} {fmt(getattr(spec, k))}" if getattr(spec, k) is not None else f"{k} auto"
        for k in ("friction", "cohesion", "kn", "kt")
    )
    if spec.weakening is not None:
        friction, cohesion = describe_strength(
            spec.friction, spec.cohesion, spec.weakening
        )
        params += f" (friction {friction}, cohesion {cohesion})"
    ends = (
        f"({fmt(float(p[0, 0]))}, {fmt(float(p[0, 1]))}) -> "
        + (f"{len(p) - 2} more -> " if len(p) > 2 else "")
        + f"({fmt(float(p[-1, 0]))}, {fmt(float(p[-1, 1]))})"
    )
    return [
        f"  [{spec.index}] {ends}, length {_with_unit(length, units['points'])}; "
        f"{params}; {spec.source}"
    ]


def _describe_fracture(spec: FractureSpec) -> list[str]:
    """Points, length, segment angles and contact parameters of one fracture."""
    if spec.source:
        return _describe_network_fracture(spec)
    p = spec.points
    seg = np.diff(p, axis=0)
    angles = np.degrees(np.arctan2(seg[:, 1], seg[:, 0]))
    units = FractureSpec.UNITS
    points = " -> ".join(f"({fmt(float(x))}, {fmt(float(y))})" for x, y in p)
    given = [
        f"{k} = {_with_unit(getattr(spec, k), units[k])}"
        if getattr(spec, k) is not None
        else f"{k} = {fmt(AUTO_PENALTY)} E/h (automatic)"
        for k in ("friction", "cohesion", "kn", "kt")
    ]
    if spec.weakening is not None:
        friction, cohesion = describe_strength(
            spec.friction, spec.cohesion, spec.weakening
        )
        given[:2] = [f"friction = {friction}", f"cohesion = {cohesion}"]
    params = ", ".join(given)
    tip = spec.tip + (
        f", radius {_with_unit(spec.tip_radius, units['tip_radius'])}"
        if spec.tip_radius is not None
        else (
            ", radius 0.1 x length within 4-6 tip-cell sizes (automatic)"
            if spec.tip == "branch"
            else ""
        )
    )
    return [
        f"  [{spec.index}] points [{units['points']}]: {points}",
        f"      length {_with_unit(float(np.hypot(*seg.T).sum()), units['points'])}, "
        f"angle {', '.join(fmt(float(a)) for a in angles)} deg",
        f"      {params}",
        f"      tip: {tip}",
    ]


def in_situ_margin(spec: CaseSpec, fracture: FractureSpec) -> tuple[float, float]:
    """(Coulomb margin [Pa], effective normal traction [Pa]) of the in-situ
    stress on the fracture's least stable segment.

    margin = c + f max(0, -sigma_n') - |tau| (xfemslip.reference.screen), with
    sigma_n' = sigma_n + p0 on the faces (Terzaghi); the segment with the
    smallest margin counts, and a segment in tension (sigma_n' > 0) before any
    other.  (nan, nan) without ``loading.initial_stress``.
    """
    stress = spec.loading.initial_stress
    if stress is None and spec.loading.in_situ is None:
        return math.nan, math.nan
    p0 = spec.pore_pressure.initial if spec.pore_pressure is not None else 0.0
    seg = np.diff(fracture.points, axis=0)
    angles = np.degrees(np.arctan2(seg[:, 1], seg[:, 0]))
    if stress is not None:
        sigma_n, tau = plane_stresses(stress, angles)
    else:  # varying with depth: at each segment's middle
        zones = build_zones(spec)
        mid = 0.5 * (fracture.points[1:] + fracture.points[:-1])
        zone = zones.at(mid)
        p0 = initial_pressure(spec, zones, mid, zone)
        S = in_situ_stress(spec, zones, mid, zone, p0)
        assert S is not None  # the case has an in-situ stress varying with depth
        pairs = [plane_stresses(S[k], angles[k]) for k in range(len(angles))]
        sigma_n = np.array([float(a) for a, _ in pairs])
        tau = np.array([float(b) for _, b in pairs])
    sigma_n = sigma_n + p0
    margin = coulomb_margin(sigma_n, tau, fracture.friction, fracture.cohesion)
    worst = int(np.argmax(sigma_n)) if np.any(sigma_n > 0.0) else int(np.argmin(margin))
    return float(margin[worst]), float(sigma_n[worst])


def _margin_text(spec: CaseSpec, fracture: FractureSpec, cp: bool = False) -> str:
    """What the in-situ stress does to the fracture, for ``check`` (a margin
    > 0 is stable in either sign convention)."""
    margin, sigma_n = in_situ_margin(spec, fracture)
    if math.isnan(margin):
        return ""
    if sigma_n > 0.0:
        return (
            f"in-situ: in tension across it (sigma_n' = {display.stress(sigma_n, cp)})"
            ": it opens in load step 1"
        )
    text = f"in-situ Coulomb margin {display.pressure(margin)}"
    if margin < 0.0:
        return text + (
            " (shear above the friction limit: the excess is released and the "
            "fracture slips in load step 1)"
        )
    return text + " (stable)"


def _describe_edge(name: str, edge: EdgeSpec, in_situ=False) -> str:
    """One edge's boundary condition (``in_situ``: the in-situ stress varies
    with depth, and a traction edge keeps its in-situ traction)."""
    if edge.kind == "traction" and in_situ:
        return f"  {name}: traction = its in-situ traction (unchanged)"
    if edge.kind == "traction":
        return f"  {name}: traction = loading.stress . n"
    if edge.kind == "free":
        note = " (not given in [boundary])" if edge.source == "default" else ""
        return f"  {name}: free (zero traction){note}"
    values = edge.values
    assert values is not None  # a displacement edge has its values
    parts = []
    for c, label in enumerate(("ux", "uy")):
        column = values[:, c]
        if np.isnan(column).all():
            extra = " (traction = loading.stress . n)" if edge.traction else ""
            parts.append(f"{label} free{extra}")
        elif np.ptp(column) == 0.0:
            parts.append(f"{label} = {display.slip(float(column[0]))}")
        else:
            parts.append(
                f"{label} = {display.number(float(column.min()) * 1e3)} .. "
                f"{display.slip(float(column.max()))}"
            )
    return (
        f"  {name}: displacement {', '.join(parts)} at {len(values)} nodes "
        f"[{edge.source}]"
    )


def _describe_stress(stress: tuple[float, float, float] | None, cp=False) -> str:
    """``(xx, yy, xy) = (...) MPa`` or none."""
    if stress is None:
        return "none"
    values = ", ".join(display.number(display.megapascals(v, cp)) for v in stress)
    return f"(xx, yy, xy) = ({values}) MPa"


def _describe_in_situ(spec: CaseSpec, cp: bool = False) -> str:
    """The in-situ stress: uniform, or how it grows with depth."""
    s = spec.loading.in_situ
    if s is None:
        return f"initial_stress {_describe_stress(spec.loading.initial_stress, cp)}"
    if s.gravity is not None:
        yy = (
            f"{display.stress(s.yy, cp)} {'+' if cp else '-'} g = {fmt(s.gravity)} "
            "m/s^2 x the rock above"
        )
    else:
        assert s.gradient_yy is not None  # gravity or a gradient (case/load.py)
        yy = (
            f"{display.stress(s.yy, cp)} + {display.gradient(s.gradient_yy, cp)} "
            "x depth"
        )
    if s.ratio_xx is None:
        assert s.xx is not None and s.gradient_xx is not None
        xx = (
            f"sigma_xx = {display.stress(s.xx, cp)} + "
            f"{display.gradient(s.gradient_xx, cp)} x depth"
        )
    elif isinstance(s.ratio_xx, str):
        xx = "sigma'_xx = nu / (1 - nu) sigma'_yy in each unit"
    else:
        xx = f"sigma'_xx = {fmt(s.ratio_xx)} sigma'_yy"
    return (
        f"initial_stress with depth below y = {display.length(s.datum)}: "
        f"sigma_yy = {yy}; {xx}; sigma_xy = {display.stress(s.xy, cp)}"
    )


def _describe_units(spec: CaseSpec, cp: bool = False) -> list[str]:
    """One line per rock unit of [[units]]."""
    lines: list[str] = []
    if spec.reservoir is not None or not spec.units:
        return lines
    zones = build_zones(spec)
    for unit, zs in zip(spec.units, zones.unit_zones, strict=True):
        r = unit.region
        if r.kind == "layer":
            base, top = r.horizons
            where = f"layer {fmt(base)} < y < {fmt(top)} m"
        elif r.kind == "offset":
            base, top = r.horizons
            where = (
                f"layer {fmt(base)} < y < {fmt(top)} m displaced "
                f"{fmt(r.throw)} m down on the {r.lowered} of fractures[{r.fracture}]"
            )
        elif r.kind == "polygon":
            where = f"polygon of {len(r.vertices)} vertices"
        else:
            where = f"{len(r.box_array)} box(es)"
        dp = ", ".join(
            f"{zones.names[z]} {display.pressure_change(float(zones.change[z]), cp)}"
            for z in zs
        )
        lines.append(
            f"unit {unit.name!r}: {where}; E = {display.modulus(unit.E)}, nu = "
            f"{fmt(unit.nu)}, biot {fmt(float(zones.biot[zs[0]]))}; "
            f"pore-pressure {display.change_label(cp).replace('dp', 'change')} {dp}"
        )
    return lines


def _describe_pore(spec: CaseSpec, cp: bool = False) -> list[str]:
    """[pore_pressure] and [reservoir] lines (none when absent)."""
    lines = []
    p = spec.pore_pressure
    if p is not None:
        where = {"reservoir": "the reservoir", "all": "the whole model"}.get(
            p.region, f"unit {p.region!r}"
        )
        grad = (
            f" + {display.gradient(p.gradient)} x depth below y = "
            f"{display.length(p.datum)}"
            if p.gradient
            else ""
        )
        if p.field is not None:
            change = f"change from {_describe_field(p.field)}"
        else:
            assert p.change is not None  # without a field, a uniform change
            change = (
                f"depletion {display.pressure_change(p.change, cp)} (a drop > 0)"
                if cp
                else f"change {display.pressure_change(p.change)} (< 0 = depletion)"
            )
        lines.append(
            f"pore pressure: initial {display.pressure(p.initial)}{grad}, {change} "
            f"over the load steps, Biot coefficient "
            f"{fmt(p.biot)}, acting in {where}; "
            "effective stress in the bulk (Biot) and on the fractures (Terzaghi)"
        )
    lines += _describe_units(spec, cp)
    r = spec.reservoir
    if r is not None:
        rows = r.boxes if r.polygon is None else r.polygon
        where = "box(es)" if r.polygon is None else "polygon"
        shapes = "; ".join(
            "[" + ", ".join(fmt(float(v)) for v in b) + "]" for b in rows
        )
        lines.append(
            f"reservoir: E = {display.modulus(r.E)}, nu = {fmt(r.nu)} in {where} "
            f"{shapes} m (cells whose centre is inside); [material] is the host rock"
        )
    return lines


def _describe_events(spec: CaseSpec) -> str:
    """The out-of-plane extent W that moment magnitudes use."""
    extent = spec.events.extent if spec.events is not None else None
    if extent is None:
        return (
            "events: moment magnitudes for W = each fracture's slipping length "
            "(no events.extent)"
        )
    return f"events: moment magnitudes for an out-of-plane extent W = {fmt(extent)} m"


def _law_text(law) -> str:
    """One fracture's aperture law, keys with their units."""
    units = HydraulicSpec.UNITS
    parts = [f"aperture = {_with_unit(law.aperture, units['aperture'])}"]
    if law.dilation_angle:
        cap = (
            "no cap"
            if math.isinf(law.dilation_slip)
            else f"up to {_with_unit(law.dilation_slip, units['dilation_slip'])}"
        )
        parts.append(f"dilation_angle = {fmt(law.dilation_angle)} deg ({cap})")
    if law.max_closure:
        parts.append(
            f"max_closure = {_with_unit(law.max_closure, units['max_closure'])}, "
            f"normal_stiffness = "
            f"{_with_unit(law.normal_stiffness, units['normal_stiffness'])}"
        )
    return ", ".join(parts)


def _describe_permeability(spec: CaseSpec) -> list[str]:
    """[permeability]: the block, the matrix and the law of each fracture
    (one line per distinct law)."""
    p = spec.permeability
    if p is None:
        return []
    x0, y0, x1, y1 = p.block
    where = "" if p.block_given else " (the domain)"
    lines = [
        f"permeability: Oda tensor of the block [{fmt(x0)}, {fmt(x1)}] x "
        f"[{fmt(y0)}, {fmt(y1)}] m{where}, matrix "
        f"{_with_unit(p.matrix, PermeabilitySpec.UNITS['matrix'])}"
    ]
    laws: dict = {}
    for fracture, law in zip(spec.fractures, p.laws, strict=True):
        laws.setdefault(law, []).append(fracture.index)
    for law, indices in laws.items():
        which = (
            "every fracture"
            if len(laws) == 1
            else "fracture " + ", ".join(str(i) for i in indices)
        )
        lines.append(f"  {which}: {_law_text(law)}")
    return lines


def _network_count(spec: CaseSpec) -> str:
    """`` ([[fractures]] 1, network.file 3, network.generate 40)`` or ""."""
    sources = [
        f.source.split(" ", 1)[0] if f.source else "[[fractures]]"
        for f in spec.fractures
    ]
    if all(s == "[[fractures]]" for s in sources):
        return ""
    counts = {s: sources.count(s) for s in dict.fromkeys(sources)}
    return " (" + ", ".join(f"{s} {n}" for s, n in counts.items()) + ")"


def _describe_field(f) -> str:
    """``dp.csv (columns dp1, dp2: a regular grid of ...; outside: error)``."""
    outside = f.outside if isinstance(f.outside, str) else display.pressure(f.outside)
    return (
        f"{f.file} (columns {', '.join(f.columns)}: {f.field.description}; "
        f"outside: {outside})"
    )


def _describe_grading(g) -> str:
    """``; graded from size 6.25 m, growth 1.2, max_size 100 m`` or ""."""
    if g is None:
        return ""
    largest = (
        "no max_size" if g.max_size == float("inf") else f"max_size {fmt(g.max_size)} m"
    )
    refine = f", {len(g.refine)} refine boxes" if len(g.refine) else ""
    return (
        f"; graded from size {fmt(g.size)} m, growth {fmt(g.growth)}, {largest}{refine}"
    )


def describe(spec: CaseSpec, compression_positive: bool = False) -> str:
    """Human-readable summary of a resolved case in engineering units (MPa,
    GPa, MPa/km, m, mm), stresses tension positive unless
    ``compression_positive`` (:mod:`xfemslip.display`).

    Printed by ``xfemslip check``: domain, mesh (element sizes, graded or not),
    material, fractures, loading, every edge's condition (edges not given in the
    file are reported as free), solver options (from SOLVER_OPTIONS) and output.
    """

    (x0, y0), (w, h) = spec.origin, spec.size
    nx, ny = spec.mesh.x.size - 1, spec.mesh.y.size - 1
    m = spec.material
    cp = compression_positive
    lines = [
        f"case {spec.name!r} ({spec.path})",
        display.convention(cp),
        f"domain: [{fmt(x0)}, {fmt(x0 + w)}] x [{fmt(y0)}, {fmt(y0 + h)}] m "
        f"(size {fmt(w)} x {fmt(h)} m)",
        f"mesh: {nx} x {ny} Q4 elements, {(nx + 1) * (ny + 1)} nodes; "
        f"{_describe_axis(spec.mesh.x, 'x')}; {_describe_axis(spec.mesh.y, 'y')}"
        f"{_describe_grading(spec.mesh.grading)}",
        f"material: E = {display.modulus(m.E)}, nu = {fmt(m.nu)}, {m.model}",
        f"fractures: {len(spec.fractures)}{_network_count(spec)}",
    ]
    for fracture in spec.fractures:
        lines += _describe_fracture(fracture)
        margin = _margin_text(spec, fracture, cp)
        if margin:
            lines[-1] += f"; {margin}" if fracture.source else ""
            lines += [] if fracture.source else [f"      {margin}"]
    steps = spec.loading.steps
    lines += [
        f"loading: stress {_describe_stress(spec.loading.stress, cp)}; "
        f"{_describe_in_situ(spec, cp)}; "
        f"{steps} step{'' if steps == 1 else 's'}",
        "boundary:",
    ]
    depth = spec.loading.in_situ is not None
    lines += [_describe_edge(e, getattr(spec.boundary, e), depth) for e in EDGES]
    lines += _describe_pore(spec, cp)
    lines.append(_describe_events(spec))
    lines += _describe_permeability(spec)
    lines.append("solver:")
    for option in SOLVER_OPTIONS:
        value = getattr(spec.solver, option.name)
        lines.append(
            f"  {option.name} = {_with_unit(value, SolverSpec.UNITS[option.name])}"
            f"  ({option.doc})"
        )
    lines.append(f"output: {spec.output.directory} ({', '.join(spec.output.formats)})")
    return "\n".join(lines)
