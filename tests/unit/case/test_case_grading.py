"""``[mesh] size`` / growth / max_size / refine: the graded mesh of a case
(xfemslip.case.grading), its refinement features and its errors; the uniform
and explicit forms keep their meaning."""

from __future__ import annotations

import numpy as np
import pytest

from xfemslip.case import MAX_ELEMENTS, build, describe, loads_case
from xfemslip.case.grading import (
    combine,
    graded_grid,
    horizon_refinement,
    region_refinement,
)
from xfemslip.case.grid import Grid
from xfemslip.case.specs import GradingSpec
from xfemslip.errors import CaseError
from xfemslip.memory import estimate_dofs

FAULT = [[-40.0, -300.0], [40.0, 300.0]]  # inclined, x-extent [-40, 40]
BOX = [-500.0, -60.0, -10.0, 40.0]  # reservoir box: edges x = -10, y = -60, 40


def _case(mesh, reservoir=True, fractures=True, domain=True):
    return build.case_text(
        {
            "domain": (
                {"size": [1000.0, 600.0], "origin": [-500.0, -300.0]}
                if domain
                else None
            ),
            "mesh": mesh,
            "material": {"E": 10.0e9, "nu": 0.2},
            "fractures": [{"points": FAULT, "friction": 0.6}] if fractures else None,
            "reservoir": {"box": BOX, "E": 5.0e9, "nu": 0.25} if reservoir else None,
            "loading": {"stress": {"xx": -40.0e6, "yy": -60.0e6}},
            "boundary": {"bottom": {"uy": 0.0}, "left": {"ux": 0.0}, "top": "traction"},
        }
    )


def _problems(text) -> dict:
    with pytest.raises(CaseError) as info:
        loads_case(text, "graded.toml")
    out: dict[str, list[str]] = {}
    for key, message in info.value.problems:
        out.setdefault(key, []).append(message)
    return out


def _check_axis(x, lo, hi, size, growth, max_size, fine, lines):
    d = np.diff(x)
    assert x[0] == lo and x[-1] == hi and np.all(d > 0)
    for v in lines:
        assert v in x, v
    ratio = np.maximum(d[1:] / d[:-1], d[:-1] / d[1:])
    assert ratio.max() <= growth
    assert d.max() <= max_size * (1 + 1e-9)
    for a, b in fine:
        touch = (x[1:] >= a) & (x[:-1] <= b)
        assert touch.any() and d[touch].max() <= size * (1 + 1e-9)


def test_graded_case_refines_the_fracture_and_the_reservoir_edges():
    mesh = {
        "size": 5.0,
        "growth": 1.15,
        "max_size": 60.0,
        "refine": [[200, 100, 250, 120]],
    }
    spec = loads_case(_case(mesh), "graded.toml")
    x, y = spec.mesh.x, spec.mesh.y
    # x: the fault's x-extent, the box's edge x = -10, the refine box
    _check_axis(
        x, -500.0, 500.0, 5.0, 1.15, 60.0, [[-40, 40], [-10, -10], [200, 250]], [-10.0]
    )
    # y: the fault spans all rows; the box's edges y = -60 and 40 are lines
    _check_axis(y, -300.0, 300.0, 5.0, 1.15, 60.0, [[-300, 300]], [-60.0, 40.0])
    assert spec.mesh.grading == GradingSpec(
        size=5.0, growth=1.15, max_size=60.0, refine=spec.mesh.grading.refine
    )
    np.testing.assert_array_equal(spec.mesh.grading.refine, [[200, 100, 250, 120]])
    # far from every feature the cells grow to max_size
    assert np.diff(x).max() == pytest.approx(60.0, rel=0.25)
    assert "graded from size 5 m, growth 1.15, max_size 60 m" in describe(spec)
    # the memory estimate sees the graded node count before any allocation
    assert estimate_dofs(spec) >= 2 * x.size * y.size


def test_defaults_and_a_reservoir_polygon():
    """growth defaults to 1.2, max_size to no cap; a polygon's horizontal
    edges are lines, its inclined edge refines its extents."""
    doc = {
        "domain": {"size": [1000.0, 600.0], "origin": [-500.0, -300.0]},
        "mesh": {"size": 10.0},
        "material": {"E": 10.0e9, "nu": 0.2},
        "reservoir": {
            "polygon": [[-500, -60], [-30, -60], [20, 40], [-500, 40]],
            "E": 5.0e9,
            "nu": 0.25,
        },
        "loading": {"stress": {"xx": -40.0e6, "yy": -60.0e6}},
        "boundary": {"bottom": {"uy": 0.0}, "left": {"ux": 0.0}, "top": "traction"},
    }
    spec = loads_case(build.case_text(doc), "poly.toml")
    x, y = spec.mesh.x, spec.mesh.y
    _check_axis(x, -500.0, 500.0, 10.0, 1.2, np.inf, [[-30, 20]], [])
    _check_axis(y, -300.0, 300.0, 10.0, 1.2, np.inf, [[-60, 40]], [-60.0, 40.0])
    assert spec.mesh.grading.growth == 1.2 and spec.mesh.grading.max_size == np.inf


def test_uniform_and_explicit_meshes_keep_their_meaning():
    spec = loads_case(_case({"elements": [40, 30]}), "uniform.toml")
    want = -500.0 + 1000.0 * np.linspace(0.0, 1.0, 41)
    assert np.array_equal(spec.mesh.x, want) and spec.mesh.grading is None
    xs = [-500.0, -10.0, 77.0, 500.0]
    spec = loads_case(
        _case({"x": xs, "y": [-300.0, 0.0, 300.0]}, reservoir=False, domain=False),
        "explicit.toml",
    )
    assert spec.mesh.x.tolist() == xs and spec.mesh.grading is None


def test_extra_features_from_the_caller():
    """Horizons added to a case's features land on node rows."""
    grading = GradingSpec(size=5.0, growth=1.2, max_size=50.0, refine=np.zeros((0, 4)))
    grid = Grid((0.0, -1000.0), (500.0, 1000.0), None, grading)
    features = combine(
        region_refinement(
            [[100.0, -700.0, 300.0, -500.0]], None, grid.origin, grid.size
        ),
        horizon_refinement([-812.5, -250.0, 0.0, 20.0], grid.origin, grid.size),
    )
    problems: list = []
    out = graded_grid(grid, features, problems)
    assert problems == []
    for v in (-812.5, -250.0, -700.0, -500.0):
        assert v in out.mesh.y
    assert out.mesh.y[-1] == 0.0 and out.mesh.y[0] == -1000.0
    assert 100.0 in out.mesh.x and 300.0 in out.mesh.x


@pytest.mark.parametrize(
    ("mesh", "key", "expected"),
    [
        (
            {"size": 5.0, "elements": [4, 4]},
            "mesh",
            "give either elements = [nx, ny] or size",
        ),
        (
            {"growth": 1.3},
            "mesh.size",
            "required key missing (growth, max_size and refine",
        ),
        ({"size": 5.0, "growth": 1.0}, "mesh.growth", "must satisfy 1 < growth <= 2"),
        ({"size": 5.0, "growth": 2.5}, "mesh.growth", "must satisfy 1 < growth <= 2"),
        ({"size": -5.0}, "mesh.size", "must be > 0"),
        ({"size": 5.0, "max_size": 2.0}, "mesh.max_size", "must be >= mesh.size = 5.0"),
        (
            {"size": 5.0, "refine": [[0, 0, -1, 1]]},
            "mesh.refine[0]",
            "x0 < x1 and y0 < y1",
        ),
        (
            {"size": 5.0, "refine": [[0, 0, 1]]},
            "mesh.refine[0]",
            "expected an array of 4",
        ),
        ({"size": 5.0, "refine": 3}, "mesh.refine", "expected an array of boxes"),
    ],
)
def test_graded_key_errors(mesh, key, expected):
    problems = _problems(_case(mesh))
    assert any(expected in m for m in problems.get(key, [])), problems


def test_graded_needs_domain_size_and_something_to_refine():
    problems = _problems(_case({"size": 5.0}, domain=False))
    assert problems["domain.size"] == [
        "required key missing (mesh.size needs domain.size)"
    ]
    problems = _problems(_case({"size": 5.0}, reservoir=False, fractures=False))
    assert "a graded mesh needs something to refine" in problems["mesh.size"][0]


def test_too_many_elements_refused_before_the_nodes():
    """2e9 cells along x would need 16 GB of coordinates alone: refused from
    the planned count (the test would not finish if the nodes were placed)."""
    problems = _problems(_case({"size": 1e-6, "growth": 2.0}))
    (message,) = problems["mesh.size"]
    assert f"exceeds the limit of {MAX_ELEMENTS}" in message
