"""Snapping rules of the junction search (geometry.find_junctions) on the
inputs where snapping could lay one fracture onto another: near-parallel pairs, X
crossings at a fraction of a degree, narrow V's, both ends of a fracture
within half a cell of another's ends, stacks of parallel fractures, dense
generated networks.

Every such network builds (geometry.build_fractures), and its junctions agree
with an independent segment test (dfn.intersecting_pairs, which measures
segment distances and knows nothing of junctions):

- on the snapped fractures, two fractures meet (within the geometric
  tolerance) exactly when they have a junction, and they never overlap;
- every pair that crossed or touched before snapping still has a junction,
  and a junction only joins fractures that were within two snap distances;
- every junction point lies on both of its fractures, at the secondary's end
  for a T, at both ends for a V, at neither for an X; no end moves by more
  than the snap distance.

Fractures that truly overlap (collinear, with a common stretch) are refused
with one line naming both.  Stuck fractures in a uniformly stressed body carry
the uniform traction sigma . n (the patch test), whatever their junctions.
"""

from __future__ import annotations

import copy
import logging
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from tests.support.casegen import SHIPPED_DFN, fracture_spec
from tests.support.tiers import examples
from xfemslip.case import build, loads_case
from xfemslip.errors import GeometryError
from xfemslip.fem.mesh import build_mesh
from xfemslip.geometry.dfn import intersecting_pairs
from xfemslip.geometry.fracture import GEOMETRY_TOL, clip_to_domain, on_boundary
from xfemslip.geometry.junctions import (
    JUNCTION_MIN_ANGLE,
    JUNCTION_SNAP_CELLS,
    build_fractures,
    find_junctions,
)

N_CELLS = 10
H = 1.0 / N_CELLS
SNAP = JUNCTION_SNAP_CELLS * H
BOX = np.array([0.0, 1.0, 0.0, 1.0])
MAIN = [[0.2, 0.5], [0.8, 0.5]]


def _segment(center, length, degrees):
    """End points of a straight fracture [m]; angle from +x [deg]."""
    rad = math.radians(degrees)
    c = np.asarray(center, float)
    d = 0.5 * length * np.array([math.cos(rad), math.sin(rad)])
    return [list(c - d), list(c + d)]


def _distance(p, a, b) -> float:
    """Distance from point p to segment a-b."""
    p, a, b = (np.asarray(v, float) for v in (p, a, b))
    d = b - a
    t = min(max((p - a) @ d / (d @ d), 0.0), 1.0)
    return float(np.linalg.norm(a + t * d - p))


def _overlap(s, r, tol) -> bool:
    """Segments s, r (2, 2) within tol of each other over more than tol."""
    length = float(np.linalg.norm(s[1] - s[0]))
    u = (s[1] - s[0]) / length
    along = sorted((r - s[0]) @ u)
    lo, hi = max(along[0], 0.0), min(along[1], length)
    return hi - lo > tol and all(_distance(s[0] + x * u, *r) <= tol for x in (lo, hi))


def _junctions(segments, box=BOX, h=H):
    """(snapped segments, junctions) of straight fractures, as build_fractures
    finds them (clipped to the box, boundary ends not free)."""
    tol = GEOMETRY_TOL * h
    polylines, free = [], []
    for k, seg in enumerate(segments):
        pts, _ = clip_to_domain(np.asarray(seg, float), box, tol, f"[{k}]")
        polylines.append(pts.copy())
        free.append([not on_boundary(p, box, tol) for p in pts[[0, -1]]])
    names = [f"fractures[{k}]" for k in range(len(segments))]
    found = find_junctions(polylines, free, names, h, tol)
    return np.array(polylines), found


def _assert_consistent(before, after, found, h=H):
    """The properties of the module docstring, for straight fractures."""
    tol = GEOMETRY_TOL * h
    snap = JUNCTION_SNAP_CELLS * h
    met = {tuple(sorted((m, s))) for _, m, s, _ in found}
    meets = set(intersecting_pairs(after, tol))
    assert meets == met
    assert set(intersecting_pairs(before, 0.0)) <= met
    assert met <= set(intersecting_pairs(before, 2.0 * snap))
    for i, j in meets:
        assert not _overlap(after[i], after[j], tol)
        assert not _overlap(after[j], after[i], tol)
    for kind, m, s, point in found:
        assert _distance(point, *after[m]) <= tol
        assert _distance(point, *after[s]) <= tol
        at_m = [np.linalg.norm(after[m][e] - point) <= tol for e in (0, 1)]
        at_s = [np.linalg.norm(after[s][e] - point) <= tol for e in (0, 1)]
        expected = {"X": (False, False), "T": (False, True), "V": (True, True)}
        assert (any(at_m), any(at_s)) == expected[kind], (kind, at_m, at_s)
    assert np.abs(after - before).max() <= snap * (1.0 + 1e-12)


def _check(segments, h=H):
    """Build the fractures on an n x n mesh of the unit square and check the
    junctions; returns (snapped segments, junctions, fractures)."""
    n = round(1.0 / h)
    grid = np.linspace(0.0, 1.0, n + 1)
    mesh = build_mesh(grid, grid)
    specs = [fracture_spec(p, i, "ramp") for i, p in enumerate(segments)]
    fractures = build_fractures(mesh, specs, BOX)
    before = np.array(segments, float)
    after, found = _junctions(segments, h=h)
    for f, seg in zip(fractures, after, strict=True):
        np.testing.assert_array_equal(f.points, seg)  # the same snapping
    _assert_consistent(before, after, found, h)
    return after, found, fractures


# ---------------------------------------------------------- the hard cases


@pytest.mark.parametrize("gap", [0.4, 0.1, 1e-2, 1e-4, 1e-6])
@pytest.mark.parametrize("tilt", [0.0, 0.2, 3.0])
def test_near_parallel_pairs_stay_apart(gap, tilt):
    """A fracture alongside another, closer than the snap distance at both
    ends: no end moves (it would lay the fracture onto the other), no
    junction, two tips each."""
    rad = math.radians(tilt)
    start = [0.3, 0.5 + gap * H]  # rising away from the main from there
    other = [start, [0.3 + 0.4 * math.cos(rad), start[1] + 0.4 * math.sin(rad)]]
    after, found, fractures = _check([MAIN, other])
    assert found == []
    np.testing.assert_array_equal(after[1], other)
    assert [len(f.tips) for f in fractures] == [2, 2]


def test_ends_left_apart_are_counted_in_the_log(caplog):
    caplog.set_level(logging.INFO, logger="xfemslip.geometry.junctions")
    _check([MAIN, [[0.3, 0.51], [0.7, 0.515]]])
    assert "2 fracture end(s) within 0.05 m (h/2) of another fracture left as " in (
        caplog.text
    )


@pytest.mark.parametrize("degrees", [0.1, 0.2, 0.5, 1.0])
@pytest.mark.parametrize("shift", [0.0, 0.013, 0.2])
def test_x_crossings_at_a_fraction_of_a_degree(degrees, shift):
    """Both ends of the crossing fracture lie within snap of the main; it
    stays a straight X, cut into two arms on opposite sides of the main."""
    other = _segment([0.5 + shift, 0.5], 0.5, degrees)
    after, found, fractures = _check([MAIN, other])
    assert [k for k, *_ in found] == ["X"]
    np.testing.assert_array_equal(after, np.array([MAIN, other]))
    sec = fractures[found[0][2]]
    (lower,), (upper,) = sec.arms
    assert lower.sign == -upper.sign and lower.far == upper.far == 0.0


@pytest.mark.parametrize("degrees", [0.1, 0.5, 1.0, 2.0, 5.0])
def test_narrow_v_with_a_shared_end(degrees):
    """Two fractures from one point at a small angle: one V at that point,
    the other end of the secondary, within snap of the main, stays put."""
    other = [MAIN[0], [0.2 + 0.6 * math.cos(math.radians(degrees)), 0.5]]
    other[1][1] += 0.6 * math.sin(math.radians(degrees))
    after, found, fractures = _check([MAIN, other])
    assert [(k, list(p)) for k, _, _, p in found] == [("V", MAIN[0])]
    np.testing.assert_array_equal(after, np.array([MAIN, other]))
    sec = fractures[found[0][2]]
    assert sec.junction_ends == (0,) and len(sec.tips) == 1


@pytest.mark.parametrize("degrees", [0.5, 2.0, 5.0, 20.0, 60.0])
def test_v_with_a_gap_snaps_only_at_an_angle(degrees):
    """Ends 0.3 h apart: moved together (a V) when the secondary then meets
    the main at JUNCTION_MIN_ANGLE or more, else left apart (two tips)."""
    rad = math.radians(degrees)
    other = [[0.2 + 0.2 * H, 0.5 + 0.2 * H], [0.2 + 0.4 * math.cos(rad), 0.0]]
    other[1][1] = 0.5 + 0.2 * H + 0.4 * math.sin(rad)
    after, found, _ = _check([MAIN, other])
    moved = other[1] - np.asarray(MAIN[0])
    turned = math.degrees(math.atan2(moved[1], moved[0]))
    if turned >= JUNCTION_MIN_ANGLE:
        assert [k for k, *_ in found] == ["V"]
        np.testing.assert_array_equal(after[1][0], MAIN[0])
    else:
        assert found == []
        np.testing.assert_array_equal(after[1], other)


@pytest.mark.parametrize("delta", [1e-6, 1e-5, 1e-3, 1.0])
@pytest.mark.parametrize("heading", [12.96, 41.19, 75.3])
def test_crossing_just_short_of_both_ends_is_a_v(heading, delta):
    """Two fractures crossing at C at a small angle delta [deg], both ending
    less than snap beyond it (the starts are 0.25 delta apart): both ends are
    trimmed back to where the fractures meet, one V there, the starts stay two
    tips.  They meet within tol of each other over tol / sin(delta) either side
    of C (6 mm at 1e-6 deg: the junction may be at the nearer end); the place
    of the crossing itself is uncertain by round-off / delta (1e-8 m at 1e-6
    deg, more than tol), and the two trims must still end on one point."""
    C = np.array([0.55, 0.45])
    u = [
        np.array([math.cos(a), math.sin(a)])
        for a in np.radians([heading, heading + delta])
    ]
    main = [C - 0.25 * u[0], C + 0.0014 * u[0]]
    other = [C - 0.25 * u[1], C + 0.0012 * u[1]]
    after, found, fractures = _check([main, other])
    assert [k for k, *_ in found] == ["V"]
    point = found[0][3]
    meet = GEOMETRY_TOL * H / math.sin(math.radians(delta))
    assert np.linalg.norm(point - C) <= meet + 1e-6 * H
    for f in (0, 1):
        assert np.linalg.norm(after[f][1] - point) <= GEOMETRY_TOL * H
    np.testing.assert_array_equal(after[:, 0], np.array([main[0], other[0]]))
    sec = fractures[found[0][2]]
    assert sec.junction_ends == (1,) and len(sec.tips) == 1


@pytest.mark.parametrize("reverse", [False, True])
@pytest.mark.parametrize("offset", [0.05, 0.2, 0.45])
def test_both_ends_within_snap_of_the_others_ends(reverse, offset):
    """A near copy of the main (each end within snap of one of the main's):
    it is not collapsed onto the main; at most one end joins it."""
    other = [[0.2 + offset * H, 0.5 + offset * H], [0.8 - offset * H, 0.5 + H / 3]]
    if reverse:
        other = other[::-1]
    after, found, _ = _check([MAIN, other])
    assert len(found) <= 1
    assert np.linalg.norm(after[1][1] - after[1][0]) > 0.5


def test_fifty_parallel_fractures_build_without_junctions():
    stack = [[[0.1, 0.1 + 0.015 * i], [0.9, 0.1 + 0.015 * i]] for i in range(50)]
    after, found, fractures = _check(stack)
    assert found == [] and len(fractures) == 50
    np.testing.assert_array_equal(after, np.array(stack))


def test_collinear_fractures_meeting_end_to_end_are_a_straight_v():
    """Two fractures on one line sharing an end: a V whose junction function
    jumps across the whole line (both fractures), constant off it."""
    left, right = [[0.2, 0.5], [0.5, 0.5]], [[0.5, 0.5], [0.75, 0.5]]
    _, found, fractures = _check([left, right])
    assert [k for k, *_ in found] == ["V"]
    sec = fractures[found[0][2]]
    assert len(sec.arms) == 1 and len(sec.arms[0]) == 1
    probes = np.array([[0.3, 0.52], [0.3, 0.48], [0.6, 0.52], [0.6, 0.48]])
    J = sec.junction_factor(0, probes, sec.side(probes))
    assert J[0] == J[2] and J[1] == J[3] and J[0] != J[1]


OVERLAPS = [
    pytest.param([[0.5, 0.5], [0.95, 0.5]], id="partly"),
    pytest.param([[0.3, 0.5], [0.6, 0.5]], id="inside"),
    pytest.param([[0.7, 0.5], [0.3, 0.5]], id="inside-reversed"),
    pytest.param([[0.3, 0.5], [0.7, 0.5 + 1e-12]], id="within-tolerance"),
    # not parallel to 1e-12, but within the geometric tolerance (1e-10 m)
    pytest.param([[0.3, 0.5], [0.7, 0.5 + 5e-11]], id="tiny-angle"),
]


@pytest.mark.parametrize("other", OVERLAPS)
def test_true_overlaps_are_refused_with_one_line(other):
    before = np.array([MAIN, other])
    assert _overlap(before[0], before[1], GEOMETRY_TOL * H) or _overlap(
        before[1], before[0], GEOMETRY_TOL * H
    )
    with pytest.raises(GeometryError) as err:
        _check([MAIN, other])
    message = str(err.value)
    assert "fractures[0] and fractures[1] overlap along a common line" in message
    assert "\n" not in message


def test_a_polyline_overlapping_another_is_refused():
    bent = [[0.1, 0.2], [0.3, 0.5], [0.6, 0.5], [0.7, 0.8]]
    mesh = build_mesh(np.linspace(0, 1, 11), np.linspace(0, 1, 11))
    specs = [fracture_spec(p, i) for i, p in enumerate([MAIN, bent])]
    with pytest.raises(GeometryError, match=r"fractures\[0\] and fractures\[1\]"):
        build_fractures(mesh, specs, BOX)


# ----------------------------------------- generated pairs and triples

scale = st.floats(-7.0, math.log10(0.6)).map(lambda e: 10.0**e)  # [h]
small_angle = st.floats(-4.0, math.log10(15.0)).map(lambda e: 10.0**e)  # [deg]
sign = st.sampled_from([-1.0, 1.0])


@st.composite
def tricky_segment(draw, base):
    """A segment made from ``base`` (2, 2) the way the hard cases are: along
    it, across it at a small angle, from one of its ends, or a near copy."""
    a, b = (np.asarray(p, float) for p in base)
    u = (b - a) / np.linalg.norm(b - a)
    n = np.array([-u[1], u[0]])
    kind = draw(st.sampled_from(["parallel", "cross", "v", "copy", "free"]))
    theta = math.radians(draw(sign) * draw(small_angle))
    cos, sin = math.cos(theta), math.sin(theta)
    rot = np.array([[cos, -sin], [sin, cos]])
    d = draw(sign) * draw(scale) * H
    length = draw(st.floats(0.05, 0.6))
    if kind == "parallel":
        start = a + draw(st.floats(-0.2, 0.8)) * (b - a) + d * n
        seg = [start, start + length * (rot @ u)]
    elif kind == "cross":
        mid = a + draw(st.floats(0.0, 1.0)) * (b - a)
        seg = [mid - 0.5 * length * (rot @ u), mid + 0.5 * length * (rot @ u)]
    elif kind == "v":
        apex = (a if draw(st.booleans()) else b) + d * (rot @ n)
        seg = [apex, apex + length * (rot @ u) * draw(sign)]
    elif kind == "copy":
        e1 = draw(sign) * draw(scale) * H * (rot @ n)
        e2 = draw(sign) * draw(scale) * H * (rot @ u)
        seg = [a + e1, b + e2] if draw(st.booleans()) else [b + e2, a + e1]
    else:
        c = np.array([draw(st.floats(0.1, 0.9)), draw(st.floats(0.1, 0.9))])
        w = draw(st.floats(0.0, math.pi))
        seg = [c, c + length * np.array([math.cos(w), math.sin(w)])]
    return np.clip(np.array(seg), 0.02, 0.98)


@st.composite
def tricky_network(draw):
    c = np.array([draw(st.floats(0.3, 0.7)), draw(st.floats(0.3, 0.7))])
    w = draw(st.floats(0.0, math.pi))
    length = draw(st.floats(0.1, 0.6))
    d = 0.5 * length * np.array([math.cos(w), math.sin(w)])
    segments = [np.array([c - d, c + d])]
    for _ in range(draw(st.integers(1, 3))):
        base = segments[draw(st.integers(0, len(segments) - 1))]
        segments.append(draw(tricky_segment(base)))
    return [s for s in segments if np.linalg.norm(s[1] - s[0]) > 1e-3]


@settings(max_examples=examples(300), deadline=None, derandomize=True)
@given(tricky_network())
@example(  # starts 3e-8 m apart, crossing at 2e-5 deg 1.2-1.4 mm from the ends
    [
        [
            [0.5843287103451505, 0.40661521424845504],
            [0.6656712896548495, 0.4778104645967063],
        ],
        [
            [0.5843287311722484, 0.40661519045282524],
            [0.665513764862967, 0.477672591202556],
        ],
    ]
)
def test_tricky_pairs_and_triples_build_with_consistent_junctions(segments):
    tol = GEOMETRY_TOL * H
    before = np.array(segments)
    overlapping = [
        (i, j)
        for i, j in intersecting_pairs(before, tol)
        if _overlap(before[i], before[j], tol) or _overlap(before[j], before[i], tol)
    ]
    if overlapping:
        with pytest.raises(GeometryError, match="overlap along a common line"):
            _check(segments)
        return
    _check(segments)


# ------------------------------------------------- generated networks

TEST_TABLE = {
    "domain": {"size": [2.0, 1.0]},
    "mesh": {"elements": [20, 10]},
    "material": {"E": 5.0e9, "nu": 0.3},
    "loading": {"stress": {"xx": -20.0e6, "yy": -40.0e6}},
    "boundary": {"bottom": {"uy": 0.0}, "top": "traction"},
    "network": {
        "friction": 0.5,
        "generate": {
            "seed": 3,
            "count": 40,
            "intersections": "allow",
            "orientation": {"distribution": "uniform"},
            "length": {"distribution": "constant", "value": 0.2},
        },
    },
}


def _network_cases():
    """(name, TOML document): the allow network of test_case_network and the
    shipped DFN sweep's base, with its count and with 100 fractures."""
    dfn = tomllib.loads(Path(SHIPPED_DFN).read_text())["base"]
    dense = copy.deepcopy(dfn)
    dense["network"]["generate"]["count"] = 100
    return [("allow-40", copy.deepcopy(TEST_TABLE)), ("dfn", dfn), ("dfn-100", dense)]


def _generated(document, seed):
    document["network"]["generate"]["seed"] = seed
    spec = loads_case(build.case_text(document), "generated.toml")
    (x0, y0), (w, h) = spec.origin, spec.size
    box = np.array([x0, x0 + w, y0, y0 + h])
    cell = min(np.diff(spec.mesh.x).min(), np.diff(spec.mesh.y).min())
    before = np.array([f.points for f in spec.fractures], float)
    clipped = np.array(
        [clip_to_domain(s, box, GEOMETRY_TOL * cell, "")[0] for s in before]
    )
    after, found = _junctions(before, box, cell)
    _assert_consistent(clipped, after, found, cell)
    return spec, found


def _check_seeds(seeds):
    """Each network over the seeds: builds, junctions consistent; they are
    networks with junctions of every kind."""
    from xfemslip.simulation import check_geometry

    for name, document in _network_cases():
        kinds = set()
        for seed in seeds:
            spec, found = _generated(document, seed)
            check_geometry(spec)  # builds, as xfemslip check does
            kinds |= {k for k, *_ in found}
        assert kinds == {"X", "T", "V"}, name


def test_generated_networks_build_with_consistent_junctions():
    # seed 3 of allow-40 and seed 50 of the DFN laid a fracture onto another
    _check_seeds([3, 50, 0, 1, 2])


@pytest.mark.slow
def test_generated_networks_over_many_seeds():
    _check_seeds(range(300))


# ------------------------------------------------------------ mechanics

CONFIGURATIONS = {
    "near-parallel 1e-4 h": [MAIN, [[0.3, 0.50001], [0.7, 0.500012]]],
    "X at 0.1 deg": [MAIN, _segment([0.513, 0.5], 0.5, 0.1)],
    "X at 1 deg": [MAIN, _segment([0.5, 0.5], 0.6, 1.0)],
    "V at 1 deg": [MAIN, [MAIN[0], [0.2 + 0.6 * math.cos(0.01745), 0.5105]]],
    "V at 10 deg with a gap": [MAIN, [[0.23, 0.51], [0.79, 0.604]]],
    "near copy": [MAIN, [[0.79, 0.52], [0.21, 0.51]]],
    "end to end": [[[0.2, 0.5], [0.5, 0.5]], [[0.5, 0.5], [0.8, 0.5]]],
}
STRESS = np.array([[-20.0e6, 5.0e6], [5.0e6, -40.0e6]])  # [Pa]


@pytest.mark.parametrize("name", list(CONFIGURATIONS))
def test_stuck_fractures_carry_the_uniform_traction(name):
    """Friction 0.3 everywhere and |tau| / |sigma_n| <= 0.2 on every fracture:
    all stick, so the body is nearly uncracked and each contact patch carries
    sigma . n of the far field (within 2.5 % of |sigma_yy|: the ramp tips
    perturb it by up to 0.8 MPa), with the penalty jump p_T / k_T; no NaN."""
    from tests.support.harness import case_text
    from xfemslip.conventions import STICK
    from xfemslip.simulation import build_model, newton_solver

    fractures = [
        {
            "points": [[float(x), float(y)] for x, y in pts],
            "friction": 0.3,
            "kn": 5.0e12,
            "kt": 5.0e12,
            "tip": "ramp",
        }
        for pts in CONFIGURATIONS[name]
    ]
    boundary = {"bottom": {"uy": 0.0}, "top": "traction", "left": "traction"}
    boundary["right"] = "traction"
    text = case_text(
        elements=(N_CELLS, N_CELLS),
        fractures=fractures,
        stress=(-20.0e6, -40.0e6, 5.0e6),
        boundary=boundary,
        tolerance=1e-10,
    )
    model = build_model(loads_case(text, "junctions.toml"))
    result = newton_solver(model).run(1)[-1]
    c = result.contact
    assert np.all(np.isfinite(c.gt)) and np.all(np.isfinite(c.pn))
    assert np.all(c.state == STICK)
    n, t = model.contact.normal, model.contact.tangent
    traction = n @ STRESS
    expected_pn = np.einsum("pk,pk->p", traction, n)
    expected_pt = np.einsum("pk,pk->p", traction, t)
    assert np.all(np.abs(expected_pt) <= 0.2 * np.abs(expected_pn))
    np.testing.assert_allclose(c.pn, expected_pn, rtol=0, atol=0.025 * 40.0e6)
    np.testing.assert_allclose(c.pt, expected_pt, rtol=0, atol=0.025 * 40.0e6)
    np.testing.assert_allclose(c.gt, c.pt / 5.0e12, rtol=1e-9, atol=0)
