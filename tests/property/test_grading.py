"""Property tests of the graded axis (xfemslip.geometry.grading), hypothesis
derandomized: for random ends, fine intervals, lines, sizes, growths and caps
the nodes run strictly increasing from one end exactly to the other, every
line is a node exactly, a cell touching a fine interval is at most the size,
neighbouring cells stay within the growth ratio, every cell is at most the
largest size; and the count is close to that of the ideal geometric grading
written out here."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from xfemslip.geometry.grading import graded_axis, plan_axis

# A size within 1e-9 relative counts as equal (ROUND_SLACK); a cell length
# is known to the rounding of its two coordinates, 2 eps max|x|.
SIZE_TOL = 1e-9
EPS = np.finfo(float).eps


@st.composite
def axes(draw):
    lo = draw(st.floats(-1e4, 1e4, allow_nan=False))
    length = draw(st.floats(1.0, 1e4, allow_nan=False))
    hi = lo + length
    size = length * draw(st.floats(1e-3, 0.5))
    growth = draw(st.floats(1.01, 2.0))
    max_size = size * draw(st.sampled_from([1.0, 1.5, 10.0, 1e3, math.inf]))
    k = draw(st.integers(0, 4))
    fine = []
    for _ in range(k):
        a = lo + length * draw(st.floats(-0.2, 1.2))
        w = length * draw(st.sampled_from([0.0, 1e-4, 0.01, 0.2]))
        fine.append([a, a + w])
    lines = [
        lo + length * draw(st.floats(0.0, 1.0)) for _ in range(draw(st.integers(0, 4)))
    ]
    if draw(st.booleans()) and fine:  # a line at a fine interval's edge
        lines.append(min(max(fine[0][0], lo), hi))
    if draw(st.booleans()) and lines:  # two lines very close
        lines.append(min(lines[0] + size * draw(st.floats(1e-6, 0.3)), hi))
    return lo, hi, size, growth, max_size, fine, lines


def _assert_properties(x, lo, hi, size, growth, max_size, fine, lines):
    d = np.diff(x)
    assert x[0] == lo and x[-1] == hi
    assert np.all(d > 0.0)
    err = 2 * EPS * max(abs(lo), abs(hi)) / d  # relative rounding of each cell
    merged = 1e-9 * size  # lines merged within LINE_MERGE * size
    for v in lines:
        gap = np.min(np.abs(x - v))
        assert gap == 0.0 or (gap <= merged), (v, gap)
    ratio = np.maximum(d[1:] / d[:-1], d[:-1] / d[1:])
    assert np.all(ratio <= growth * (1 + err[1:] + err[:-1])), ratio.max()
    assert np.all(d <= max_size * (1 + SIZE_TOL + err))
    for a, b in fine:
        touch = (x[1:] >= a) & (x[:-1] <= b)
        bound = size * (1 + SIZE_TOL + err[touch])
        assert np.all(d[touch] <= bound), (a, b, d[touch].max())


@settings(derandomize=True, max_examples=150, deadline=None)
@given(axes())
def test_graded_axis_properties(args):
    lo, hi, size, growth, max_size, fine, lines = args
    x = graded_axis(lo, hi, size, growth, max_size, fine, lines)
    _assert_properties(x, lo, hi, size, growth, max_size, fine, lines)
    assert plan_axis(lo, hi, size, growth, max_size, fine, lines).n_cells == x.size - 1


def _ideal_count(length, size, growth, max_size, fine_width):
    """Cells of the geometric grading written out: the fine interval widened
    by one size on each side, then cells size g, size g^2, ... up to max_size
    on each side until the ends (the interval in the middle)."""
    n = math.ceil((fine_width + 2 * size) / size)
    side = 0.5 * (length - n * size)
    count, cell = 0, size
    while side > 0:
        cell = min(cell * growth, max_size)
        side -= cell
        count += 1
    return n + 2 * count


@settings(derandomize=True, max_examples=40, deadline=None)
@given(
    st.floats(1.05, 2.0),
    st.floats(0.0, 50.0),
    st.sampled_from([20.0, 100.0, math.inf]),
)
def test_count_is_close_to_the_geometric_grading(growth, width, max_size):
    """One fine interval in the middle of [0, 1000], size 1: within 2 cells
    per side plus one per segment of the ideal count."""
    x = graded_axis(
        0.0, 1000.0, 1.0, growth, max_size, [[500 - width / 2, 500 + width / 2]]
    )
    ideal = _ideal_count(1000.0, 1.0, growth, max_size, width)
    assert abs((x.size - 1) - ideal) <= 5, (x.size - 1, ideal)


def test_a_uniform_axis_stays_uniform():
    """The whole axis fine: the exact number of cells of the size, all equal."""
    x = graded_axis(0.0, 2000.0, 25.0, 1.2, 100.0, [[0.0, 2000.0]])
    np.testing.assert_allclose(np.diff(x), 25.0, rtol=1e-12)
    assert x.size == 81


def test_lines_split_a_fine_interval_exactly():
    """Lines 2.3 sizes apart bounding a fine interval: three cells between
    them (the fewest of at most the size), and the axis no longer than its
    ideal grading by more than a cell per side."""
    x = graded_axis(0.0, 10.0, 1.0, 1.2, 10.0, [[4.0, 6.3]], [4.0, 6.3])
    i, j = np.flatnonzero(x == 4.0)[0], np.flatnonzero(x == 6.3)[0]
    assert j - i == 3
    assert np.diff(x[i : j + 1]).max() <= 1.0
    _assert_properties(x, 0.0, 10.0, 1.0, 1.2, 10.0, [[4.0, 6.3]], [4.0, 6.3])
    assert x.size - 1 <= _ideal_count(10.0, 1.0, 1.2, 10.0, 2.3) + 2
