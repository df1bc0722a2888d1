"""Quantities with units in a case file ("25 MPa", "3 km", "23 MPa/km"):
converted to the key's unit against hand values, refused at a key of another
dimension (one line, exit 2), and giving bitwise the case written in SI."""

from __future__ import annotations

import dataclasses
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from xfemslip.case import build, load_case, loads_case
from xfemslip.case.quantities import DIMENSIONS, KEY_DIMENSIONS, quantity
from xfemslip.cli import cli
from xfemslip.errors import CaseError
from xfemslip.simulation import run_case

ROOT = Path(__file__).resolve().parents[3]
CASES = ROOT / "cases"


@pytest.mark.parametrize(
    ("text", "dimension", "value"),
    [
        ("25 MPa", "pressure", 25.0e6),
        ("-25 MPa", "pressure", -25.0e6),
        ("-0.6 MPa", "pressure", -6.0e5),
        ("100 bar", "pressure", 1.0e7),
        ("20 GPa", "modulus", 20.0e9),
        ("3 km", "length", 3000.0),
        ("-2.85 km", "length", -2850.0),
        ("5 mm", "length", 0.005),
        ("1.2e-3 m", "length", 0.0012),
        ("23 MPa/km", "pressure gradient", 23.0e3),
        ("-16.1 MPa/km", "pressure gradient", -16.1e3),
        ("1 psi/ft", "pressure gradient", 6894.757293168361 / 0.3048),
        ("5e12 Pa/m", "stiffness", 5.0e12),
        ("30 deg", "angle", 30.0),
        ("0.5 rad", "angle", 0.5 * 180.0 / np.pi),
        ("60 %", "dimensionless", 0.6),
        ("2.4 g/cm^3", "density", 2400.0),
        ("9.81 m/s^2", "acceleration", 9.81),
        ("1e-15 m^2", "area", 1.0e-15),
    ],
)
def test_conversion_to_the_unit_of_the_key(text, dimension, value):
    """Each value as a hand conversion (1 psi = 6894.757... Pa, 1 ft = 0.3048
    m exactly); decimal factors give the double the SI literal gives."""
    got, why = quantity(text, dimension)
    assert why is None
    if "psi" in text or "rad" in text:
        assert got == pytest.approx(value, rel=1e-15)
    else:
        assert got == value  # bitwise: "5 mm" is the double 0.005


@pytest.mark.parametrize(
    ("text", "dimension", "said"),
    [
        ("3 km", "pressure", "a length"),
        ("25 MPa", "length", "a pressure"),
        ("25 MPa", "pressure gradient", "a pressure"),
        ("30 deg", "dimensionless", "an angle"),
        ("0.6", "angle", "expected a number, or a string with a unit"),
        ("3 MPa", "angle", "a pressure"),
        ("3 kmm", "length", "'kmm' is not defined"),
        ("3 MPa 4", "pressure", "scaling factor"),
    ],
)
def test_wrong_dimension_refused(text, dimension, said):
    got, why = quantity(text, dimension)
    assert got is None
    assert why.startswith("expected ")
    assert DIMENSIONS[dimension].example in why and said in why


def test_every_key_names_a_known_dimension():
    assert set(KEY_DIMENSIONS.values()) <= set(DIMENSIONS)


def _with_units(path: Path, **dotted) -> str:
    return build.case_text(build.file_case(path, **dotted))


def _same(a, b, where="spec"):
    """Two specs equal field for field, arrays bitwise (the text aside)."""
    if dataclasses.is_dataclass(a):
        assert type(a) is type(b), where
        for f in dataclasses.fields(a):
            if f.name not in ("text", "path"):
                _same(getattr(a, f.name), getattr(b, f.name), f"{where}.{f.name}")
    elif isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and np.array_equal(a, b, equal_nan=True), where
    elif isinstance(a, tuple | list):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _same(x, y, f"{where}[{i}]")
    elif isinstance(a, dict):
        assert a.keys() == b.keys(), where
        for k in a:
            _same(a[k], b[k], f"{where}.{k}")
    else:
        assert a == b and type(a) is type(b), where


FIELD_SECTION_UNITS = {
    "domain.size": ["2 km", "1 km"],
    "domain.origin": ["0 m", "-3.5 km"],
    "mesh.size": "10 m",
    "mesh.max_size": "100 m",
    "material.E": "20 GPa",
    "units.0.top": "-2.85 km",
    "units.0.base": "-2900 m",
    "units.0.E": "25 GPa",
    "units.0.offset.throw": "50 m",
    "units.1.top": "-2.9 km",
    "units.1.base": "-3.1 km",
    "units.1.E": "10 GPa",
    "units.1.biot": "90 %",
    "pore_pressure.gradient": "10 MPa/km",
    "pore_pressure.change": "-25 MPa",
    "fractures.0.point": ["1 km", "-3 km"],
    "fractures.0.dip": "60 deg",
    "fractures.0.top": "-2.6 km",
    "fractures.0.base": "-3.4 km",
    "loading.initial_stress.gradient_yy": "-23 MPa/km",
    "loading.initial_stress.gradient_xx": "-16.1 MPa/km",
}


def test_shipped_case_with_units_reads_bitwise_as_in_si():
    """cases/field_section.toml with every quantity written with units is
    the same CaseSpec, double for double (graded mesh included)."""
    si = load_case(CASES / "field_section.toml")
    text = _with_units(CASES / "field_section.toml", **FIELD_SECTION_UNITS)
    assert text.count(' km"') >= 8  # the rewrite did write unit strings
    units = loads_case(text, CASES / "field_section.toml")
    _same(si, units)


def test_shipped_case_with_units_runs_bitwise_as_in_si():
    """cases/reservoir_depletion.toml with units gives the same fields."""
    path = CASES / "reservoir_depletion.toml"
    text = _with_units(
        path,
        **{
            "domain.size": ["1 m", "1000 mm"],
            "material.E": "5 GPa",
            "fractures.0.center": ["50 cm", "0.5 m"],
            "fractures.0.length": "600 mm",
            "fractures.0.angle": "45 deg",
            "fractures.0.kn": "5e12 Pa/m",
            "fractures.0.kt": "5000 GPa/m",
            "loading.stress": {"xx": "-20 MPa", "yy": "-40 MPa", "xy": "0 Pa"},
        },
    )
    a = run_case(load_case(path))
    b = run_case(loads_case(text, path))
    assert b.converged and a.load_steps == b.load_steps
    assert np.array_equal(a.displacement, b.displacement)
    assert np.array_equal(a.stress, b.stress)
    for fa, fb in zip(a.fractures, b.fractures, strict=True):
        for name in ("slip", "opening", "normal_traction", "shear_traction", "state"):
            assert np.array_equal(getattr(fa, name), getattr(fb, name)), name
    assert abs(a.fractures[0].slip).max() > 0  # the case slips: a real comparison


def test_wrong_dimension_is_one_line_naming_file_and_key(tmp_path):
    """'3 km' for a stress: exit 2, one line with the file, the key and what
    was expected; nothing written."""
    path = tmp_path / "bad.toml"
    path.write_text(
        _with_units(
            CASES / "reservoir_depletion.toml",
            **{"loading.stress.xx": "3 km", "output.directory": str(tmp_path / "o")},
        )
    )
    result = CliRunner().invoke(cli, ["run", str(path)])
    assert result.exit_code == 2
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert str(path) in lines[0] and "loading.stress.xx" in lines[0]
    assert re.search(r"expected a pressure such as \"25 MPa\".*\(a length\)", lines[0])
    assert not (tmp_path / "o").exists()


def test_wrong_unit_and_other_problems_each_told_once():
    text = _with_units(
        CASES / "reservoir_depletion.toml",
        **{"material.E": "20 km", "material.nu": 0.7},
    )
    with pytest.raises(CaseError) as err:
        loads_case(text, "x.toml")
    keys = [k for k, _ in err.value.problems]
    assert keys == ["material.E", "material.nu"]


def test_words_at_quantity_keys_stay_words():
    """A fracture's fluid pressure "higher" is not a quantity; it still reads."""
    text = _with_units(
        CASES / "depleting_reservoir.toml",
        **{
            "fractures.0.fluid_pressure": "higher",
            "fractures.1.fluid_pressure": "3 MPa",
        },
    )
    spec = loads_case(text, CASES / "depleting_reservoir.toml")
    assert spec.fractures[0].fluid_pressure == "higher"
    assert spec.fractures[1].fluid_pressure == 3.0e6


def test_case_without_unit_strings_does_not_import_pint():
    code = (
        "import sys; from xfemslip.case import load_case;"
        f"load_case({str(CASES / 'field_section.toml')!r});"
        "print('pint' in sys.modules)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    )
    assert out.stdout.strip() == "False"
