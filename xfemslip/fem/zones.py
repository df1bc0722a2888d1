"""The rock at a point: zones, their constants and the in-situ state.

One place for "which rock is here": the host (zone 0, ``[material]``) and
each rock unit of the case (:class:`xfemslip.case.specs.UnitSpec`: a layer,
a layer displaced by a fault, boxes or a polygon), a displaced layer with a
pore-pressure change per side of its fault split into its two compartments.
Units later in the case override earlier ones where they overlap.  The
solver (stiffness, Biot load, fluid pressure on the fractures), the
post-processing and the plots all ask :meth:`Zones.at`.

In-situ state (tension positive, depth d = datum - y):

- the initial pore pressure p0 = initial + gradient d + the unit's
  overpressure (``[pore_pressure]``);
- the vertical total stress sigma_yy = yy + gradient_yy d, or with
  ``gravity`` yy - g int_y^datum rho(x, y') dy', the weight of the rock
  above (the zones' densities, integrated exactly: rho is constant between
  the heights where a vertical line meets a zone boundary, so the integral
  is piecewise linear between them);
- the horizontal total stress sigma_xx = xx + gradient_xx d, or from a ratio
  of effective stresses sigma'_xx = K sigma'_yy (sigma' = sigma + alpha p0,
  alpha of the zone), K a number or "uniaxial_strain" = nu / (1 - nu) of the
  zone (a laterally confined elastic layer loaded by its weight);
- sigma_xy uniform.

With horizontal layers this state is in equilibrium with the weight of the
rock (d sigma_yy / dy = rho g, and sigma_xx depends on y only); the model
starts in equilibrium with it and every displacement is relative to it (the
solver sees the changes only).  Where units end sideways (a displaced layer,
a polygon) sigma_xx also changes sideways, and the state is in equilibrium
with a body force that differs from gravity there; the changes the solver
computes do not depend on it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from xfemslip.geometry.box import Box
from xfemslip.geometry.regions import edges, fault_side, in_region

__all__ = [
    "FLUID_RULES",
    "HOST",
    "Zones",
    "build_zones",
    "fluid_value",
    "in_situ_stress",
    "initial_pressure",
    "loading_breaks",
    "overburden",
]

HOST = 0
FLUID_RULES = ("mean", "higher", "lower")


@dataclass(frozen=True)
class Zones:
    """The host and the units' zones of a case, with their constants.

    Arrays (k,) by zone, zone 0 the host.  ``unit_zones[u]`` are the zones of
    unit u: one, or (left, right) for a displaced layer with a change per
    side.
    """

    names: tuple[str, ...]
    E: np.ndarray  # [Pa]
    nu: np.ndarray  # [-]
    biot: np.ndarray  # [-]
    density: np.ndarray  # [kg/m^3]; NaN where the case gives none
    change: np.ndarray  # pore-pressure change at load factor 1 [Pa]
    overpressure: np.ndarray  # added to the initial pore pressure [Pa]
    units: tuple = ()  # the UnitSpecs
    unit_zones: tuple[tuple[int, ...], ...] = ()

    @property
    def n(self) -> int:
        return self.E.size

    def at(self, xy: np.ndarray) -> np.ndarray:
        """(n,) int64 zone of each point (n, 2) [m]."""
        xy = np.asarray(xy, float).reshape(-1, 2)
        zone = np.full(xy.shape[0], HOST, np.int64)
        for unit, zs in zip(self.units, self.unit_zones, strict=True):
            inside = in_region(xy, unit.region)
            if len(zs) == 1:
                zone[inside] = zs[0]
            elif inside.any():
                right = fault_side(xy[inside], unit.region.fault)
                zone[inside] = np.where(right, zs[1], zs[0])
        return zone


def _unit_change(unit, pore) -> float:
    """The pore-pressure change of a unit without sides [Pa]."""
    if unit.change is not None:
        return unit.change
    if (
        pore is not None
        and pore.change is not None
        and pore.region
        in (
            "all",
            unit.name,
        )
    ):
        return pore.change
    return 0.0


def build_zones(spec) -> Zones:
    """The zones of a validated case."""
    m, pore = spec.material, spec.pore_pressure
    biot = pore.biot if pore is not None else 1.0
    density = m.density if m.density is not None else np.nan
    rows = [
        (
            "host",
            m.E,
            m.nu,
            biot,
            density,
            pore.change
            if pore is not None and pore.change is not None and pore.region == "all"
            else 0.0,
            0.0,
        )
    ]
    unit_zones: list[tuple[int, ...]] = []
    for unit in spec.units:
        base = (
            unit.E,
            unit.nu,
            unit.biot if unit.biot is not None else biot,
            unit.density if unit.density is not None else density,
        )
        if unit.change_sides is None:
            unit_zones.append((len(rows),))
            rows.append((unit.name, *base, _unit_change(unit, pore), unit.overpressure))
            continue
        unit_zones.append((len(rows), len(rows) + 1))
        for side, dp in zip(("left", "right"), unit.change_sides, strict=True):
            rows.append((f"{unit.name} ({side})", *base, dp, unit.overpressure))
    cols = list(zip(*rows, strict=True))
    return Zones(
        names=tuple(cols[0]),
        E=np.array(cols[1], float),
        nu=np.array(cols[2], float),
        biot=np.array(cols[3], float),
        density=np.array(cols[4], float),
        change=np.array(cols[5], float),
        overpressure=np.array(cols[6], float),
        units=tuple(spec.units),
        unit_zones=tuple(unit_zones),
    )


# --------------------------------------------------------------------------- #
# The in-situ state
# --------------------------------------------------------------------------- #


def _heights(zones: Zones, x: float) -> list[float]:
    """The heights [m] where the vertical line at x may cross a zone
    boundary (horizons, box and polygon edges, displaced layers' faults)."""
    ys = []
    for unit in zones.units:
        r = unit.region
        if r.kind == "layer":
            ys += [r.top, r.base]
        elif r.kind == "offset":
            ys += [r.top, r.base, r.top - r.throw, r.base - r.throw]
            ys += _fault_crossings(r.fault, x)
        elif r.kind == "boxes":
            ys += list(np.asarray(r.boxes)[:, [1, 3]].ravel())
        else:
            P = np.asarray(r.polygon, float)
            Q = np.roll(P, -1, axis=0)
            ys += list(P[:, 1])
            dx = Q[:, 0] - P[:, 0]
            cross = (np.minimum(P[:, 0], Q[:, 0]) <= x) & (
                x <= np.maximum(P[:, 0], Q[:, 0])
            )
            cross &= dx != 0.0
            t = (x - P[cross, 0]) / dx[cross]
            ys += list(P[cross, 1] + t * (Q[cross, 1] - P[cross, 1]))
    return ys


def _fault_crossings(fault: np.ndarray, x: float) -> list[float]:
    """Heights where the fault line (extended straight beyond its ends)
    passes x."""
    P = np.asarray(fault, float)
    if P[-1, 1] < P[0, 1]:
        P = P[::-1]
    out = []
    for a, b in zip(P[:-1], P[1:], strict=True):
        if a[0] != b[0] and min(a[0], b[0]) <= x <= max(a[0], b[0]):
            out.append(a[1] + (x - a[0]) / (b[0] - a[0]) * (b[1] - a[1]))
    for a, b in ((P[0], P[1]), (P[-1], P[-2])):  # the two straight extensions
        if a[0] != b[0]:
            y = a[1] + (x - a[0]) / (b[0] - a[0]) * (b[1] - a[1])
            if (y < P[0, 1] and a is P[0]) or (y > P[-1, 1] and a is P[-1]):
                out.append(y)
    return out


def overburden(zones: Zones, xy: np.ndarray, datum: float) -> np.ndarray:
    """(n,) int_y^datum rho(x, y') dy' [kg/m^2] at each point (n, 2) [m]:
    the mass of rock per unit area between the point and the datum (negative
    above the datum)."""
    xy = np.asarray(xy, float).reshape(-1, 2)
    out = np.zeros(xy.shape[0])
    columns, where = np.unique(xy[:, 0], return_inverse=True)
    lo = min(float(xy[:, 1].min(initial=datum)), datum)
    hi = max(float(xy[:, 1].max(initial=datum)), datum)
    for c, x in enumerate(columns):
        ys = np.array([lo, hi, datum, *_heights(zones, float(x))], float)
        ys = np.unique(ys[(ys >= lo) & (ys <= hi)])
        mid = np.column_stack([np.full(ys.size - 1, x), 0.5 * (ys[1:] + ys[:-1])])
        rho = zones.density[zones.at(mid)]
        mass = np.concatenate([[0.0], np.cumsum(rho * np.diff(ys))])  # from lo
        at_datum = np.interp(datum, ys, mass)
        mine = where == c
        out[mine] = at_datum - np.interp(xy[mine, 1], ys, mass)
    return out


def initial_pressure(spec, zones: Zones, xy: np.ndarray, zone: np.ndarray):
    """(n,) initial pore pressure p0 [Pa] at points in their zones."""
    pore = spec.pore_pressure
    n = np.asarray(xy).reshape(-1, 2).shape[0]
    if pore is None:
        return np.zeros(n)
    p0 = np.full(n, pore.initial)
    if pore.gradient != 0.0:
        p0 = p0 + pore.gradient * (pore.datum - np.asarray(xy, float)[:, 1])
    if np.any(zones.overpressure):
        p0 = p0 + zones.overpressure[zone]
    return p0


def in_situ_stress(spec, zones: Zones, xy, zone, p0=None) -> np.ndarray | None:
    """(n, 3) in-situ total stress (xx, yy, xy) [Pa] at points in their
    zones, or None without one.  ``p0`` (n,): the initial pore pressure there
    (for a ratio of effective stresses; default :func:`initial_pressure`)."""
    loading = spec.loading
    xy = np.asarray(xy, float).reshape(-1, 2)
    if loading.in_situ is None:
        if loading.initial_stress is None:
            return None
        return np.broadcast_to(
            np.asarray(loading.initial_stress, float), (xy.shape[0], 3)
        ).copy()
    s = loading.in_situ
    depth = s.datum - xy[:, 1]
    if s.gravity is not None:
        syy = s.yy - s.gravity * overburden(zones, xy, s.datum)
    else:
        syy = s.yy + s.gradient_yy * depth
    if s.ratio_xx is None:
        sxx = s.xx + s.gradient_xx * depth
    else:
        if p0 is None:
            p0 = initial_pressure(spec, zones, xy, zone)
        ap = zones.biot[zone] * p0
        nu = zones.nu[zone]
        K = nu / (1.0 - nu) if s.ratio_xx == "uniaxial_strain" else s.ratio_xx
        sxx = K * (syy + ap) - ap
    return np.column_stack([sxx, syy, np.full(xy.shape[0], s.xy)])


def fluid_value(rule, plus: np.ndarray, minus: np.ndarray) -> np.ndarray:
    """The fluid pressure in a fracture from the pore pressures on its two
    faces [Pa]: their mean (the fracture connects them), the higher or the
    lower (the fracture is open to one side), or a fixed number (sealed)."""
    if rule == "mean":
        return 0.5 * (plus + minus)
    if rule == "higher":
        return np.maximum(plus, minus)
    if rule == "lower":
        return np.minimum(plus, minus)
    return np.full(np.shape(plus), float(rule))


# --------------------------------------------------------------------------- #
# Where the loading jumps along a fracture
# --------------------------------------------------------------------------- #


def _crossings(p, q, a, b, tol) -> list[float]:
    """Parameters t in [0, 1] along the fracture segment a-b where the edge
    p-q meets it (its ends, where p-q lies along the segment)."""
    d, e = b - a, q - p
    L = float(np.hypot(*d))
    n = np.array([-d[1], d[0]]) / L
    dp, dq = float((p - a) @ n), float((q - a) @ n)
    if abs(dp) <= tol and abs(dq) <= tol:  # along the fracture
        return [float((v - a) @ d) / L**2 for v in (p, q)]
    if (dp > tol and dq > tol) or (dp < -tol and dq < -tol):
        return []
    den = d[0] * e[1] - d[1] * e[0]
    if den == 0.0:
        return []
    w = p - a
    t = (w[0] * e[1] - w[1] * e[0]) / den
    u = (w[0] * d[1] - w[1] * d[0]) / den
    return [float(t)] if -1e-12 <= u <= 1.0 + 1e-12 else []


def loading_breaks(zones: Zones, fractures, box: Box, eps: float) -> list[np.ndarray]:
    """Per fracture, the arc lengths [m] where the zone on one of its faces
    changes (a unit boundary meets it: a reservoir corner on a fault).

    Candidates are where the units' edges (:func:`xfemslip.geometry.regions.
    edges`, horizons across ``box``) meet the fracture; those where the
    faces' zones (probed ``eps`` off the fracture, ``eps`` along it on
    either side) differ are kept.
    """
    out = []
    segments = [e for unit in zones.units for e in edges(unit.region, box)]
    for fr in fractures:
        found: list[float] = []
        for k, (a, b) in enumerate(zip(fr.points[:-1], fr.points[1:], strict=True)):
            L = float(np.hypot(*(b - a)))
            for _, p, q in segments:
                ts = _crossings(np.asarray(p), np.asarray(q), a, b, eps)
                found.extend(float(fr.s_start[k]) + t * L for t in ts if 0 < t < 1)
        out.append(_kept(zones, fr, np.unique(found), eps))
    return out


def _kept(zones: Zones, fr, s: np.ndarray, eps: float) -> np.ndarray:
    """The arc lengths of ``s`` where the zones of the faces change."""
    if s.size == 0:
        return s
    sides = []
    for ds in (-eps, eps):
        xy, normal = fr.point_at(s + ds)
        sides.append((zones.at(xy + eps * normal), zones.at(xy - eps * normal)))
    change = (sides[0][0] != sides[1][0]) | (sides[0][1] != sides[1][1])
    return s[change]
