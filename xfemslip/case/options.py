"""The key tables of a case file and the one table of ``[solver]`` options.

``SOLVER_OPTIONS`` is the single source of the ``[solver]`` keys: their type,
default, meaning and allowed values serve the validation
(:mod:`xfemslip.case.load`), the ``xfemslip check`` printout
(:mod:`xfemslip.case.describe`) and the documentation.
"""

from __future__ import annotations

from xfemslip.case.tables import Option, Range
from xfemslip.contact.defaults import CONTACT_PATCH_CELLS
from xfemslip.solve import pardiso


def pardiso_installed() -> bool:
    """Whether linear_solver = "pardiso" can run: the solver's own answer."""
    return pardiso.available()


# The constants of [domain]/[mesh], [[fractures]], [boundary] and the CSV files
# live beside their readers (grid.py, fractures.py, boundary.py, files.py).
TOP_KEYS = (
    "name",
    "domain",
    "mesh",
    "material",
    "fractures",
    "network",
    "loading",
    "boundary",
    "solver",
    "output",
    "pore_pressure",
    "reservoir",
    "units",
    "events",
    "permeability",
)
STRESS_KEYS = ("xx", "yy", "xy")
# loading.initial_stress varying with depth (xfemslip.fem.zones.in_situ_stress)
IN_SITU_KEYS = ("datum", "gradient_xx", "gradient_yy", "ratio_xx", "gravity")
MATERIAL_MODELS = ("plane_strain", "plane_stress")
# "csv": the profiles of the fractures (profile.csv, xfemslip.post.profile)
OUTPUT_FORMATS = ("h5", "vtu", "csv")
MAX_STEPS = 100_000


SOLVER_OPTIONS: tuple[Option, ...] = (
    Option(
        "tolerance",
        float,
        1.0e-8,
        "Newton stops when ||residual|| / ||F_ext|| <= tolerance (eta_0)",
        Range(0.0, 1.0, lo_open=True, hi_open=True),
    ),
    Option(
        "max_iterations", int, 30, "Newton iterations per load step", Range(1, 10_000)
    ),
    Option(
        "tangent",
        str,
        "consistent",
        "contact tangent: 'consistent' (Newton) or 'secant' (paper eq. 28)",
        ("consistent", "secant"),
    ),
    Option(
        "contact_patch",
        float,
        CONTACT_PATCH_CELLS,
        "length of a contact patch in cell sizes: the contact law acts on the jump "
        "averaged over each patch, which removes the traction oscillation of "
        "pointwise penalty XFEM; 0 = pointwise (every Gauss point on its own)",
        Range(0.0, 100.0),
    ),
    Option(
        "max_step_cuts",
        int,
        5,
        "bisections of a load step that does not converge (0: none); the "
        "smallest sub-step is 1/2**max_step_cuts of the step",
        Range(0, 30),
    ),
    Option(
        "linear_solver",
        str,
        "auto",
        "linear solver of the Newton systems: 'superlu' (sparse LU, factorization "
        "kept), 'amg' (pyamg-preconditioned GMRES), 'pardiso' (MKL PARDISO, "
        "pip install 'xfemslip[mkl]') or 'auto' (pardiso from 50,000 free dofs "
        "when installed, else amg from 50,000 free dofs on cells up to 4:1)",
        ("auto", "superlu", "amg", "pardiso"),
    ),
    Option(
        "kernels",
        str,
        "auto",
        "how the cell and contact loops run: 'numpy' (whole-array NumPy, no "
        "Numba start-up), 'numba' (compiled, cached once per install) or 'auto' "
        "(numpy unless the enriched cells are many; the answer is the same to "
        "round-off)",
        ("auto", "numba", "numpy"),
    ),
)
