"""ParaView output: ``result.vtu``, ``fractures.vtu`` and the PVD series
``result.pvd`` / ``fractures.pvd``.

- ``write_bulk``: the bulk mesh with cut elements split along the fractures
  (:class:`~xfemslip.post.fields.VisMesh`), so that "Warp By Vector" on the point
  field ``displacement`` shows the jump.  Points and displacement are padded to
  3D with z = 0, as ParaView expects.
- ``write_fractures``: every fracture as a polyline through its contact
  integration points, with the contact fields as point data and, given the
  faces' displacements, their mean ``displacement`` (so the fracture warps
  with the bulk) and their ``displacement_jump``.
- ``write_pvd``: a ParaView collection (time series over load steps).

The arrays of a file are one dict (point data per fracture point in
``_fracture_part``, cell data per bulk cell in ``write_bulk``'s
``cell_data``): an array is added there.  Multi-component arrays get the
component names of COMPONENT_NAMES.

Every file is written atomically (:mod:`xfemslip.io.atomic`); the VTU files
by :mod:`xfemslip.io.vtkxml`.  Given a
``run_id``, each file carries it: the VTU files as the field data array
``run_id`` (1,) int64, the PVD as a comment.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from xfemslip.io.atomic import atomic_path, refuse_non_finite
from xfemslip.io.vtkxml import write_vtu
from xfemslip.post.fields import FractureFields, VisMesh

logger = logging.getLogger(__name__)

FRACTURE_POINT_DATA = ("slip", "opening", "normal_traction", "shear_traction")
OPTIONAL_FRACTURE_POINT_DATA = (
    "plastic_slip",
    "fluid_pressure",
    "effective_normal_traction",
    "utilisation",
    "aperture",
    "transmissivity",
    "accumulated_slip",
    "friction_coefficient",
)


def write_bulk(
    path: Path | str,
    vis: VisMesh,
    cell_data: Mapping[str, np.ndarray],
    *,
    run_id: int | None = None,
) -> None:
    """Write the visualisation mesh as an unstructured grid (``result.vtu``).

    Parameters
    ----------
    path : Path
        Final file name.
    vis : VisMesh
        Points (P, 2) [m], displacement (P, 2) [m], quads (Q, 4) and triangles
        (T, 3) with their bulk element ids ``quad_cell`` (Q,) and
        ``triangle_cell`` (T,).  An empty block is left out.
    cell_data : mapping of name -> (M,) or (M, k) array
        Values per BULK element (e.g. ``stress`` [Pa]); each vis cell gets the
        value of its bulk element.  ``cell_id`` (the bulk element id) is added.
    run_id : int, optional
        The output set's id, written as the field data array ``run_id`` (1,)
        int64.

    Raises
    ------
    ValueError
        Inconsistent shapes, or ``cell_id`` given in ``cell_data``.
    OutputError
        The file cannot be written.
    """
    if "cell_id" in cell_data:
        raise ValueError("write_bulk: 'cell_id' is reserved (added automatically)")
    points = _pad_3d(vis.points, "points")
    displacement = _pad_3d(vis.displacement, "displacement")
    if displacement.shape != points.shape:
        raise ValueError(
            f"write_bulk: displacement has shape {vis.displacement.shape}"
            f", points {np.shape(vis.points)}"
        )
    blocks = [
        (
            cell_type,
            np.asarray(conn, dtype=np.int64).reshape(-1, n_vertices),
            np.asarray(owner, dtype=np.int64).reshape(-1),
        )
        for cell_type, conn, owner, n_vertices in (
            ("quad", vis.quads, vis.quad_cell, 4),
            ("triangle", vis.triangles, vis.triangle_cell, 3),
        )
    ]
    blocks = [block for block in blocks if block[1].shape[0] > 0]
    for cell_type, conn, owner in blocks:
        if owner.shape[0] != conn.shape[0]:
            raise ValueError(
                f"write_bulk: {cell_type} block has {conn.shape[0]} "
                f"cells but {owner.shape[0]} bulk ids"
            )
    gathered = {"cell_id": [owner for _, _, owner in blocks]}
    for name, values in cell_data.items():
        values = np.asarray(values)
        gathered[name] = [values[owner] for _, _, owner in blocks]
    _write_vtu(
        path,
        points,
        [(cell_type, conn) for cell_type, conn, _ in blocks],
        {"displacement": displacement},
        gathered,
        run_id,
    )


def write_fractures(
    path: Path | str,
    fractures: Sequence[tuple[int, FractureFields]],
    *,
    faces: Sequence[tuple[np.ndarray, np.ndarray]] | None = None,
    run_id: int | None = None,
) -> bool:
    """Write the fractures as polylines with their contact fields (``fractures.vtu``).

    Parameters
    ----------
    path : Path
        Final file name.
    fractures : list of (index, FractureFields)
        ``index`` is the fracture's position in the case file.  Each fracture's
        K points, sorted by ``s``, are joined by "line" cells; a fracture with a
        single point becomes a "vertex" cell, one with none is left out.
    faces : list of (u_minus, u_plus), optional
        Per fracture (same order), the displacement of its - and + faces at
        its K points, each (K, 2) [m] sorted by ``s``
        (:func:`xfemslip.post.fields.fracture_faces`).  Given, the point data
        gets ``displacement`` = (u_minus + u_plus) / 2, so that "Warp By
        Vector" moves the fracture with the body, and ``displacement_jump`` =
        u_plus - u_minus ([[u]]), both 3 components with z = 0.
    run_id : int, optional
        The output set's id (field data ``run_id``, as in :func:`write_bulk`).

    Point data: ``slip``, ``plastic_slip`` (the slip that slid), ``opening``
    [m], ``normal_traction``,
    ``shear_traction``, ``contact_pressure`` = max(0, -normal_traction) [Pa],
    ``state`` (int32: 0 open, 1 stick, 2 slip), ``utilisation`` (the Coulomb
    utilisation, 1 where it slips), ``s`` [m] and ``fracture`` (the index),
    with ``faces`` the two displacements above, with pore pressure
    ``fluid_pressure`` and ``effective_normal_traction`` [Pa], and with
    ``[permeability]`` also ``aperture`` [m] and ``transmissivity`` [m^3],
    with a slip-weakening friction ``accumulated_slip`` [m] and
    ``friction_coefficient`` [-].
    Points are 3D with z = 0.

    Returns
    -------
    bool
        False when there is no fracture point at all: then nothing is written
        (a VTU without cells cannot be read back by meshio), and the caller
        decides whether to list the file anywhere.

    Raises
    ------
    OutputError
        The file cannot be written.
    """
    if faces is not None and len(faces) != len(fractures):
        raise ValueError(
            f"write_fractures: {len(faces)} face pairs for {len(fractures)} fractures"
        )
    parts = [
        _fracture_part(index, fields, None if faces is None else faces[k])
        for k, (index, fields) in enumerate(fractures)
    ]
    parts = [part for part in parts if part["points"].shape[0] > 0]
    if not parts:
        logger.debug("%s: no fracture points, file not written", path)
        return False
    lines, vertices, offset = [], [], 0
    for part in parts:
        n_points = part["points"].shape[0]
        ids = np.arange(offset, offset + n_points, dtype=np.int64)
        if n_points >= 2:
            lines.append(np.column_stack([ids[:-1], ids[1:]]))
        else:
            vertices.append(ids[:, None])
        offset += n_points
    cells = [
        (name, np.concatenate(block))
        for name, block in (("line", lines), ("vertex", vertices))
        if block
    ]
    point_data = {
        name: np.concatenate([part[name] for part in parts])
        for name in parts[0]
        if name != "points"
    }
    points = _pad_3d(np.concatenate([part["points"] for part in parts]), "points")
    _write_vtu(path, points, cells, point_data, {}, run_id)
    return True


def write_pvd(
    path: Path | str,
    entries: Sequence[tuple[float, str]],
    *,
    run_id: int | None = None,
) -> None:
    """Write a ParaView collection file (``result.pvd``).

    Parameters
    ----------
    path : Path
        Final file name.
    entries : list of (timestep, file)
        ``timestep`` is typically the load factor; ``file`` is the data set's
        path relative to the .pvd file.  Data sets that share a timestep (e.g.
        the bulk mesh and the fractures of one load step) get consecutive
        ``part`` numbers from 0, so ParaView shows them together.
    run_id : int, optional
        The output set's id, written as the comment ``<!-- xfemslip run_id N
        -->`` after the XML declaration (a comment: ParaView's collection
        reader gives meaning to every attribute of a data set).

    Raises
    ------
    OutputError
        The file cannot be written.
    """
    lines = ['<?xml version="1.0"?>']
    if run_id is not None:
        lines.append(f"<!-- xfemslip run_id {int(run_id)} -->")
    lines += [
        '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
        "  <Collection>",
    ]
    parts: dict[float, int] = {}
    for timestep, file in entries:
        part = parts.get(float(timestep), 0)
        parts[float(timestep)] = part + 1
        lines.append(
            f'    <DataSet timestep="{float(timestep)!r}" group="" '
            f'part="{part}" file={quoteattr(str(file))}/>'
        )
    lines += ["  </Collection>", "</VTKFile>", ""]
    with atomic_path(Path(path)) as tmp:
        tmp.write_text("\n".join(lines), encoding="utf-8")


def _fracture_part(
    index: int, fields: FractureFields, faces=None
) -> dict[str, np.ndarray]:
    """Point arrays of one fracture, sorted by arc length s (``faces``: its
    (u_minus, u_plus) at the same points, or None)."""
    s = np.asarray(fields.s, dtype=np.float64).reshape(-1)
    order = np.argsort(s, kind="stable")
    n_points = s.shape[0]
    part: dict[str, np.ndarray] = {
        "points": np.asarray(fields.points, dtype=np.float64).reshape(n_points, 2)
    }
    for name in FRACTURE_POINT_DATA:
        part[name] = np.asarray(getattr(fields, name), dtype=np.float64).reshape(
            n_points
        )
    # + 0.0 turns the -0.0 of max(-0.0, 0.0) into 0.0.
    part["contact_pressure"] = np.maximum(-part["normal_traction"], 0.0) + 0.0
    part["state"] = np.asarray(fields.state, dtype=np.int32).reshape(n_points)
    part["s"] = s
    part["fracture"] = np.full(n_points, index, dtype=np.int32)
    # plastic_slip [m] and utilisation [-] (None only when read from an older
    # result.h5); with pore pressure fluid_pressure and
    # effective_normal_traction [Pa]; [permeability]: aperture [m],
    # transmissivity a^3 / 12 [m^3]; slip weakening: accumulated_slip
    # [m], friction_coefficient [-]
    for name in OPTIONAL_FRACTURE_POINT_DATA:
        value = getattr(fields, name, None)
        if value is not None:
            part[name] = np.asarray(value, dtype=np.float64).reshape(n_points)
    if faces is not None:
        u_minus, u_plus = (
            np.asarray(face, dtype=np.float64).reshape(n_points, 2) for face in faces
        )
        part["displacement"] = _pad_3d(0.5 * (u_minus + u_plus), "displacement")
        part["displacement_jump"] = _pad_3d(u_plus - u_minus, "displacement_jump")
    return {name: value[order] for name, value in part.items()}


def _pad_3d(xy, name: str) -> np.ndarray:
    """(P, 2) -> (P, 3) float64 with z = 0 (ParaView works in 3D)."""
    xy = np.asarray(xy, dtype=np.float64)
    if xy.ndim != 2 or xy.shape[1] != 2:
        raise ValueError(f"{name} has shape {xy.shape}, expected (P, 2)")
    return np.column_stack([xy, np.zeros(xy.shape[0])])


def _write_vtu(path, points, cells, point_data, cell_data, run_id) -> None:
    """Write a VTU (binary, zlib) through a temporary file, with the field
    data ``run_id`` (when given) and the component names of COMPONENT_NAMES;
    non-finite values are refused first."""
    refuse_non_finite(points, f"{path}: points")
    for name, value in point_data.items():
        refuse_non_finite(value, f"{path}: {name}")
    for name, blocks in cell_data.items():
        for value in blocks:
            refuse_non_finite(value, f"{path}: {name}")
    with atomic_path(Path(path)) as tmp:
        write_vtu(
            tmp,
            points,
            cells,
            point_data,
            cell_data,
            None if run_id is None else {"run_id": int(run_id)},
            COMPONENT_NAMES,
        )


# Names of the components of the multi-component arrays (VTK reads the
# ComponentName<k> attributes of a DataArray; ParaView shows them in its
# colouring and calculator menus instead of 0, 1, 2 or X, Y, Z).
# stress_tensor follows VTK's symmetric tensor order.
COMPONENT_NAMES = {
    "stress_tensor": ("XX", "YY", "ZZ", "XY", "YZ", "XZ"),
    "stress": ("XX", "YY", "XY"),
    "effective_stress": ("XX", "YY", "XY"),
    "principal_stress": ("max", "min"),
}


_VTU_RUN_ID = re.compile(rb'Name="run_id" NumberOfTuples="1" format="ascii">\s*(\d+)')
_PVD_RUN_ID = re.compile(rb"<!-- xfemslip run_id (\d+) -->")


def read_run_id(path: Path | str) -> int | None:
    """The ``run_id`` of a VTU or PVD file written here (None when it has none
    or cannot be read); only the file's first 4 kB are read."""
    path = Path(path)
    pattern = _PVD_RUN_ID if path.suffix == ".pvd" else _VTU_RUN_ID
    try:
        with open(path, "rb") as fh:
            match = pattern.search(fh.read(4096))
    except OSError:
        return None
    return int(match[1]) if match else None


def pvd_files(path: Path | str) -> list[str]:
    """The data set files a PVD names (relative to it)."""
    from xml.etree import ElementTree

    root = ElementTree.parse(path).getroot()
    return [item.get("file", "") for item in root.iter("DataSet")]
