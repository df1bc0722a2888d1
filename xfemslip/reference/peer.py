"""The OpenGeoSys peer problem (../shared/peers/ogs/ogs_lie_slip.py) as an
xfemslip case: one case writer for benchmarks/ogs_compare.py,
benchmarks/slip_convergence.py and tests/verification/test_slip_convergence.py.

A crack of half-length A = 1 m at PSI = 45 degrees through the centre of a
square box of half-width ``half``, remote stress STRESS as edge tractions
(bottom edge a roller that also carries the x traction: a case needs one
prescribed displacement, where OGS pins two corners), f = 0.1, c = 0,
kn = kt = 5e12 Pa/m, E = 5 GPa, nu = 0.3, plane strain, one load step.  The
mesh is rectilinear: cells of size h on [-fine, fine]^2 (the crack and a
margin), growing by ``growth`` per cell to the edges.  Reference:
closed_form.slip_profile (the infinite plane; a finite traction box is
softer, by about +0.55 % of the slip at half = 10 m, falling like
(A / half)^2: docs/performance.md, "Slip convergence on the OpenGeoSys
peer problem").
"""

from __future__ import annotations

import math

import numpy as np

from xfemslip.reference.closed_form import relative_l2, slip_profile

A, E, NU, F, PSI = 1.0, 5.0e9, 0.3, 0.1, 45.0
STRESS = (-20.0e6, -40.0e6, 0.0)
PENALTY = 5.0e12  # kn = kt [Pa/m]


def graded(h, fine=0.8, half=10.0, growth=1.3) -> np.ndarray:
    """Node coordinates: uniform h on [-fine, fine], then cells growing by
    ``growth`` to +-half (the last one merged if it would be under half a
    step)."""
    n = max(1, round(2 * fine / h))
    core = np.linspace(-fine, fine, n + 1)
    outer = []
    x, step = fine, core[1] - core[0]
    while x < half - 1e-9:
        step = step * growth
        x = min(half, x + step)
        if half - x < 0.5 * step:
            x = half
        outer.append(x)
    ring = np.array(outer)
    return np.concatenate([-ring[::-1], core, ring])


def case_table(
    h, *, half=10.0, fine=0.8, growth=1.3, radius=None, tip=None, kn=PENALTY
) -> dict:
    """The case on graded(h, fine, half, growth) as the tables of its file
    (``xfemslip.case.build.case_text`` writes it); ``radius`` fixes the branch
    radius [m] (None: automatic), or ``tip`` names the tip kind; ``kn`` is
    both penalties [Pa/m].  Mesh lines are rounded to 12 significant digits."""
    coords = [float(f"{v:.12g}") for v in graded(h, fine, half, growth)]
    t = (math.cos(math.radians(PSI)), math.sin(math.radians(PSI)))
    if radius is not None:
        tip = {"kind": "branch", "radius": radius}
    return {
        "name": "ogs-peer",
        "mesh": {"x": coords, "y": coords},
        "material": {"E": E, "nu": NU, "model": "plane_strain"},
        "fractures": [
            {
                "points": [[-A * t[0], -A * t[1]], [A * t[0], A * t[1]]],
                "friction": F,
                "cohesion": 0.0,
                "tip": tip,
                "kn": kn,
                "kt": kn,
            }
        ],
        "loading": {"stress": {"xx": STRESS[0], "yy": STRESS[1], "xy": 0.0}},
        "boundary": {
            "bottom": {"uy": 0.0, "traction": True},
            "top": "traction",
            "left": "traction",
            "right": "traction",
        },
    }


def slip_error(s, slip, stress=STRESS, psi=PSI) -> float:
    """Relative L2 error of the slip (its sign as the exact one's) at arc
    lengths s against the closed form."""
    exact = slip_profile(s, A, E, NU, "plane_strain", stress, psi, F)
    sign = np.sign(np.sum(slip * exact)) or 1.0
    return relative_l2(s, sign * slip, exact)
