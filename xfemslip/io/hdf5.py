"""``result.h5``: the complete result of a run (``output-format.md``, version 1).

Layout (every dataset carries ``attrs["units"]``: ``"m"``, ``"Pa"``, ``"-"``,
or for the derived quantities ``"m^2"``, ``"m^3"``, ``"N m/m"``, ``"N m"``)::

    /                         attrs: format_version, xfemslip_version, case_toml,
                                     converged, load_steps, newton_iterations,
                                     wall_time_s (+ any extra attrs of the caller)
    /mesh/points              (N, 2) float64 [m]
    /mesh/cells               (M, 4) int64   [-]  Q4, counter-clockwise
    /fields/displacement      (N, 2) float64 [m]      final converged step
    /fields/stress            (M, 3) float64 [Pa]     sxx, syy, sxy
    /fields/stress_zz         (M,)   float64 [Pa]
    /fields/principal_stress  (M, 2) float64 [Pa]     s_max, s_min
    /fractures/<i>/s, points, slip, opening, normal_traction, shear_traction,
                   state (int8: 0 open, 1 stick, 2 slip),
                   contact_pressure = max(0, -normal_traction) [Pa],
                   plastic_slip [m] (the slip that slid; root and every step)
    /fractures/<i>/shear_modulus, poisson_ratio  (K,) at the contact points
                   [Pa], [-], and attribute ends (2,) [m]: root only, the
                   same at every step (FractureProperties)
    with [pore_pressure] (xfemslip.fem.poro) also: /fields/effective_stress (M, 3)
    sigma + alpha p I, /fields/pore_pressure (M,), and per fracture
    fluid_pressure and effective_normal_traction (normal_traction is total)
    /steps/<kkkk>/            only when load_steps > 1; attrs load_factor,
                              newton_iterations; holds fields/displacement and
                              fractures/<i>/* of that step
    /events/                  event sizes (xfemslip.post.events), S converged
                              steps by F fractures: step (S,), slipped (S, F)
                              int8, max_slip, slipping_length, extent [m],
                              moment_per_length [N m/m], moment [N m],
                              stress_drop [Pa] (NaN where undefined),
                              max_slip_increment [m] and
                              moment_per_length_increment [N m/m] of the
                              step's own slip; attr extent_given
    with a slip-weakening friction on a fracture, every fracture also:
    accumulated_slip [m] and friction_coefficient [-]
    with [permeability] (xfemslip.post.hydraulics) also: per fracture aperture
    [m] and transmissivity [m^3], and /permeability/ with step (S,), in_situ
    (2, 2) and tensor (S, 2, 2) [m^2], initial_aperture (F,) [m], attrs block,
    matrix [m^2]

``<i>`` is the fracture's index in the case file (its position in
``StepFields.fractures``).  ``contact_pressure`` is an extra dataset for readers
who think compression-positive; it is *named* so and never replaces
``normal_traction`` (tension positive).

When ``steps`` is empty (the first load step did not converge) the file holds
the mesh and the root attributes only: no ``/fields``, ``/fractures`` or
``/steps``.  The file is written atomically (:mod:`xfemslip.io.atomic`) and
carries no timestamps, so the same input gives the same bytes.  The root
attribute ``run_id`` (:func:`xfemslip.post.result.run_id`, given by the caller)
is the id that every file of its output set carries.
"""

from __future__ import annotations

import functools
import io
import logging
from collections.abc import Mapping, Sequence
from pathlib import Path

import h5py
import numpy as np

from xfemslip import __version__, interrupt
from xfemslip.conventions import STATE_CODES
from xfemslip.io.atomic import atomic_path, refuse_non_finite
from xfemslip.post.fields import FractureFields, FractureProperties, StepFields
from xfemslip.post.result import DepletionTable, EventTable, PermeabilityHistory

logger = logging.getLogger(__name__)

FORMAT_VERSION = 1

# Root attributes of output-format.md that the caller must provide.
REQUIRED_ATTRS = ("case_toml", "converged", "newton_iterations", "wall_time_s")

# (name, units, dtype, trailing shape) of each fracture dataset; K rows each.
FRACTURE_DATASETS = (
    ("s", "m", np.float64, ()),
    ("points", "m", np.float64, (2,)),
    ("slip", "m", np.float64, ()),
    ("opening", "m", np.float64, ()),
    ("normal_traction", "Pa", np.float64, ()),
    ("shear_traction", "Pa", np.float64, ()),
    ("state", "-", np.int8, ()),
)


def write_result(
    path: Path | str,
    *,
    points: np.ndarray,
    cells: np.ndarray,
    steps: Sequence[StepFields],
    attrs: Mapping[str, object],
    load_steps: int,
    events: EventTable | None = None,
    permeability: PermeabilityHistory | None = None,
    properties: Sequence[FractureProperties] | None = None,
    depletion: DepletionTable | None = None,
) -> None:
    """Write ``result.h5`` atomically.

    Parameters
    ----------
    path : Path
        Final file name (normally ``<out_dir>/result.h5``).
    points : (N, 2) float64 [m]
        Node coordinates.
    cells : (M, 4) int64
        Q4 connectivity, counter-clockwise.
    steps : list of StepFields
        The converged load steps in order; the last one is written at the root.
        May be empty (then the file holds the mesh only).
    attrs : mapping
        Root attributes: at least ``case_toml``, ``converged``,
        ``newton_iterations`` and ``wall_time_s``; ``format_version``,
        ``xfemslip_version`` and ``load_steps`` default to 1, the package
        version and ``load_steps``.  Extra entries (scalars, strings or arrays)
        are written as given.
    load_steps : int
        Number of load steps of the case; ``/steps/`` is written when > 1.
    events, permeability : optional
        The derived tables ``/events`` and ``/permeability`` of the steps.
    properties : list of FractureProperties, optional
        Per fracture (same order as the steps' fractures) its ends and elastic
        constants at its contact points, written into ``/fractures/<i>``.
    depletion : DepletionTable, optional
        What ``deplete`` found per fracture, written as ``/depletion``.

    Raises
    ------
    ValueError
        Missing required attributes or arrays of the wrong shape (programming
        errors).
    OutputError
        The file cannot be written.
    """
    points = _as_array(points, np.float64, (None, 2), "points")
    cells = _as_array(cells, np.int64, (None, 4), "cells")
    root_attrs = _root_attrs(attrs, load_steps)
    # HDF5 builds the file in memory and Python writes it out: a write that
    # fails (a full disk) is then a plain OSError here, whereas a failure inside
    # the HDF5 library leaves identifiers it cannot close, which print errors
    # from their destructors and can crash the interpreter at exit.
    with atomic_path(Path(path)) as tmp:
        image = io.BytesIO()
        with h5py.File(image, "w", track_order=True) as h5:
            _fill(h5, root_attrs, points, cells, steps, load_steps)
            if steps and properties:
                _write_properties(h5["fractures"], properties)
            if steps:
                _write_derived(h5, steps, events, permeability)
            if depletion is not None:
                _write_depletion(h5, depletion)
        with open(tmp, "wb") as fh:
            fh.write(image.getbuffer())


def _fill(h5, root_attrs, points, cells, steps, load_steps) -> None:
    """The content of ``result.h5`` (see the module docstring)."""
    n_nodes, n_cells = points.shape[0], cells.shape[0]
    for key, value in root_attrs.items():
        h5.attrs[key] = value
    mesh = h5.create_group("mesh", track_order=True)
    _dataset(mesh, "points", points, "m")
    _dataset(mesh, "cells", cells, "-")
    if not steps:
        logger.debug("no converged step: writing the mesh only")
        return
    final = steps[-1]
    _write_bulk_fields(
        h5.create_group("fields", track_order=True), final, n_nodes, n_cells
    )
    _write_fractures(h5, final.fractures)
    if load_steps > 1:
        steps_group = h5.create_group("steps", track_order=True)
        for step in steps:
            _write_step(steps_group, step, n_nodes)


def _root_attrs(attrs: Mapping[str, object], load_steps: int) -> dict[str, object]:
    """Root attributes: contract defaults, then the caller's; checked for the rest."""
    missing = [key for key in REQUIRED_ATTRS if key not in attrs]
    if missing:
        raise ValueError(f"write_result: missing root attributes {missing}")
    merged: dict[str, object] = {
        "format_version": FORMAT_VERSION,
        "xfemslip_version": __version__,
        "case_toml": None,
        "converged": None,
        "load_steps": int(load_steps),
        "newton_iterations": None,
        "wall_time_s": None,
    }
    merged.update(attrs)
    for key, value in merged.items():
        if value is None:
            raise ValueError(f"write_result: root attribute {key!r} is None")
        if isinstance(value, bool):
            merged[key] = np.bool_(value)
    return merged


def _write_bulk_fields(
    group: h5py.Group, step: StepFields, n_nodes: int, n_cells: int
) -> None:
    """``/fields/*`` of the final step."""
    _dataset(
        group,
        "displacement",
        _as_array(step.displacement, np.float64, (n_nodes, 2), "displacement"),
        "m",
    )
    _dataset(
        group,
        "stress",
        _as_array(step.stress, np.float64, (n_cells, 3), "stress"),
        "Pa",
    )
    _dataset(
        group,
        "stress_zz",
        _as_array(step.stress_zz, np.float64, (n_cells,), "stress_zz"),
        "Pa",
    )
    _dataset(
        group,
        "principal_stress",
        _as_array(step.principal_stress, np.float64, (n_cells, 2), "principal_stress"),
        "Pa",
    )
    # with pore pressure only (xfemslip.fem.poro); /fields/stress stays total
    optional = (("effective_stress", (n_cells, 3)), ("pore_pressure", (n_cells,)))
    for name, shape in optional:
        value = getattr(step, name, None)
        if value is not None:
            _dataset(group, name, _as_array(value, np.float64, shape, name), "Pa")


def _write_step(steps_group: h5py.Group, step: StepFields, n_nodes: int) -> None:
    """``/steps/<kkkk>/``: displacement and fracture fields of one load step."""
    group = steps_group.create_group(f"{int(step.step):04d}", track_order=True)
    group.attrs["load_factor"] = float(step.load_factor)
    group.attrs["newton_iterations"] = int(step.newton_iterations)
    fields = group.create_group("fields", track_order=True)
    _dataset(
        fields,
        "displacement",
        _as_array(step.displacement, np.float64, (n_nodes, 2), "displacement"),
        "m",
    )
    _write_fractures(group, step.fractures)


def _write_fractures(parent: h5py.Group, fractures: Sequence[FractureFields]) -> None:
    """``<parent>/fractures/<i>/*`` for each fracture (``i`` = case-file index)."""
    if not fractures:
        return
    group = parent.create_group("fractures", track_order=True)
    for index, fracture in enumerate(fractures):
        _write_fracture(group.create_group(str(index), track_order=True), fracture)


def _write_fracture(group: h5py.Group, fracture: FractureFields) -> None:
    """The contact fields of one fracture, K points each, plus contact_pressure."""
    n_points = np.shape(fracture.s)[0]
    for name, units, dtype, trailing in FRACTURE_DATASETS:
        value = _as_array(getattr(fracture, name), dtype, (n_points, *trailing), name)
        dataset = _dataset(group, name, value, units)
        if name == "state":
            h5py.Dataset(dataset).attrs["codes"] = STATE_CODES
    normal = _as_array(
        fracture.normal_traction, np.float64, (n_points,), "normal_traction"
    )
    # + 0.0 turns the -0.0 of max(-0.0, 0.0) into 0.0.
    _dataset(group, "contact_pressure", np.maximum(-normal, 0.0) + 0.0, "Pa")
    optional = (
        ("plastic_slip", "m"),  # None only in a result read from an older file
        ("fluid_pressure", "Pa"),  # with pore pressure
        ("effective_normal_traction", "Pa"),
        ("aperture", "m"),  # with [permeability]
        ("transmissivity", "m^3"),
        ("utilisation", "-"),  # None only in a result read from an older file
        ("accumulated_slip", "m"),  # with a slip-weakening friction
        ("friction_coefficient", "-"),
    )
    for name, units in optional:
        given = getattr(fracture, name, None)
        if given is not None:
            _dataset(
                group, name, _as_array(given, np.float64, (n_points,), name), units
            )


def _write_properties(
    group: h5py.Group, properties: Sequence[FractureProperties]
) -> None:
    """``/fractures/<i>/shear_modulus``, ``poisson_ratio`` and the attribute
    ``ends`` of every fracture (``group`` is ``/fractures``)."""
    if len(properties) != len(group):
        raise ValueError(
            f"write_result: {len(properties)} fracture properties for "
            f"{len(group)} fractures"
        )
    for index, prop in enumerate(properties):
        g = group[str(index)]
        n_points = g["s"].shape[0]
        for name, units in PROPERTY_DATASETS:
            value = getattr(prop, name)
            if value is not None:
                value = _as_array(value, np.float64, (n_points,), name)
                _dataset(g, name, value, units)
        g.attrs["ends"] = _as_array(prop.ends, np.float64, (2,), "ends")
        if prop.breaks is not None:
            g.attrs["breaks"] = _as_array(prop.breaks, np.float64, (None,), "breaks")
            g.attrs["units_plus"] = np.array(prop.units_plus, dtype=h5py.string_dtype())
            g.attrs["units_minus"] = np.array(
                prop.units_minus, dtype=h5py.string_dtype()
            )


# (name, units) of the datasets of FractureProperties, K rows each, root only
PROPERTY_DATASETS = (
    ("shear_modulus", "Pa"),
    ("poisson_ratio", "-"),
    ("in_situ_normal_traction", "Pa"),
    ("in_situ_shear_traction", "Pa"),
    ("in_situ_utilisation", "-"),
)

# (name, units) of the event datasets, each (S, F)
EVENT_DATASETS = (
    ("max_slip", "m"),
    ("slipping_length", "m"),
    ("moment_per_length", "N m/m"),
    ("stress_drop", "Pa"),
    ("extent", "m"),
    ("max_slip_increment", "m"),
    ("moment_per_length_increment", "N m/m"),
)


def _write_derived(h5, steps, events, permeability) -> None:
    """``/events`` and ``/permeability`` (module docstring)."""
    numbers = np.array([int(step.step) for step in steps], dtype=np.int64)
    if events is not None:
        group = h5.create_group("events", track_order=True)
        group.attrs["extent_given"] = np.bool_(events.extent_given)
        _dataset(group, "step", numbers, "-")
        shape = (len(steps), None)
        _dataset(
            group,
            "slipped",
            _as_array(events.slipped, np.int8, shape, "slipped"),
            "-",
        )
        for name, units in EVENT_DATASETS:
            value = _as_array(getattr(events, name), np.float64, shape, name)
            # NaN where the crack model is undefined (no slipping length)
            _dataset(group, name, value, units, nan=name == "stress_drop")
        moment = events.moment_per_length * events.extent
        _dataset(group, "moment", _as_array(moment, np.float64, shape, "moment"), "N m")
    if permeability is not None:
        group = h5.create_group("permeability", track_order=True)
        group.attrs["block"] = np.array(permeability.block, dtype=np.float64)
        group.attrs["matrix"] = float(permeability.matrix)
        _dataset(group, "step", numbers, "-")
        _dataset(
            group,
            "in_situ",
            _as_array(permeability.in_situ, np.float64, (2, 2), "in_situ"),
            "m^2",
        )
        _dataset(
            group,
            "tensor",
            _as_array(permeability.tensors, np.float64, (len(steps), 2, 2), "tensor"),
            "m^2",
        )
        a0 = permeability.initial_aperture
        _dataset(
            group,
            "initial_aperture",
            _as_array(a0, np.float64, (len(a0),), "initial_aperture"),
            "m",
        )


# (name, units) of the /depletion datasets, each (F,); NaN: did not happen
DEPLETION_DATASETS = (
    ("dp_lower", "Pa"),
    ("dp_upper", "Pa"),
    ("x", "m"),
    ("y", "m"),
    ("dp_patch", "Pa"),
    ("dp_seismic", "Pa"),
    ("nucleation_length", "m"),
    ("x_nucleation", "m"),
    ("y_nucleation", "m"),
)


def _write_depletion(h5, table: DepletionTable) -> None:
    """``/depletion``: per fracture what ``deplete`` found."""
    group = h5.create_group("depletion", track_order=True)
    group.attrs["patch_length"] = float(table.patch_length)
    group.attrs["tolerance"] = float(table.tolerance)
    n = len(table.singularity)
    for name, units in DEPLETION_DATASETS:
        value = _as_array(getattr(table, name), np.float64, (n,), name)
        _dataset(group, name, value, units, nan=True)
    at = _as_array(table.at_singularity, np.int8, (n,), "at_singularity")
    _dataset(group, "first_slip_at_singularity", at, "-")
    group.attrs["singularity"] = np.array(table.singularity, dtype=h5py.string_dtype())


def _dataset(
    group: h5py.Group, name: str, value: np.ndarray, units: str, nan: bool = False
) -> h5py.h5d.DatasetID:
    """Create one dataset without timestamps and tag it with its units
    (``nan``: NaN stands for "undefined" in it; inf is refused all the same).

    The file is the one ``group.create_dataset(name, data=value,
    track_times=False, fletcher32=...)`` and ``attrs["units"] = units`` write,
    to the byte, made through h5py's low-level calls with the type and
    property objects kept between datasets: a result holds about a hundred
    small datasets, and the high-level calls rebuild them for each one (a
    third of the time of a study's sample)."""
    interrupt.checkpoint()  # between data sets: a deferred signal stops here
    refuse_non_finite(
        np.where(np.isnan(value), 0.0, value) if nan else value,
        lambda: f"{group.name}/{name}",
    )
    value = np.ascontiguousarray(value)
    dataset = h5py.h5d.create(
        group.id,
        name.encode(),
        _file_type(value.dtype.str),
        h5py.h5s.create_simple(value.shape),
        dcpl=_creation(value.shape, value.dtype.itemsize),
    )
    dataset.write(h5py.h5s.ALL, h5py.h5s.ALL, value)
    attr = h5py.h5a.create(dataset, b"units", _STRING[0], _SCALAR_SPACE)
    try:
        attr.write(_units_value(units), mtype=_STRING[1])
    finally:
        attr.close()
    return dataset


@functools.cache
def _units_value(units: str) -> np.ndarray:
    """The units attribute's value as h5py writes a str (made once per units)."""
    return np.array(units, dtype=_STRING_DTYPE)


# a str attribute as h5py stores it: variable-length UTF-8, a scalar space
_STRING_DTYPE = h5py.string_dtype()
_STRING = (
    h5py.h5t.py_create(_STRING_DTYPE, logical=True),
    h5py.h5t.py_create(_STRING_DTYPE),
)
_SCALAR_SPACE = h5py.h5s.create_simple(())


@functools.cache
def _file_type(dtype: str):
    """The HDF5 type a dataset of numpy ``dtype`` is stored as."""
    return h5py.h5t.py_create(np.dtype(dtype), logical=1)


@functools.lru_cache(maxsize=256)
def _creation(shape: tuple, itemsize: int):
    """The dataset creation properties of an array: chunked as h5py chunks
    it, with a Fletcher-32 checksum per chunk (a flipped bit fails the read
    of the data set instead of reading as a wrong number); a scalar is
    stored whole, without a filter.  No timestamps, no attribute order."""
    dcpl = h5py.h5p.create(h5py.h5p.DATASET_CREATE)
    if shape:
        dcpl.set_chunk(h5py.filters.guess_chunk(shape, None, itemsize))
        dcpl.set_fletcher32()
    dcpl.set_obj_track_times(False)
    dcpl.set_attr_creation_order(0)
    return dcpl


def _as_array(value, dtype, shape: tuple, name: str) -> np.ndarray:
    """``value`` as a C-contiguous array of ``dtype`` and ``shape`` (None = any)."""
    array = np.ascontiguousarray(value, dtype=dtype)
    ok = array.ndim == len(shape) and all(
        want is None or want == got
        for want, got in zip(shape, array.shape, strict=True)
    )
    if not ok:
        want = tuple("*" if n is None else n for n in shape)
        raise ValueError(
            f"write_result: {name} has shape {array.shape}, expected {want}"
        )
    return array
