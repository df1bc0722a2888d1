"""Inputs whose cost must follow the mesh, not their number of vertices: a
zigzag inside one cell, a digitised arc, a many-vertex reservoir polygon, and
a depletion tolerance below what the load steps resolve.  The whole-process
runs are bounded by the harness (a subprocess timeout), never by a timed
assertion; their peak memory is the child's own ru_maxrss."""

from __future__ import annotations

import csv
import logging
import sys

import numpy as np
import pytest

from tests.support.casegen import fracture_spec
from tests.support.hardcases import arc, depletion, measure, polygon, zigzag
from xfemslip.case import loads_case
from xfemslip.errors import GeometryError, UsageError
from xfemslip.fem.mesh import build_mesh
from xfemslip.geometry.fracture import MAX_PIECES_PER_CELL, SIMPLIFY_MIN_SEGMENT
from xfemslip.geometry.junctions import build_fractures
from xfemslip.studies import depletion as depletion_module

# Harness bound of one process; each ran for minutes (or for ever) when it was
# walked point by point, and takes a few seconds now.
TIMEOUT = 120.0
# Peak resident memory allowed per process [MB]: the interpreter with NumPy,
# SciPy and the model of a 50 x 50 case is about 100 MB; the zigzag and the
# arc reached 3.4 and 14.7 GB when every vertex was kept.
PEAK_MB = 600.0


def _run(tmp_path, text, *command):
    case = tmp_path / "case.toml"
    case.write_text(text)
    argv = [sys.executable, "-m", "xfemslip", *command, str(case)]
    argv += ["-o", str(tmp_path / "out")]
    return measure(argv, TIMEOUT, tmp_path / "log.txt")


@pytest.mark.parametrize(
    ("make", "points"), [(zigzag, "1,000"), (arc, "2,000")], ids=["zigzag", "arc"]
)
def test_dense_polyline_runs_simplified_with_a_warning(tmp_path, make, points):
    code, _, peak, lines = _run(tmp_path, make(), "run")
    assert code == 0, lines[-3:]
    warned = [ln for ln in lines if "simplified to" in ln]
    assert len(warned) == 1
    assert warned[0].startswith(f"WARNING: fractures[0]: {points} points simplified")
    assert peak < PEAK_MB


@pytest.mark.slow  # (benchmarks/hard_inputs.py measures it)
def test_many_vertex_reservoir_polygon_runs(tmp_path):
    code, _, peak, lines = _run(tmp_path, polygon(), "run")
    assert code == 0, lines[-3:]
    # one warning line for the edges off the mesh lines, not one per edge
    off = [ln for ln in lines if "not on a mesh line" in ln]
    assert len(off) == 1 and "and 4,997 more edges are" in off[0]
    assert peak < PEAK_MB


def test_deplete_tolerance_below_resolution_is_raised(tmp_path):
    """--tolerance 1e-10 Pa is raised to |change| x solver.tolerance =
    20 MPa x 1e-8 = 0.2 Pa, and the bracket found is that narrow."""
    code, _, _, lines = _run(tmp_path, depletion(), "deplete", "--tolerance", "1e-10")
    assert code == 0, lines[-3:]
    assert any("--tolerance 1e-10 Pa is below" in ln for ln in lines)
    with (tmp_path / "out" / "critical_depletion.csv").open() as fh:
        row = next(csv.DictReader(fh))
    assert float(row["tolerance_Pa"]) == pytest.approx(0.2, rel=1e-12)
    width = float(row["dp_upper_Pa"]) - float(row["dp_lower_Pa"])
    assert 0.0 < abs(width) <= 0.2


# --------------------------------------------------------------------------- #
# In-process checks of the same rules
# --------------------------------------------------------------------------- #

BOX = np.array([0.0, 1.0, 0.0, 1.0])


def test_build_fractures_simplifies_and_says_so(caplog):
    n, h = 1000, 0.05
    x = 0.452 + 0.046 * np.arange(n) / (n - 1)
    pts = np.column_stack([x, np.where(np.arange(n) % 2 == 0, 0.47, 0.48)])
    mesh = build_mesh(np.linspace(0, 1, 21), np.linspace(0, 1, 21))
    with caplog.at_level(logging.WARNING):
        (fr,) = build_fractures(mesh, [fracture_spec(pts)], BOX)
    k = len(fr.points)
    assert f"fractures[0]: 1,000 points simplified to {k} below the mesh" in caplog.text
    np.testing.assert_array_equal(fr.points[[0, -1]], pts[[0, -1]])
    assert fr.length.min() >= SIMPLIFY_MIN_SEGMENT * h
    # the kept vertices are vertices of the case file's polyline
    assert all(np.any(np.all(pts == p, axis=1)) for p in fr.points)


def test_resolved_polyline_is_built_as_given(caplog):
    pts = np.array([[0.1, 0.1], [0.5, 0.3], [0.9, 0.2]])
    mesh = build_mesh(np.linspace(0, 1, 21), np.linspace(0, 1, 21))
    with caplog.at_level(logging.WARNING):
        (fr,) = build_fractures(mesh, [fracture_spec(pts)], BOX)
    np.testing.assert_array_equal(fr.points, pts)
    assert "simplified" not in caplog.text


def test_polyline_folded_inside_one_cell_is_refused():
    """Strokes 0.9 cell long, 0.002 cell apart: no segment is short, nothing
    to simplify, but 40 pieces in one cell cannot be resolved."""
    h = 0.1
    k = 40
    x = np.where(np.arange(k) % 2 == 0, 0.405, 0.495)
    pts = np.column_stack([x, 0.45 + 0.0002 * np.arange(k)])
    mesh = build_mesh(np.linspace(0, 1, 11), np.linspace(0, 1, 11))
    assert k - 1 > MAX_PIECES_PER_CELL and np.diff(pts, axis=0)[:, 0].min() < -h / 2
    with pytest.raises(GeometryError, match=r"fractures\[0\]: 39 pieces of the "):
        build_fractures(mesh, [fracture_spec(pts)], BOX)


@pytest.fixture(scope="module")
def depletion_spec(tmp_path_factory):
    return loads_case(depletion(), str(tmp_path_factory.mktemp("d") / "d.toml"))


def test_resolved_tolerance(depletion_spec, caplog):
    """Default 0.1 % of |change|; a value above the resolution is kept; one
    below is raised to |change| x solver.tolerance with a warning."""
    resolve = depletion_module.resolved_tolerance
    assert resolve(depletion_spec) == pytest.approx(20e6 * 1e-3)
    assert resolve(depletion_spec, 5.0) == 5.0
    with caplog.at_level(logging.WARNING):
        assert resolve(depletion_spec, 1e-10) == pytest.approx(0.2)
    assert "--tolerance 1e-10 Pa is below what the load steps resolve" in caplog.text


def test_bisection_is_capped(depletion_spec, tmp_path, monkeypatch, caplog):
    """With the cap at 3 solves, the bracket is one step (2 MPa) / 2^3."""
    monkeypatch.setattr(depletion_module, "MAX_BISECTIONS", 3)
    with caplog.at_level(logging.WARNING):
        report = depletion_module.deplete(depletion_spec, tmp_path, tolerance=1.0)
    (onset,) = report.onsets
    assert onset.trials == 3
    assert onset.dp_upper - onset.dp_lower == pytest.approx(-2e6 / 8, rel=1e-9)
    assert "bisection stopped after 3 solves" in caplog.text


def test_deplete_refuses_a_zero_change(tmp_path):
    text = depletion(change=0.0)
    spec = loads_case(text, str(tmp_path / "zero.toml"))
    with pytest.raises(UsageError, match=r"zero\.toml: pore_pressure\.change = 0"):
        depletion_module.deplete(spec, tmp_path / "out")
    assert not (tmp_path / "out").exists()
