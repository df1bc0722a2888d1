"""The Numba backend's namespace: the compiled kernels under the names the
NumPy backend (vectorized.py) also has.  Importing it imports Numba."""

from xfemslip.kernels.bulk import enriched_cell_matrices, rectangle_stiffness
from xfemslip.kernels.contact import contact_response, coulomb_return_map
from xfemslip.kernels.scatter import (
    block_triplets,
    csr_add_entries,
    scatter_column_values,
)
from xfemslip.kernels.subcells import cell_subtriangles
from xfemslip.kernels.triangular import lower_unit_forward, upper_backward

__all__ = [
    "block_triplets",
    "cell_subtriangles",
    "contact_response",
    "coulomb_return_map",
    "csr_add_entries",
    "enriched_cell_matrices",
    "rectangle_stiffness",
    "scatter_column_values",
    "lower_unit_forward",
    "upper_backward",
]
