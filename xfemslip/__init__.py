"""xfemslip: XFEM frictional contact on 2D fractures (Numba-accelerated).

The public Python API (imported on first access, so that ``import xfemslip``
stays cheap: neither NumPy nor Numba is loaded until it is used):

- ``load_case(path) -> CaseSpec``: read and validate a case file
  (:mod:`xfemslip.case`; ``CaseError`` lists every problem);
- ``run_case(spec, out_dir=None, *, overwrite=False) -> Result``: solve it;
  ``out_dir`` None writes nothing, a folder gets the output set of
  ``output-format.md`` (:mod:`xfemslip.simulation`);
- ``read_result(path) -> Result``: read a ``result.h5`` back into the same
  object (:mod:`xfemslip.io.read`);
- ``Result``: the mesh, the fields of every load step (displacement, element
  stresses, and per fracture s, points, slip, opening, normal and shear
  traction, state) and the run's attributes (:mod:`xfemslip.post.result`);
- ``errors`` and its classes ``XfemslipError``, ``CaseError``,
  ``UsageError``, ``MeshError``, ``GeometryError``, ``ConvergenceError``,
  ``OutputError`` and its ``ResultError`` (a file that is not a result).

>>> import xfemslip
>>> spec = xfemslip.load_case("cases/liu_borja_plate.toml")  # doctest: +SKIP
>>> result = xfemslip.run_case(spec)  # doctest: +SKIP
>>> result.fractures[0].slip.max()  # doctest: +SKIP

Layout: ``case`` (input validation), ``geometry``, ``fem``, ``kernels`` (all
Numba code), ``contact``, ``solve``, ``post``, ``io``, ``reference`` (closed
forms), ``verify``, ``studies``, ``plot``, ``cli``; at the top ``simulation``
(the pipeline), ``conventions`` (signs and state codes), ``errors``,
``memory`` and ``interrupt``.
"""

from __future__ import annotations

import importlib

__version__ = "0.1.0"

__all__ = [
    "CaseError",
    "ConvergenceError",
    "GeometryError",
    "MeshError",
    "OutputError",
    "Result",
    "ResultError",
    "UsageError",
    "XfemslipError",
    "__version__",
    "errors",
    "load_case",
    "read_result",
    "run_case",
]

# name -> (module, attribute or None for the module itself)
_LAZY = {
    "load_case": ("xfemslip.case", "load_case"),
    "run_case": ("xfemslip.simulation", "run_case"),
    "read_result": ("xfemslip.io.read", "read_result"),
    "Result": ("xfemslip.post.result", "Result"),
    "errors": ("xfemslip.errors", None),
    **{
        name: ("xfemslip.errors", name)
        for name in (
            "XfemslipError",
            "CaseError",
            "UsageError",
            "MeshError",
            "GeometryError",
            "ConvergenceError",
            "OutputError",
            "ResultError",
        )
    },
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
