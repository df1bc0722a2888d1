"""The in-situ release problem: the OpenGeoSys peer crack (a = 1 m at 45
degrees, xfemslip.reference.peer) in a graded box of half-width HALF, as a
case document; shared by the in-situ and event-size verification tests."""

from __future__ import annotations

import math

from xfemslip.reference import peer

A, E, NU, F = peer.A, peer.E, peer.NU, peer.F
SIGMA0 = peer.STRESS  # (-20, -40, 0) MPa: |tau| = 10 MPa > f |sigma_n| = 3 MPa
HALF = 40.0  # half-width of the box [m]


def strain(stress):
    """Plane-strain (exx, eyy) of a uniform stress (xy = 0)."""
    sxx, syy, _ = stress
    exx = ((1 - NU**2) * sxx - NU * (1 + NU) * syy) / E
    eyy = ((1 - NU**2) * syy - NU * (1 + NU) * sxx) / E
    return exx, eyy


def rollers(stress=None):
    """Rollers on the four edges, imposing the uniform strain of ``stress``
    (None: no displacement)."""
    exx, eyy = strain(stress) if stress is not None else (0.0, 0.0)
    return {
        "bottom": {"uy": -HALF * eyy},
        "top": {"uy": HALF * eyy},
        "left": {"ux": -HALF * exx},
        "right": {"ux": HALF * exx},
    }


def crack_case(h, *, initial=None, stress=SIGMA0, boundary=None, steps=1, angle=45.0):
    """The peer crack on the graded mesh as a case document (dict)."""
    coords = [float(v) for v in peer.graded(h, half=HALF)]
    t = (math.cos(math.radians(angle)), math.sin(math.radians(angle)))
    loading = {"stress": dict(zip(("xx", "yy", "xy"), stress, strict=True))}
    if initial is not None:
        loading["initial_stress"] = dict(zip(("xx", "yy", "xy"), initial, strict=True))
    loading["steps"] = steps
    return {
        "name": "in-situ",
        "mesh": {"x": coords, "y": coords},
        "material": {"E": E, "nu": NU, "model": "plane_strain"},
        "fractures": [
            {
                "points": [[-A * t[0], -A * t[1]], [A * t[0], A * t[1]]],
                "friction": F,
                "cohesion": 0.0,
                "kn": peer.PENALTY,
                "kt": peer.PENALTY,
            }
        ],
        "loading": loading,
        "boundary": boundary if boundary is not None else rollers(),
        "output": {"formats": ["h5"]},
    }
