"""Scalar measures of a result: the columns of a sweep's ``summary.csv``.

Per fracture the contact points stand for the stretch of fracture between the
midpoints to their neighbours, the ends reaching the part of the fracture
inside the domain (``arc_extent``); the slipping length is the length of the
stretches in state SLIP.
"""

from __future__ import annotations

import math

import numpy as np

from xfemslip.case.specs import CaseSpec
from xfemslip.conventions import SLIP
from xfemslip.geometry.box import Box
from xfemslip.geometry.fracture import clip_segment
from xfemslip.post.result import Result

__all__ = [
    "METRICS",
    "arc_extent",
    "fracture_ends",
    "point_stretches",
    "result_metrics",
    "slipping_length",
]

METRICS = (
    "converged",
    "max_abs_slip_m",
    "slip_length_m",
    "slip_share",
    "newton_iterations",
    "wall_time_s",
    # per fracture (networks, docs/networks.md "Random networks"):
    "fractures",
    "slipping_fractures",
    "slipping_fraction",
    "mean_slip_m",
)


def arc_extent(points: np.ndarray, box: Box) -> tuple[float, float]:
    """Arc-length range [s_lo, s_hi] of a polyline inside the box."""
    points = np.asarray(points, dtype=float)
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    start = np.concatenate([[0.0], np.cumsum(seg)[:-1]])
    lo, hi = math.inf, -math.inf
    for k in range(len(seg)):
        ta, tb = clip_segment(points[k], points[k + 1], np.asarray([box], float))
        if tb[0] > ta[0]:
            lo = min(lo, start[k] + ta[0] * seg[k])
            hi = max(hi, start[k] + tb[0] * seg[k])
    return lo, hi


def point_stretches(s, s_lo: float, s_hi: float) -> np.ndarray:
    """Length [m] each contact point stands for: the stretch between the
    midpoints to its neighbours (the ends reach s_lo and s_hi)."""
    s = np.asarray(s, dtype=float)
    if s.size == 0:
        return np.zeros(0)
    mid = 0.5 * (s[1:] + s[:-1])
    return np.diff(np.concatenate([[min(s_lo, s[0])], mid, [max(s_hi, s[-1])]]))


def slipping_length(s, state, s_lo: float, s_hi: float) -> float:
    """Length [m] of fracture in slip: each point stands for the stretch between
    the midpoints to its neighbours (the ends reach s_lo and s_hi)."""
    stretch = point_stretches(s, s_lo, s_hi)
    return float(np.sum(stretch[np.asarray(state) == SLIP]))


def fracture_ends(result: Result, spec: CaseSpec | None) -> list[tuple[float, float]]:
    """The arc-length range [m] of each fracture of ``result`` inside the
    domain: as the result stores it (``fracture_properties``), else from the
    case ``spec`` (a result written before the ends were kept)."""
    if result.fracture_properties is not None:
        return [p.ends for p in result.fracture_properties]
    assert spec is not None  # a result without the ends needs its case
    return [arc_extent(fracture.points, spec.box) for fracture in spec.fractures]


def result_metrics(result: Result, spec: CaseSpec) -> dict:
    """The METRICS of a result (final step) of the case ``spec``; the slip is
    the one that slid (``FractureFields.slid``)."""
    slip_max, length, n_slip, n_points = 0.0, 0.0, 0, 0
    slipping_means = []  # mean |slip| of each fracture with a point in slip
    fields = result.final.fractures if result.final is not None else []
    for ends, ff in zip(fracture_ends(result, spec), fields, strict=False):
        s, slip, state = ff.s, ff.slid, ff.state
        if slip.size:
            slip_max = max(slip_max, float(np.max(np.abs(slip))))
        stretch = point_stretches(s, *ends)
        length += float(np.sum(stretch[state == SLIP]))
        if np.any(state == SLIP):
            slipping_means.append(
                float(np.sum(stretch * np.abs(slip)) / np.sum(stretch))
            )
        n_slip += int(np.sum(state == SLIP))
        n_points += int(state.size)
    attrs = result.attrs
    n_fractures = len(spec.fractures)
    return {
        "converged": bool(attrs.get("converged", False)),
        "max_abs_slip_m": slip_max,
        "slip_length_m": length,
        "slip_share": n_slip / n_points if n_points else 0.0,
        "newton_iterations": int(attrs.get("newton_iterations", 0)),
        "wall_time_s": float(attrs.get("wall_time_s", math.nan)),
        "fractures": n_fractures,
        "slipping_fractures": len(slipping_means),
        "slipping_fraction": len(slipping_means) / n_fractures if n_fractures else 0.0,
        "mean_slip_m": float(np.mean(slipping_means)) if slipping_means else 0.0,
    }
