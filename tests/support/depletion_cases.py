"""Case texts of the depletion verification tests (test_depletion.py)."""

from __future__ import annotations

import numpy as np

from xfemslip.case import build


def graded_axis(lo, hi, h, far_lo, far_hi, ratio=1.3):
    """Nodes: uniform h on [lo, hi], growing by ``ratio`` out to far_lo / far_hi."""
    core = np.linspace(lo, hi, int(round((hi - lo) / h)) + 1)
    right, step, x = [], h, hi
    while x < far_hi:
        step *= ratio
        x = min(x + step, far_hi)
        if far_hi - x < 0.5 * step:
            x = far_hi
        right.append(x)
    left, step, x = [], h, lo
    while x > far_lo:
        step *= ratio
        x = max(x - step, far_lo)
        if x - far_lo < 0.5 * step:
            x = far_lo
        left.append(x)
    return np.concatenate([left[::-1], core, right])


def offset_fault_case(
    *,
    h=5.0,
    thickness=100.0,
    throw=30.0,
    far=3000.0,
    friction=0.0,
    cohesion=0.0,
    dp=-10.0e6,
    E=10.0e9,
    nu=0.25,
    fault_half_length=300.0,
    steps=1,
    on_boundary=True,
):
    """Vertical fault through an offset reservoir (Jansen & Meulenbroek 2022).

    Left reservoir a < y < b for x < 0, right c < y < d for x > 0 (c = a +
    throw); both reach the rollers at x = +-far (laterally infinite).  The
    fault runs ON the pressure boundary x = 0, in the middle of a column of
    cells (mesh lines at x = +-h/2): the XFEM cut is mid-cell and the cut cells
    are split between the two reservoirs per quadrature point (xfemslip.fem.poro).
    ``on_boundary=False``: the former set-up, mesh line at x = 0 and the fault
    half a cell off it at x = h / 2.  Homogeneous rock; in-situ stress -30 MPa
    isotropic, p0 = 10 MPa.  Returns (text, (a, b, c, d), x_fault).
    """
    a, b = -thickness / 2.0, thickness / 2.0
    c, d = a + throw, b + throw
    shift = h / 2.0 if on_boundary else 0.0
    x = graded_axis(-20 * h - shift, 20 * h + shift, h, -far, far)
    y = graded_axis(a - 2.5 * thickness, d + 2.5 * thickness, h, -far, far)
    xf = 0.0 if on_boundary else h / 2.0
    text = build.case_text(
        {
            "mesh": {"x": [float(v) for v in x], "y": [float(v) for v in y]},
            "material": {"E": E, "nu": nu},
            "reservoir": {
                "boxes": [[-far, a, 0.0, b], [0.0, c, far, d]],
                "E": E,
                "nu": nu,
            },
            "pore_pressure": {
                "initial": 10.0e6,
                "change": dp,
                "region": "reservoir",
            },
            "fractures": [
                {
                    "points": [
                        [xf, -fault_half_length],
                        [xf, fault_half_length + throw],
                    ],
                    "friction": friction,
                    "cohesion": cohesion,
                }
            ],
            "loading": {
                "initial_stress": {"xx": -30.0e6, "yy": -30.0e6},
                "stress": {"xx": -30.0e6, "yy": -30.0e6},
                "steps": steps,
            },
            "boundary": {
                "left": {"ux": 0.0},
                "right": {"ux": 0.0},
                "bottom": {"uy": 0.0},
                "top": "traction",
            },
            "output": {"formats": ["h5"]},
        }
    )
    return text, (a, b, c, d), xf
