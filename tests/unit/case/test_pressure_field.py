"""``[pore_pressure.field]``: pressure changes from a CSV of points, a CSV
grid, a VTU or legacy VTK file (xfemslip.case.pressure_field,
xfemslip.geometry.sampled): each format reproduces the fields it can
represent exactly, the outside rules, and every error names the file."""

from __future__ import annotations

import meshio
import numpy as np
import pytest

from xfemslip.case import build, describe, loads_case
from xfemslip.case.pressure_field import read_pressure_field
from xfemslip.errors import CaseError

RNG = np.random.default_rng(7)


def linear(x, y):
    return -25.0e6 + 3.0e4 * x - 1.5e4 * y


def bilinear(x, y):
    return 1.0e6 + 2.0e3 * x - 4.0e3 * y + 35.0 * x * y


def _write_csv(path, header, rows):
    lines = [",".join(header)] + [",".join(repr(float(v)) for v in r) for r in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


def _inside_points(n, x0, x1, y0, y1):
    return np.column_stack([RNG.uniform(x0, x1, n), RNG.uniform(y0, y1, n)])


def test_scattered_points_reproduce_a_linear_field(tmp_path):
    pts = RNG.uniform(-100.0, 100.0, (60, 2))
    pts = np.vstack([pts, [[-100, -100], [100, -100], [100, 100], [-100, 100]]])
    rows = np.column_stack([pts, linear(*pts.T), 2 * linear(*pts.T) - 3.0, pts[:, 0]])
    f = _write_csv(tmp_path / "dp.csv", ["x", "y", "dp1", "dp2", "other"], rows)
    field = read_pressure_field(f, ["dp1", "dp2"])
    q = _inside_points(500, -99.0, 99.0, -99.0, 99.0)
    got = field.values(q)
    assert got.shape == (2, 500) and field.n_fields == 2
    want = linear(*q.T)
    np.testing.assert_allclose(got[0], want, rtol=1e-12, atol=1e-12 * 25e6)
    np.testing.assert_allclose(got[1], 2 * want - 3.0, rtol=1e-12, atol=1e-12 * 50e6)
    # on the data's edge (its hull, round-off included): covered
    edge = np.array([[0.3, -100.0], [100.0, 42.0 + 1e-13]])
    np.testing.assert_allclose(field.values(edge)[0], linear(*edge.T), rtol=1e-12)


def test_a_grid_is_detected_and_interpolated_bilinearly(tmp_path):
    xs, ys = np.array([0.0, 10.0, 25.0, 60.0]), np.array([-30.0, -5.0, 0.0])
    X, Y = np.meshgrid(xs, ys)
    pts = np.column_stack([X.ravel(), Y.ravel()])
    rows = np.column_stack([pts, bilinear(*pts.T)])[RNG.permutation(len(pts))]
    f = _write_csv(tmp_path / "grid.csv", ["Y", "X", "dp"], rows[:, [1, 0, 2]])
    text = f.read_text().splitlines()
    f.write_text("\n".join([text[0], "# a comment", "", *text[1:]]) + "\n")
    field = read_pressure_field(f, ["dp"])
    q = _inside_points(300, 0.0, 60.0, -30.0, 0.0)
    np.testing.assert_allclose(field.values(q)[0], bilinear(*q.T), rtol=1e-12)
    assert "regular grid of 4 x 3 nodes" in field.description


def _mesh(kind):
    """A 2D mesh of quads and triangles on [0, 40] x [0, 20], z = 5."""
    xs, ys = np.linspace(0.0, 40.0, 5), np.linspace(0.0, 20.0, 3)
    X, Y = np.meshgrid(xs, ys)
    pts = np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, 5.0)])
    node = np.arange(X.size).reshape(ys.size, xs.size)
    quads = [
        [node[j, i], node[j, i + 1], node[j + 1, i + 1], node[j + 1, i]]
        for j in range(2)
        for i in range(2)
    ]
    tris = []
    for j in range(2):
        for i in range(2, 4):
            a, b, c, d = node[j, i], node[j, i + 1], node[j + 1, i + 1], node[j + 1, i]
            tris += [[a, b, c], [a, c, d]]
    cells = [("quad", np.array(quads)), ("triangle", np.array(tris))]
    point_data = {"dp0": linear(pts[:, 0], pts[:, 1]), "dp1": 0.5 * pts[:, 0]}
    cell_data = {"pc": [np.arange(4.0), 10.0 + np.arange(8.0)]}
    return meshio.Mesh(pts, cells, point_data=point_data, cell_data=cell_data)


@pytest.mark.parametrize("suffix", [".vtu", ".vtk"])
def test_vtk_point_data_is_linear_on_the_cells(tmp_path, suffix):
    path = tmp_path / f"dp{suffix}"
    _mesh("point").write(path)
    field = read_pressure_field(path, ["dp0", "dp1"])
    q = _inside_points(400, 0.0, 40.0, 0.0, 20.0)
    got = field.values(q)
    np.testing.assert_allclose(got[0], linear(*q.T), rtol=1e-12)
    np.testing.assert_allclose(got[1], 0.5 * q[:, 0], rtol=1e-12, atol=1e-12)


def test_vtk_cell_data_is_the_containing_cell(tmp_path):
    path = tmp_path / "dp.vtu"
    _mesh("cell").write(path)
    field = read_pressure_field(path, ["pc"])
    # the quad cells i = 0, 1 (x < 20), rows j = 0, 1; triangles beyond
    q = np.array([[3.0, 4.0], [13.0, 15.0], [25.0, 2.0], [27.0, 8.0], [39.0, 12.0]])
    np.testing.assert_array_equal(field.values(q)[0], [0.0, 3.0, 10.0, 11.0, 16.0])


def test_outside_rules(tmp_path):
    pts = np.array([[0, 0], [10, 0], [10, 10], [0, 10], [5, 5]], float)
    rows = np.column_stack([pts, linear(*pts.T)])
    f = _write_csv(tmp_path / "dp.csv", ["x", "y", "dp"], rows)
    far = np.array([[5.0, 5.0], [12.0, 9.5], [-3.0, -1.0]])
    with pytest.raises(CaseError) as err:
        read_pressure_field(f, ["dp"]).values(far)
    assert str(err.value).startswith(f"{f}: point (12.0, 9.5) lies outside the data")
    near = read_pressure_field(f, ["dp"], outside="nearest").values(far)[0]
    np.testing.assert_allclose(near, linear(*pts[[4, 2, 0]].T))
    fixed = read_pressure_field(f, ["dp"], outside=-1.0e6).values(far)[0]
    np.testing.assert_allclose(fixed, [linear(5.0, 5.0), -1.0e6, -1.0e6])
    cover = read_pressure_field(f, ["dp"]).covers(far)
    assert cover.tolist() == [True, False, False]


def _problem(path, columns=("dp",)) -> str:
    with pytest.raises(CaseError) as err:
        read_pressure_field(path, columns)
    assert str(err.value).startswith(str(path))
    return str(err.value)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("x,y,dp\n0,0,1\n1,0,2\n0,1,abc\n", "line 4: dp is not a number: 'abc'"),
        ("x,y,dp\n0,0,1\n1,0,nan\n0,1,3\n", "line 3: dp must be finite, got 'nan'"),
        ("x,y,dp\n0,0,1\n1,0\n0,1,3\n", "line 3: expected 3 values, got 2"),
        ("x,y,d_p\n0,0,1\n", "line 1: no column 'dp'; did you mean 'd_p'?"),
        ("x,z,dp\n0,0,1\n", "line 1: no column 'y'"),
        ("x,y,dp\n0,0,1\n1,1,2\n0,0,3\n2,0,1\n", "lines 2 and 4 give the same point"),
        ("x,y,dp\n0,0,1\n1,1,2\n", "2 point(s); at least 3"),
        ("x,y,dp\n0,0,1\n1,1,2\n2,2,3\n", "lie on one line"),
        ("", "empty file"),
    ],
)
def test_csv_errors_name_the_file_and_the_line(tmp_path, text, expected):
    path = tmp_path / "dp.csv"
    path.write_text(text)
    assert expected in _problem(path)


def test_vtk_errors(tmp_path):
    mesh = _mesh("point")
    path = tmp_path / "dp.vtu"
    mesh.write(path)
    assert "no array named 'dp'; did you mean" in _problem(path)
    assert "point arrays and cell arrays together" in _problem(path, ("dp0", "pc"))
    mesh.points[3, 2] = 7.0
    mesh.write(path)
    assert "point 3 has z = 7.0" in _problem(path, ("dp0",))
    solid = meshio.Mesh(
        np.eye(4, 3),
        [("tetra", np.array([[0, 1, 2, 3]]))],
        point_data={"dp": np.ones(4)},
    )
    solid.write(path)
    assert "has 3D cells (tetra)" in _problem(path)
    path.write_text("not xml")
    assert "cannot read it as VTK" in _problem(path)
    nan = _mesh("point")
    nan.point_data["dp0"][5] = np.nan
    nan.write(path)
    assert "point array 'dp0' is nan at point 5" in _problem(path, ("dp0",))


def test_size_caps(tmp_path, monkeypatch):
    import xfemslip.case.pressure_field as pf

    monkeypatch.setattr(pf, "MAX_CSV_BYTES", 10)
    monkeypatch.setattr(pf, "MAX_VTK_BYTES", 10)
    csv = _write_csv(tmp_path / "dp.csv", ["x", "y", "dp"], [[0, 0, 1]] * 3)
    assert "more than the limit" in _problem(csv)
    vtu = tmp_path / "dp.vtu"
    _mesh("point").write(vtu)
    assert "more than the limit" in _problem(vtu, ("dp0",))


# --------------------------------------------------------------------------- #
# The case keys
# --------------------------------------------------------------------------- #


def _case(tmp_path, pore):
    doc = {
        "domain": {"size": [10.0, 10.0]},
        "mesh": {"elements": [4, 4]},
        "material": {"E": 10.0e9, "nu": 0.2},
        "loading": {
            "initial_stress": {"xx": -40.0e6, "yy": -60.0e6},
            "stress": {"xx": -40.0e6, "yy": -60.0e6},
        },
        "boundary": {"bottom": {"uy": 0.0}, "left": {"ux": 0.0}, "top": "traction"},
        "pore_pressure": pore,
    }
    path = tmp_path / "case.toml"
    path.write_text(build.case_text(doc))
    return path


def _grid_file(tmp_path):
    xs = ys = np.array([0.0, 5.0, 10.0])
    X, Y = np.meshgrid(xs, ys)
    pts = np.column_stack([X.ravel(), Y.ravel()])
    data = np.column_stack([pts, linear(*pts.T), 0.5 * linear(*pts.T)])
    (tmp_path / "data").mkdir()
    return _write_csv(tmp_path / "data" / "dp.csv", ["x", "y", "t1", "t2"], data)


def test_case_reads_the_field_relative_to_the_case_file(tmp_path):
    _grid_file(tmp_path)
    pore = {
        "initial": 30.0e6,
        "biot": 0.9,
        "field": {"file": "data/dp.csv", "columns": ["t1", "t2"], "outside": 0.0},
    }
    spec = loads_case(_case(tmp_path, pore).read_text(), tmp_path / "case.toml")
    f = spec.pore_pressure.field
    assert spec.pore_pressure.change is None
    assert f.columns == ("t1", "t2") and f.outside == 0.0 and f.kind == "grid"
    assert f.file == tmp_path / "data" / "dp.csv"
    q = np.array([[2.0, 3.0], [11.0, 3.0]])
    np.testing.assert_allclose(
        f.field.values(q), [[linear(2, 3), 0], [0.5 * linear(2, 3), 0]]
    )
    assert "change from " in describe(spec) and "columns t1, t2" in describe(spec)


@pytest.mark.parametrize(
    ("pore", "key", "expected"),
    [
        (
            {"change": -1e6, "field": {"file": "data/dp.csv", "columns": ["t1"]}},
            "pore_pressure",
            "give either change (one value) or a field table",
        ),
        ({"field": {"columns": ["t1"]}}, "pore_pressure.field.file", "required key"),
        ({"field": {"file": "data/dp.csv"}}, "pore_pressure.field.columns", "required"),
        (
            {"field": {"file": "data/dp.csv", "columns": ["t1", "t1"]}},
            "pore_pressure.field.columns",
            "names 't1' twice",
        ),
        (
            {"field": {"file": "data/dp.txt", "columns": ["t1"]}},
            "pore_pressure.field.file",
            "expected a .csv, .vtu or .vtk file",
        ),
        (
            {"field": {"file": "data/dp.csv", "columns": ["t1"], "outside": "zero"}},
            "pore_pressure.field.outside",
            'must be one of "error", "nearest"',
        ),
        (
            {"field": {"file": "data/dp.csv", "columns": ["t1"], "outside": True}},
            "pore_pressure.field.outside",
            'expected "error", "nearest" or a pressure change in Pa',
        ),
        (
            {"field": {"file": "data/dp.csv", "columns": ["t3"]}},
            "pore_pressure.field.file",
            "line 1: no column 't3'",
        ),
        (
            {"field": {"file": "data/missing.csv", "columns": ["t1"]}},
            "pore_pressure.field.file",
            "cannot read it: No such file or directory",
        ),
        ({"initial": 0.0}, "pore_pressure.change", "(or a field table"),
    ],
)
def test_case_key_errors(tmp_path, pore, key, expected):
    _grid_file(tmp_path)
    pore = {"initial": 30.0e6, **pore}
    path = _case(tmp_path, pore)
    with pytest.raises(CaseError) as err:
        loads_case(path.read_text(), path)
    found = [m for k, m in err.value.problems if k == key]
    assert any(expected in m for m in found), err.value.problems
