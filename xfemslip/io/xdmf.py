"""XDMF3 descriptions of ``result.h5``, so ParaView (and ``meshio.read``)
open it directly: ``result.xdmf`` and, with load steps, ``result_steps.xdmf``.

Both are XML files that point into the datasets of ``result.h5`` beside them
(``result.h5:/mesh/points``); they hold no numbers of their own.

- ``result.xdmf``: one uniform grid, the final converged step: the Q4 mesh
  (``/mesh/cells``, ``/mesh/points``), ``displacement`` at the nodes and every
  other array of ``/fields`` on the cells, under its dataset's name.  One grid
  only, so that ``meshio.read`` reads it.
- ``result_steps.xdmf``: a temporal collection with one grid per step of
  ``/steps``, each with that step's ``displacement``; the time of each grid is
  the one of ``result.pvd`` (the load factor, or the pore-pressure change).

The XDMF mesh is the bulk mesh of ``result.h5``: its displacement is the
nodal one, continuous across the fractures (the split cells that show the
jump are in ``result.vtu``).  The file is written from the datasets the HDF5
file holds, read back after it was written, so the two always agree.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import h5py
import numpy as np

from xfemslip.io.atomic import atomic_path

__all__ = ["write_xdmf"]

_NUMBER = {"f": "Float", "i": "Int", "u": "UInt"}


def write_xdmf(
    folder: Path,
    h5_name: str = "result.h5",
    *,
    step_time: Callable[[float], float] | None = None,
) -> list[str]:
    """Write the XDMF files describing ``folder / h5_name``.

    Parameters
    ----------
    folder : Path
        The folder of the HDF5 file; the XDMF files go beside it.
    h5_name : str
        The HDF5 file's name, as the XDMF files name it (relative).
    step_time : callable load_factor -> time, optional
        The time of each step of the series (default: the load factor).

    Returns
    -------
    list of str : the names of the files written (none when the HDF5 file has
    no ``/fields``, i.e. no converged step).
    """
    with h5py.File(folder / h5_name, "r") as h5:
        if "fields" not in h5:
            return []
        mesh = _mesh_items(h5, h5_name)
        final = [
            _attribute(h5_name, dataset, "Node" if name == "displacement" else "Cell")
            for name, dataset in h5["fields"].items()
        ]
        grids = [_grid("result", mesh, final)]
        names = ["result.xdmf"]
        _write(folder / names[0], grids)
        if "steps" in h5:
            series = []
            for key, group in h5["steps"].items():
                factor = float(group.attrs["load_factor"])
                time = factor if step_time is None else step_time(factor)
                items = [_attribute(h5_name, group["fields/displacement"], "Node")]
                series.append(_grid(f"step {int(key)}", mesh, items, time=time))
            names.append("result_steps.xdmf")
            _write(folder / names[1], [_collection(series)])
    return names


def _mesh_items(h5: h5py.File, h5_name: str) -> list[str]:
    """Topology and geometry of the Q4 mesh."""
    cells, points = h5["mesh/cells"], h5["mesh/points"]
    return [
        f'<Topology TopologyType="Quadrilateral" NumberOfElements="{cells.shape[0]}">',
        f"  {_data_item(h5_name, cells)}",
        "</Topology>",
        '<Geometry GeometryType="XY">',
        f"  {_data_item(h5_name, points)}",
        "</Geometry>",
    ]


# XML escapes (xml.sax.saxutils has them, but its import pulls in
# urllib.request, http and ssl: 20 ms of every run); str.translate replaces
# each character once, so "&" in a reference is never escaped again.
# Character data: & < >; a double-quoted attribute value: those, the quote,
# and white space other than blanks (attribute normalisation would turn it
# into blanks).
_TEXT = str.maketrans({"&": "&amp;", "<": "&lt;", ">": "&gt;"})
_ATTR = str.maketrans(
    {
        "&": "&amp;",
        "<": "&lt;",
        ">": "&gt;",
        '"': "&quot;",
        "\n": "&#10;",
        "\r": "&#13;",
        "\t": "&#9;",
    }
)


def _text(text: str) -> str:
    """``text`` as XML character data."""
    return text.translate(_TEXT)


def _attr(text: str) -> str:
    """``text`` as a double-quoted XML attribute value."""
    return f'"{text.translate(_ATTR)}"'


def _attribute(h5_name: str, dataset: h5py.Dataset, center: str) -> list[str]:
    """An attribute named as its dataset: Scalar (one value per node or cell),
    Vector (2 or 3 components) or Matrix."""
    shape = dataset.shape
    width = 1 if len(shape) == 1 else shape[1]
    kind = "Scalar" if width == 1 else ("Vector" if width in (2, 3) else "Matrix")
    name = dataset.name.rsplit("/", 1)[-1]
    return [
        f'<Attribute Name={_attr(name)} AttributeType="{kind}" Center="{center}">',
        f"  {_data_item(h5_name, dataset)}",
        "</Attribute>",
    ]


def _data_item(h5_name: str, dataset: h5py.Dataset) -> str:
    """A DataItem pointing into the HDF5 file."""
    dtype = np.dtype(dataset.dtype)
    number, precision = _NUMBER[dtype.kind], dtype.itemsize
    dims = " ".join(str(n) for n in dataset.shape)
    return (
        f'<DataItem Dimensions="{dims}" NumberType="{number}" '
        f'Precision="{precision}" Format="HDF">'
        f"{_text(h5_name)}:{_text(dataset.name)}</DataItem>"
    )


def _grid(name, mesh, attributes, time=None) -> list[str]:
    """A uniform grid of the mesh with its attributes (and time)."""
    lines = [f'<Grid Name={_attr(name)} GridType="Uniform">']
    if time is not None:
        lines.append(f'  <Time Value="{float(time)!r}"/>')
    lines += [f"  {line}" for line in mesh]
    for attribute in attributes:
        lines += [f"  {line}" for line in attribute]
    return [*lines, "</Grid>"]


def _collection(grids) -> list[str]:
    lines = ['<Grid Name="steps" GridType="Collection" CollectionType="Temporal">']
    for grid in grids:
        lines += [f"  {line}" for line in grid]
    return [*lines, "</Grid>"]


def _write(path: Path, grids) -> None:
    lines = ['<?xml version="1.0"?>', '<Xdmf Version="3.0">', "  <Domain>"]
    for grid in grids:
        lines += [f"    {line}" for line in grid]
    lines += ["  </Domain>", "</Xdmf>", ""]
    with atomic_path(path) as tmp:
        tmp.write_text("\n".join(lines), encoding="utf-8")
