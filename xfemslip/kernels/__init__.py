"""The kernels: loops over cells and contact points, in two backends.

- ``"numba"``: bulk.py, contact.py, scatter.py, shape.py, subcells.py (gathered in
  jit.py), compiled by Numba (``cache=True``: once per install).  All Numba
  code of xfemslip lives in this subpackage, and only here.  jit.py also
  holds the sparse triangular substitutions of triangular.py, which have no
  NumPy twin (a substitution is a sequential loop): with the NumPy backend
  their caller solves whole systems with SuperLU instead.
- ``"numpy"``: vectorized.py, the same functions as whole-array NumPy code.
  It imports no Numba, so a small run skips Numba's import and its target
  set-up at the first dispatch (about 0.5 s of a 1 s warm run, and the 9 s of
  compilation of the first run after install).

``choose`` picks one per model from the work it has to do (``[solver]
kernels = "auto"``); the model keeps the name and passes it to every caller
of a kernel, which calls ``backend(name).contact_response(...)``.  There is
no process-wide backend: two models in one process may use different ones.
Importing this package imports neither backend.
"""

from __future__ import annotations

import importlib
import logging
import os
import sys
from pathlib import Path

from xfemslip.kernels._config import NUMBA_CACHE, numba_settings

logger = logging.getLogger(__name__)

BACKENDS = ("auto", "numba", "numpy")
KERNELS = (
    "block_triplets",
    "cell_subtriangles",
    "contact_response",
    "coulomb_return_map",
    "csr_add_entries",
    "enriched_cell_matrices",
    "rectangle_stiffness",
    "scatter_column_values",
)
# "auto" takes NumPy up to this many enriched-cell quadrature points times
# (8 + 2 S)^2 (simulation.kernel_work), and Numba above.  Measured
# (benchmarks/kernels_backend.py, docs/performance.md *Kernel backends*): whole
# runs with NumPy are as fast or faster on every shipped case (up to the
# shipped 15-fracture network, work 1.9e8), for Numba's import and set-up
# in every process (about 0.5 s; 9 s of compilation after install); at
# 1.4e9 (100 branch-tipped fractures on 200 x 200 cells) NumPy's
# enriched-cell entries took 5.5 s against Numba's 0.6 s, and its sum into
# the grid's matrix 1.4 s against 0.4 s.
AUTO_NUMPY_MAX_WORK = 2.5e8
# XFEMSLIP_KERNELS=numba|numpy overrides "auto" (the test suite runs both).
ENV_OVERRIDE = "XFEMSLIP_KERNELS"

# each backend's namespace, imported on first use
_MODULES = {"numba": "xfemslip.kernels.jit", "numpy": "xfemslip.kernels.vectorized"}


def backend(name: str):
    """The kernel namespace of backend ``name`` ("numba" | "numpy"): a module
    with the functions named in KERNELS.  The first use of the Numba kernels
    in a process whose on-disk cache lacks them says so (their compilation
    is a silent pause otherwise)."""
    if name not in _MODULES:
        raise ValueError(f"unknown kernel backend {name!r}; expected numba or numpy")
    if name == "numba" and _MODULES[name] not in sys.modules and cache_is_cold():
        logger.info(COMPILING)
    return importlib.import_module(_MODULES[name])


# The compilation of every kernel, timed as a run of
# cases/reservoir_depletion.toml with kernels = "numba" and an empty
# NUMBA_CACHE_DIR: 9 s on a free core, 43 s on two cores busy with other work.
COMPILING = (
    "compiling kernels (first run, about 15 s; longer on a busy machine): "
    "later runs load them from Numba's cache"
)
# the modules whose functions Numba compiles (one cache index per function)
JIT_MODULES = ("bulk", "contact", "scatter", "shape", "subcells", "triangular")


def _cache_folders() -> list[Path]:
    """Where Numba keeps the compiled kernels: NUMBA_CACHE_DIR when set, else
    __pycache__ beside the sources or, when that is not writable, the user's
    cache folder."""
    given = os.environ.get("NUMBA_CACHE_DIR", "").strip()
    if given:
        return [Path(given)]
    home = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return [Path(__file__).parent / "__pycache__", Path(home) / "numba"]


def cache_is_cold() -> bool:
    """Whether a Numba run would compile: the on-disk cache is off, or holds
    no index of one of the JIT_MODULES."""
    if not NUMBA_CACHE:
        return True
    indexes: set[str] = set()
    for folder in _cache_folders():
        if folder.is_dir():
            indexes.update(p.name.split(".", 1)[0] for p in folder.rglob("*.nbi"))
    return not indexes.issuperset(JIT_MODULES)


def choose(requested: str, work: float) -> str:
    """The backend for a model: ``requested`` unless it is "auto"; then NumPy
    while ``work`` (see AUTO_NUMPY_MAX_WORK) is at most the crossover."""
    if requested not in BACKENDS:
        raise ValueError(f"unknown kernel backend {requested!r}")
    if requested != "auto":
        return requested
    forced = os.environ.get(ENV_OVERRIDE, "").strip().lower()
    if forced in ("numba", "numpy"):
        return forced
    return "numpy" if work <= AUTO_NUMPY_MAX_WORK else "numba"


__all__ = [
    "BACKENDS",
    "COMPILING",
    "backend",
    "cache_is_cold",
    "choose",
    "numba_settings",
]
