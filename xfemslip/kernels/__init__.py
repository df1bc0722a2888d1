"""All Numba code of xfemslip lives in this subpackage, and only here."""

from xfemslip.kernels.bulk import (
    enriched_cell_matrices,
    rectangle_stiffness,
)
from xfemslip.kernels.contact import (
    OPEN,
    SLIP,
    STICK,
    TANGENT_CONSISTENT,
    TANGENT_SECANT,
    contact_response,
    coulomb_return_map,
)
from xfemslip.kernels.scatter import block_triplets

__all__ = [
    "OPEN",
    "SLIP",
    "STICK",
    "TANGENT_CONSISTENT",
    "TANGENT_SECANT",
    "block_triplets",
    "contact_response",
    "coulomb_return_map",
    "enriched_cell_matrices",
    "rectangle_stiffness",
]
