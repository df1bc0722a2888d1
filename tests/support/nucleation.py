"""The Uenishi & Rice (2003) nucleation problem as an xfemslip model, and the
reference constant of its critical length (tests.support).

A straight fault y = 0 across a box clamped on its four edges, plane strain,
under a uniform in-situ stress: normal traction SIGMA_N on the fault and a
shear TAU0 below its static strength.  The fault obeys linear slip weakening
(FS -> FD over DC).  A peaked shear load tau_load(x) = lambda AMPLITUDE g(x)
acts on the fault itself: equal and opposite face tractions
(fem.boundary.fracture_face_load), which on a locked fault add to the
contact shear without deforming the body, the "loading stress" of Uenishi &
Rice.  With W = (FS - FD) |SIGMA_N| / DC the slipping zone loses stability at
the half-length a_c = 0.579 mu* / W, mu* = mu / (1 - nu) (in-plane), whatever
the shape g.

The mesh is uniform (cell h) over |x| <= FINE_REACH a_c and over FINE_ROWS
rows on each side of the fault, which runs through the middle of a row of
cells; from there the cells grow by GROWTH per cell out to the box edges at
BOX a_c.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sl

from xfemslip.case import build, loads_case
from xfemslip.contact.interface import patch_geometry
from xfemslip.fem.boundary import fracture_face_load
from xfemslip.simulation import build_model, newton_solver

E, NU = 10.0e9, 0.25  # [Pa], [-]
MU_STAR = E / (2.0 * (1.0 + NU)) / (1.0 - NU)  # mu / (1 - nu) [Pa]
FS, FD, DC = 0.6, 0.45, 5.0e-3  # static, dynamic friction [-]; D_c [m]
SIGMA_N = -10.0e6  # normal traction on the fault [Pa]
TAU0 = 0.55 * abs(SIGMA_N)  # in-situ shear on the fault [Pa] (strength 6 MPa)
W = (FS - FD) * abs(SIGMA_N) / DC  # softening rate [Pa/m]
AMPLITUDE = 2.0e6  # peak of the load at load factor 1 [Pa]
FINE_REACH, FINE_ROWS, GROWTH, BOX = 1.6, 4, 1.15, 20.0


def nucleation_constant(n_modes: int = 60) -> float:
    """beta_0 of a_c = beta_0 mu* / W, from the eigenproblem of Uenishi & Rice
    (2003) solved here independently.

    Neutral stability of a slipping zone |x| < a with linear weakening: a
    slip delta (zero at +-a) whose elastic stress drop equals the strength
    drop, K[delta] = W delta.  With delta = a sqrt(1 - s^2) sum_n c_n
    U_{n-1}(s) (s = x / a; U Chebyshev polynomials of the second kind), the
    in-plane operator gives K[a sqrt(1 - s^2) U_{n-1}] = (mu* / 2) n U_{n-1}
    (n = 1: a uniform stress drop dtau opens the slip 2 dtau a sqrt(1 - s^2)
    / mu*, the mode II crack).  Projected on U_{m-1} with weight
    sqrt(1 - s^2): (pi / 2) diag(n) c = (2 a W / mu*) G c with G_mn =
    int (1 - s^2) U_{m-1} U_{n-1} ds, and beta_0 = a W / mu* is half the
    smallest eigenvalue.
    """
    s, w = np.polynomial.legendre.leggauss(400)
    theta = np.arccos(s)
    U = np.array([np.sin(n * theta) / np.sin(theta) for n in range(1, n_modes + 1)])
    G = (U * (1.0 - s**2) * w) @ U.T
    A = np.diag(0.5 * np.pi * np.arange(1, n_modes + 1))
    return 0.5 * float(sl.eigh(A, G, eigvals_only=True).min())


def critical_half_length() -> float:
    """a_c = 0.579 mu* / W [m] (Uenishi & Rice 2003, in-plane)."""
    return 0.579 * MU_STAR / W


def load_shape(name: str, x: np.ndarray) -> np.ndarray:
    """g(x) of the two loads: a Gaussian of standard deviation a_c, and a
    parabola reaching zero at +-2 a_c."""
    a = critical_half_length()
    if name == "gaussian":
        return np.exp(-0.5 * (x / a) ** 2)
    if name == "parabola":
        return np.maximum(0.0, 1.0 - (x / (2.0 * a)) ** 2)
    raise ValueError(name)


def _axis(h: float, fine: float, half: float, centred: bool) -> np.ndarray:
    """Node coordinates symmetric about 0: uniform h up to ``fine``, then
    cells growing by GROWTH up to ``half``; ``centred``: 0 is a cell centre."""
    nodes = [0.5 * h] if centred else [0.0]
    while nodes[-1] < fine - 1e-9 * h:
        nodes.append(nodes[-1] + h)
    size = h
    while nodes[-1] < half:
        size *= GROWTH
        nodes.append(nodes[-1] + size)
    pos = np.array(nodes)
    return np.concatenate([-pos[::-1], pos if centred else pos[1:]])


def case_table(h: float) -> dict:
    """The case (without its load) on cells of size h along the fault."""
    a = critical_half_length()
    x = _axis(h, FINE_REACH * a, BOX * a, centred=False)
    y = _axis(h, FINE_ROWS * h, BOX * a, centred=True)
    law = {"law": "slip_weakening", "static": FS, "dynamic": FD, "slip_distance": DC}
    return {
        "name": "uenishi-rice",
        "mesh": {"x": x.tolist(), "y": y.tolist()},
        "material": {"E": E, "nu": NU},
        "fractures": [{"points": [[x[0], 0.0], [x[-1], 0.0]], "friction": law}],
        "loading": {
            "initial_stress": build.stress_table((SIGMA_N, SIGMA_N, TAU0)),
            "steps": 1,
        },
        "boundary": {
            edge: {"ux": 0.0, "uy": 0.0} for edge in ("bottom", "top", "left", "right")
        },
    }


def model_and_solver(h: float, shape: str, **case_keys):
    """(model, solver, patch geometry) of the problem on cells of size h
    under the load ``shape``; ``case_keys``: dotted keys set in the case."""
    table = build.with_keys(case_table(h), **case_keys)
    model = build_model(loads_case(build.case_text(table)))
    ip = model.ip
    shear = ip.weight * AMPLITUDE * load_shape(shape, ip.xy[:, 0])
    model.problem.F_unit = fracture_face_load(model.contact, shear=shear)
    solver = newton_solver(model)
    geometry = patch_geometry(model.contact, ip, [fr.index for fr in model.fractures])
    return model, solver, geometry
