"""A small one-fracture case shared by the unit tests (imported by basename)."""

from __future__ import annotations

import numpy as np

from xfemslip.case import FractureSpec, loads_case


def fracture_case(points, tip="ramp", n=6, size=6.0):
    """Square of side ``size`` on n x n cells, one fracture, bottom fixed,
    top loaded by sigma = (-20, -40, 0) MPa; E = 10 GPa, nu = 0.3, f = 0.5."""
    return loads_case(f"""
[domain]
size = [{size!r}, {size!r}]
[mesh]
elements = [{n}, {n}]
[material]
E = 10.0e9
nu = 0.3
model = "plane_strain"
[[fractures]]
points = {points!r}
friction = 0.5
kn = 1.0e12
kt = 1.0e12
tip = "{tip}"
[loading]
stress = {{ xx = -20.0e6, yy = -40.0e6, xy = 0.0 }}
[boundary]
bottom = {{ ux = 0.0, uy = 0.0 }}
top = "traction"
""")


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
