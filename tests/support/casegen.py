"""Small cases shared by the unit tests and the benchmarks (tests.support)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from xfemslip.case import FractureSpec, build, loads_case


def fracture_case(points, tip="ramp", n=6, size=6.0, friction=0.5):
    """Square of side ``size`` on n x n cells, one fracture, bottom fixed,
    top loaded by sigma = (-20, -40, 0) MPa; E = 10 GPa, nu = 0.3, friction
    f (default 0.5)."""
    return loads_case(
        build.case_text(
            {
                "domain": {"size": [size, size]},
                "mesh": {"elements": [n, n]},
                "material": {"E": 10.0e9, "nu": 0.3, "model": "plane_strain"},
                "fractures": [
                    {
                        "points": points,
                        "friction": friction,
                        "kn": 1.0e12,
                        "kt": 1.0e12,
                        "tip": tip,
                    }
                ],
                "loading": {"stress": build.stress_table((-20.0e6, -40.0e6, 0.0))},
                "boundary": {"bottom": {"ux": 0.0, "uy": 0.0}, "top": "traction"},
            }
        )
    )


def fracture_spec(points, index=0, tip="ramp", friction=0.5) -> FractureSpec:
    """A FractureSpec with penalties 1e12 Pa/m, no cohesion, automatic tip radius
    (for tests that build fractures without a case file)."""
    return FractureSpec(
        index=index,
        points=np.asarray(points, dtype=float),
        friction=friction,
        cohesion=0.0,
        kn=1.0e12,
        kt=1.0e12,
        tip=tip,
        tip_radius=None,
    )


SHIPPED_DFN = Path(__file__).resolve().parents[2] / "cases/sweeps/dfn_realizations.toml"


def sweep_member(path=SHIPPED_DFN, index=0, **keys) -> str:
    """TOML text of case ``index`` of a sweep file as `xfemslip sweep` makes
    it, with dotted key paths set on top (``**{"mesh.elements": [100, 100]}``):
    the shipped DFN realizations at other sizes without a copy of the file."""
    import tomllib

    from xfemslip.studies.sweep import load_sweep, parse_key_path, set_key_path

    document = tomllib.loads(load_sweep(path).cases[index].text)
    for key, value in keys.items():
        message = set_key_path(document, parse_key_path(key), value)
        assert message is None, message
    return build.case_text(document)


# A small, fast case: 10 x 10 cells, a 45-degree fracture that slips (f = 0.1).
SWEEP_CASE = {
    "name": "tiny",
    "domain": {"size": [1.0, 1.0]},
    "mesh": {"elements": [10, 10]},
    "material": {"E": 5.0e9, "nu": 0.3},
    "fractures": [
        {
            "center": [0.5, 0.5],
            "length": 0.6,
            "angle": 45.0,
            "friction": 0.1,
            "kn": 5.0e12,
            "kt": 5.0e12,
        }
    ],
    "loading": {"stress": {"xx": -20.0e6, "yy": -40.0e6, "xy": 0.0}},
    "boundary": {
        "bottom": {"uy": 0.0},
        "top": "traction",
        "left": "traction",
        "right": "traction",
    },
    "output": {"formats": ["h5"]},
}
SWEEP_BASE = build.case_text(SWEEP_CASE)
