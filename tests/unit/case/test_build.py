"""The case builder: Python values -> TOML text -> the same values and specs."""

from __future__ import annotations

import math
import re
import struct
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from xfemslip.case import build, load_case, loads_case
from xfemslip.errors import CaseError

ROOT = Path(__file__).resolve().parents[3]
RESERVOIR = ROOT / "cases" / "reservoir_depletion.toml"


def _bits(value):
    """Floats by their bit pattern (so -0.0 != 0.0), any NaN as one value (TOML's
    nan has no sign or payload), the rest with its type."""
    if isinstance(value, dict):
        return {k: _bits(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_bits(v) for v in value]
    if isinstance(value, float):
        return ("float", b"nan" if math.isnan(value) else struct.pack("<d", value))
    return (type(value).__name__, value)


scalars = st.one_of(
    st.floats(),  # NaN and infinities too: TOML has nan and inf
    st.integers(min_value=-(2**63), max_value=2**63 - 1),
    st.booleans(),
    st.text(max_size=20),
)
keys = st.text(min_size=1, max_size=12)
documents = st.recursive(
    st.dictionaries(keys, scalars, max_size=4),
    lambda inner: st.dictionaries(
        keys, st.one_of(scalars, inner, st.lists(scalars, max_size=4)), max_size=4
    ),
    max_leaves=20,
)


@settings(max_examples=200, deadline=None, database=None)
@given(documents)
def test_any_document_reads_back_bit_for_bit(doc):
    assert _bits(tomllib.loads(build.case_text(doc))) == _bits(doc)


def _case(E, nu, size, n, points, friction, stress):
    return {
        "name": "built",
        "domain": {"size": size},
        "mesh": {"elements": [n, n]},
        "material": {"E": E, "nu": nu},
        "fractures": [{"points": points, "friction": friction}],
        "loading": {"stress": build.stress_table(stress)},
        "boundary": {"bottom": {"uy": 0.0}, "top": "traction"},
    }


@settings(max_examples=40, deadline=None, database=None)
@given(
    E=st.floats(1e6, 1e12),
    nu=st.floats(0.0, 0.49),
    width=st.floats(0.5, 100.0),
    n=st.integers(2, 12),
    a=st.tuples(st.floats(0.2, 0.45), st.floats(0.2, 0.45)),
    b=st.tuples(st.floats(0.55, 0.8), st.floats(0.55, 0.8)),
    friction=st.floats(0.0, 1.0),
    stress=st.tuples(*[st.floats(-1e9, 1e9)] * 3),
)
def test_a_built_case_loads_to_the_values_it_was_built_from(
    E, nu, width, n, a, b, friction, stress
):
    size = [width, 1.0]
    points = np.array([[a[0] * width, a[1]], [b[0] * width, b[1]]])
    spec = loads_case(
        build.case_text(_case(E, nu, size, n, points, friction, stress)), "b.toml"
    )
    assert spec.material.E == E and spec.material.nu == nu
    assert tuple(spec.size) == (width, 1.0)
    assert len(spec.mesh.x) == n + 1 and len(spec.mesh.y) == n + 1
    np.testing.assert_array_equal(spec.fractures[0].points, points)
    assert spec.fractures[0].friction == friction
    assert tuple(spec.loading.stress) == tuple(float(v) for v in stress)


def test_numpy_values_tuples_and_paths_become_toml_values():
    doc = {
        "a": np.float32(0.1),
        "b": np.int64(7),
        "c": np.bool_(True),
        "d": (1.5, 2),
        "e": np.array([[1.0, 2.0], [3.0, 4.0]]),
        "f": Path("x") / "y.csv",
        "g": None,
    }
    back = tomllib.loads(build.case_text(doc))
    assert back == {
        "a": float(np.float32(0.1)),
        "b": 7,
        "c": True,
        "d": [1.5, 2],
        "e": [[1.0, 2.0], [3.0, 4.0]],
        "f": str(Path("x") / "y.csv"),
    }
    assert type(back["b"]) is int and type(back["a"]) is float


def test_with_keys_sets_and_removes_by_dotted_path_without_touching_the_original():
    case = _case(5e9, 0.3, [1.0, 1.0], 4, [[0.2, 0.2], [0.8, 0.8]], 0.1, (-1, -2, 0))
    changed = build.with_keys(
        case,
        **{
            "mesh.elements": [8, 8],
            "fractures.0.friction": 0.6,
            "loading.stress": None,
            "solver.tolerance": 1e-10,
        },
    )
    assert changed["mesh"]["elements"] == [8, 8]
    assert changed["fractures"][0]["friction"] == 0.6
    assert "stress" not in changed["loading"]
    assert changed["solver"] == {"tolerance": 1e-10}
    assert (
        case["mesh"]["elements"] == [4, 4] and case["fractures"][0]["friction"] == 0.1
    )
    assert "solver" not in case


def test_a_shipped_case_with_keys_set_loads_as_the_file_with_those_values(tmp_path):
    text = build.case_text(build.file_case(RESERVOIR, **{"mesh.elements": [12, 12]}))
    built = loads_case(text, tmp_path / "r.toml")
    shipped = load_case(RESERVOIR)
    assert len(built.mesh.x) == 13 and len(shipped.mesh.x) == 51
    assert built.material == shipped.material and built.loading == shipped.loading
    assert built.fractures[0].friction == shipped.fractures[0].friction
    np.testing.assert_array_equal(
        built.fractures[0].points, shipped.fractures[0].points
    )


@pytest.mark.parametrize(
    "doc, where",
    [
        ({"fractures": [{"points": [[0.0, 0.0], None]}]}, "fractures[0].points[1]"),
        ({"material": {"E": 1j}}, "material.E"),
        ({"loading": {"stress": object()}}, "loading.stress"),
    ],
)
def test_a_value_without_a_toml_form_names_its_key(doc, where):
    with pytest.raises(TypeError, match=rf"^{re.escape(where)}: .* has no TOML form"):
        build.case_text(doc)


def test_nan_is_written_and_refused_by_the_case_loader_with_its_key():
    case = _case(math.nan, 0.3, [1.0, 1.0], 4, [[0.2, 0.2], [0.8, 0.8]], 0.1, (0, 0, 0))
    text = build.case_text(case)
    assert "E = nan" in text
    with pytest.raises(CaseError) as err:
        loads_case(text, "nan.toml")
    assert "material.E: must be finite, got nan" in str(err.value)
