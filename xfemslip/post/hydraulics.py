"""What the slip does to permeability, per fracture and load step.

With ``[permeability]`` in the case, every converged step gets, at the contact
points of every fracture, the hydraulic aperture and the cubic-law
transmissivity (:class:`~xfemslip.post.permeability.ApertureLaw`, the law of
that fracture), and the block gets its equivalent permeability tensor (Oda's
crack tensor, :func:`~xfemslip.post.permeability.oda_tensor`) in situ and
after the step.

- The slip is the one that slid (``plastic_slip``, cumulative from the
  in-situ state): a stuck point does not dilate, whatever the elastic give
  of the penalty; an open point's slip is its whole tangential jump.  The
  normal stress is the effective one that the contact law sees
  (``effective_normal_traction`` with pore pressure, else
  ``normal_traction``), and the in-situ one is sigma_n0' = n . sigma0 . n + p0
  (``loading.initial_stress``, ``pore_pressure.initial``), the state the
  initial aperture a0 belongs to.  In situ, every aperture is therefore a0.
- Each contact point stands for the stretch of fracture between the midpoints
  to its neighbours (:func:`~xfemslip.post.metrics.point_stretches`, the ends
  reaching the part of the fracture inside the domain); the block counts the
  part of each stretch that lies in the arc-length range of the fracture
  inside the block, so a straight fracture is cut at the block's edges
  exactly (a polyline leaving and re-entering the block is counted over the
  whole range between).
- The opening adds to the aperture only where the contact point is open
  (state OPEN); in contact, the normal jump is the elastic give of the
  penalty law, a numerical device that the closure law replaces.
- The tangent at a contact point is that of the polyline segment it lies on.
"""

from __future__ import annotations

import numpy as np

from xfemslip import display
from xfemslip.case.specs import CaseSpec
from xfemslip.conventions import OPEN
from xfemslip.fem.poro import FACE_OFFSET
from xfemslip.fem.zones import build_zones, in_situ_stress, initial_pressure
from xfemslip.geometry.box import Box
from xfemslip.post.metrics import arc_extent, fracture_ends, point_stretches
from xfemslip.post.permeability import ApertureLaw, oda_tensor, transmissivity
from xfemslip.post.result import PermeabilityHistory, Result

__all__ = [
    "add_permeability",
    "aperture_law",
    "block_stretches",
    "in_situ_normal",
    "permeability_lines",
    "polyline_tangents",
    "ratio_phrase",
]


def aperture_law(law) -> ApertureLaw:
    """The ApertureLaw of a complete ``HydraulicSpec``."""
    return ApertureLaw(
        initial_aperture=law.aperture,
        dilation_angle=law.dilation_angle,
        dilation_slip=law.dilation_slip,
        max_closure=law.max_closure,
        normal_stiffness=law.normal_stiffness,
    )


def polyline_tangents(points, s) -> np.ndarray:
    """(K, 2) unit tangent of the polyline ``points`` (k, 2) at arc lengths
    ``s`` (K,) from its first vertex: that of the segment holding each."""
    points = np.asarray(points, float)
    d = np.diff(points, axis=0)
    length = np.linalg.norm(d, axis=1)
    start = np.concatenate([[0.0], np.cumsum(length)[:-1]])
    k = np.clip(np.searchsorted(start, np.asarray(s, float), side="right") - 1, 0, None)
    return d[k] / length[k, None]


def in_situ_normal(spec: CaseSpec, tangents, points=None) -> np.ndarray:
    """sigma_n0' = n . sigma0 . n + p0 [Pa] at points of the given unit
    tangents (K, 2): the effective normal traction of the in-situ state;
    ``points`` (K, 2) [m] where it varies with depth (the mean of the two
    faces' in-situ stress and initial pore pressure)."""
    t = np.asarray(tangents, float)
    n = np.column_stack([-t[:, 1], t[:, 0]])
    if spec.loading.in_situ is not None and points is not None:
        zones = build_zones(spec)
        xy = np.asarray(points, float)
        eps = FACE_OFFSET * float(
            min(np.diff(spec.mesh.x).min(), np.diff(spec.mesh.y).min())
        )
        S = np.zeros((xy.shape[0], 3))
        p0 = np.zeros(xy.shape[0])
        for sign in (0.5, -0.5):
            face = xy + 2.0 * sign * eps * n
            zone = zones.at(face)
            p = initial_pressure(spec, zones, xy, zone)
            face_stress = in_situ_stress(spec, zones, face, zone, p)
            assert face_stress is not None  # the case has an in-situ stress
            S += 0.5 * face_stress
            p0 += 0.5 * p
        sn = S[:, 0] * n[:, 0] ** 2 + S[:, 1] * n[:, 1] ** 2
        return sn + 2.0 * S[:, 2] * n[:, 0] * n[:, 1] + p0
    sigma0 = spec.loading.initial_stress or (0.0, 0.0, 0.0)
    sxx, syy, sxy = sigma0
    sn = sxx * n[:, 0] ** 2 + syy * n[:, 1] ** 2 + 2.0 * sxy * n[:, 0] * n[:, 1]
    if spec.pore_pressure is not None:
        sn = sn + spec.pore_pressure.initial
    return sn


def block_stretches(s, domain_ends, block_ends) -> np.ndarray:
    """Length [m] of the stretch of each contact point (``point_stretches``
    with the fracture's ``domain_ends``) that lies within ``block_ends``, the
    arc-length range of the fracture inside the block."""
    s = np.asarray(s, float)
    w = point_stretches(s, *domain_ends)
    if s.size == 0:
        return w
    lo = np.concatenate([[min(domain_ends[0], s[0])], 0.5 * (s[1:] + s[:-1])])
    hi = lo + w
    inside = np.minimum(hi, block_ends[1]) - np.maximum(lo, block_ends[0])
    return np.maximum(inside, 0.0)


def add_permeability(result: Result, spec: CaseSpec) -> None:
    """Fill, for a case with ``[permeability]``, the ``aperture`` and
    ``transmissivity`` of every fracture of every step of ``result`` and
    ``result.permeability`` (module doc); nothing without the table."""
    p = spec.permeability
    if p is None or not result.steps:
        return
    block = Box.from_corners(*p.block)
    area = block.area
    laws = [aperture_law(law) for law in p.laws]
    geometry = []  # per fracture: tangents, sigma_n0', block stretches
    ends = fracture_ends(result, spec)
    for k, ff in enumerate(result.steps[0].fractures):
        fracture = spec.fractures[k]
        t = polyline_tangents(fracture.points, ff.s)
        weights = block_stretches(ff.s, ends[k], arc_extent(fracture.points, block))
        geometry.append((t, in_situ_normal(spec, t, ff.points), weights))
    in_situ = oda_tensor(
        [
            (wk, t, np.full(wk.shape, law.initial_aperture))
            for (t, _, wk), law in zip(geometry, laws, strict=True)
        ],
        area,
        p.matrix,
    )
    tensors = []
    for step in result.steps:
        parts = []
        for ff, law, (t, sn0, wk) in zip(step.fractures, laws, geometry, strict=True):
            sn = (
                ff.effective_normal_traction
                if ff.effective_normal_traction is not None
                else ff.normal_traction
            )
            # only an open fracture's jump opens it: in contact, the normal
            # jump is the penalty's elastic give, which the closure law stands for
            opening = np.where(ff.state == OPEN, ff.opening, 0.0)
            ff.aperture = law.aperture(ff.slid, sn, sn0, opening)
            ff.transmissivity = transmissivity(ff.aperture)
            parts.append((wk, t, ff.aperture))
        tensors.append(oda_tensor(parts, area, p.matrix))
    result.permeability = PermeabilityHistory(
        block=p.block,
        matrix=float(p.matrix),
        in_situ=in_situ,
        tensors=np.array(tensors).reshape(-1, 2, 2),
        initial_aperture=np.array([law.initial_aperture for law in laws]),
    )


# --------------------------------------------------------------------------- #
# In words


def _times(value: float) -> str:
    return f"x {value:.3g}" if np.isfinite(value) else "x - (0 in situ)"


def ratio_phrase(history: PermeabilityHistory, index: int = -1) -> str:
    """``k_xx x 3.1, k_yy x 1.2``: the block's permeability after step
    ``index`` over its in-situ value."""
    rx, ry = history.ratio(index)
    return f"k_xx {_times(rx)}, k_yy {_times(ry)}"


def permeability_lines(result: Result, index: int = -1) -> list[str]:
    """Per fracture its aperture and mean transmissivity against the initial
    ones after step ``index``, and the block's tensor in situ and after."""
    history = result.permeability
    if history is None:
        return []
    step = result.steps[index]
    rows = []
    for i, ff in enumerate(step.fractures):
        a0 = float(history.initial_aperture[i])
        if ff.aperture is None or not np.size(ff.aperture):
            rows.append([str(i), f"{a0 * 1e3:.4g}", "-", "-", "-"])
            continue
        s = np.asarray(ff.s, float)
        w = point_stretches(s, s[0], s[-1]) if s.size > 1 else np.ones(1)
        mean_a = float(np.sum(w * ff.aperture) / np.sum(w))
        assert ff.transmissivity is not None  # filled with the aperture
        ratio = float(np.sum(w * ff.transmissivity) / np.sum(w)) / (a0**3 / 12.0)
        rows.append(
            [
                str(i),
                f"{a0 * 1e3:.4g}",
                f"{mean_a * 1e3:.4g}",
                f"{float(np.max(ff.aperture)) * 1e3:.4g}",
                f"{ratio:.4g}",
            ]
        )
    head = ["fracture", "a0 [mm]", "mean a [mm]", "max a [mm]", "T/T0"]
    lines = display.table(head, rows).splitlines()
    x0, x1, y0, y1 = Box.from_corners(*history.block)
    k0, k = history.in_situ, history.tensors[index]
    lines.append(
        f"block [{x0:g}, {x1:g}] x [{y0:g}, {y1:g}] m, permeability [m^2] in situ "
        f"-> now: k_xx {k0[0, 0]:.3g} -> {k[0, 0]:.3g}, k_yy {k0[1, 1]:.3g} -> "
        f"{k[1, 1]:.3g}, k_xy {k0[0, 1]:.3g} -> {k[0, 1]:.3g} "
        f"({ratio_phrase(history, index)})"
    )
    return lines
