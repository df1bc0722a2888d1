"""The axis-aligned box: each form a box arrives in gives the same box, the
conversions give the file order back, and the domain of a case, of its mesh
and of its permeability block are Boxes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from xfemslip.case import build, loads_case
from xfemslip.fem.mesh import build_mesh
from xfemslip.geometry.box import Box
from xfemslip.geometry.regions import in_boxes

ROOT = Path(__file__).resolve().parents[3]


def test_every_form_gives_the_same_box():
    """[x0, y0, x1, y1] = [1, -2, 4, 3]: width 3, height 5, area 15."""
    box = Box(1.0, 4.0, -2.0, 3.0)
    assert Box.from_corners(1, -2, 4, 3) == box
    assert Box.from_origin_size((1, -2), (3, 5)) == box
    assert Box.from_lines(np.array([1.0, 2.5, 4.0]), np.array([-2.0, 0.0, 3.0])) == box
    assert box.corners == (1.0, -2.0, 4.0, 3.0)
    assert (box.lo, box.hi) == ((1.0, -2.0), (4.0, 3.0))
    assert (box.width, box.height, box.area) == (3.0, 5.0, 15.0)
    # the named tuple is the order of the cell bounds and of the clipping
    np.testing.assert_array_equal(np.asarray(box), [1.0, 4.0, -2.0, 3.0])
    assert all(type(v) is float for v in Box.from_corners(*np.arange(4.0)))
    np.testing.assert_array_equal(
        box.vertices(), [[1.0, -2.0], [4.0, -2.0], [4.0, 3.0], [1.0, 3.0]]
    )


def test_membership_is_strict():
    """Inside, on each edge, at a corner and outside of [0, 2] x [0, 1]."""
    box = Box.from_corners(0.0, 0.0, 2.0, 1.0)
    xy = np.array(
        [
            [1.0, 0.5],
            [0.0, 0.5],
            [2.0, 0.5],
            [1.0, 0.0],
            [1.0, 1.0],
            [0.0, 0.0],
            [3, 0.5],
        ]
    )
    assert box.contains(xy).tolist() == [True] + [False] * 6
    # two boxes in the case file's order: a point inside either
    boxes = np.array([[0.0, 0.0, 2.0, 1.0], [5.0, 5.0, 6.0, 6.0]])
    pts = np.array([[1.0, 0.5], [5.5, 5.5], [4.0, 4.0]])
    assert in_boxes(pts, boxes).tolist() == [True, True, False]


def test_domain_of_a_case_of_its_mesh_and_of_its_block():
    """The permeability case without its block (so the block is the domain),
    at its origin (0, 0) and moved to (-300, 100): the case's box is origin
    + size, the mesh's box its first and last grid lines, the block the
    domain's corners."""
    path = ROOT / "cases" / "permeability.toml"
    for origin in ((0.0, 0.0), (-300.0, 100.0)):
        keys = {"permeability.block": None, "domain.origin": list(origin)}
        spec = loads_case(build.case_text(build.file_case(path, **keys)), path)
        x0, y0 = origin
        w, h = spec.size
        assert spec.origin == origin
        assert spec.box == (x0, x0 + w, y0, y0 + h)
        mesh = build_mesh(spec.mesh.x, spec.mesh.y)
        assert mesh.box == (mesh.x[0], mesh.x[-1], mesh.y[0], mesh.y[-1])
        assert mesh.box == pytest.approx(spec.box, abs=1e-9 * max(w, h))
        assert spec.permeability is not None and not spec.permeability.block_given
        assert spec.permeability.block == (x0, y0, x0 + w, y0 + h)
