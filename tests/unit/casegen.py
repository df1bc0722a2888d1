"""A small one-fracture case shared by the unit tests (imported by basename)."""

from __future__ import annotations

from xfemslip.case import loads_case


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
