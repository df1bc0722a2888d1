"""Graded rectilinear meshes: node coordinates of one axis from a few numbers.

An axis [lo, hi] is refined to cells of at most ``size`` h over its *fine
intervals* (where fractures and region boundaries run), its cells grow away
from them by at most ``growth`` g from one cell to the next and stay at most
``max_size`` H, and every *line* (a horizon, a region edge) and both ends
are nodes exactly.

How (one size field, then one rounding per segment between lines):

1. The size field s(x) = min(H, min_j (sigma_j + mu dist(x, S_j))), mu =
   ln g (1 - GROWTH_MARGIN): the sources S_j are the fine intervals widened
   by h on each side (sigma_j = h: a cell that touches a fine interval then
   lies inside the widened one, so it is at most h) and, where a segment
   between two lines is too short for its cells, points at its ends with a
   smaller sigma (step 3).  s is piecewise linear and mu-Lipschitz.
2. Cells are unit steps of Phi(x) = int dx / s~(x): a node where Phi is an
   integer.  Between two lines p < q the integral is rounded up to
   n = ceil(int_p^q dx / s) cells by lowering s to s~ = min(s, C_T),
   C_T(x) = max(T, s(p) - mu (x - p), s(q) - mu (q - x)), with T found so
   that int_p^q dx / s~ = n exactly (at an end of the axis the descending
   line of that end is left out).  C_T >= s at p and q, so s~ = s at every
   line and s~ stays continuous and mu-Lipschitz along the whole axis.
3. If no T reaches n (the two descending lines meet above zero: a segment
   short for the sizes at its ends), the sizes at both its ends are lowered
   until it is reachable, as point sources of step 1 (at the latest at
   mu L / 2, where the lines meet at zero; sizes only go down, so this ends).

Why it holds: a cell is a unit step of Phi, and d(ln s~)/dPhi = ds~/dx, so
neighbouring cells differ by at most e^mu <= g; a cell is at most the
largest s~ over it, so at most h over a fine interval and H everywhere.  The
count is the geometric grading's plus less than one cell per segment.
Everything is integrated and inverted in closed form (s~ is piecewise
linear), so the guarantees hold to the rounding of the coordinates.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = [
    "GROWTH_MARGIN",
    "LINE_MERGE",
    "AxisPlan",
    "graded_axes",
    "graded_axis",
    "plan_axis",
]

# mu = ln(growth) (1 - GROWTH_MARGIN): the neighbour ratio stays below growth
# by 1e-6 of ln(growth), far above the rounding of node coordinates (1e-16 of
# the coordinate over the cell), far below anything a user sees.
GROWTH_MARGIN = 1.0e-6
# int dx / s is rounded up to whole cells after this relative slack: an
# interval of exactly k sizes gets k cells (not k + 1 for a rounding error).
ROUND_SLACK = 1.0e-10
# Lines closer than LINE_MERGE * size to each other or to an end of the axis
# are one line (the first, or the end): such a pair is one horizon typed
# twice, and separate lines would need cells of that width.
LINE_MERGE = 1.0e-9
# Step 3 finds the sizes at a short segment's ends by this many bisections
# (of their logarithm, between a size that surely works and one that does
# not): within a factor (ratio)^(1/4096) of the largest that works.
SHRINK_STEPS = 12


class _Field(NamedTuple):
    """A piecewise-linear positive function: knots xs (increasing), values vs."""

    xs: np.ndarray
    vs: np.ndarray


def _integral(f: _Field) -> np.ndarray:
    """(k - 1,) int dx / f over each piece, in closed form."""
    dx = np.diff(f.xs)
    v0, v1 = f.vs[:-1], f.vs[1:]
    # an axis of 1e18 m over sizes of 1e-300 m overflows to inf: the element
    # count that follows refuses it, so the overflow itself is not news
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        r = (v1 - v0) / v0
        out = dx * np.log1p(r) / (v1 - v0)
        return np.where(v1 == v0, dx / v0, out)


def _pl_min(f: _Field, g: _Field) -> _Field:
    """min(f, g) of two piecewise-linear functions on the same interval."""
    xs = np.union1d(f.xs, g.xs)
    a, b = np.interp(xs, f.xs, f.vs), np.interp(xs, g.xs, g.vs)
    d = a - b
    cross = np.flatnonzero(d[:-1] * d[1:] < 0.0)
    if cross.size:
        t = d[cross] / (d[cross] - d[cross + 1])
        xc = xs[cross] + t * (xs[cross + 1] - xs[cross])
        xs = np.union1d(xs, xc)
        a, b = np.interp(xs, f.xs, f.vs), np.interp(xs, g.xs, g.vs)
    return _Field(xs, np.minimum(a, b))


def _line(x0: float, x1: float, v0: float, slope: float) -> _Field:
    """v0 + slope (x - x0) on [x0, x1] as a _Field."""
    return _Field(np.array([x0, x1]), np.array([v0, v0 + slope * (x1 - x0)]))


def _size_field(lo, hi, mu, cap, sources) -> _Field:
    """s(x) = min(cap, min_j (sigma_j + mu dist(x, [p_j, q_j]))) on [lo, hi];
    sources: (k, 3) rows p, q, sigma."""
    p, q, sig = sources.T if sources.size else (np.zeros(0),) * 3
    knots = np.unique(np.clip(np.concatenate([[lo, hi], p, q]), lo, hi))
    # on each piece between knots: min(C, A + mu x, B - mu x) (see _value_at)
    a0, a1 = knots[:-1], knots[1:]
    A, B, C = _influences(a0, a1, p, q, sig, mu)
    with np.errstate(invalid="ignore"):  # inf - inf where a side has no source
        extra = [(B - A) / (2 * mu), (C - A) / mu, (B - C) / mu, (cap - A) / mu]
        extra.append((B - cap) / mu)
        cand = np.concatenate([np.where((e > a0) & (e < a1), e, np.nan) for e in extra])
    xs = np.union1d(knots, cand[np.isfinite(cand)])
    return _Field(xs, _value_at(xs, p, q, sig, mu, cap))


def _influences(a0, a1, p, q, sig, mu):
    """Per piece [a0, a1]: A (sources left of it give A + mu x), B (right:
    B - mu x), C (covering it: the constant C); inf where none."""
    inf = np.full(a0.shape, np.inf)
    if p.size == 0:
        return inf, inf, inf
    order = np.argsort(q)
    left = np.minimum.accumulate((sig - mu * q)[order])
    k = np.searchsorted(q[order], a0, side="right")
    A = np.where(k > 0, left[np.maximum(k - 1, 0)], np.inf)
    order = np.argsort(p)
    right = np.minimum.accumulate(((sig + mu * p)[order])[::-1])[::-1]
    k = np.searchsorted(p[order], a1, side="left")
    B = np.where(k < p.size, right[np.minimum(k, p.size - 1)], np.inf)
    covers = (p[None, :] <= a0[:, None]) & (q[None, :] >= a1[:, None])
    C = np.where(covers, sig[None, :], np.inf).min(axis=1)
    return A, B, C


def _value_at(xs, p, q, sig, mu, cap) -> np.ndarray:
    """s at points xs (the min over sources of sigma + mu dist, and cap)."""
    if p.size == 0:
        return np.full(xs.shape, float(cap))
    out = np.full(xs.shape, float(cap))
    for lo in range(0, p.size, 4096):  # bounded memory for many sources
        pp, qq, ss = p[lo : lo + 4096], q[lo : lo + 4096], sig[lo : lo + 4096]
        dist = np.maximum(0.0, np.maximum(pp[None, :] - xs[:, None], xs[:, None] - qq))
        out = np.minimum(out, (ss[None, :] + mu * dist).min(axis=1))
    return out


def _restrict(f: _Field, a: float, b: float) -> _Field:
    """f on [a, b] (a, b inside f's range)."""
    inner = f.xs[(f.xs > a) & (f.xs < b)]
    xs = np.concatenate([[a], inner, [b]])
    return _Field(xs, np.interp(xs, f.xs, f.vs))


class _Segment(NamedTuple):
    """One segment between lines: its size field and which ends are lines."""

    s: _Field
    left_line: bool
    right_line: bool


def _capped(seg: _Segment, mu: float, T: float) -> _Field:
    """s~ = min(s, C_T) on the segment (step 2)."""
    s = seg.s
    p, q = float(s.xs[0]), float(s.xs[-1])
    cap = _Field(np.array([p, q]), np.array([T, T]))
    if seg.left_line:
        cap = _pl_max(cap, _line(p, q, float(s.vs[0]), -mu))
    if seg.right_line:
        cap = _pl_max(cap, _line(p, q, float(s.vs[-1]) - mu * (q - p), mu))
    return _pl_min(s, cap)


def _pl_max(f: _Field, g: _Field) -> _Field:
    """max(f, g) = -min(-f, -g)."""
    m = _pl_min(_Field(f.xs, -f.vs), _Field(g.xs, -g.vs))
    return _Field(m.xs, -m.vs)


# a cell count no mesh can have: what an axis needs when int dx / s
# overflows (a cell size far below the axis' length), for the element-count
# check to refuse
UNBOUNDED_CELLS = 10**18


def _cells(phi: float) -> int:
    """Whole cells for int dx / s = phi (rounded up after ROUND_SLACK)."""
    if not math.isfinite(phi) or phi > UNBOUNDED_CELLS:
        return UNBOUNDED_CELLS
    return max(1, math.ceil(phi * (1.0 - ROUND_SLACK)))


def _reach(seg: _Segment, mu: float) -> tuple[int, float]:
    """(n, most cells any T gives): reachable when the second >= the first."""
    n = _cells(float(_integral(seg.s).sum()))
    tiny = float(seg.s.vs.max()) * 1e-280
    return n, float(_integral(_capped(seg, mu, tiny)).sum())


def _shrunk_end_size(seg: _Segment, mu: float) -> float:
    """The size at the line end(s) of a short segment that makes it reachable
    (step 3): between mu L / 2, which surely does (the descending lines of
    step 2 then meet at zero), and the smaller end size, which does not, by
    SHRINK_STEPS bisections of its logarithm."""
    s = seg.s
    p, q = float(s.xs[0]), float(s.xs[-1])
    ends = ((s.vs[0], seg.left_line), (s.vs[-1], seg.right_line))
    hi = float(min(v for v, line in ends if line))
    lo = min(hi, 0.5 * mu * (q - p)) * (1.0 - 1e-9)

    def reachable(sigma):
        new = s
        if seg.left_line:
            new = _pl_min(new, _line(p, q, sigma, mu))
        if seg.right_line:
            new = _pl_min(new, _line(p, q, sigma + mu * (q - p), -mu))
        return not _unreachable(_Segment(new, seg.left_line, seg.right_line), mu)

    for _ in range(SHRINK_STEPS):
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if reachable(mid) else (lo, mid)
    return lo


class AxisPlan(NamedTuple):
    """A graded axis before its nodes are placed: ``n_cells`` is known
    without allocating them (the memory guard of the case reader).

    breaks : (m + 1,) float64 the ends and the lines, increasing [m]
    counts : (m,) int64 cells per segment between breaks
    fields : the size field s~ of each segment (private)
    """

    breaks: np.ndarray
    counts: np.ndarray
    fields: tuple

    @property
    def n_cells(self) -> int:
        return int(self.counts.sum())

    def nodes(self) -> np.ndarray:
        """(n_cells + 1,) float64 node coordinates, strictly increasing [m]."""
        parts = [self.breaks[:1]]
        for f, n, end in zip(self.fields, self.counts, self.breaks[1:], strict=True):
            parts.append(np.append(_invert(f, int(n)), end))
        return np.concatenate(parts)


def _invert(f: _Field, n: int) -> np.ndarray:
    """(n - 1,) points where int dx / f from f.xs[0] reaches 1 .. n - 1."""
    if n <= 1:
        return np.zeros(0)
    cum = np.concatenate([[0.0], np.cumsum(_integral(f))])
    target = np.arange(1, n, dtype=np.float64)
    k = np.clip(np.searchsorted(cum, target, side="right") - 1, 0, f.xs.size - 2)
    x0, v0 = f.xs[k], f.vs[k]
    slope = (f.vs[k + 1] - v0) / (f.xs[k + 1] - x0)
    d = target - cum[k]
    with np.errstate(divide="ignore", invalid="ignore"):
        x = x0 + v0 * np.expm1(slope * d) / slope
    x = np.where(slope == 0.0, x0 + v0 * d, x)
    return np.minimum(x, f.xs[k + 1])


def _segments(s: _Field, breaks: np.ndarray) -> list[_Segment]:
    m = breaks.size - 1
    return [
        _Segment(_restrict(s, breaks[i], breaks[i + 1]), i > 0, i < m - 1)
        for i in range(m)
    ]


def plan_axis(
    lo: float,
    hi: float,
    size: float,
    growth: float,
    max_size: float = math.inf,
    fine=(),
    lines=(),
) -> AxisPlan:
    """The cells of a graded axis [lo, hi], before their nodes are placed.

    Parameters
    ----------
    lo, hi : the ends of the axis, lo < hi [m]
    size : h, the largest cell over a fine interval [m] > 0
    growth : g, 1 < g: neighbouring cells differ by at most this ratio [-]
    max_size : H >= h, the largest cell anywhere [m] (inf: no cap)
    fine : (k, 2) intervals [a, b], a <= b [m], where cells are at most h
        (a cell touching one is at most h); parts beyond [lo, hi] are ignored
    lines : (l,) coordinates [m] in [lo, hi] that must be nodes (merged
        within LINE_MERGE * size)

    Raises ValueError on arguments outside these ranges (the case reader
    validates what a user types).
    """
    if not (lo < hi and size > 0.0 and growth > 1.0 and max_size >= size):
        raise ValueError(
            f"need lo < hi, size > 0, growth > 1, max_size >= size; got "
            f"{lo}, {hi}, {size}, {growth}, {max_size}"
        )
    mu = math.log(growth) * (1.0 - GROWTH_MARGIN)
    cap = min(max_size, hi - lo)  # no cell is longer than the axis
    widened = _widened(np.asarray(fine, dtype=np.float64).reshape(-1, 2), lo, hi, size)
    breaks = _breaks(lo, hi, np.asarray(lines, dtype=np.float64), size)
    points = np.zeros((0, 3))
    while True:
        sources = np.concatenate([widened, points])
        segs = _segments(_size_field(lo, hi, mu, cap, sources), breaks)
        short = [seg for seg in segs if _unreachable(seg, mu)]
        if not short:
            break
        added = []
        for seg in short:
            sigma = _shrunk_end_size(seg, mu)
            if seg.left_line:
                added.append([seg.s.xs[0], seg.s.xs[0], sigma])
            if seg.right_line:
                added.append([seg.s.xs[-1], seg.s.xs[-1], sigma])
        points = np.concatenate([points, np.array(added)])
    fields, counts = [], []
    for seg in segs:
        n, f = _round(seg, mu)
        fields.append(f)
        counts.append(n)
    return AxisPlan(breaks, np.array(counts, dtype=np.int64), tuple(fields))


def _unreachable(seg: _Segment, mu: float) -> bool:
    n, most = _reach(seg, mu)
    return most < n


def _widened(fine: np.ndarray, lo: float, hi: float, size: float) -> np.ndarray:
    """(k, 3) sources p, q, sigma = size: the fine intervals touching [lo, hi],
    widened by size on each side and merged where they overlap."""
    if np.any(fine[:, 0] > fine[:, 1]):
        raise ValueError("fine intervals need a <= b")
    fine = fine[(fine[:, 1] >= lo) & (fine[:, 0] <= hi)]
    fine = fine[np.argsort(fine[:, 0])] + np.array([-size, size])
    merged: list[list[float]] = []
    for a, b in fine:
        if merged and a <= merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], b)
        else:
            merged.append([a, b])
    out = np.array(merged, dtype=np.float64).reshape(-1, 2)
    return np.column_stack([out, np.full(len(out), size)])


def _breaks(lo, hi, lines, size) -> np.ndarray:
    """The ends and the lines, sorted, near-duplicates merged (LINE_MERGE)."""
    if lines.size and (lines.min() < lo or lines.max() > hi):
        raise ValueError(f"lines must lie in [{lo}, {hi}]")
    tol = LINE_MERGE * size
    out = [lo]
    for v in np.sort(lines):
        if v - out[-1] > tol and hi - v > tol:
            out.append(float(v))
    out.append(hi)
    return np.array(out)


def _round(seg: _Segment, mu: float) -> tuple[int, _Field]:
    """(n, s~) of a reachable segment: T with int dx / s~ = n (step 2)."""
    phi = float(_integral(seg.s).sum())
    n = _cells(phi)
    if n <= phi:  # an exact whole number of cells: s~ = s
        return n, seg.s
    top = float(seg.s.vs.max())

    def excess(T):
        return float(_integral(_capped(seg, mu, T)).sum()) - n

    hi, lo = top, 0.5 * top  # bracket the root by halving (reachable: it ends)
    while excess(lo) < 0.0 and lo > top * 1e-280:
        hi, lo = lo, 0.5 * lo
    # imported here: scipy.optimize takes 0.3 s to import, and a uniform
    # mesh never gets here
    from scipy.optimize import brentq

    T = brentq(excess, lo, hi, xtol=1e-300, rtol=4 * np.finfo(float).eps)
    return n, _capped(seg, mu, T)


def graded_axis(
    lo: float,
    hi: float,
    size: float,
    growth: float,
    max_size: float = math.inf,
    fine=(),
    lines=(),
) -> np.ndarray:
    """(n + 1,) float64 node coordinates of a graded axis [m]: the nodes of
    ``plan_axis`` (see there for the arguments).

    Guarantees (to the rounding of the coordinates): nodes strictly
    increasing from lo to hi exactly; every line a node exactly; a cell
    touching a fine interval at most ``size``; neighbouring cells within a
    ratio ``growth``; every cell at most ``max_size``.
    """
    return plan_axis(lo, hi, size, growth, max_size, fine, lines).nodes()


def graded_axes(
    origin,
    extent,
    size: float,
    growth: float,
    max_size: float = math.inf,
    fine_x=(),
    fine_y=(),
    lines_x=(),
    lines_y=(),
) -> tuple[AxisPlan, AxisPlan]:
    """The two axes of a graded rectilinear mesh, as plans (``n_cells``
    first, ``nodes()`` when the count is accepted).

    origin : (x0, y0) lower-left corner [m]; extent : (width, height) [m];
    fine_x, fine_y : (k, 2) intervals of each axis [m]; lines_x, lines_y :
    coordinates that must be nodes [m]; size, growth, max_size: as
    ``plan_axis``.  A fracture contributes its x-extent to fine_x and its
    y-extent to fine_y; a horizontal edge at y = c the line c and the
    interval [c, c] to fine_y.
    """
    (x0, y0), (w, h) = origin, extent
    px = plan_axis(x0, x0 + w, size, growth, max_size, fine_x, lines_x)
    py = plan_axis(y0, y0 + h, size, growth, max_size, fine_y, lines_y)
    return px, py
