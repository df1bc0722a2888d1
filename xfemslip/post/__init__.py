"""Post-processing: what a converged load step gives beyond the unknowns.

- ``fields``: the fields of a step in the output sign convention
  (``StepFields``, ``FractureFields``, ``VisMesh``; element stresses, contact
  fields per fracture, the split visualisation mesh);
- ``result``: ``Result``, what a run gives back (in memory or read back from
  ``result.h5``), and the ``run_id`` digest of an output set;
- ``metrics``: scalar measures of a result (the columns of a sweep summary);
- ``jintegral``: stress intensity factors at fracture tips (interaction
  integral);
- ``permeability``: aperture laws and the Oda permeability tensor;
- ``seismic``: seismic moment, magnitude and stress drop of a slip patch.

Public names are imported on first access, so that reading a ``Result``
does not import the finite-element modules.
"""

from __future__ import annotations

import importlib

__all__ = [
    "FractureFields",
    "Result",
    "StepFields",
    "VisMesh",
    "result_metrics",
    "run_id",
    "step_fields",
]

_HOME = {
    "FractureFields": "fields",
    "StepFields": "fields",
    "VisMesh": "fields",
    "step_fields": "fields",
    "Result": "result",
    "run_id": "result",
    "result_metrics": "metrics",
}


def __getattr__(name: str):
    """The public names, imported from their module on first access."""
    if name not in _HOME:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{_HOME[name]}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
