"""Closed-form critical pore-pressure change of many samples of a case.

The Mohr-Coulomb screen of :mod:`xfemslip.reference.screen`, vectorised over
samples x fracture segments, along the stress path the case's depletion
follows.  :func:`stress_path` states which path it assumes, read from the
case's ``[pore_pressure]``, ``[boundary]``, ``[reservoir]`` and loading:

- **uniaxial strain** ("uniaxial_strain"): rollers on the left and right
  edges (u_x = 0, u_y free), u_y = 0 at the bottom, a traction top edge, plane
  strain; the pore pressure changes everywhere, or in a ``[reservoir]`` that is
  one box across the whole width (a laterally confined layer).  Inside the
  layer where the pressure changes by dp (Biot alpha, Poisson nu of the layer)
  Delta sigma_xx = -alpha (1 - 2 nu) / (1 - nu) dp + nu / (1 - nu) Delta t_y,
  Delta sigma_yy = Delta t_y (the top traction's change: zero under constant
  overburden), and the fracture's fluid pressure changes by dp; elsewhere the
  pressure does not change and Delta sigma_xx = nu / (1 - nu) Delta t_y
  (closed_form_depletion, eq. 1: exact away from fractures for a laterally
  infinite layer);
- **constant total stress** ("constant_total_stress"): every edge a traction
  edge, or a roller (u_n = 0) on at most one edge of each direction, so the
  body expands freely: the total stress follows the boundary tractions,
  sigma = initial_stress + lambda (stress - initial_stress), and the pore
  pressure (``region = "all"``, no ``[reservoir]``) changes by dp everywhere.

The load factor is lambda = dp / pore_pressure.change (the case's steps
apply both proportionally).  Every other set-up (a reservoir inclusion, a
polygon, a prescribed displacement ramp, a shear load on the top edge between
rollers, free edges, plane stress with rollers) is refused with the reason:
its stress path needs the full solve (``evaluate = "xfem"``).

Along the path each segment part sees sigma_n' = A0 + A1 dp and
tau = B0 + B1 dp (sigma_n' = sigma_n + p, Terzaghi on the fracture; tension
positive); its critical change is the first dp, in the direction of the
case's change, at which it slips (|tau| = c - f sigma_n', the contact law of
xfemslip) or opens (sigma_n' = 0), within the pore pressures that can be
reached (p >= 0 under depletion): :func:`xfemslip.reference.onset.onset`,
the one law of the screen, the closed forms and this module.  A part
already at or beyond its limit slips at dp = 0 (as ``deplete`` reports a
fracture slipping in situ).  A fracture's critical change is the first of
its parts'.  The closed form is exact for
a fracture that does not disturb the stress before it slips (isolated, or
stuck fractures far apart); interaction and stress transfer around a
reservoir that is not a full-width layer are what the xfem path adds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from xfemslip.reference.onset import (
    INJECTION,
    Onset,
    onset,
    plane_directions,
    plane_tractions,
)
from xfemslip.reference.screen import (
    effective_stress,
    plane_stresses,
    pressure_to_slip,
)

UNIAXIAL = "uniaxial_strain"
CONSTANT_TOTAL = "constant_total_stress"
STRESS_KEYS = ("xx", "yy", "xy")
# Case keys whose values the closed form reads, with the rule a sample must
# meet (the case format's own bounds); key names end the key path.
FRACTURE_KEYS = {
    "friction": (0.0, math.inf, False),
    "cohesion": (0.0, math.inf, False),
    "angle": (-math.inf, math.inf, False),
    "length": (0.0, math.inf, True),
}
# Keys the closed form does not depend on: stiffness sets how much a fracture
# slips, not when a stuck isolated fracture starts to (the stress path of a
# uniform layer does not depend on E).
INERT = ("material.E", "reservoir.E")
INERT_FRACTURE = ("kn", "kt")


@dataclass(frozen=True)
class StressPath:
    """The stress path the screen assumes for a case."""

    kind: str  # UNIAXIAL | CONSTANT_TOTAL
    layer: tuple[float, float] | None  # (y0, y1) of the reservoir layer [m]
    pressure_in_layer_only: bool  # region = "reservoir"
    description: str  # one sentence, printed with the results


def _roller(edge, component: int) -> bool:
    """A displacement edge fixing only ``component`` (0 = x, 1 = y) at 0."""
    if edge.kind != "displacement" or edge.values is None:
        return False
    fixed = edge.values[:, component]
    free = edge.values[:, 1 - component]
    return bool(np.all(fixed == 0.0) and np.all(np.isnan(free)))


def _load_change(spec) -> np.ndarray:
    """stress - initial_stress [Pa] (xx, yy, xy) of the traction edges."""
    final = spec.loading.stress
    start = spec.loading.initial_stress or (0.0, 0.0, 0.0)
    if final is None:
        return np.zeros(3)
    return np.asarray(final, float) - np.asarray(start, float)


def stress_path(spec) -> tuple[StressPath | None, str]:
    """(the path the screen assumes for ``spec``, "") or (None, why it cannot)."""
    pore = spec.pore_pressure
    if pore is not None and pore.field is not None:
        return (
            None,
            "the pore-pressure change comes from a file ([pore_pressure.field])",
        )
    if pore is None or pore.change == 0.0:
        return None, "the case has no [pore_pressure] change to follow"
    if spec.loading.in_situ is not None or pore.gradient != 0.0:
        return None, (
            "the in-situ state varies with depth: the closed form follows one "
            "uniform state"
        )
    if spec.units and spec.reservoir is None:
        return None, (
            "the case has [[units]]: the closed form follows at most one "
            "reservoir layer ([reservoir])"
        )
    b = spec.boundary
    edges = {"left": b.left, "right": b.right, "bottom": b.bottom, "top": b.top}
    bad = [
        n
        for n, e in edges.items()
        if e.kind == "free"
        or (
            e.kind == "displacement"
            and not _roller(e, 0 if n in ("left", "right") else 1)
        )
    ]
    if bad:
        return None, (
            f"boundary.{bad[0]} is neither a traction edge nor a roller at u_n = 0 "
            "(a free edge or a prescribed displacement makes the stress path "
            "non-uniform)"
        )
    side_rollers = [n for n in ("left", "right") if edges[n].kind == "displacement"]
    if len(side_rollers) == 2:
        return _uniaxial(spec, edges)
    return _constant_total(spec)


def _uniaxial(spec, edges) -> tuple[StressPath | None, str]:
    """Rollers on both sides: a laterally confined layer (or refused)."""
    pore, res = spec.pore_pressure, spec.reservoir
    if edges["bottom"].kind != "displacement" or edges["top"].kind != "traction":
        return None, (
            "rollers on both sides need u_y = 0 at the bottom and a traction top "
            "edge for the uniaxial-strain path"
        )
    if spec.material.model != "plane_strain":
        return None, "the uniaxial-strain path is a plane-strain closed form"
    if _load_change(spec)[2] != 0.0:
        return None, (
            "a change of the top edge's shear load between rollers is not "
            "laterally uniform"
        )
    layer = None
    if res is not None:
        x0, x1 = spec.box.x0, spec.box.x1
        if res.polygon is not None or len(res.boxes) != 1:
            return None, "the [reservoir] is not one box (a layer)"
        bx0, by0, bx1, by1 = res.boxes[0]
        if bx0 > x0 or bx1 < x1:
            return None, (
                "the [reservoir] box does not span the whole width: the stress "
                "around a reservoir of finite extent needs the full solve"
            )
        layer = (float(by0), float(by1))
    if pore.region == "reservoir":
        assert layer is not None  # region "reservoir" needs a [reservoir]
        where = f"in the reservoir layer {layer[0]:g} m < y < {layer[1]:g} m"
    else:
        where = "everywhere"
    text = (
        "stress path: uniaxial strain of a laterally confined layer with "
        "constant overburden (rollers on the sides, u_y = 0 at the bottom); "
        f"the pore pressure changes {where}"
    )
    return StressPath(UNIAXIAL, layer, pore.region == "reservoir", text), ""


def _constant_total(spec) -> tuple[StressPath | None, str]:
    """Free expansion: the total stress follows the boundary tractions."""
    if spec.pore_pressure.region != "all":
        return None, (
            'pore_pressure.region = "reservoir" without lateral rollers: the '
            "stress around the reservoir needs the full solve"
        )
    if spec.reservoir is not None:
        return None, (
            "a [reservoir] of other elastic constants under a uniform pressure "
            "change stresses its surroundings: the full solve is needed"
        )
    b = spec.boundary
    if _roller_count(b.top, b.bottom) > 1 or _roller_count(b.left, b.right) > 1:
        return None, "two opposite rollers confine the body"
    if _load_change(spec)[2] != 0.0 and any(
        e.kind == "displacement" and not e.traction
        for e in (b.left, b.right, b.top, b.bottom)
    ):
        return None, "a shear load change with a roller edge that carries no shear"
    text = (
        "stress path: constant total stress (the body expands freely; the "
        "total stress follows the boundary tractions) with the pore pressure "
        "changing everywhere"
    )
    return StressPath(CONSTANT_TOTAL, None, False, text), ""


def _roller_count(*edges) -> int:
    return sum(e.kind == "displacement" for e in edges)


# --------------------------------------------------------------------------- #
# Samples -> per-fracture critical change
# --------------------------------------------------------------------------- #


def screen_key_problem(spec, key: str) -> str:
    """Why the screen cannot take ``key`` as an input, or ""."""
    from xfemslip.studies.vary import key_parts

    parts = key_parts(key)
    if key in INERT or key in ("pore_pressure.initial", "pore_pressure.biot"):
        return ""
    if key in ("material.nu", "reservoir.nu"):
        return ""
    if (
        len(parts) == 3
        and parts[0] == "loading"
        and parts[1] in ("initial_stress", "stress")
        and parts[2] in STRESS_KEYS
    ):
        if parts[1] == "initial_stress" and spec.loading.initial_stress is None:
            return "the base case has no loading.initial_stress to vary"
        return ""
    if len(parts) == 3 and parts[0] == "fractures" and isinstance(parts[1], int):
        name = parts[2]
        if name in INERT_FRACTURE or name in ("friction", "cohesion"):
            return ""
        if name in ("angle", "length"):
            return ""  # center form checked against the base document
    return (
        "the closed-form screen does not read this key (it reads friction, "
        "cohesion, angle and length of fractures, loading stresses, "
        'pore_pressure.initial/biot and nu); use evaluate = "xfem"'
    )


def _vector(base: tuple | None, values: dict, prefix: str, n: int) -> np.ndarray:
    """(n, 3) stress (xx, yy, xy) [Pa]: the base with sampled components."""
    out = np.tile(np.asarray(base if base is not None else (0.0,) * 3, float), (n, 1))
    for j, comp in enumerate(STRESS_KEYS):
        key = f"{prefix}.{comp}"
        if key in values:
            out[:, j] = values[key]
    return out


@dataclass(frozen=True)
class PathStart:
    """Where a stress path starts and how its load grows, per sample (n,)."""

    stress: np.ndarray  # (n, 3) in-situ total stress (xx, yy, xy) [Pa]
    load_rate: np.ndarray  # (n, 3) boundary load change per unit dp [-]
    pressure: np.ndarray  # (n,) initial pore pressure p0 [Pa]
    biot: np.ndarray  # (n,) [-]
    nu_layer: np.ndarray  # (n,) Poisson ratio where the pressure changes
    nu_host: np.ndarray  # (n,)
    direction: float  # DEPLETION (-1) or INJECTION (+1): the sign of the change


def path_start(spec, values: dict | None = None, n: int = 1) -> PathStart:
    """The start of ``spec``'s stress path, with the sampled ``values``
    ({key path: (n,) array}) in place of the case's own."""
    v = values or {}
    pore = spec.pore_pressure
    initial = spec.loading.initial_stress
    S0 = _vector(initial, v, "loading.initial_stress", n)  # None: from zero
    S1 = _vector(spec.loading.stress or initial, v, "loading.stress", n)
    nu_host = v.get("material.nu", spec.material.nu)
    nu_layer = (
        v.get("reservoir.nu", spec.reservoir.nu)
        if spec.reservoir is not None
        else nu_host
    )
    return PathStart(
        stress=S0,
        load_rate=(S1 - S0) / pore.change,
        pressure=np.broadcast_to(v.get("pore_pressure.initial", pore.initial), (n,)),
        biot=np.broadcast_to(v.get("pore_pressure.biot", pore.biot), (n,)),
        nu_layer=np.broadcast_to(nu_layer, (n,)),
        nu_host=np.broadcast_to(nu_host, (n,)),
        direction=math.copysign(1.0, pore.change),
    )


def segment_onset(path: StressPath, start: PathStart, P0, P1, friction, cohesion):
    """:func:`xfemslip.reference.onset.onset` of a straight segment P0 -> P1
    ((n, 2) [m]) along the path: the first of its parts (in the reservoir
    layer, outside it) to reach its limit.  Its plane tractions are
    sigma_n' = n.S.n + p, tau = t.S.n (Terzaghi on the fracture), with S and
    p linear in dp along the path (:func:`_parts`)."""
    d = np.asarray(P1, float) - np.asarray(P0, float)
    norm = np.hypot(d[:, 0], d[:, 1])
    ct, st = d[:, 0] / norm, d[:, 1] / norm
    A0, B0 = plane_tractions(start.stress, ct, st)
    inside, outside = _layer_parts(path, P0, P1)
    change = np.full(d.shape[0], np.nan)
    opens = np.zeros(d.shape[0], bool)
    for present, rate, fluid in _parts(path, start):
        A1, B1 = plane_tractions(rate, ct, st)
        part = onset(
            (A0 + start.pressure, A1 + fluid),
            (B0, B1),
            friction,
            cohesion,
            start.direction,
            start.pressure,
        )
        mask = inside if present else outside
        better = mask & ~np.isnan(part.change)
        better &= np.isnan(change) | (np.abs(part.change) < np.abs(change))
        change = np.where(better, part.change, change)
        opens = np.where(better, part.opens, opens)
    return Onset(change, opens)


def _segments(spec, document: dict, values: dict, n: int) -> list:
    """[(fracture position, P0 (n, 2), P1 (n, 2))] of every straight segment.

    A center-form fracture whose ``angle`` or ``length`` is an input gets its
    end points per sample (case-format: center -/+ length/2 (cos, sin))."""
    out = []
    items = document.get("fractures", [])
    for pos, fracture in enumerate(spec.fractures):
        keys = {f"fractures[{pos}].{k}" for k in ("angle", "length")} & set(values)
        if keys and pos < len(items) and "center" in items[pos]:
            item = items[pos]
            angle = values.get(f"fractures[{pos}].angle", float(item["angle"]))
            length = values.get(f"fractures[{pos}].length", float(item["length"]))
            c, s = plane_directions(np.broadcast_to(angle, (n,)))
            half = 0.5 * np.broadcast_to(length, (n,))
            centre = np.asarray(item["center"], float)
            d = np.column_stack([c, s]) * half[:, None]
            out.append((pos, centre - d, centre + d))
            continue
        pts = np.asarray(fracture.points, float)
        out.extend(
            (pos, np.tile(pts[k], (n, 1)), np.tile(pts[k + 1], (n, 1)))
            for k in range(len(pts) - 1)
        )
    return out


def _layer_parts(path: StressPath, P0, P1):
    """(in the layer, outside it): whether each sample's segment has a part of
    positive length there (all in / none out without a layer)."""
    n = P0.shape[0]
    if path.layer is None:
        return np.ones(n, bool), np.zeros(n, bool)
    y0, y1 = path.layer
    lo, hi = np.minimum(P0[:, 1], P1[:, 1]), np.maximum(P0[:, 1], P1[:, 1])
    flat = lo == hi
    inside = np.where(
        flat, (lo > y0) & (lo < y1), np.minimum(hi, y1) > np.maximum(lo, y0)
    )
    outside = np.where(flat, ~((lo > y0) & (lo < y1)), (lo < y0) | (hi > y1))
    return inside, outside


def critical_changes(spec, document, path: StressPath, keys, values) -> np.ndarray:
    """(n, n_fractures) critical pore-pressure change [Pa] of every sample:
    the first of a fracture's segments to reach its limit
    (:func:`segment_onset`).

    spec : the base CaseSpec; document : the base case's TOML tables;
    keys : input key paths; values : (n, len(keys)) sampled values.
    """
    n = values.shape[0]
    v = {k: values[:, j] for j, k in enumerate(keys)}
    start = path_start(spec, v, n)
    out = np.full((n, len(spec.fractures)), np.nan)
    for pos, P0, P1 in _segments(spec, document, v, n):
        fr = spec.fractures[pos]
        f = v.get(f"fractures[{pos}].friction", fr.friction)
        c = v.get(f"fractures[{pos}].cohesion", fr.cohesion)
        dp = segment_onset(path, start, P0, P1, f, c).change
        better = np.isnan(out[:, pos]) | (np.abs(dp) < np.abs(out[:, pos]))
        out[:, pos] = np.where(~np.isnan(dp) & better, dp, out[:, pos])
    return out


def _parts(path: StressPath, start: PathStart):
    """(in the layer?, d sigma / d dp (n, 3), d p_fracture / d dp) of each part."""
    dS, biot = start.load_rate, start.biot
    n = dS.shape[0]
    if path.kind == CONSTANT_TOTAL:
        return [(True, dS, 1.0)]

    def uniaxial(nu, pressure: bool):
        k = nu / (1.0 - nu)
        xx = k * dS[:, 1] - (biot * (1.0 - 2.0 * nu) / (1.0 - nu) if pressure else 0.0)
        return np.column_stack([xx, dS[:, 1], np.zeros(n)])

    layer_rate = uniaxial(start.nu_layer, True)
    host_pressure = not path.pressure_in_layer_only
    parts = [(True, layer_rate, 1.0)]
    if path.layer is not None:
        parts.append(
            (False, uniaxial(start.nu_host, host_pressure), float(host_pressure))
        )
    return parts


# --------------------------------------------------------------------------- #
# xfemslip screen on a case
# --------------------------------------------------------------------------- #


@dataclass(frozen=True)
class ScreenPlan:
    """What ``xfemslip screen`` screens: the in-situ state, the path and the
    pore-pressure change at which each plane reaches its limit."""

    stress: tuple[float, float, float]  # in-situ total stress [Pa]
    pore_pressure: float  # in-situ pore pressure [Pa]
    onsets: list  # one Onset (of one plane) per plane
    text: str  # the sentence naming the stress path, printed with the report
    refused: str  # why the case's own path is not followed ("": it is, or none)


def _constant_total_text(direction: float) -> str:
    way = "drops" if direction < 0 else "rises"
    return (
        "stress path: constant total stress (the total stress stays as given "
        f"while the pore pressure {way}: the dp to slip below)"
    )


def screen_plan(spec, planes, stress=None, pore_pressure=None) -> ScreenPlan:
    """The plan of ``xfemslip screen`` for ``spec`` (a CaseSpec or None).

    planes : [(label, theta [deg], f, c, ends)] with ends = (P0, P1) [m] of a
    case's segment, or None for a plane given by its angle (screened inside
    the layer whose pressure changes).  ``stress`` (xx, yy, xy) and
    ``pore_pressure`` replace the case's in-situ values.  A case with a
    ``[pore_pressure]`` change is followed along its own stress path
    (:func:`stress_path`) in the direction of the change; one whose path
    needs the full solve, and a stress without a case, keep the total stress
    (:func:`xfemslip.reference.screen.pressure_to_slip`).
    """
    pore = None if spec is None else spec.pore_pressure
    if pore is None or pore.change in (None, 0.0):
        p = (
            pore_pressure
            if pore_pressure is not None
            else (pore.initial if pore else 0.0)
        )
        S = tuple(
            stress
            if stress is not None
            else spec.loading.stress or spec.loading.initial_stress
        )
        return ScreenPlan(
            S, p, _total(S, p, planes, INJECTION), _constant_total_text(1.0), ""
        )
    path, why = stress_path(spec)
    start = path_start(spec)
    if stress is not None:
        start = replace(start, stress=np.asarray([stress], float))
    if pore_pressure is not None:
        start = replace(start, pressure=np.asarray([pore_pressure], float))
    p = float(start.pressure[0])
    if path is None:
        S = tuple(stress or spec.loading.initial_stress or spec.loading.stress)
        onsets = _total(S, p, planes, start.direction)
        return ScreenPlan(S, p, onsets, _constant_total_text(start.direction), why)
    onsets = []
    for _, theta, f, c, ends in planes:
        P0, P1 = _plane_ends(path, theta, ends)
        onsets.append(segment_onset(path, start, P0, P1, f, c))
    S = tuple(float(v) for v in start.stress[0])
    way = "depletion (dp < 0)" if start.direction < 0 else "injection (dp > 0)"
    return ScreenPlan(
        S, p, onsets, f"{path.description}; the dp to slip below: {way}", ""
    )


def _total(stress, p, planes, direction) -> list:
    """Onsets of the planes at constant total stress."""
    eff = effective_stress(stress, p)
    out = []
    for _, theta, f, c, _ in planes:
        sn, tau = plane_stresses(eff, theta)
        out.append(pressure_to_slip(sn, tau, f, c, direction, p))
    return out


def _plane_ends(path: StressPath, theta: float, ends):
    """(P0, P1) (1, 2) of a case's segment, or of a short segment at theta
    in the middle of the layer whose pressure changes."""
    if ends is not None:
        return np.asarray([ends[0]], float), np.asarray([ends[1]], float)
    y0, y1 = path.layer if path.layer is not None else (0.0, 1.0)
    c, s = plane_directions(theta)
    half = 0.25 * (y1 - y0) * np.array([c, s])
    mid = np.array([0.0, 0.5 * (y0 + y1)])
    return (mid - half)[None, :], (mid + half)[None, :]


def sample_problems(keys, values) -> list[str]:
    """Per sample, why the case format refuses one of its values ("" when
    none): each input against the rule of its key
    (:func:`xfemslip.case.load.value_rule`, the rule the case reader checks),
    and a value that is not finite (a draw that overflowed)."""
    from xfemslip.case.load import value_rule
    from xfemslip.case.tables import range_problem

    reasons = [""] * values.shape[0]
    for j, key in enumerate(keys):
        x = values[:, j]
        rule = value_rule(key)
        bad = ~np.isfinite(x)
        if rule is not None:
            if rule.lo is not None:
                bad |= (x <= rule.lo) if rule.lo_open else (x < rule.lo)
            if rule.hi is not None:
                bad |= (x >= rule.hi) if rule.hi_open else (x > rule.hi)
        for i in np.flatnonzero(bad):
            if not reasons[i]:
                why = (
                    range_problem(float(x[i]), rule, key.rsplit(".", 1)[-1])
                    if np.isfinite(x[i])
                    else f"must be finite, got {float(x[i])!r}"
                )
                reasons[i] = f"{key}: {why}"
    return reasons
