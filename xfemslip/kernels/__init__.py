"""The kernels: loops over cells and contact points, in two backends.

- ``"numba"``: bulk.py, contact.py, scatter.py, shape.py, compiled by Numba
  (``cache=True``: once per install).  All Numba code of xfemslip lives in
  this subpackage, and only here.
- ``"numpy"``: vectorized.py, the same functions as whole-array NumPy code.
  It imports no Numba, so a small run skips Numba's import and its target
  set-up at the first dispatch (about 0.5 s of a 1 s warm run, and the 9 s of
  compilation of the first run after install).

``choose`` picks one per model from the work it has to do (``[solver]
kernels = "auto"``); ``use`` makes it the backend of the module-level names
(``kernels.contact_response(...)``), which resolve on every access, so
importing this package imports neither backend.
"""

from __future__ import annotations

import importlib
import logging

from xfemslip.kernels.codes import (
    OPEN,
    SLIP,
    STICK,
    TANGENT_CONSISTENT,
    TANGENT_SECANT,
)

logger = logging.getLogger(__name__)

BACKENDS = ("auto", "numba", "numpy")
KERNELS = (
    "block_triplets",
    "contact_response",
    "coulomb_return_map",
    "enriched_cell_matrices",
    "rectangle_stiffness",
)
# "auto" takes NumPy up to this many enriched-cell quadrature points times
# enriched-cell columns squared (the enriched-cell assembly, NumPy's one
# per-cell loop), and Numba above; measured crossover in benchmarks/RESULTS.md
# (*Start-up, session 4*).
AUTO_NUMPY_MAX_WORK = 2.0e8

_active = "numba"


class _Numba:
    """The Numba kernels, imported on first use."""

    def __getattr__(self, name):
        if name not in KERNELS:
            raise AttributeError(name)
        module = {
            "block_triplets": "scatter",
            "contact_response": "contact",
            "coulomb_return_map": "contact",
            "enriched_cell_matrices": "bulk",
            "rectangle_stiffness": "bulk",
        }[name]
        return getattr(importlib.import_module(f"xfemslip.kernels.{module}"), name)


_NUMBA = _Numba()


def backend(name: str | None = None):
    """The kernel namespace of backend ``name`` (None: the active one)."""
    name = _active if name is None else name
    if name == "numpy":
        return importlib.import_module("xfemslip.kernels.vectorized")
    if name == "numba":
        return _NUMBA
    raise ValueError(f"unknown kernel backend {name!r}; expected numba or numpy")


def active() -> str:
    return _active


def use(name: str) -> str:
    """Make ``name`` ("numba" | "numpy") the backend of the module-level
    kernel names; returns the previous one."""
    global _active
    backend(name)  # validates
    previous, _active = _active, name
    return previous


def choose(requested: str, work: float) -> str:
    """The backend for a model: ``requested`` unless it is "auto"; then NumPy
    while ``work`` (see AUTO_NUMPY_MAX_WORK) is at most the crossover."""
    if requested not in BACKENDS:
        raise ValueError(f"unknown kernel backend {requested!r}")
    if requested != "auto":
        return requested
    return "numpy" if work <= AUTO_NUMPY_MAX_WORK else "numba"


def __getattr__(name):
    if name in KERNELS:
        return getattr(backend(), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "BACKENDS",
    "OPEN",
    "SLIP",
    "STICK",
    "TANGENT_CONSISTENT",
    "TANGENT_SECANT",
    "active",
    "backend",
    "choose",
    "use",
    *KERNELS,
]
