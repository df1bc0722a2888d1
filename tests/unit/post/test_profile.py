"""Profiles along the fractures: the Coulomb utilisation against hand
values, profile.csv against the fields it comes from, the arrays ParaView
gets, and the units on each face."""

from __future__ import annotations

import csv
import math

import meshio
import numpy as np
import pytest

from tests.support.golden import ROOT
from xfemslip import load_case, read_result, run_case
from xfemslip.case import build, loads_case
from xfemslip.conventions import OPEN, SLIP, STICK
from xfemslip.post.fields import coulomb_utilisation
from xfemslip.post.profile import PROFILE_COLUMNS, profile_rows


def test_utilisation_by_hand():
    pn = np.array([-10.0e6, -10.0e6, 5.0e6, -10.0e6, 0.0])
    pt = np.array([3.0e6, -7.0e6, 0.0, 0.0, 1.0e6])
    state = np.array([STICK, SLIP, OPEN, STICK, STICK])
    got = coulomb_utilisation(pn, pt, state, 0.6, 1.0e6)
    np.testing.assert_allclose(got, [3.0 / 7.0, 1.0, 1.0, 0.0, 1.0], rtol=1e-15)
    # no strength and no shear: nothing used
    assert (
        coulomb_utilisation(np.array([0.0]), np.array([0.0]), [STICK], 0.6, 0.0)[0] == 0
    )


@pytest.fixture(scope="module")
def depleted(tmp_path_factory):
    out = tmp_path_factory.mktemp("dep") / "run"
    spec = load_case(ROOT / "cases" / "depleting_reservoir.toml")
    result = run_case(spec, out)
    return spec, result, out


def test_in_situ_utilisation_is_the_in_situ_coulomb_ratio(depleted):
    """Uniform in-situ stress (-44, -62) MPa, p0 = 30 MPa, f = 0.5: on a
    plane at 60 degrees |tau| / (f (-sigma_n - p0))."""
    spec, result, _ = depleted
    th = math.radians(60.0)
    t, n = (
        np.array([math.cos(th), math.sin(th)]),
        np.array([-math.sin(th), math.cos(th)]),
    )
    S = np.array([[-44.0e6, 0.0], [0.0, -62.0e6]])
    want = abs(t @ S @ n) / (0.5 * -(n @ S @ n + 30.0e6))
    prop = result.fracture_properties[0]
    np.testing.assert_allclose(prop.in_situ_utilisation, want, rtol=1e-9)
    np.testing.assert_allclose(
        prop.in_situ_normal_traction, n @ S @ n + 30e6, rtol=1e-9
    )


def test_profile_csv_is_the_fields(depleted):
    spec, result, out = depleted
    with open(out / "profile.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    assert tuple(rows[0]) == PROFILE_COLUMNS
    col = {name: k for k, name in enumerate(PROFILE_COLUMNS)}
    last = [r for r in rows[1:] if int(r[col["step"]]) == len(result.steps)]
    ff = result.steps[-1].fractures[0]
    mine = [r for r in last if r[col["fracture"]] == "0"]
    np.testing.assert_array_equal([float(r[col["slip_m"]]) for r in mine], ff.slid)
    np.testing.assert_array_equal(
        [float(r[col["utilisation"]]) for r in mine], ff.utilisation
    )
    slipping = ff.state == SLIP
    assert slipping.any() and np.all(ff.utilisation[slipping] == 1.0)
    # the change adds up from the in-situ state to the last step
    total = np.zeros(ff.s.size)
    for step in range(1, len(result.steps) + 1):
        rs = [r for r in rows[1:] if int(r[col["step"]]) == step and r[2] == "0"]
        total += [float(r[col["utilisation_change"]]) for r in rs]
    prop = result.fracture_properties[0]
    np.testing.assert_allclose(
        prop.in_situ_utilisation + total, ff.utilisation, atol=1e-12
    )
    # the same rows from the written result.h5
    again = list(profile_rows(read_result(out / "result.h5")))
    assert len(again) == len(rows) - 1
    assert [str(v) for v in again[0]] == rows[1]
    # units on the faces: fracture 1 crosses the reservoir top
    units = {
        (r[col["unit_plus"]], r[col["unit_minus"]]) for r in rows[1:] if r[2] == "1"
    }
    assert units == {("reservoir", "reservoir"), ("host", "host")}


def test_fractures_vtu_has_the_fluid_pressure_and_utilisation(depleted):
    _, result, out = depleted
    mesh = meshio.read(out / "fractures.vtu")
    ff = result.fractures
    for name in ("fluid_pressure", "effective_normal_traction", "utilisation"):
        got = mesh.point_data[name]
        want = np.concatenate([getattr(f, name) for f in ff])
        np.testing.assert_allclose(np.sort(got), np.sort(want), rtol=1e-15)


def test_depth_column_below_the_datum(tmp_path):
    text = build.case_text(
        {
            "mesh": {
                "x": [float(v) for v in np.linspace(0, 200, 11)],
                "y": [float(v) for v in np.linspace(-3100, -2900, 11)],
            },
            "material": {"E": 20e9, "nu": 0.25},
            "fractures": [
                {
                    "point": [100.0, -3000.0],
                    "dip": 60.0,
                    "length": 100.0,
                    "friction": 0.6,
                }
            ],
            "loading": {
                "initial_stress": {"datum": 0.0, "gradient_yy": -23e3, "ratio_xx": 0.7},
                "steps": 1,
            },
            "pore_pressure": {"initial": 0.0, "gradient": 1e4, "change": -5e6},
            "boundary": {
                "left": {"ux": 0.0},
                "right": {"ux": 0.0},
                "bottom": {"uy": 0.0},
                "top": "traction",
            },
        }
    )
    result = run_case(loads_case(text, tmp_path / "d.toml"))
    rows = list(profile_rows(result))
    k = PROFILE_COLUMNS.index
    for r in rows:
        assert r[k("depth_m")] == pytest.approx(-r[k("y_m")], rel=1e-15)
