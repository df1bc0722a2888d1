"""[[units]], faults as drawn and an in-situ state growing with depth: what
the case reader accepts, resolves and refuses (one line per problem)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from xfemslip.case import build, loads_case
from xfemslip.case.plausibility import plausibility_warnings
from xfemslip.errors import CaseError


def _case(**extra) -> dict:
    """A 2 km x 1 km section (y is elevation: -3500 to -2500 m) with a
    normal fault dipping 60 degrees to the right through (1000, -3000)."""
    case = {
        "mesh": {
            "x": list(np.linspace(0.0, 2000.0, 21)),
            "y": list(np.linspace(-3500.0, -2500.0, 11)),
        },
        "material": {"E": 20.0e9, "nu": 0.25, "density": 2400.0},
        "fractures": [
            {"point": [1000.0, -3000.0], "dip": 60.0, "length": 800.0, "friction": 0.6}
        ],
        "loading": {
            "initial_stress": {
                "datum": 0.0,
                "gradient_yy": -23.0e3,
                "ratio_xx": 0.7,
            },
            "steps": 2,
        },
        "pore_pressure": {"initial": 0.0, "gradient": 10.0e3, "change": -25.0e6},
        "boundary": {
            "left": {"ux": 0.0},
            "right": {"ux": 0.0},
            "bottom": {"uy": 0.0},
            "top": "traction",
        },
    }
    for key, value in extra.items():
        table, _, name = key.partition(".")
        if value is None:
            if name:
                case[table].pop(name)
            else:
                case.pop(table)
        elif name:
            case.setdefault(table, {})[name] = value
        else:
            case[table] = value
    return case


def _load(case):
    return loads_case(build.case_text(case), "section.toml")


def _problems(case) -> list[tuple[str, str]]:
    with pytest.raises(CaseError) as err:
        _load(case)
    return err.value.problems


def _messages(case) -> str:
    return "\n".join(f"{k}: {m}" for k, m in _problems(case))


# --------------------------------------------------------------------------- #
# Faults as drawn


def test_fault_from_point_dip_and_length_runs_down_the_dip():
    """Upper end first; 60 degrees below horizontal towards +x."""
    spec = _load(_case())
    p = spec.fractures[0].points
    half = 400.0
    np.testing.assert_allclose(
        p,
        [
            [1000.0 - half * 0.5, -3000.0 + half * math.sqrt(3) / 2],
            [1000.0 + half * 0.5, -3000.0 - half * math.sqrt(3) / 2],
        ],
        rtol=1e-14,
    )


def test_fault_from_point_dip_top_and_base_ends_at_those_depths():
    fault = {
        "point": [1000.0, -3000.0],
        "dip": 60.0,
        "top": -2600.0,
        "base": -3400.0,
        "dip_direction": "left",
        "friction": 0.6,
    }
    p = _load(_case(fractures=[fault])).fractures[0].points
    np.testing.assert_allclose(p[:, 1], [-2600.0, -3400.0], rtol=1e-15)
    # dipping to the left: going down moves to -x, by dy / tan(60)
    np.testing.assert_allclose(
        p[:, 0],
        [1000.0 + 400.0 / math.sqrt(3), 1000.0 - 400.0 / math.sqrt(3)],
        rtol=1e-14,
    )


@pytest.mark.parametrize(
    ("fault", "key", "words"),
    [
        ({"point": [1000.0, -3000.0], "dip": 90.5, "length": 10.0}, "dip", "90"),
        (
            {"point": [1000.0, -3000.0], "dip": 60.0, "length": 10.0, "angle": 30.0},
            "fractures[0]",
            "not mixed",
        ),
        (
            {"point": [1000.0, -3000.0], "dip": 60.0, "top": -3100.0, "base": -2900.0},
            "top",
            "above base",
        ),
        (
            {"point": [1000.0, -3000.0], "dip": 60.0, "length": 10.0, "top": -2900.0},
            "fractures[0]",
            "not both",
        ),
        (
            {"points": [[0.0, -3000.0], [10.0, -3000.0]], "top": -2900.0},
            "top",
            "only used with point and dip",
        ),
    ],
)
def test_bad_fault_geometry_is_named(fault, key, words):
    fault = {**fault, "friction": 0.6}
    problems = _problems(_case(fractures=[fault]))
    assert any(k.endswith(key) and words in m for k, m in problems), problems


# --------------------------------------------------------------------------- #
# Units


def test_a_layer_takes_the_host_constants_it_leaves_out():
    units = [
        {"name": "caprock", "top": -2800.0, "base": -2900.0, "E": 10.0e9},
        {
            "name": "reservoir",
            "top": -2900.0,
            "base": -3100.0,
            "biot": 0.9,
            "density": 2200.0,
            "change": -20.0e6,
        },
    ]
    spec = _load(_case(units=units))
    cap, res = spec.units
    assert (cap.E, cap.nu, cap.biot, cap.density) == (10.0e9, 0.25, None, None)
    assert (res.region.kind, res.region.top, res.region.base) == (
        "layer",
        -2900.0,
        -3100.0,
    )
    assert (res.biot, res.density, res.change) == (0.9, 2200.0, -20.0e6)


def test_a_displaced_layer_takes_its_fault_and_the_hanging_wall():
    units = [
        {
            "name": "reservoir",
            "top": -2900.0,
            "base": -3100.0,
            "offset": {"fracture": 0, "throw": 50.0},
            "change": {"left": -25.0e6, "right": -10.0e6},
        }
    ]
    (res,) = _load(_case(units=units)).units
    r = res.region
    assert r.kind == "offset" and r.throw == 50.0 and r.fracture == 0
    # the fault dips towards +x: the hanging wall (lowered) is on the right
    assert r.lowered == "right"
    np.testing.assert_array_equal(r.fault, _load(_case()).fractures[0].points)
    assert res.change_sides == (-25.0e6, -10.0e6)


def test_a_vertical_fault_needs_the_lowered_side():
    fault = {"points": [[1000.0, -3400.0], [1000.0, -2600.0]], "friction": 0.6}
    units = [
        {"top": -2900.0, "base": -3100.0, "offset": {"fracture": 0, "throw": 50.0}}
    ]
    problems = _problems(_case(fractures=[fault], units=units))
    assert any(
        k == "units[0].offset.lowered" and "vertical" in m for k, m in problems
    ), problems
    units[0]["offset"]["lowered"] = "left"
    (u,) = _load(_case(fractures=[fault], units=units)).units
    assert u.region.lowered == "left"


@pytest.mark.parametrize(
    ("units", "key", "words"),
    [
        ([{"top": -2900.0}], "units[0].base", "required"),
        ([{"top": -3100.0, "base": -2900.0}], "units[0].top", "above base"),
        (
            [{"top": -2900.0, "base": -3100.0, "box": [0, 0, 1, 1]}],
            "units[0]",
            "not both",
        ),
        ([{"name": "a"}], "units[0]", "top and base"),
        (
            [
                {
                    "top": -2900.0,
                    "base": -3100.0,
                    "offset": {"fracture": 3, "throw": 5.0},
                }
            ],
            "units[0].offset.fracture",
            "names fractures[3]",
        ),
        (
            [
                {
                    "top": -2900.0,
                    "base": -3100.0,
                    "offset": {"fracture": 0, "throw": -5.0},
                }
            ],
            "units[0].offset.throw",
            ">= 0",
        ),
        (
            [{"top": -2900.0, "base": -3100.0, "change": {"left": 1.0, "right": 2.0}}],
            "units[0].change",
            "one number",
        ),
        (
            [
                {"name": "a", "top": -2900.0, "base": -3100.0},
                {"name": "a", "top": -2800.0, "base": -2900.0},
            ],
            "units[1].name",
            "repeats",
        ),
        ([{"top": 900.0, "base": 800.0}], "units[0].top", "no element centre"),
        ([{"top": -2900.0, "base": -3100.0, "nu": 0.5}], "units[0].nu", "0.5"),
    ],
)
def test_bad_units_are_named(units, key, words):
    problems = _problems(_case(units=units))
    assert any(k == key and words in m for k, m in problems), problems


def test_units_and_reservoir_together_are_refused():
    case = _case(
        units=[{"top": -2900.0, "base": -3100.0}],
        reservoir={"box": [0.0, -3100.0, 2000.0, -2900.0], "E": 8e9, "nu": 0.2},
    )
    assert "not both" in _messages(case)


def test_keys_users_try_get_a_pointer():
    """Words a user tries for layers and depth gradients say where they go."""
    text = _messages(_case(layers=[{"top": 0.0}]))
    assert "[[units]]" in text
    text = _messages(_case(reservoir=[{"box": [0, 0, 1, 1]}]))
    assert "[[units]]" in text and "array of tables" in text
    case = _case()
    case["loading"]["gravity"] = 9.81
    assert "loading.initial_stress" in _messages(case)


def test_reservoir_is_the_unit_named_reservoir():
    case = _case(
        reservoir={"box": [0.0, -3100.0, 2000.0, -2900.0], "E": 8e9, "nu": 0.2}
    )
    case["pore_pressure"]["region"] = "reservoir"
    (unit,) = _load(case).units
    assert unit.name == "reservoir" and (unit.E, unit.nu) == (8e9, 0.2)
    np.testing.assert_array_equal(unit.region.boxes, [[0.0, -3100.0, 2000.0, -2900.0]])


def test_pore_pressure_region_may_name_a_unit():
    units = [{"name": "sand", "top": -2900.0, "base": -3100.0}]
    case = _case(units=units)
    case["pore_pressure"]["region"] = "sand"
    assert _load(case).pore_pressure.region == "sand"
    case["pore_pressure"]["region"] = "snad"
    assert "'sand'" in _messages(case)


# --------------------------------------------------------------------------- #
# Snapping


def test_a_polygon_edge_typed_off_the_fault_is_moved_onto_it():
    """1e-3 of a cell off (0.1 m on 100 m cells): snapped, and said."""
    spec = _load(_case())
    a, b = spec.fractures[0].points
    t = (b - a) / np.linalg.norm(b - a)
    n = np.array([-t[1], t[0]])
    p, q = a + 0.25 * (b - a), a + 0.75 * (b - a)
    off = 0.1 * n
    polygon = [
        list(p + off),
        list(q + off),
        list(q + off + [500.0, 0.0]),
        list(p + off + [500.0, 0.0]),
    ]
    units = [{"name": "block", "polygon": polygon}]
    (u,) = _load(_case(units=units)).units
    # each end slides along its other (horizontal) edge onto the fault
    for v, got in zip((p + off, q + off), u.region.polygon[:2], strict=True):
        x_on_fault = a[0] + (v[1] - a[1]) * t[0] / t[1]
        np.testing.assert_allclose(got, [x_on_fault, v[1]], rtol=1e-14)
    ((edge, fracture, distance),) = u.snapped
    assert (edge, fracture) == ("polygon edge 0", 0)
    assert distance == pytest.approx(0.1, rel=1e-9)
    (warning,) = plausibility_warnings(_load(_case(units=units)))
    assert warning.startswith("units[0]: polygon edge 0 lies 0.1 m off fractures[0]")
    # half a cell off: a feature the mesh resolves, kept as typed
    polygon[0] = list(p + 50.0 * n)
    polygon[1] = list(q + 50.0 * n)
    (u,) = _load(_case(units=[{"polygon": polygon}])).units
    assert u.snapped == ()


# --------------------------------------------------------------------------- #
# In situ with depth


def test_in_situ_with_a_datum_reads_as_a_depth_profile():
    s = _load(_case()).loading
    assert s.initial_stress is None and s.has_in_situ
    assert (s.in_situ.datum, s.in_situ.gradient_yy, s.in_situ.ratio_xx) == (
        0.0,
        -23.0e3,
        0.7,
    )


@pytest.mark.parametrize(
    ("initial_stress", "key", "words"),
    [
        ({"gradient_yy": -23e3, "ratio_xx": 0.7}, "datum", "required"),
        (
            {"datum": 0.0, "gradient_yy": 23e3, "ratio_xx": 0.7},
            "gradient_yy",
            "negative gradient",
        ),
        ({"datum": 0.0, "ratio_xx": 0.7}, "initial_stress", "exactly one of"),
        (
            {"datum": 0.0, "gradient_yy": -23e3, "gravity": 9.81, "ratio_xx": 0.7},
            "initial_stress",
            "exactly one of",
        ),
        (
            {"datum": 0.0, "gradient_yy": -23e3, "ratio_xx": 0.7, "xx": -1.0},
            "xx",
            "ratio_xx",
        ),
        ({"datum": 0.0, "gradient_yy": -23e3}, "xx", "required"),
        (
            {"datum": 0.0, "gradient_yy": -23e3, "ratio_xx": "elastic"},
            "ratio_xx",
            "uniaxial_strain",
        ),
    ],
)
def test_bad_depth_profiles_are_named(initial_stress, key, words):
    case = _case()
    case["loading"]["initial_stress"] = initial_stress
    problems = _problems(case)
    assert any(k.endswith(key) and words in m for k, m in problems), problems


def test_uniform_far_field_stress_beside_a_depth_profile_is_refused():
    case = _case()
    case["loading"]["stress"] = {"xx": -1.0, "yy": -1.0}
    assert "varies with depth" in _messages(case)


def test_gravity_needs_the_host_density():
    case = _case()
    case["loading"]["initial_stress"] = {"datum": 0.0, "gravity": 9.81, "ratio_xx": 0.7}
    assert _load(case).loading.in_situ.gravity == 9.81
    case["material"].pop("density")
    assert "material.density" in _messages(case)


def test_pore_pressure_gradient_uses_the_stress_datum_unless_given():
    case = _case()
    case["loading"]["initial_stress"]["datum"] = 100.0
    assert _load(case).pore_pressure.datum == 100.0
    case["pore_pressure"]["datum"] = 50.0
    assert _load(case).pore_pressure.datum == 50.0


@pytest.mark.parametrize(
    ("value", "ok"),
    [
        ("mean", True),
        ("higher", True),
        ("lower", True),
        (12.0e6, True),
        ("middle", False),
        (-1.0, False),
    ],
)
def test_fluid_pressure_rule(value, ok):
    fault = {**_case()["fractures"][0], "fluid_pressure": value}
    if ok:
        assert _load(_case(fractures=[fault])).fractures[0].fluid_pressure == value
    else:
        assert "fluid_pressure" in _messages(_case(fractures=[fault]))
