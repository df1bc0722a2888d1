"""``[permeability]`` and a fracture's ``hydraulic`` table: the aperture law
of each fracture and the block of the permeability tensor."""

from __future__ import annotations

import math

import pytest
from click.testing import CliRunner

from tests.unit.case.test_case import base, error_of, messages, write
from xfemslip.case import describe, load_case
from xfemslip.case.specs import HydraulicSpec
from xfemslip.cli import cli

# BASE: domain [1, 3] x [-1, 0], one fracture from (1.5, -0.5) to (2.5, -0.5)
SECOND = {"points": [[1.2, -0.8], [1.8, -0.2]], "friction": 0.6}


def _doc(permeability=None, **fracture_keys):
    doc = base()
    doc["fractures"][0].update(fracture_keys)
    doc["fractures"].append(dict(SECOND))
    if permeability is not None:
        doc["permeability"] = permeability
    return doc


def test_without_the_table_nothing_hydraulic_is_read(tmp_path):
    spec = load_case(write(tmp_path, _doc()))
    assert spec.permeability is None
    assert all(f.hydraulic is None for f in spec.fractures)
    assert "permeability" not in describe(spec)


def test_defaults_fill_every_fracture_and_the_block_is_the_domain(tmp_path):
    spec = load_case(write(tmp_path, _doc({"aperture": 2.0e-4})))
    p = spec.permeability
    assert p.block == (1.0, -1.0, 3.0, 0.0) and not p.block_given
    assert p.matrix == 0.0
    law = HydraulicSpec(
        aperture=2.0e-4,
        dilation_angle=0.0,
        dilation_slip=math.inf,
        max_closure=0.0,
        normal_stiffness=math.inf,
    )
    assert p.laws == (law, law)


def test_a_fracture_overrides_the_defaults_key_by_key(tmp_path):
    doc = _doc(
        {
            "aperture": 1.0e-4,
            "dilation_angle": 3.0,
            "max_closure": 4.0e-5,
            "normal_stiffness": 2.0e10,
            "matrix": 1.0e-17,
            "block": [1.5, -0.9, 2.5, -0.1],
        },
        hydraulic={"aperture": 3.0e-4, "dilation_slip": 2.0e-3},
    )
    spec = load_case(write(tmp_path, doc))
    first, second = spec.permeability.laws
    assert first == HydraulicSpec(
        aperture=3.0e-4,
        dilation_angle=3.0,
        dilation_slip=2.0e-3,
        max_closure=4.0e-5,
        normal_stiffness=2.0e10,
    )
    assert second.aperture == 1.0e-4 and second.dilation_slip == math.inf
    assert spec.permeability.block == (1.5, -0.9, 2.5, -0.1)
    assert spec.permeability.matrix == 1.0e-17
    result = CliRunner().invoke(cli, ["check", str(write(tmp_path, doc, "c.toml"))])
    assert result.exit_code == 0, result.output
    assert (
        "permeability: Oda tensor of the block [1.5, 2.5] x [-0.9, -0.1] m, "
        "matrix 1e-17 m^2" in result.output
    )
    assert (
        "fracture 0: aperture = 0.0003 m, dilation_angle = 3 deg (up to 0.002 m)"
        in (result.output)
    )
    assert "fracture 1: aperture = 0.0001 m" in result.output


def test_the_network_hydraulic_table_applies_to_its_fractures(tmp_path):
    (tmp_path / "seg.csv").write_text("x0,y0,x1,y1\n1.1,-0.3,2.9,-0.3\n")
    doc = base()
    doc["network"] = {
        "file": "seg.csv",
        "friction": 0.5,
        "hydraulic": {"dilation_angle": 7.0},
    }
    doc["permeability"] = {"aperture": 1.0e-4}
    spec = load_case(write(tmp_path, doc))
    inline, network = spec.permeability.laws
    assert inline.dilation_angle == 0.0 and network.dilation_angle == 7.0


@pytest.mark.parametrize(
    ("permeability", "hydraulic", "key", "words"),
    [
        (
            {"aperture": 0.0},
            None,
            "permeability.aperture",
            "1e-09 <= aperture <= 1, got 0.0",
        ),
        (
            {"aperture": 1e-110},
            None,
            "permeability.aperture",
            "1e-09 <= aperture <= 1, got 1e-110",
        ),
        (
            {"aperture": 1e110},
            None,
            "permeability.aperture",
            "1e-09 <= aperture <= 1, got 1e+110",
        ),
        (
            {"aperture": 1e-4},
            {"aperture": 2.0},
            "fractures[0].hydraulic.aperture",
            "1e-09 <= aperture <= 1",
        ),
        (
            {"aperture": 1e-4, "max_closure": 1e-4, "normal_stiffness": 5e-324},
            None,
            "permeability.normal_stiffness",
            "1000 <= normal_stiffness <= 1e+16",
        ),
        (
            {"aperture": 1e-4, "matrix": 1e300},
            None,
            "permeability.matrix",
            "0 <= matrix <= 1e-06",
        ),
        (
            {"aperture": 1e-4, "block": [1.0, -1.0, 1.4, -0.5]},
            None,
            "permeability.block",
            "at least one cell of the mesh wide and high (0.5 x 0.5 m), got 0.4",
        ),
        (
            {"aperture": 1e-4, "dilation_angle": 90.0},
            None,
            "permeability.dilation_angle",
            "0 <= dilation_angle < 90",
        ),
        (
            {"aperture": 1e-4, "dilation_angle": -1.0},
            None,
            "permeability.dilation_angle",
            "0 <= dilation_angle < 90",
        ),
        (
            {"aperture": 1e-4, "dilation_slip": 0.0},
            None,
            "permeability.dilation_slip",
            "must be > 0",
        ),
        (
            {"aperture": 1e-4, "matrix": -1e-18},
            None,
            "permeability.matrix",
            "0 <= matrix <= 1e-06, got -1e-18",
        ),
        (
            {"aperture": 1e-4, "max_closure": 2e-4, "normal_stiffness": 1e10},
            None,
            "permeability.max_closure",
            "must be <= the aperture",
        ),
        (
            {"aperture": 1e-4},
            {"max_closure": 2e-4, "normal_stiffness": 1e10},
            "fractures[0].hydraulic.max_closure",
            "must be <= the aperture",
        ),
        (
            {"aperture": 1e-4, "max_closure": 5e-5},
            None,
            "permeability.max_closure",
            "needs normal_stiffness",
        ),
        (
            {"dilation_angle": 5.0},
            None,
            "permeability.aperture",
            "fracture 0 has no aperture",
        ),
        (
            {"aperture": 1e-4, "block": [1.0, -1.0, 3.5, 0.0]},
            None,
            "permeability.block",
            "must lie inside the domain",
        ),
        (
            {"aperture": 1e-4, "block": [2.0, -1.0, 1.5, 0.0]},
            None,
            "permeability.block",
            "x0 < x1",
        ),
        (
            {"aperture": 1e-4, "apperture": 1e-4},
            None,
            "permeability.apperture",
            "did you mean 'aperture'",
        ),
        (
            {"aperture": 1e-4},
            {"friction": 0.3},
            "fractures[0].hydraulic.friction",
            "unknown key",
        ),
        (
            None,
            {"aperture": 1e-4},
            "fractures[0].hydraulic",
            "needs a [permeability] table",
        ),
    ],
)
def test_bad_keys_name_the_key_and_exit_2(
    tmp_path, permeability, hydraulic, key, words
):
    extra = {"hydraulic": hydraulic} if hydraulic is not None else {}
    doc = _doc(permeability, **extra)
    assert words in messages(error_of(tmp_path, doc), key)
    result = CliRunner().invoke(cli, ["check", str(write(tmp_path, doc, "b.toml"))])
    assert result.exit_code == 2
    assert key in result.output
