"""xfemslip: XFEM frictional contact on 2D fractures (Numba-accelerated).

Public entry points, imported lazily so that ``import xfemslip`` stays cheap
(neither numba nor scipy is loaded until a simulation is run):

- ``load_case(path) -> CaseSpec``  (:mod:`xfemslip.case`)
- ``run_case(spec, out_dir=None, *, overwrite=False) -> RunSummary``
  (:mod:`xfemslip.simulation`)
- ``errors``  (:mod:`xfemslip.errors`, the exception classes)
"""

from __future__ import annotations

import importlib

__version__ = "0.1.0"

__all__ = ["__version__", "errors", "load_case", "run_case"]

# name -> (module, attribute or None for the module itself)
_LAZY = {
    "load_case": ("xfemslip.case", "load_case"),
    "run_case": ("xfemslip.simulation", "run_case"),
    "errors": ("xfemslip.errors", None),
}


def __getattr__(name: str):
    """Import the public re-exports on first access (PEP 562)."""
    try:
        module_name, attr = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'xfemslip' has no attribute {name!r}") from None
    module = importlib.import_module(module_name)
    value = module if attr is None else getattr(module, attr)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
