"""The rock at a point (fem/zones.py): zones of layers, displaced layers and
polygons, the weight of the rock above, the in-situ state and where the
loading jumps along a fault; each against values worked out by hand here."""

from __future__ import annotations

import math

import numpy as np
import pytest

from xfemslip.case import build, loads_case
from xfemslip.fem.zones import (
    build_zones,
    fluid_value,
    in_situ_stress,
    initial_pressure,
    loading_breaks,
    overburden,
)
from xfemslip.simulation import build_model

G = 9.81
TOP, BASE, THROW = -2900.0, -3100.0, 50.0


def _spec(units, fault=None, in_situ=None, pore=None):
    fault = fault or {
        "point": [1000.0, -3000.0],
        "dip": 60.0,
        "length": 900.0,
        "friction": 0.6,
    }
    case = {
        "mesh": {
            "x": [float(v) for v in np.linspace(0.0, 2000.0, 41)],
            "y": [float(v) for v in np.linspace(-3500.0, -2500.0, 41)],
        },
        "material": {"E": 20.0e9, "nu": 0.25, "density": 2500.0},
        "units": units,
        "fractures": [fault],
        "loading": {
            "initial_stress": in_situ
            or {"datum": 0.0, "gravity": G, "ratio_xx": "uniaxial_strain"},
            "steps": 1,
        },
        "pore_pressure": pore
        or {"initial": 0.0, "gradient": 1.0e4, "change": -20.0e6, "biot": 0.8},
        "boundary": {
            "left": {"ux": 0.0},
            "right": {"ux": 0.0},
            "bottom": {"uy": 0.0},
            "top": "traction",
        },
    }
    return loads_case(build.case_text(case), "zones.toml")


RESERVOIR = {
    "name": "reservoir",
    "top": TOP,
    "base": BASE,
    "E": 8.0e9,
    "nu": 0.2,
    "density": 2200.0,
    "biot": 0.9,
    "offset": {"fracture": 0, "throw": THROW},
}


def _fault_x(y):
    """x of the fault at height y: through (1000, -3000), dipping 60 degrees
    to the right."""
    return 1000.0 + (-3000.0 - np.asarray(y)) / math.tan(math.radians(60.0))


def test_zones_of_a_displaced_layer_follow_the_fault_exactly():
    """Footwall (left) between TOP and BASE, hanging wall (right) THROW lower;
    a point a micrometre either side of the fault takes its side."""
    z = build_zones(_spec([RESERVOIR]))
    assert z.names == ("host", "reservoir")
    y = np.array([-2960.0, -3120.0, -3130.0, -2920.0])
    eps = 1e-6
    left = np.column_stack([_fault_x(y) - eps, y])
    right = np.column_stack([_fault_x(y) + eps, y])
    np.testing.assert_array_equal(z.at(left), [1, 0, 0, 1])
    np.testing.assert_array_equal(z.at(right), [1, 1, 1, 0])


def test_compartments_and_later_units_override():
    units = [
        {"name": "cap", "top": -2700.0, "base": -2900.0, "E": 5e9},
        {**RESERVOIR, "change": {"left": -25e6, "right": -5e6}},
        {"name": "lens", "box": [100.0, -3000.0, 300.0, -2950.0]},
    ]
    pore = {"initial": 0.0, "gradient": 1.0e4, "change": -20.0e6, "region": "reservoir"}
    z = build_zones(_spec(units, pore=pore))
    assert z.names == ("host", "cap", "reservoir (left)", "reservoir (right)", "lens")
    np.testing.assert_array_equal(z.change, [0.0, 0.0, -25e6, -5e6, 0.0])
    # region = "all": every zone without its own change takes [pore_pressure]'s
    z = build_zones(_spec(units))
    np.testing.assert_array_equal(z.change, [-20e6, -20e6, -25e6, -5e6, -20e6])
    pts = [[200.0, -2975.0], [200.0, -2800.0], [1900.0, -3100.0], [150.0, -3050.0]]
    np.testing.assert_array_equal(z.at(np.array(pts)), [4, 1, 3, 2])


def test_overburden_integrates_the_densities_above_exactly():
    """On the footwall at x = 200: host to TOP, reservoir TOP..BASE, host
    below; on the hanging wall at x = 1900 the reservoir is THROW lower."""
    z = build_zones(_spec([RESERVOIR]))
    y = np.array([-2800.0, -3000.0, -3200.0])
    for x, top, base in ((200.0, TOP, BASE), (1900.0, TOP - THROW, BASE - THROW)):
        got = overburden(z, np.column_stack([np.full(3, x), y]), 0.0)
        want = []
        for v in y:
            res = max(0.0, min(top, 0.0) - max(base, v))  # reservoir above v
            want.append(2500.0 * (0.0 - v) + (2200.0 - 2500.0) * res)
        np.testing.assert_allclose(got, want, rtol=1e-13)
    # above the datum the integral is negative (the rock there is not above)
    got = overburden(z, np.array([[200.0, 100.0]]), 0.0)
    assert got[0] == pytest.approx(-2500.0 * 100.0, rel=1e-14)


def test_overburden_through_a_fault_crossing_column():
    """A column crossing the fault: above the fault it is on the hanging
    wall side (right of the fault line), below it on the footwall side."""
    z = build_zones(_spec([RESERVOIR]))
    x = 1030.0  # the fault passes x = 1030 at y = -3000 - 30 tan 60 = -3051.96
    y_f = -3000.0 - 30.0 * math.tan(math.radians(60.0))
    got = overburden(z, np.array([[x, -3300.0]]), 0.0)[0]
    # right of the fault above y_f: reservoir from TOP - THROW to y_f; left
    # below y_f: reservoir from y_f to BASE
    res = ((TOP - THROW) - y_f) + (y_f - BASE)
    assert got == pytest.approx(2500.0 * 3300.0 - 300.0 * res, rel=1e-13)


def test_in_situ_state_with_a_ratio_of_effective_stresses():
    """sigma'_xx = nu / (1 - nu) sigma'_yy with each zone's nu and alpha."""
    spec = _spec([RESERVOIR])
    z = build_zones(spec)
    xy = np.array([[200.0, -3000.0], [200.0, -3300.0]])
    zone = z.at(xy)
    p0 = initial_pressure(spec, z, xy, zone)
    np.testing.assert_allclose(p0, [3.0e7, 3.3e7], rtol=1e-15)
    s = in_situ_stress(spec, z, xy, zone)
    for k, (nu, alpha) in enumerate(((0.2, 0.9), (0.25, 0.8))):
        syy_eff = s[k, 1] + alpha * p0[k]
        sxx_eff = s[k, 0] + alpha * p0[k]
        assert sxx_eff == pytest.approx(nu / (1 - nu) * syy_eff, rel=1e-13)
    assert s[0, 1] == pytest.approx(-G * (2500.0 * 3000.0 - 300.0 * 100.0), rel=1e-13)
    np.testing.assert_array_equal(s[:, 2], 0.0)


def test_in_situ_state_with_gradients():
    stress = {
        "datum": -2500.0,
        "yy": -57.5e6,
        "gradient_yy": -23.0e3,
        "xx": -40.0e6,
        "gradient_xx": -16.0e3,
        "xy": 1.0e6,
    }
    spec = _spec([RESERVOIR], in_situ=stress)
    z = build_zones(spec)
    xy = np.array([[10.0, -2500.0], [10.0, -3500.0]])
    s = in_situ_stress(spec, z, xy, z.at(xy))
    np.testing.assert_allclose(
        s, [[-40.0e6, -57.5e6, 1.0e6], [-56.0e6, -80.5e6, 1.0e6]], rtol=1e-15
    )


def test_loading_jumps_at_the_four_corners_of_a_displaced_reservoir():
    """Patches and quadrature end where a face's zone changes along the
    fault: where the footwall's TOP and BASE and the hanging wall's TOP -
    THROW and BASE - THROW meet it."""
    model = build_model(_spec([RESERVOIR]))
    fr = model.fractures[0]
    eps = 1e-6 * model.mesh.h_min
    (breaks,) = loading_breaks(
        model.materials.zones, [fr], (0, 2000, -3500, -2500), eps
    )
    y_top = fr.points[0, 1]
    s_of_y = (y_top - np.array([TOP, TOP - THROW, BASE, BASE - THROW])) / math.sin(
        math.radians(60.0)
    )
    np.testing.assert_allclose(np.sort(breaks), np.sort(s_of_y), atol=1e-9)
    # no patch holds interface points on both sides of a corner
    ip, c = model.ip, model.contact
    for s in breaks:
        below = np.unique(c.patch[ip.s < s])
        above = np.unique(c.patch[ip.s > s])
        assert not set(below) & set(above)


def test_fluid_rules():
    plus, minus = np.array([10.0, 30.0]), np.array([20.0, 10.0])
    np.testing.assert_array_equal(fluid_value("mean", plus, minus), [15.0, 20.0])
    np.testing.assert_array_equal(fluid_value("higher", plus, minus), [20.0, 30.0])
    np.testing.assert_array_equal(fluid_value("lower", plus, minus), [10.0, 10.0])
    np.testing.assert_array_equal(fluid_value(7.0, plus, minus), [7.0, 7.0])


def test_fields_are_reached_in_turn():
    """m fields: field j at load factor j / m, linear between, none at 0."""
    from xfemslip.fem.poro import PorePressure

    z = np.zeros(1)
    p = PorePressure(1.0, 0.0, 1.0, 1.0, z, z, z, z, z, z, z, z)
    three = type(p)(**{**p.__dict__, "later": (p, p)})
    np.testing.assert_allclose(three.weights(0.0), [0, 0, 0])
    np.testing.assert_allclose(three.weights(1 / 6), [0.5, 0, 0])
    np.testing.assert_allclose(three.weights(0.5), [0.5, 0.5, 0])
    np.testing.assert_allclose(three.weights(1.0), [0, 0, 1])
    assert p.weights(0.3)[0] == 0.3
