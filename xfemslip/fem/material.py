"""Linear elastic constants (paper eqs. 24-25)."""

from __future__ import annotations

import numpy as np


def shear_modulus(young_modulus, poisson_ratio):
    """mu = E / (2 (1 + nu)) [Pa]; scalars or arrays."""
    return young_modulus / (2.0 * (1.0 + poisson_ratio))


def elasticity_matrix(
    young_modulus: float, poisson_ratio: float, model: str
) -> np.ndarray:
    """D (3, 3) [Pa] in Voigt order [xx, yy, xy(engineering shear)]."""
    E, nu = young_modulus, poisson_ratio
    if model == "plane_stress":  # eq. 24
        c = E / (1.0 - nu**2)
        return c * np.array(
            [[1.0, nu, 0.0], [nu, 1.0, 0.0], [0.0, 0.0, (1.0 - nu) / 2.0]]
        )
    if model == "plane_strain":  # eq. 25
        c = E * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu))
        r = nu / (1.0 - nu)
        return c * np.array(
            [
                [1.0, r, 0.0],
                [r, 1.0, 0.0],
                [0.0, 0.0, (1.0 - 2.0 * nu) / (2.0 * (1.0 - nu))],
            ]
        )
    raise ValueError(f"unknown model {model!r}")
