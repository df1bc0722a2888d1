"""Numbers as the terminal prints them (xfemslip.display): engineering units
against hand conversions, the sign conventions, aligned tables."""

from __future__ import annotations

import pytest

from xfemslip import display


@pytest.mark.parametrize(
    ("function", "value", "text"),
    [
        (display.stress, -13.7109e6, "-13.7109 MPa"),
        (display.pressure, 30.0e6, "30 MPa"),
        (display.pressure_change, -25.0e6, "-25 MPa"),
        (display.modulus, 2.0e10, "20 GPa"),
        (display.gradient, -23.0e3, "-23 MPa/km"),
        (display.length, 3500.0, "3500 m"),
        (display.length, 12500.0, "12.5 km"),
        (display.slip, 1.5e-4, "0.15 mm"),
        (display.stress, -0.0, "0 MPa"),
    ],
)
def test_engineering_units(function, value, text):
    assert function(value) == text


def test_compression_positive_turns_stresses_not_pressures():
    assert display.stress(-20.0e6, compression_positive=True) == "20 MPa"
    assert display.gradient(-23.0e3, compression_positive=True) == "23 MPa/km"
    assert display.pressure_change(-25.0e6, compression_positive=True) == "25 MPa"
    assert display.pressure(30.0e6) == "30 MPa"  # a pressure either way
    assert display.change_label(True) == "depletion"
    assert display.change_label(False) == "dp"
    assert "tension positive" in display.convention(False)
    assert "compression positive" in display.convention(True)


def test_table_aligns_right_and_keeps_brackets():
    text = display.table(
        ["fracture", "dp [MPa]", "bracket [MPa]"],
        [["0", "-13.7", "[-13.8, -13.7]"], ["12", "no slip", ""]],
    )
    lines = text.splitlines()
    assert lines[0] == "fracture  dp [MPa]   bracket [MPa]"
    assert lines[1] == "       0     -13.7  [-13.8, -13.7]"
    assert lines[2] == "      12   no slip"
    # every column ends where its header ends
    assert all(not ln.endswith(" ") for ln in lines)
