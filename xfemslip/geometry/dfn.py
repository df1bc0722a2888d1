"""Random discrete fracture networks (DFN): straight fractures with random
centres, orientations and lengths, drawn from a seeded NumPy ``Generator``.

Pure NumPy.  The parameters arrive validated (``[network.generate]`` is read
by :mod:`xfemslip.case.network`); ``generate`` returns the segments, and the
case reader turns them into ``FractureSpec`` entries.

The model (docs/networks.md, *Random networks*):

- **centres**: uniform in the region (a box, default the domain), i.e. a
  Poisson process conditioned on its count;
- **count**: given, or from a density over the region's area A:
  P20 (fractures per m^2) gives ``round(P20 A)``; P21 (fracture length per
  m^2, m/m^2) gives ``round(P21 A / E[L])`` with E[L] the mean of the length
  distribution (the weighted mean over the sets), before any clipping;
- **orientation** [deg, counter-clockwise from +x] per set: ``uniform`` on
  [0, 180); ``von_mises`` around ``mean`` with concentration ``kappa``
  (numpy's ``vonmises``, pdf ~ exp(kappa cos(theta - mean))); ``normal``
  around ``mean`` with standard deviation ``std``;
- **length** [m] per set: ``constant``; ``power_law`` with pdf ~ l^-exponent
  on [min, max] (inverse-CDF sampling); ``lognormal`` with median ``median``
  and log-standard deviation ``sigma``, truncated to [min, max] when given
  (resampling);
- **sets**: each candidate picks a set with probability weight / sum(weights);
- **domain**: ``outside = "clip"`` cuts a fracture at the domain boundary
  (a piece shorter than ``min_length`` is redrawn); ``"reject"`` redraws any
  fracture that does not lie wholly inside the domain;
- **intersections**: ``"allow"`` keeps every candidate; ``"avoid"`` redraws a
  candidate closer than ``min_spacing`` to (or touching, or crossing) a fracture
  already placed.  Redrawing biases the kept lengths and orientations towards
  the ones that fit; the statistics of the draws themselves are exact.

Candidates are drawn in blocks, always in the same order from one
``numpy.random.default_rng(seed)``: the same seed gives the same network,
bit for bit, on the same NumPy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from xfemslip.geometry.box import Box

ORIENTATIONS = ("uniform", "von_mises", "normal")
LENGTHS = ("constant", "power_law", "lognormal")
INTERSECTIONS = ("allow", "avoid")
OUTSIDE = ("clip", "reject")
# Candidates drawn per fracture asked for before giving up (avoid / reject /
# min_length redraws); a network that does not fit in that many is refused.
ATTEMPTS_PER_FRACTURE = 200
# Truncated lognormal: draws per round of resampling, at least this many.
_MIN_BLOCK = 64


@dataclass(frozen=True, kw_only=True)
class Orientation:
    """Orientation law of one set; angles in degrees."""

    kind: str = "uniform"  # ORIENTATIONS
    mean: float = 0.0  # [deg]
    kappa: float = 0.0  # von Mises concentration [-]
    std: float = 0.0  # normal spread [deg]
    UNITS: ClassVar[dict[str, str]] = {"mean": "deg", "kappa": "-", "std": "deg"}


@dataclass(frozen=True, kw_only=True)
class LengthLaw:
    """Length law of one set [m]."""

    kind: str = "constant"  # LENGTHS
    value: float = 0.0  # constant length [m]
    exponent: float = 0.0  # power law: pdf ~ l^-exponent
    lmin: float | None = None  # [m] power law (required), lognormal (optional)
    lmax: float | None = None  # [m]
    median: float = 0.0  # lognormal median exp(mu) [m]
    sigma: float = 0.0  # lognormal std of ln(l) [-]
    UNITS: ClassVar[dict[str, str]] = {
        "value": "m",
        "exponent": "-",
        "lmin": "m",
        "lmax": "m",
        "median": "m",
        "sigma": "-",
    }

    @property
    def bounds(self) -> tuple[float, float]:
        """(lmin, lmax) [m] of a power law (both required)."""
        if self.lmin is None or self.lmax is None:
            raise ValueError(f"a {self.kind!r} length law without lmin and lmax")
        return self.lmin, self.lmax


@dataclass(frozen=True, kw_only=True)
class FractureSet:
    weight: float
    orientation: Orientation
    length: LengthLaw


@dataclass(frozen=True, kw_only=True)
class DfnParams:
    """A validated ``[network.generate]`` table (SI; angles in degrees)."""

    seed: int
    count: int | None = None  # exactly one of count, p20, p21
    p20: float | None = None  # [1/m^2]
    p21: float | None = None  # [m/m^2]
    region: Box | None = None  # where the centres are drawn [m]
    sets: tuple[FractureSet, ...]
    intersections: str = "allow"
    min_spacing: float = 0.0  # [m], with intersections = "avoid"
    outside: str = "clip"
    min_length: float = 0.0  # [m] shortest clipped piece kept
    UNITS: ClassVar[dict[str, str]] = {
        "seed": "-",
        "count": "-",
        "p20": "1/m^2",
        "p21": "m/m^2",
        "region": "m",
        "min_spacing": "m",
        "min_length": "m",
    }


@dataclass(frozen=True)
class Network:
    """A realized network of n straight fractures.

    segments : (n, 2, 2) float64 [m], end points after clipping, in placement order
    centers : (n, 2) float64 [m], drawn centres
    angles : (n,) float64 [deg], drawn orientation
    lengths : (n,) float64 [m], drawn (unclipped) lengths
    set_index : (n,) int64, the set of each fracture
    requested : the count asked for; candidates : how many were drawn
    """

    segments: np.ndarray
    centers: np.ndarray
    angles: np.ndarray
    lengths: np.ndarray
    set_index: np.ndarray
    requested: int
    candidates: int

    @property
    def placed(self) -> int:
        return int(self.segments.shape[0])


# --------------------------------------------------------------------------- #
# Distributions
# --------------------------------------------------------------------------- #


def sample_angles(rng: np.random.Generator, law: Orientation, n: int) -> np.ndarray:
    """(n,) angles [deg] drawn from ``law``."""
    if law.kind == "uniform":
        return 180.0 * rng.random(n)
    if law.kind == "von_mises":
        return np.degrees(rng.vonmises(math.radians(law.mean), law.kappa, n))
    if law.kind == "normal":
        return law.mean + law.std * rng.standard_normal(n)
    raise ValueError(f"unknown orientation law {law.kind!r}")


def power_law_ppf(u: np.ndarray, exponent: float, lmin: float, lmax: float):
    """Inverse CDF of pdf ~ l^-exponent on [lmin, lmax]."""
    a = 1.0 - exponent
    if abs(a) < 1e-12:  # pdf ~ 1/l: log-uniform
        return lmin * (lmax / lmin) ** u
    return (lmin**a + u * (lmax**a - lmin**a)) ** (1.0 / a)


def sample_lengths(rng: np.random.Generator, law: LengthLaw, n: int) -> np.ndarray:
    """(n,) lengths [m] drawn from ``law``."""
    if law.kind == "constant":
        return np.full(n, law.value)
    if law.kind == "power_law":
        return power_law_ppf(rng.random(n), law.exponent, *law.bounds)
    if law.kind == "lognormal":
        lo = law.lmin if law.lmin is not None else 0.0
        hi = law.lmax if law.lmax is not None else math.inf
        out = np.empty(0)
        while out.size < n:  # truncation by resampling
            draw = rng.lognormal(math.log(law.median), law.sigma, max(n, _MIN_BLOCK))
            out = np.concatenate([out, draw[(draw >= lo) & (draw <= hi)]])
        return out[:n]
    raise ValueError(f"unknown length law {law.kind!r}")


def _normal_cdf(z: float) -> float:
    return 0.5 * (1.0 + math.erf(z / math.sqrt(2.0)))


def mean_length(law: LengthLaw) -> float:
    """E[L] [m] of a length law (closed forms)."""
    if law.kind == "constant":
        return law.value
    if law.kind == "power_law":
        a, (lo, hi) = law.exponent, law.bounds
        if abs(a - 1.0) < 1e-12:
            return (hi - lo) / math.log(hi / lo)
        if abs(a - 2.0) < 1e-12:
            return math.log(hi / lo) / (1.0 / lo - 1.0 / hi)
        return (
            (1.0 - a)
            / (2.0 - a)
            * (hi ** (2 - a) - lo ** (2 - a))
            / (hi ** (1 - a) - lo ** (1 - a))
        )
    if law.kind == "lognormal":
        mu, s = math.log(law.median), law.sigma
        full = math.exp(mu + 0.5 * s * s)
        if law.lmin is None and law.lmax is None:
            return full

        def z(x, shift):  # standardized log bound
            if x is None:
                return math.inf if shift == "hi" else -math.inf
            return (math.log(x) - mu) / s if x > 0 else -math.inf

        zlo, zhi = z(law.lmin, "lo"), z(law.lmax, "hi")
        # E[L | lo < L < hi] = e^(mu + s^2/2) [Phi(zhi - s) - Phi(zlo - s)]
        #                                    / [Phi(zhi) - Phi(zlo)]
        mass = _normal_cdf(zhi) - _normal_cdf(zlo)
        return full * (_normal_cdf(zhi - s) - _normal_cdf(zlo - s)) / mass
    raise ValueError(f"unknown length law {law.kind!r}")


def resolve_count(params: DfnParams, box: Box) -> int:
    """The number of fractures asked for: count, round(P20 A) or
    round(P21 A / E[L]) over the region (default the domain box)."""
    if params.count is not None:
        return params.count
    area = Box(*(params.region or box)).area
    if params.p20 is not None:
        return int(round(params.p20 * area))
    assert params.p21 is not None  # exactly one of count, p20, p21
    weights = np.array([s.weight for s in params.sets])
    mean = float(
        np.dot(weights / weights.sum(), [mean_length(s.length) for s in params.sets])
    )
    return int(round(params.p21 * area / mean))


# --------------------------------------------------------------------------- #
# Geometry
# --------------------------------------------------------------------------- #


def clip_to_box(p0: np.ndarray, p1: np.ndarray, box: Box) -> tuple[float, float]:
    """Liang-Barsky for one segment: (t_in, t_out) in [0, 1]; empty if t_in >= t_out."""
    x0, x1, y0, y1 = box
    ta, tb = 0.0, 1.0
    for k, (lo, hi) in enumerate(((x0, x1), (y0, y1))):
        d = p1[k] - p0[k]
        if d == 0.0:
            if not lo <= p0[k] <= hi:
                return 1.0, 0.0
            continue
        t_lo, t_hi = (lo - p0[k]) / d, (hi - p0[k]) / d
        ta, tb = max(ta, min(t_lo, t_hi)), min(tb, max(t_lo, t_hi))
    return ta, tb


def _point_segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray):
    """Distance of points p (n, 2) to segments a-b (n, 2)."""
    d = b - a
    t = np.clip(np.sum((p - a) * d, axis=-1) / np.sum(d * d, axis=-1), 0.0, 1.0)
    return np.hypot(*(a + t[..., None] * d - p).T)


def segment_distances(a0, a1, b0: np.ndarray, b1: np.ndarray) -> np.ndarray:
    """Distance [m] from segment a0-a1 to each segment b0-b1 (m, 2); 0 where
    they cross or touch."""
    a0 = np.broadcast_to(np.asarray(a0, float), b0.shape)
    a1 = np.broadcast_to(np.asarray(a1, float), b0.shape)

    def orient(p, q, r):
        return np.sign(
            (q[:, 0] - p[:, 0]) * (r[:, 1] - p[:, 1])
            - (q[:, 1] - p[:, 1]) * (r[:, 0] - p[:, 0])
        )

    cross = (orient(a0, a1, b0) * orient(a0, a1, b1) < 0) & (
        orient(b0, b1, a0) * orient(b0, b1, a1) < 0
    )
    dist = np.minimum.reduce(
        [
            _point_segment_distance(a0, b0, b1),
            _point_segment_distance(a1, b0, b1),
            _point_segment_distance(b0, a0, a1),
            _point_segment_distance(b1, a0, a1),
        ]
    )
    return np.where(cross, 0.0, dist)


def intersecting_pairs(segments: np.ndarray, spacing: float = 0.0) -> list[tuple]:
    """Pairs (i, j), i < j, of segments (n, 2, 2) closer than or at ``spacing``."""
    pairs = []
    for i in range(len(segments) - 1):
        d = segment_distances(
            segments[i, 0], segments[i, 1], segments[i + 1 :, 0], segments[i + 1 :, 1]
        )
        pairs += [(i, i + 1 + int(j)) for j in np.flatnonzero(d <= spacing)]
    return pairs


# --------------------------------------------------------------------------- #
# The network
# --------------------------------------------------------------------------- #


def _draw_block(rng, params: DfnParams, region: Box, n: int) -> tuple:
    """n candidates: (set index, centres (n, 2), angles [deg], lengths [m])."""
    weights = np.array([s.weight for s in params.sets], dtype=float)
    which = rng.choice(len(weights), size=n, p=weights / weights.sum())
    x0, x1, y0, y1 = region
    centers = np.column_stack(
        [x0 + (x1 - x0) * rng.random(n), y0 + (y1 - y0) * rng.random(n)]
    )
    angles, lengths = np.empty(n), np.empty(n)
    for k, fset in enumerate(params.sets):
        mask = which == k
        angles[mask] = sample_angles(rng, fset.orientation, int(mask.sum()))
        lengths[mask] = sample_lengths(rng, fset.length, int(mask.sum()))
    return which, centers, angles, lengths


def _fit(
    p0: np.ndarray, p1: np.ndarray, params: DfnParams, box: Box
) -> tuple[np.ndarray, np.ndarray] | None:
    """End points kept in the domain, or None if the candidate is redrawn."""
    ta, tb = clip_to_box(p0, p1, box)
    if params.outside == "reject":
        return (p0, p1) if (ta == 0.0 and tb == 1.0) else None
    if tb <= ta:
        return None
    # p0 + t (p1 - p0) may round a hair outside the box: put it on the edge
    lo, hi = box.lo, box.hi
    q0 = np.clip(p0 + ta * (p1 - p0), lo, hi)
    q1 = np.clip(p0 + tb * (p1 - p0), lo, hi)
    if math.hypot(*(q1 - q0)) <= params.min_length:
        return None
    return q0, q1


def generate(
    params: DfnParams, box: Box, existing: np.ndarray | None = None
) -> Network:
    """Realize the network of ``params`` in the domain ``box``.

    existing : (m, 2, 2) float64 [m], segments of the case's other fractures;
        with intersections = "avoid" the new ones keep away from these too.

    Returns a Network; ``placed < requested`` when the candidates ran out
    (ATTEMPTS_PER_FRACTURE per fracture asked for), which the caller reports.
    """
    box = Box(*(float(v) for v in box))
    region = params.region or box
    rng = np.random.default_rng(params.seed)
    wanted = resolve_count(params, box)
    budget = ATTEMPTS_PER_FRACTURE * max(wanted, 1)
    kept: list[tuple] = []
    fixed = np.zeros((0, 2, 2)) if existing is None else np.asarray(existing, float)
    ends = np.concatenate([fixed.reshape(-1, 2, 2), np.empty((wanted, 2, 2))])
    first = len(fixed)
    drawn = 0
    while len(kept) < wanted and drawn < budget:
        block = min(max(2 * (wanted - len(kept)), 16), budget - drawn)
        which, centers, angles, lengths = _draw_block(rng, params, region, block)
        drawn += block
        rad = np.radians(angles)
        half = 0.5 * lengths[:, None] * np.column_stack([np.cos(rad), np.sin(rad)])
        for k in range(block):
            fitted = _fit(centers[k] - half[k], centers[k] + half[k], params, box)
            if fitted is None:
                continue
            n = first + len(kept)
            if params.intersections == "avoid" and n:
                dist = segment_distances(*fitted, ends[:n, 0], ends[:n, 1])
                if np.any(dist <= params.min_spacing):
                    continue
            ends[n] = fitted
            kept.append((which[k], centers[k], angles[k], lengths[k]))
            if len(kept) == wanted:
                break
    n = len(kept)
    return Network(
        segments=ends[first : first + n].copy(),
        centers=np.array([k[1] for k in kept]).reshape(n, 2),
        angles=np.array([k[2] for k in kept], dtype=float),
        lengths=np.array([k[3] for k in kept], dtype=float),
        set_index=np.array([k[0] for k in kept], dtype=np.int64),
        requested=wanted,
        candidates=drawn,
    )


# --------------------------------------------------------------------------- #
# Export and statistics of a case's fractures
# --------------------------------------------------------------------------- #

CSV_COLUMNS = ("fracture", "x0", "y0", "x1", "y1", "friction", "cohesion", "kn", "kt")


def segments_csv_text(fractures) -> str:
    """The CSV of segments (the ``network.file`` format) of FractureSpecs: one
    row per polyline segment, ``fracture`` = the fracture's index; an automatic
    penalty (None) is an empty cell.  Numbers are written exactly (repr)."""
    lines = [",".join(CSV_COLUMNS)]
    for f in fractures:
        props = [f.friction, f.cohesion, f.kn, f.kt]
        tail = ",".join("" if v is None else repr(float(v)) for v in props)
        for a, b in zip(f.points[:-1], f.points[1:], strict=True):
            ends = ",".join(repr(float(v)) for v in (*a, *b))
            lines.append(f"{f.index},{ends},{tail}")
    return "\n".join(lines) + "\n"


def length_in_box(points: np.ndarray, box: Box) -> float:
    """Length [m] of a polyline (k, 2) inside the box."""
    total = 0.0
    for a, b in zip(points[:-1], points[1:], strict=True):
        ta, tb = clip_to_box(a, b, box)
        if tb > ta:
            total += (tb - ta) * math.hypot(*(b - a))
    return total


def network_stats(polylines, box: Box) -> dict:
    """Count, P20 [1/m^2], length in the domain [m] (total, min, mean, max)
    and P21 [m/m^2] of polylines in the domain box."""
    area = Box(*box).area
    lengths = np.array([length_in_box(np.asarray(p), box) for p in polylines])
    n = lengths.size
    return {
        "count": n,
        "p20": n / area,
        "total_length": float(lengths.sum()),
        "p21": float(lengths.sum()) / area,
        "min_length": float(lengths.min()) if n else 0.0,
        "mean_length": float(lengths.mean()) if n else 0.0,
        "max_length": float(lengths.max()) if n else 0.0,
    }
