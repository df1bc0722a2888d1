"""Tests of xfemslip.case: resolution of valid cases and every kind of error."""

from __future__ import annotations

import copy
import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from xfemslip.case import (
    MAX_ELEMENTS,
    SOLVER_OPTIONS,
    SolverSpec,
    build,
    describe,
    load_case,
    loads_case,
)
from xfemslip.errors import CaseError

# The seed paper's reservoir case, as in case-format.md, written as text: the
# spec keeps the file's text verbatim (spec.text), comments and layout included.
RESERVOIR = """\
name = "reservoir-depletion"

[domain]
size = [1.0, 1.0]
origin = [0.0, 0.0]

[mesh]
elements = [50, 50]

[material]
E = 5.0e9
nu = 0.3
model = "plane_strain"

[[fractures]]
center = [0.5, 0.5]
length = 0.6
angle = 45.0
friction = 0.1
cohesion = 0.0
kn = 5.0e12
kt = 5.0e12

[loading]
stress = { xx = -20.0e6, yy = -40.0e6, xy = 0.0 }
steps = 1

[boundary]
bottom = { uy = 0.0 }
top = "traction"
left = "traction"
right = "traction"

[solver]
tolerance = 1.0e-8
max_iterations = 30

[output]
directory = "out/reservoir-depletion"
formats = ["h5", "vtu"]
"""

BASE = {
    "domain": {"size": [2.0, 1.0], "origin": [1.0, -1.0]},
    "mesh": {"elements": [4, 2]},
    "material": {"E": 1.0e9, "nu": 0.25},
    "fractures": [
        {
            "points": [[1.5, -0.5], [2.5, -0.5]],
            "friction": 0.6,
            "kn": 1.0e12,
            "kt": 1.0e12,
        }
    ],
    "loading": {"stress": {"xx": -1.0e6, "yy": -2.0e6}},
    "boundary": {
        "bottom": {"uy": 0.0},
        "left": {"ux": 0.0},
        "top": "traction",
        "right": "traction",
    },
}


def write(tmp_path, doc, name="case.toml"):
    """Write a case (a dict, or TOML text) into tmp_path and return its path."""
    path = tmp_path / name
    path.write_text(
        doc if isinstance(doc, str) else build.case_text(doc), encoding="utf-8"
    )
    return path


def base(**tables):
    """A deep copy of BASE with top-level entries replaced (None removes one)."""
    doc = copy.deepcopy(BASE)
    for key, value in tables.items():
        if value is None:
            doc.pop(key, None)
        else:
            doc[key] = value
    return doc


def error_of(tmp_path, doc, name="case.toml") -> CaseError:
    with pytest.raises(CaseError) as info:
        load_case(write(tmp_path, doc, name))
    return info.value


def messages(err: CaseError, key: str) -> str:
    """All messages recorded at ``key``, joined (empty if none)."""
    return " | ".join(m for k, m in err.problems if k == key)


# --------------------------------------------------------------------------- #
# Valid cases
# --------------------------------------------------------------------------- #


def test_reservoir_example_resolves(tmp_path):
    spec = load_case(write(tmp_path, RESERVOIR, "reservoir.toml"))
    assert spec.name == "reservoir-depletion"
    assert spec.origin == (0.0, 0.0) and spec.size == (1.0, 1.0)
    np.testing.assert_allclose(
        spec.mesh.x, np.linspace(0.0, 1.0, 51), rtol=0, atol=1e-15
    )
    np.testing.assert_allclose(
        spec.mesh.y, np.linspace(0.0, 1.0, 51), rtol=0, atol=1e-15
    )
    assert spec.mesh.x.dtype == np.float64 and spec.mesh.x[-1] == 1.0
    assert spec.material.E == 5.0e9 and spec.material.nu == 0.3
    assert spec.material.model == "plane_strain"
    (fracture,) = spec.fractures
    d = 0.3 * math.sqrt(0.5)
    np.testing.assert_allclose(
        fracture.points, [[0.5 - d, 0.5 - d], [0.5 + d, 0.5 + d]], rtol=0, atol=1e-15
    )
    assert fracture.index == 0 and fracture.friction == 0.1 and fracture.cohesion == 0.0
    assert fracture.kn == 5.0e12 and fracture.kt == 5.0e12
    assert spec.loading.stress == (-20.0e6, -40.0e6, 0.0)
    assert spec.loading.initial_stress is None and spec.loading.steps == 1
    bottom = spec.boundary.bottom
    assert bottom.kind == "displacement" and bottom.source == "table"
    assert bottom.values.shape == (51, 2) and not bottom.traction
    assert np.isnan(bottom.values[:, 0]).all() and (bottom.values[:, 1] == 0.0).all()
    assert spec.boundary.top.kind == "traction" and spec.boundary.top.values is None
    assert spec.solver == SolverSpec()
    assert str(spec.output.directory) == "out/reservoir-depletion"
    assert spec.output.formats == ("h5", "vtu")
    assert spec.text == RESERVOIR


def test_specs_are_frozen_and_arrays_read_only(tmp_path):
    spec = load_case(write(tmp_path, RESERVOIR))
    with pytest.raises(dataclasses.FrozenInstanceError):
        spec.name = "other"
    for array in (
        spec.mesh.x,
        spec.mesh.y,
        spec.fractures[0].points,
        spec.boundary.bottom.values,
    ):
        with pytest.raises(ValueError, match="read-only"):
            array[0] = 1.0


def test_defaults_of_optional_keys(tmp_path):
    doc = base(loading=None, boundary={"bottom": {"ux": 0.0, "uy": 0.0}})
    doc["domain"].pop("origin")
    doc["fractures"][0]["points"] = [[0.5, 0.5], [1.5, 0.5]]
    spec = load_case(write(tmp_path, doc, "my-case.toml"))
    assert spec.name == "my-case" and spec.origin == (0.0, 0.0)
    assert spec.material.model == "plane_strain"
    assert spec.fractures[0].cohesion == 0.0
    assert spec.loading.stress is None and spec.loading.steps == 1
    assert spec.solver == SolverSpec()
    assert str(spec.output.directory) == "out/my-case"
    assert spec.output.formats == ("h5", "vtu", "csv")
    for edge in ("top", "left", "right"):
        assert getattr(spec.boundary, edge).kind == "free"
        assert getattr(spec.boundary, edge).source == "default"


def test_solver_option_table_matches_spec_defaults():
    defaults = SolverSpec()
    assert [o.name for o in SOLVER_OPTIONS] == [
        f.name for f in dataclasses.fields(SolverSpec)
    ]
    for option in SOLVER_OPTIONS:
        assert getattr(defaults, option.name) == option.default


def test_uniform_mesh_with_origin(tmp_path):
    spec = load_case(write(tmp_path, base()))
    np.testing.assert_array_equal(spec.mesh.x, [1.0, 1.5, 2.0, 2.5, 3.0])
    np.testing.assert_array_equal(spec.mesh.y, [-1.0, -0.5, 0.0])
    assert spec.boundary.left.values.shape == (3, 2)
    assert spec.boundary.bottom.values.shape == (5, 2)


def test_graded_mesh_from_x_and_y(tmp_path):
    spec = load_case(
        write(
            tmp_path,
            base(
                domain=None,
                mesh={"x": [1.0, 1.1, 1.3, 2.0, 3.0], "y": [-1.0, -0.9, 0.0]},
            ),
        )
    )
    assert spec.origin == (1.0, -1.0) and spec.size == (2.0, 1.0)
    np.testing.assert_array_equal(spec.mesh.x, [1.0, 1.1, 1.3, 2.0, 3.0])
    np.testing.assert_array_equal(spec.mesh.y, [-1.0, -0.9, 0.0])
    assert "graded" in describe(spec)


def test_graded_mesh_with_agreeing_domain(tmp_path):
    spec = load_case(
        write(tmp_path, base(mesh={"x": [1.0, 1.2, 3.0], "y": [-1.0, -0.3, 0.0]}))
    )
    assert spec.size == (2.0, 1.0)


@pytest.mark.parametrize(
    ("angle", "expected"),
    [
        (90.0, [[0.5, 0.3], [0.5, 0.7]]),
        (0.0, [[0.3, 0.5], [0.7, 0.5]]),
        (180.0, [[0.7, 0.5], [0.3, 0.5]]),
        (-90.0, [[0.5, 0.7], [0.5, 0.3]]),
        (135.0, None),
    ],
)
def test_center_length_angle_points_are_exact(tmp_path, angle, expected):
    fracture = {
        "center": [0.5, 0.5],
        "length": 0.4,
        "angle": angle,
        "friction": 0.5,
        "kn": 1.0,
        "kt": 1.0,
    }
    doc = base(domain={"size": [1.0, 1.0]}, fractures=[fracture])
    points = load_case(write(tmp_path, doc)).fractures[0].points
    if expected is None:  # 135 degrees: exactly on the line x + y = 1
        assert points[0, 0] + points[0, 1] == 1.0 and points[0, 0] > points[1, 0]
        assert np.hypot(*(points[1] - points[0])) == pytest.approx(0.4, rel=1e-15)
    else:
        np.testing.assert_allclose(points, expected, rtol=0, atol=1e-16)
        assert points[0, 0] == expected[0][0] or points[0, 1] == expected[0][1]


def test_partly_outside_polyline_is_allowed(tmp_path):
    fracture = dict(BASE["fractures"][0], points=[[0.0, 0.0], [1.5, -0.5], [2.0, -0.8]])
    spec = load_case(write(tmp_path, base(fractures=[fracture, fracture])))
    assert [f.index for f in spec.fractures] == [0, 1]


def test_initial_stress_and_traction_on_displacement_edge(tmp_path):
    doc = base()
    doc["loading"] = {
        "stress": {"xx": -1.0, "yy": -2.0, "xy": 0.5},
        "initial_stress": {"xx": -3.0, "yy": -4.0},
        "steps": 10,
    }
    doc["boundary"]["left"] = {"ux": 0.001, "traction": True}
    spec = load_case(write(tmp_path, doc))
    assert spec.loading.stress == (-1.0, -2.0, 0.5)
    assert spec.loading.initial_stress == (-3.0, -4.0, 0.0)
    assert spec.loading.steps == 10
    left = spec.boundary.left
    assert left.traction and (left.values[:, 0] == 0.001).all()
    assert np.isnan(left.values[:, 1]).all()


def test_loads_case_uses_path_for_name_and_messages(tmp_path):
    spec = loads_case(build.case_text(base()), tmp_path / "from-text.toml")
    assert spec.name == "from-text"
    with pytest.raises(CaseError, match=r"^x/y\.toml: material: required key missing$"):
        loads_case(build.case_text(base(material=None)), "x/y.toml")


def test_describe_summarises_the_resolved_case(tmp_path):
    doc = base(boundary={"bottom": {"uy": 0.0}, "top": "traction"})
    doc["solver"] = {"tangent": "secant"}
    text = describe(load_case(write(tmp_path, doc, "desc.toml")))
    for part in (
        "desc",
        "[1, 3] x [-1, 0] m",
        "4 x 2 Q4 elements",
        "uniform",
        "signs: tension positive",
        "E = 1 GPa",
        "nu = 0.25",
        "plane_strain",
        "[0] points [m]",
        "(1.5, -0.5) -> (2.5, -0.5)",
        "length 1 m",
        "angle 0 deg",
        "kn = 1000 GPa/m",
        "friction = 0.6",
        "(xx, yy, xy) = (-1, -2, 0) MPa",
        "1 step",
        "uy = 0 mm",
        "ux free",
        "[table]",
        "top: traction = loading.stress . n",
        "left: free (zero traction) (not given in [boundary])",
        "tangent = secant",
        "max_iterations = 30",
        "tolerance = 1e-08",
        "output: out/desc (h5, vtu, csv)",
    ):
        assert part in text, part
    # compression positive: the stresses turn sign, nothing else does
    other = describe(load_case(tmp_path / "desc.toml"), compression_positive=True)
    assert "signs: compression positive" in other
    assert "(xx, yy, xy) = (1, 2, 0) MPa" in other and "E = 1 GPa" in other


# --------------------------------------------------------------------------- #
# Errors: reading and syntax
# --------------------------------------------------------------------------- #


def test_missing_case_file(tmp_path):
    with pytest.raises(CaseError) as info:
        load_case(tmp_path / "nope.toml")
    assert info.value.problems[0][0] == ""
    assert "cannot read the case file" in str(info.value)
    assert str(info.value).startswith(str(tmp_path / "nope.toml"))


def test_toml_syntax_error_names_the_line(tmp_path):
    err = error_of(tmp_path, "name = 'a'\n[material]\nE = = 3\n")
    assert err.problems[0][0] == ""
    assert "TOML syntax error" in err.problems[0][1] and "line 3" in err.problems[0][1]


# --------------------------------------------------------------------------- #
# Errors: keys and types
# --------------------------------------------------------------------------- #


def test_unknown_keys_get_suggestions(tmp_path):
    doc = base()
    doc["materail"] = doc.pop("material")
    doc["fractures"][0]["frction"] = doc["fractures"][0].pop("friction")
    doc["solver"] = {"zzz": 1}
    err = error_of(tmp_path, doc)
    assert "unknown key 'materail'; did you mean 'material'?" in messages(
        err, "materail"
    )
    assert messages(err, "material") == "required key missing"
    assert (
        "unknown key 'frction' in [fractures[0]]; did you mean 'friction'?"
        in messages(err, "fractures[0].frction")
    )
    assert messages(err, "fractures[0].friction") == "required key missing"
    assert "allowed: tolerance, max_iterations, tangent" in messages(err, "solver.zzz")


def test_missing_required_key(tmp_path):
    doc = base()
    del doc["material"]["E"]
    err = error_of(tmp_path, doc)
    assert err.problems == [("material.E", "required key missing")]
    assert str(err).endswith("case.toml: material.E: required key missing")


@pytest.mark.parametrize(
    ("table", "key", "value", "message"),
    [
        ("material", "nu", "abc", "expected a number, got string 'abc'"),
        ("material", "E", True, "expected a number, got boolean true"),
        ("material", "E", [1.0], "expected a number, got array of 1 item"),
        ("material", "E", math.nan, "must be finite, got nan"),
        ("material", "E", -math.inf, "must be finite, got -inf"),
        ("material", "E", 0.0, "must be > 0, got 0.0"),
        ("material", "nu", 0.5, "must satisfy 0 <= nu < 0.5, got 0.5"),
        ("material", "nu", -0.1, "must satisfy 0 <= nu < 0.5, got -0.1"),
        (
            "material",
            "model",
            "plane_strian",
            'must be one of "plane_strain", "plane_stress", got \'plane_strian\'; '
            "did you mean 'plane_strain'?",
        ),
        ("loading", "steps", 0, "must satisfy 1 <= steps <= 100000, got 0"),
        ("loading", "steps", 2.0, "expected an integer, got float 2.0"),
        (
            "domain",
            "size",
            [1.0],
            "expected an array of 2 numbers, got array of 1 item",
        ),
    ],
)
def test_bad_values(tmp_path, table, key, value, message):
    doc = base()
    doc[table][key] = value
    err = error_of(tmp_path, doc)
    assert messages(err, f"{table}.{key}") == message


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("friction", -0.1, "must be >= 0, got -0.1"),
        ("cohesion", -1.0, "must be >= 0, got -1.0"),
        ("kn", 0.0, "must be > 0, got 0.0"),
        ("kt", math.inf, "must be finite, got inf"),
    ],
)
def test_bad_fracture_parameters(tmp_path, key, value, message):
    doc = base()
    doc["fractures"][0][key] = value
    assert messages(error_of(tmp_path, doc), f"fractures[0].{key}") == message


def test_element_paths_of_arrays(tmp_path):
    doc = base(domain={"size": [2.0, -1.0], "origin": [0.0, "a"]})
    doc["mesh"]["elements"] = [4, 0]
    doc["fractures"][0]["points"] = [[1.5, -0.5], [2.5, math.nan]]
    err = error_of(tmp_path, doc)
    assert messages(err, "domain.size[1]") == "must be > 0, got -1.0"
    assert messages(err, "domain.origin[1]") == "expected a number, got string 'a'"
    assert messages(err, "mesh.elements[1]") == "must be >= 1, got 0"
    assert messages(err, "fractures[0].points[1][1]") == "must be finite, got nan"


def test_wrong_table_type_does_not_stop_validation(tmp_path):
    doc = base(material=3)
    doc["fractures"][0]["friction"] = -1.0
    err = error_of(tmp_path, doc)
    assert messages(err, "material") == "expected a table, got integer 3"
    assert messages(err, "fractures[0].friction") == "must be >= 0, got -1.0"


def test_fractures_must_be_an_array_of_tables(tmp_path):
    err = error_of(tmp_path, base(fractures=dict(BASE["fractures"][0])))
    assert "expected an array of tables [[fractures]], got table" in messages(
        err, "fractures"
    )


def test_name_must_be_a_plain_non_empty_string(tmp_path):
    assert "non-empty string" in messages(error_of(tmp_path, base(name="")), "name")
    assert "must not contain a path separator" in messages(
        error_of(tmp_path, base(name="a/b")), "name"
    )


def test_several_problems_reported_together_on_one_line(tmp_path):
    doc = base()
    doc["material"]["nu"] = 0.5
    doc["fractures"][0]["friction"] = -0.1
    doc["boundary"]["top"] = "tracton"
    doc["solver"] = {"tolerance": 2.0}
    err = error_of(tmp_path, doc)
    keys = [k for k, _ in err.problems]
    assert keys == [
        "material.nu",
        "fractures[0].friction",
        "boundary.top",
        "solver.tolerance",
    ]
    text = str(err)
    assert "\n" not in text and "4 problems" in text
    for key in keys:
        assert f"{key}: " in text


# --------------------------------------------------------------------------- #
# Errors: domain and mesh
# --------------------------------------------------------------------------- #


def test_domain_disagreeing_with_x_and_y(tmp_path):
    err = error_of(
        tmp_path,
        base(
            domain={"size": [2.0, 1.5], "origin": [0.0, -1.0]},
            mesh={"x": [1.0, 2.0, 3.0], "y": [-1.0, 0.0]},
        ),
    )
    assert "disagrees with mesh.x / mesh.y" in messages(err, "domain.size")
    assert "expected [2.0, 1.0], got [2.0, 1.5]" in messages(err, "domain.size")
    assert "expected [1.0, -1.0], got [0.0, -1.0]" in messages(err, "domain.origin")


def test_elements_and_x_y_together(tmp_path):
    err = error_of(
        tmp_path, base(mesh={"elements": [2, 2], "x": [0.0, 1.0], "y": [0.0, 1.0]})
    )
    assert "either elements" in messages(err, "mesh") and "not both" in messages(
        err, "mesh"
    )


def test_elements_need_domain_size(tmp_path):
    err = error_of(tmp_path, base(domain=None))
    assert messages(err, "domain.size").startswith("required key missing")


def test_x_without_y_and_non_increasing_x(tmp_path):
    err = error_of(tmp_path, base(domain=None, mesh={"x": [0.0, 0.5, 0.5, 1.0]}))
    assert messages(err, "mesh.y").startswith("required key missing")
    assert messages(err, "mesh.x[2]") == (
        "must be > x[1] = 0.5 (strictly increasing), got 0.5"
    )


@pytest.mark.parametrize("width", [1e-300, 5e-10, 9.9e-10])
def test_a_cell_too_thin_for_the_geometry_is_refused(tmp_path, width):
    """A cell narrower than 1e-9 of the mesh's extent (1 m here) is named
    (the geometry's tolerances follow the cell sizes: 1e-300 m overflowed
    them); one of 1e-8 m is kept."""
    fracture = {**BASE["fractures"][0], "points": [[0.25, 0.5], [0.75, 0.5]]}

    def doc(x):
        return base(domain=None, mesh={"x": x, "y": [0.0, 1.0]}, fractures=[fracture])

    err = error_of(tmp_path, doc([0.0, width, 0.5, 1.0]))
    assert "narrower than 1e-09 of the mesh's extent (1 m)" in messages(
        err, "mesh.x[1]"
    )
    assert load_case(write(tmp_path, doc([0.0, 1e-8, 0.5, 1.0]))).mesh.x[1] == 1e-8


def test_mesh_without_elements_or_x_y(tmp_path):
    err = error_of(tmp_path, base(mesh={}))
    assert "give elements = [nx, ny]" in messages(err, "mesh")


def test_absurd_mesh_size_is_refused(tmp_path):
    err = error_of(tmp_path, base(mesh={"elements": [100_000, 100_000]}))
    message = messages(err, "mesh.elements")
    assert f"10000000000 elements exceeds the limit of {MAX_ELEMENTS}" in message
    assert "GB" in message


# --------------------------------------------------------------------------- #
# Errors: fractures
# --------------------------------------------------------------------------- #


def fracture_error(tmp_path, **geometry):
    fracture = {"friction": 0.5, "kn": 1.0, "kt": 1.0, **geometry}
    return error_of(tmp_path, base(fractures=[fracture]))


def test_center_and_points_together(tmp_path):
    err = fracture_error(
        tmp_path, center=[2.0, -0.5], points=[[1.5, -0.5], [2.5, -0.5]]
    )
    assert "either points or center, length and angle, not both" in messages(
        err, "fractures[0]"
    )


def test_partial_center_length_angle(tmp_path):
    err = fracture_error(tmp_path, center=[2.0, -0.5], length=0.5)
    assert messages(err, "fractures[0].angle").startswith("required key missing")
    assert "go together" in messages(err, "fractures[0].angle")


def test_no_geometry_at_all(tmp_path):
    err = fracture_error(tmp_path)
    assert messages(err, "fractures[0].points").startswith("required key missing")


def test_zero_length_fracture(tmp_path):
    err = fracture_error(tmp_path, points=[[2.0, -0.5], [2.0, -0.5]])
    assert "zero length" in messages(err, "fractures[0].points")
    err = fracture_error(tmp_path, center=[2.0, -0.5], length=0.0, angle=10.0)
    assert messages(err, "fractures[0].length") == "must be > 0, got 0.0"


def test_repeated_consecutive_point(tmp_path):
    err = fracture_error(
        tmp_path, points=[[1.5, -0.5], [2.0, -0.5], [2.0, -0.5], [2.5, -0.4]]
    )
    assert "repeats the previous point (2.0, -0.5): zero-length segment" == messages(
        err, "fractures[0].points[2]"
    )


def test_too_few_points(tmp_path):
    err = fracture_error(tmp_path, points=[[1.5, -0.5]])
    assert "expected an array of >= 2 points" in messages(err, "fractures[0].points")


def test_fracture_outside_the_domain(tmp_path):
    err = fracture_error(tmp_path, points=[[5.0, 5.0], [6.0, 7.0]])
    assert messages(err, "fractures[0]") == "lies outside the domain [1, 3] x [-1, 0]"
    # crosses the bounding lines of the domain but never the rectangle itself
    err = fracture_error(tmp_path, points=[[0.0, -0.5], [1.5, 1.0]])
    assert "lies outside the domain" in messages(err, "fractures[0]")


def test_fracture_touching_the_domain_corner_is_inside(tmp_path):
    doc = base(
        fractures=[
            {"points": [[0.0, 1.0], [1.0, 0.0]], "friction": 0.5, "kn": 1.0, "kt": 1.0}
        ]
    )
    assert len(load_case(write(tmp_path, doc)).fractures) == 1


@pytest.mark.parametrize(
    ("points", "pair"),
    [
        ([[1.2, -0.8], [2.8, -0.2], [2.8, -0.8], [1.2, -0.2]], "segments 0 and 2"),
        ([[1.2, -0.5], [2.5, -0.5], [1.8, -0.5]], "segments 0 and 1"),  # turns back
        (
            [[1.2, -0.8], [2.0, -0.8], [2.0, -0.2], [1.2, -0.8]],
            "segments 0 and 2",
        ),  # closed
    ],
)
def test_self_intersecting_polyline(tmp_path, points, pair):
    message = messages(fracture_error(tmp_path, points=points), "fractures[0].points")
    assert message.startswith("self-intersecting polyline") and pair in message


# --------------------------------------------------------------------------- #
# Errors: boundary and loading
# --------------------------------------------------------------------------- #


def test_bad_edge_string_lists_allowed_values(tmp_path):
    doc = base()
    doc["boundary"]["top"] = "tracton"
    message = messages(error_of(tmp_path, doc), "boundary.top")
    assert message.startswith('must be "traction", "free", a table such as')
    assert "got string 'tracton'; did you mean 'traction'?" in message


def test_traction_edge_needs_loading_stress(tmp_path):
    doc = base(loading={"steps": 2})
    message = messages(error_of(tmp_path, doc), "loading.stress")
    assert message.startswith("required key missing")
    assert "boundary.top, boundary.right" in message


def test_traction_flag_needs_loading_stress(tmp_path):
    doc = base(loading=None, boundary={"bottom": {"uy": 0.0, "traction": True}})
    message = messages(error_of(tmp_path, doc), "loading.stress")
    assert "required key missing" in message and "boundary.bottom" in message


def test_stress_needs_xx_and_yy(tmp_path):
    doc = base(loading={"stress": {"xx": 1.0, "xz": 0.0}})
    err = error_of(tmp_path, doc)
    assert messages(err, "loading.stress.yy") == "required key missing"
    assert "unknown key 'xz' in [loading.stress]" in messages(err, "loading.stress.xz")


@pytest.mark.parametrize(
    ("entry", "key", "words"),
    [
        (
            {"ux": 0.0, "uy": 0.0, "traction": True},
            "boundary.left.traction",
            "needs a free component",
        ),
        ({}, "boundary.left", "prescribes nothing"),
        (
            {"file": "left.csv", "ux": 0.0},
            "boundary.left.ux",
            "cannot be combined with file",
        ),
        (
            {"ux": 0.0, "traction": "yes"},
            "boundary.left.traction",
            "expected true or false, got string 'yes'",
        ),
        ({"ux": "0"}, "boundary.left.ux", "expected a number, got string '0'"),
        (3, "boundary.left", "got integer 3"),
    ],
)
def test_bad_edge_tables(tmp_path, entry, key, words):
    doc = base()
    doc["boundary"]["left"] = entry
    assert words in messages(error_of(tmp_path, doc), key)


def test_no_displacement_anywhere(tmp_path):
    doc = base(boundary={"bottom": "free", "top": "traction"})
    err = error_of(tmp_path, doc)
    assert err.problems == [
        (
            "boundary",
            (
                "no displacement is prescribed on any edge: the body can move freely; "
                "prescribe at least one component (e.g. bottom = { uy = 0.0 })"
            ),
        )
    ]


def test_missing_boundary_table(tmp_path):
    err = error_of(tmp_path, base(boundary=None))
    assert messages(err, "boundary") == "required key missing"


# --------------------------------------------------------------------------- #
# Errors: solver and output
# --------------------------------------------------------------------------- #


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("tolerance", 1.0, "must satisfy 0 < tolerance < 1, got 1.0"),
        ("tolerance", 0, "must satisfy 0 < tolerance < 1, got 0.0"),
        ("max_iterations", 0, "must satisfy 1 <= max_iterations <= 10000, got 0"),
        (
            "tangent",
            "secnt",
            'must be one of "consistent", "secant", got \'secnt\'; '
            "did you mean 'secant'?",
        ),
    ],
)
def test_bad_solver_options(tmp_path, key, value, message):
    assert (
        messages(error_of(tmp_path, base(solver={key: value})), f"solver.{key}")
        == message
    )


def test_output_options(tmp_path):
    spec = load_case(
        write(tmp_path, base(output={"directory": "results/a", "formats": ["h5"]}))
    )
    assert str(spec.output.directory) == "results/a" and spec.output.formats == ("h5",)
    err = error_of(tmp_path, base(output={"formats": ["vtu"]}))
    assert messages(err, "output.formats").startswith('must include "h5"')
    err = error_of(tmp_path, base(output={"formats": ["h5", "vtk"], "directory": ""}))
    assert "got 'vtk'" in messages(err, "output.formats[1]")
    assert "non-empty string" in messages(err, "output.directory")
    err = error_of(tmp_path, base(output={"formats": []}))
    assert "non-empty array" in messages(err, "output.formats")


# --------------------------------------------------------------------------- #
# Boundary CSV files
# --------------------------------------------------------------------------- #


def csv_case(tmp_path, rows, header="x,y,ux,uy", edge="left"):
    """Graded mesh on [0, 2] x [0, 1]; ``edge`` driven by ``left.csv``."""
    (tmp_path / "left.csv").write_text(header + "\n" + "\n".join(rows) + "\n")
    doc = base(
        domain=None,
        mesh={"x": [0.0, 0.5, 2.0], "y": [0.0, 0.1, 0.25, 0.7, 1.0]},
        fractures=[],
        loading=None,
        boundary={edge: {"file": "left.csv"}},
    )
    return write(tmp_path, doc)


def csv_error(tmp_path, rows, **kwargs) -> str:
    with pytest.raises(CaseError) as info:
        load_case(csv_case(tmp_path, rows, **kwargs))
    edge = kwargs.get("edge", "left")
    assert {k for k, _ in info.value.problems} == {f"boundary.{edge}.file"}
    return messages(info.value, f"boundary.{edge}.file")


def test_csv_interpolates_a_linear_field_exactly(tmp_path):
    def exact(y):
        return 1e-3 * y - 2e-4, -5e-4 * y

    ys = [0.8, 0.0, 1.0, 0.35, 0.6]  # any order, not at the nodes
    rows = [f" 0.0 , {y!r}, {exact(y)[0]!r}, {exact(y)[1]!r}" for y in ys]
    spec = load_case(csv_case(tmp_path, rows, header=" X, y ,UX,uy "))
    left = spec.boundary.left
    assert left.kind == "displacement" and left.source == str(tmp_path / "left.csv")
    nodes = spec.mesh.y
    np.testing.assert_allclose(
        left.values, np.column_stack(exact(nodes)), rtol=1e-12, atol=1e-18
    )
    assert "[" + str(tmp_path / "left.csv") + "]" in describe(spec)


def test_csv_bottom_edge_ordered_by_x(tmp_path):
    rows = [
        "2.0,0.0,2.0,0.0",
        "0.0,0.0,0.0,0.0",
        "0.0,0.0,0.0,0.0",
    ]  # exact duplicate ok
    spec = load_case(csv_case(tmp_path, rows, edge="bottom"))
    np.testing.assert_allclose(spec.boundary.bottom.values[:, 0], [0.0, 0.5, 2.0])


def test_csv_point_off_the_edge(tmp_path):
    message = csv_error(tmp_path, ["0.0,0.0,0,0", "0.01,0.5,0,0", "0.0,1.0,0,0"])
    assert (
        "left.csv line 3: point (0.01, 0.5) is not on the left edge (x = 0.0)"
        in message
    )


def test_csv_point_beyond_the_edge_end(tmp_path):
    message = csv_error(tmp_path, ["0.0,0.0,0,0", "0.0,1.5,0,0"])
    assert (
        "line 3" in message and "lies beyond the left edge (y in [0.0, 1.0])" in message
    )


def test_csv_not_covering_the_edge(tmp_path):
    message = csv_error(tmp_path, ["0.0,0.0,0,0", "0.0,0.9,0,0"])
    assert "points cover y in [0.0, 0.9]" in message and "end to end" in message


def test_csv_malformed_rows(tmp_path):
    message = csv_error(
        tmp_path, ["0.0,0.0,0,0", "0.0,0.5,0", "0.0,abc,0,0", "0.0,1.0,nan,0"]
    )
    assert "left.csv line 3: expected 4 values x,y,ux,uy, got 3" in message
    assert "left.csv line 4: y is not a number: 'abc'" in message
    assert "left.csv line 5: ux must be finite" in message


def test_csv_bad_header(tmp_path):
    message = csv_error(tmp_path, ["0.0,0.0,0,0", "0.0,1.0,0,0"], header="x,y,u,v")
    assert "left.csv line 1: header must be x,y,ux,uy, got 'x,y,u,v'" in message


def test_csv_single_point_and_conflicting_duplicates(tmp_path):
    assert "at least 2 distinct points" in csv_error(tmp_path, ["0.0,0.5,0,0"])
    message = csv_error(tmp_path, ["0.0,0.0,0,0", "0.0,0.0,1,0", "0.0,1.0,0,0"])
    assert "lines 2 and 3: the same point with different values" in message


def test_csv_missing_file(tmp_path):
    doc = base(boundary={"left": {"file": "nowhere.csv"}})
    err = error_of(tmp_path, doc)
    assert "cannot read" in messages(err, "boundary.left.file")
    assert "nowhere.csv" in messages(err, "boundary.left.file")


def test_csv_row_problems_are_capped(tmp_path):
    rows = ["0.0,0.0,0,0"] + [f"0.0,{i / 100},x,0" for i in range(1, 16)]
    message = csv_error(tmp_path, rows)
    assert message.count("ux is not a number") == 10
    assert message.endswith("... and 5 more rows")


def test_unknown_edge_name_is_suggested_and_edge_stays_free(tmp_path):
    doc = base()
    doc["boundary"]["rigth"] = doc["boundary"].pop("right")
    err = error_of(tmp_path, doc)
    assert err.problems == [
        (
            "boundary.rigth",
            "unknown key 'rigth' in [boundary]; did you mean 'right'?",
        )
    ]


# --------------------------------------------------------------------------- #
# Robustness: whatever the file holds, only CaseError escapes
# --------------------------------------------------------------------------- #

LEAF_VALUES = st.one_of(
    st.integers(-(2**70), 2**70),
    st.floats(allow_nan=True, allow_infinity=True),
    st.booleans(),
    st.text(max_size=8),
    st.lists(st.floats(-3.0, 3.0), max_size=3),
    st.lists(st.lists(st.floats(-3.0, 3.0), min_size=2, max_size=2), max_size=4),
    st.just({}),
    st.sampled_from(["traction", "free", "h5", "vtu", "plane_stress"]),
)


def _leaf_paths(obj, path=()):
    """Paths of every value inside a nested dict/list document."""
    if path:
        yield path
    if isinstance(obj, dict | list):
        children = obj.items() if isinstance(obj, dict) else enumerate(obj)
        for key, value in children:
            yield from _leaf_paths(value, (*path, key))


@settings(derandomize=True, max_examples=300, deadline=None)
@given(data=st.data())
def test_mutated_cases_raise_only_case_error(tmp_path_factory, data):
    doc = base(solver={"tolerance": 1e-6}, output={"formats": ["h5"]})
    for _ in range(data.draw(st.integers(1, 3))):
        paths = list(_leaf_paths(doc))
        path = data.draw(st.sampled_from(paths))
        parent = doc
        for key in path[:-1]:
            parent = parent[key]
        parent[path[-1]] = data.draw(LEAF_VALUES)
    folder = tmp_path_factory.mktemp("fuzz")
    try:
        spec = load_case(write(folder, doc))
    except CaseError as err:
        assert err.problems and "\n" not in str(err)
    else:
        assert describe(spec).startswith("case ")


# --- crack-tip option (extension of case-format v1) --------------------------


def _tip_case(tmp_path, tip=None):
    fracture = {
        "points": [[0.2, 0.3], [0.7, 0.6]],
        "friction": 0.2,
        "kn": 1.0e12,
        "kt": 1.0e12,
        "tip": tip,
    }
    case = {
        "domain": {"size": [1.0, 1.0]},
        "mesh": {"elements": [4, 4]},
        "material": {"E": 1.0e9, "nu": 0.25},
        "fractures": [fracture],
        "boundary": {"bottom": {"uy": 0.0}, "top": {"uy": -0.001}},
    }
    path = tmp_path / "tip.toml"
    path.write_text(build.case_text(case))
    return path


def test_tip_defaults_to_branch_with_automatic_radius(tmp_path):
    spec = load_case(_tip_case(tmp_path))
    assert spec.fractures[0].tip == "branch"
    assert spec.fractures[0].tip_radius is None


def test_tip_string_and_table_forms(tmp_path):
    assert load_case(_tip_case(tmp_path, "ramp")).fractures[0].tip == "ramp"
    spec = load_case(_tip_case(tmp_path, {"kind": "branch", "radius": 0.05}))
    assert spec.fractures[0].tip == "branch"
    assert spec.fractures[0].tip_radius == 0.05


@pytest.mark.parametrize(
    ("tip", "key", "words"),
    [
        ("brnch", "fractures[0].tip", "did you mean 'branch'"),
        ({"kind": "branch", "radius": -1.0}, "fractures[0].tip.radius", "> 0"),
        ({"kind": "ramp", "radius": 0.1}, "fractures[0].tip.radius", "only used"),
        ({"knd": "ramp"}, "fractures[0].tip.knd", "did you mean 'kind'"),
    ],
)
def test_tip_errors(tmp_path, tip, key, words):
    with pytest.raises(CaseError) as info:
        load_case(_tip_case(tmp_path, tip))
    assert any(k == key and words in m for k, m in info.value.problems), (
        info.value.problems
    )


# --------------------------------------------------------------------------- #
# Sizes beyond the float range
# --------------------------------------------------------------------------- #


def test_an_element_count_of_401_digits_is_reported_without_overflow(tmp_path):
    big = 10**400  # a TOML integer; no float holds it
    err = error_of(tmp_path, build.with_keys(base(), **{"mesh.elements": [big, 2]}))
    assert messages(err, "mesh.elements") == (
        "1.00e+400 x 2 = 2.00e+400 elements exceeds the limit of 25000000 (would "
        "need at least ~4.09e+394 GB of memory, ~2 kB per element)"
    )


@pytest.mark.parametrize(
    ("fracture", "key", "got"),
    [
        ({"points": [[1.5, -0.5], [1e308, -0.5]]}, "points", "1e+308"),
        ({"points": [[1.5, -0.5], [2.5, 1e151]]}, "points", "1e+151"),
        ({"center": [2.0, -0.5], "length": 4e150, "angle": 0.0}, "length", "2e+150"),
    ],
)
def test_fracture_vertices_beyond_1e150_are_refused(tmp_path, fracture, key, got):
    doc = base()
    doc["fractures"][0] = {"friction": 0.6, **fracture}
    err = error_of(tmp_path, doc)
    assert messages(err, f"fractures[0].{key}") == (
        "a vertex lies beyond +-1e+150 m (squared distances in the geometry would "
        f"overflow), got {got}"
    )


def test_a_domain_reaching_beyond_1e150_is_refused(tmp_path):
    err = error_of(tmp_path, base(domain={"size": [1e151, 1.0]}, fractures=None))
    assert messages(err, "domain.size").startswith(
        "node coordinates from 0.0 to 1e+151 reach beyond +-1e+150 m"
    )
