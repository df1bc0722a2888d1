"""Files in and out: the output set of a run, its folder, and the one reader.

- ``results``: the output set of a run (``result.h5``, ``result.vtu``,
  ``fractures.vtu``, ``result.pvd``, ``fractures.pvd``, ``result.xdmf``)
  written into its folder;
- ``read``: ``read_result`` / ``read_attrs``, the one reader of ``result.h5``;
- ``hdf5``, ``vtu``, ``xdmf``: the formats (``output-format.md``; the XDMF
  files describe ``result.h5`` for ParaView);
- ``folder``, ``lock``, ``fileset``: output folders and sets of files that
  appear whole or not at all (locked, staged, swapped);
- ``atomic``: single files written under a temporary name and renamed;
- ``csv``: the CSV and text tables of the commands.

Public names: ``read_result``, ``read_attrs``, ``write_results``,
``run_folder``, ``OUTPUT_FILES``, ``write_csv``, ``write_rows``,
``write_text``.  They are imported on first access: h5py and meshio cost
0.2-0.3 s of imports each, which a command that writes only a CSV file does
not pay.
"""

from __future__ import annotations

import importlib

__all__ = [
    "OUTPUT_FILES",
    "read_attrs",
    "read_result",
    "run_folder",
    "write_csv",
    "write_results",
    "write_rows",
    "write_text",
]

_HOME = {
    "OUTPUT_FILES": "results",
    "read_attrs": "read",
    "read_result": "read",
    "run_folder": "results",
    "write_csv": "csv",
    "write_results": "results",
    "write_rows": "csv",
    "write_text": "csv",
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
