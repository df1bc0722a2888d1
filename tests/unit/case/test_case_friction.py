"""``friction`` and ``cohesion`` as slip-weakening laws (xfemslip.case.friction):
the resolved spec, the errors (one line naming the key), [network] defaults
and CSV values, and the ``check`` printout."""

from __future__ import annotations

import copy

import pytest

from xfemslip.case import build, describe, load_case
from xfemslip.case.specs import SlipWeakeningSpec
from xfemslip.errors import CaseError

CASE = {
    "domain": {"size": [2.0, 1.0]},
    "mesh": {"elements": [20, 10]},
    "material": {"E": 5.0e9, "nu": 0.3},
    "fractures": [{"points": [[0.2, 0.5], [1.8, 0.5]], "friction": 0.6}],
    "loading": {"stress": {"xx": -20.0e6, "yy": -40.0e6}},
    "boundary": {"bottom": {"uy": 0.0}, "top": "traction"},
}
LAW = {"law": "slip_weakening", "static": 0.6, "dynamic": 0.45, "slip_distance": 5e-3}


def _write(tmp_path, fracture=None, network=None, csv=None):
    doc = copy.deepcopy(CASE)
    if fracture is not None:
        doc["fractures"][0] = {"points": [[0.2, 0.5], [1.8, 0.5]], **fracture}
    if network is not None:
        doc["network"] = network
    if csv is not None:
        (tmp_path / "seg.csv").write_text(csv, encoding="utf-8")
    path = tmp_path / "case.toml"
    path.write_text(build.case_text(doc), encoding="utf-8")
    return path


def _problems(tmp_path, **kw) -> list:
    with pytest.raises(CaseError) as info:
        load_case(_write(tmp_path, **kw))
    return info.value.problems


def test_a_number_is_constant_coulomb_friction(tmp_path):
    fr = load_case(_write(tmp_path)).fractures[0]
    assert (fr.friction, fr.cohesion, fr.weakening) == (0.6, 0.0, None)


def test_slip_weakening_friction_resolves_to_static_values_and_a_law(tmp_path):
    fr = load_case(_write(tmp_path, {"friction": LAW, "cohesion": 1e5})).fractures[0]
    assert (fr.friction, fr.cohesion) == (0.6, 1e5)  # the static values
    # a number cohesion with a weakening friction does not weaken
    assert fr.weakening == SlipWeakeningSpec(
        dynamic_friction=0.45, dynamic_cohesion=1e5, slip_distance=5e-3
    )
    cohesion = {"static": 2e6, "dynamic": 0.0}
    fr = load_case(_write(tmp_path, {"friction": LAW, "cohesion": cohesion}))
    fr = fr.fractures[0]
    assert fr.cohesion == 2e6 and fr.weakening.dynamic_cohesion == 0.0


def test_equal_static_and_dynamic_values_are_allowed(tmp_path):
    law = {**LAW, "dynamic": 0.6}
    fr = load_case(_write(tmp_path, {"friction": law})).fractures[0]
    assert fr.friction == fr.weakening.dynamic_friction == 0.6


@pytest.mark.parametrize(
    "friction, cohesion, key, message",
    [
        ({**LAW, "dynamic": 0.7}, None, "fractures[0].friction.dynamic",
         "must be <= static = 0.6 (the friction weakens with slip), got 0.7"),
        ({**LAW, "slip_distance": 0.0}, None, "fractures[0].friction.slip_distance",
         "must be > 0, got 0.0"),
        ({**LAW, "static": -0.1}, None, "fractures[0].friction.static",
         "must be >= 0, got -0.1"),
        ({**LAW, "law": "rate_state"}, None, "fractures[0].friction.law",
         """must be one of "slip_weakening", got 'rate_state'"""),
        ({k: v for k, v in LAW.items() if k != "slip_distance"}, None,
         "fractures[0].friction.slip_distance", "required key missing"),
        ({k: v for k, v in LAW.items() if k != "law"}, None,
         "fractures[0].friction.law", "required key missing"),
        ({**LAW, "dc": 1.0}, None, "fractures[0].friction.dc",
         "unknown key 'dc' in [fractures[0].friction]"),
        (LAW, {"static": 1e6, "dynamic": 2e6}, "fractures[0].cohesion.dynamic",
         "must be <= static = 1e+06 (the cohesion weakens with slip), got 2000000.0"),
        (LAW, {"static": 1e6}, "fractures[0].cohesion.dynamic",
         "required key missing"),
        (0.6, {"static": 1e6, "dynamic": 0.0}, "fractures[0].cohesion",
         'a weakening cohesion { static, dynamic } needs friction = { law = '
         '"slip_weakening", ... }: it weakens over that slip_distance'),
        ("0.6", None, "fractures[0].friction",
         'expected a number (constant friction) or a table { law = '
         '"slip_weakening", static, dynamic, slip_distance }, got string'),
        (LAW, "1e6", "fractures[0].cohesion",
         "expected a number (Pa) or a table { static, dynamic }, got string"),
    ],
)  # fmt: skip
def test_errors_name_the_key(tmp_path, friction, cohesion, key, message):
    fracture = {"friction": friction}
    if cohesion is not None:
        fracture["cohesion"] = cohesion
    problems = _problems(tmp_path, fracture=fracture)
    found = [m for k, m in problems if k == key]
    assert found and found[0].startswith(message), problems


def test_errors_are_one_line_naming_the_file(tmp_path):
    with pytest.raises(CaseError) as info:
        load_case(_write(tmp_path, {"friction": {**LAW, "dynamic": 0.9}}))
    text = str(info.value)
    assert "\n" not in text
    assert "case.toml" in text and "fractures[0].friction.dynamic" in text


def test_network_friction_law_applies_where_the_csv_gives_no_value(tmp_path):
    csv = (
        "fracture,x0,y0,x1,y1,friction,cohesion\n"
        "a,0.1,0.1,0.9,0.2,,\n"
        "b,1.1,0.1,1.9,0.2,0.5,\n"
        "c,1.1,0.7,1.9,0.8,,3e5\n"
    )
    network = {
        "file": "seg.csv",
        "friction": LAW,
        "cohesion": {"static": 1e6, "dynamic": 1e5},
    }
    spec = load_case(_write(tmp_path, network=network, csv=csv))
    a, b, c = spec.fractures[1:]
    assert (a.friction, a.cohesion) == (0.6, 1e6)
    assert a.weakening == SlipWeakeningSpec(
        dynamic_friction=0.45, dynamic_cohesion=1e5, slip_distance=5e-3
    )
    # a friction of the file is constant; the cohesion still weakens
    assert (b.friction, b.weakening.dynamic_friction) == (0.5, 0.5)
    assert (b.cohesion, b.weakening.dynamic_cohesion) == (1e6, 1e5)
    # a cohesion of the file is constant; the friction still weakens
    assert (c.cohesion, c.weakening.dynamic_cohesion) == (3e5, 3e5)
    assert c.weakening.dynamic_friction == 0.45
    # the inline fracture keeps its own constant friction
    assert spec.fractures[0].weakening is None


def test_network_generated_fractures_take_the_law(tmp_path):
    network = {
        "friction": LAW,
        "generate": {
            "seed": 1,
            "count": 3,
            "orientation": {"distribution": "uniform"},
            "length": {"distribution": "constant", "value": 0.3},
        },
    }
    spec = load_case(_write(tmp_path, network=network))
    generated = spec.fractures[1:]
    assert len(generated) == 3
    assert all(f.weakening.dynamic_friction == 0.45 for f in generated)
    assert all(f.friction == 0.6 and f.cohesion == 0.0 for f in generated)


def test_network_law_errors_name_network_keys(tmp_path):
    network = {"file": "seg.csv", "friction": {**LAW, "slip_distance": -1.0}}
    problems = _problems(
        tmp_path, network=network, csv="x0,y0,x1,y1\n0.1,0.1,0.9,0.2\n"
    )
    assert ("network.friction.slip_distance", "must be > 0, got -1.0") in problems


def test_check_prints_the_law(tmp_path):
    cohesion = {"static": 2e6, "dynamic": 0.0}
    spec = load_case(_write(tmp_path, {"friction": LAW, "cohesion": cohesion}))
    text = describe(spec)
    assert (
        "friction = slip weakening 0.6 -> 0.45 over 5 mm of slip, "
        "cohesion = 2 -> 0 MPa over 5 mm of slip" in text
    )
