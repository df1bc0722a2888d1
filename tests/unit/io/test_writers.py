"""Round trips of the writers (output-format.md): write, read back, compare."""

from __future__ import annotations

import copy
import os
import signal
import xml.etree.ElementTree as ET

import h5py
import meshio
import numpy as np
import pytest

import xfemslip
from xfemslip import __version__, interrupt
from xfemslip.errors import OutputError, ResultError
from xfemslip.io.atomic import atomic_path
from xfemslip.io.csv import ROWS_PER_CHECKPOINT, write_rows
from xfemslip.io.hdf5 import write_result
from xfemslip.io.read import read_result
from xfemslip.io.vtu import write_bulk, write_fractures, write_pvd
from xfemslip.post.fields import FractureFields, StepFields, VisMesh
from xfemslip.post.result import EventTable

FRACTURE_UNITS = {
    "s": "m",
    "points": "m",
    "slip": "m",
    "opening": "m",
    "normal_traction": "Pa",
    "shear_traction": "Pa",
    "state": "-",
    "contact_pressure": "Pa",
}


# --------------------------------------------------------------------------- data


def _mesh():
    """2 x 2 Q4 mesh of the unit square: 9 nodes, 4 cells (counter-clockwise)."""
    xs, ys = np.meshgrid([0.0, 0.5, 1.0], [0.0, 0.5, 1.0])
    points = np.column_stack([xs.ravel(), ys.ravel()])
    cells = np.array(
        [[0, 1, 4, 3], [1, 2, 5, 4], [3, 4, 7, 6], [4, 5, 8, 7]], dtype=np.int64
    )
    return points, cells


def _fracture(scale: float) -> FractureFields:
    """A 3-point fracture along the diagonal; values scaled per step."""
    s = np.array([0.1, 0.7, 1.3])
    return FractureFields(
        s=s,
        points=np.column_stack([s, s]) / np.sqrt(2.0),
        slip=scale * np.array([-1.0e-5, -2.0e-5, -1.5e-5]),
        opening=scale * np.array([-1.0e-9, 0.0, 2.0e-6]),
        normal_traction=scale * np.array([-2.0e6, -0.0, 0.0]),
        shear_traction=scale * np.array([1.0e5, 2.0e5, 0.0]),
        state=np.array([1, 2, 0], dtype=np.int8),
    )


def _step(k: int, n_nodes: int = 9, n_cells: int = 4) -> StepFields:
    rng = np.random.default_rng(k)
    return StepFields(
        step=k,
        load_factor=k / 2.0,
        newton_iterations=3 + k,
        displacement=rng.normal(size=(n_nodes, 2)) * 1.0e-4,
        stress=rng.normal(size=(n_cells, 3)) * 1.0e6,
        stress_zz=rng.normal(size=n_cells) * 1.0e6,
        principal_stress=rng.normal(size=(n_cells, 2)) * 1.0e6,
        fractures=[_fracture(float(k))],
    )


def _attrs(load_steps: int) -> dict:
    return {
        "format_version": 1,
        "xfemslip_version": __version__,
        "case_toml": 'name = "synthetic"\n',
        "converged": True,
        "load_steps": load_steps,
        "newton_iterations": 9,
        "wall_time_s": 0.25,
        "newton_iterations_per_step": np.array([4, 5], dtype=np.int64),
        "status_codes": "0 open, 1 stick, 2 slip",
    }


def _write(path, load_steps: int = 2, steps=None):
    points, cells = _mesh()
    steps = [_step(1), _step(2)] if steps is None else steps
    write_result(
        path,
        points=points,
        cells=cells,
        steps=steps,
        attrs=_attrs(load_steps),
        load_steps=load_steps,
    )
    return points, cells, steps


def _vis():
    """Two quads plus one element split into two triangles on points of its own."""
    points = np.array(
        [
            [0, 0],
            [1, 0],
            [2, 0],
            [0, 1],
            [1, 1],
            [2, 1],
            [2, 0],
            [3, 0],
            [3, 1],
            [2, 1],
        ],
        dtype=float,
    )
    return VisMesh(
        points=points,
        displacement=np.arange(20, dtype=float).reshape(10, 2) * 1.0e-3,
        quads=np.array([[0, 1, 4, 3], [1, 2, 5, 4]], dtype=np.int64),
        quad_cell=np.array([0, 1], dtype=np.int64),
        triangles=np.array([[6, 7, 8], [6, 8, 9]], dtype=np.int64),
        triangle_cell=np.array([2, 2], dtype=np.int64),
    )


# --------------------------------------------------------------------------- hdf5


def test_result_h5_datasets_match_contract(tmp_path):
    path = tmp_path / "result.h5"
    points, cells, steps = _write(path)
    final = steps[-1]
    with h5py.File(path, "r") as h5:
        expected = {
            "mesh/points": (points, np.float64, "m"),
            "mesh/cells": (cells, np.int64, "-"),
            "fields/displacement": (final.displacement, np.float64, "m"),
            "fields/stress": (final.stress, np.float64, "Pa"),
            "fields/stress_zz": (final.stress_zz, np.float64, "Pa"),
            "fields/principal_stress": (final.principal_stress, np.float64, "Pa"),
        }
        for name, (value, dtype, units) in expected.items():
            dataset = h5[name]
            assert dataset.dtype == dtype, name
            assert dataset.shape == value.shape, name
            assert dataset.attrs["units"] == units, name
            np.testing.assert_array_equal(dataset[()], value, err_msg=name)
        _check_fracture(h5["fractures/0"], final.fractures[0])


def _check_fracture(group, fracture: FractureFields):
    assert set(group) == set(FRACTURE_UNITS)
    for name, units in FRACTURE_UNITS.items():
        assert group[name].attrs["units"] == units, name
    for name in ("s", "points", "slip", "opening", "normal_traction", "shear_traction"):
        assert group[name].dtype == np.float64
        np.testing.assert_array_equal(group[name][()], getattr(fracture, name))
    assert group["state"].dtype == np.int8
    np.testing.assert_array_equal(group["state"][()], fracture.state)
    pressure = group["contact_pressure"][()]
    np.testing.assert_array_equal(pressure, np.maximum(-fracture.normal_traction, 0.0))
    assert not np.signbit(pressure).any()  # no -0.0


def test_result_h5_data_sets_carry_checksums(tmp_path):
    """Every array data set has a Fletcher-32 checksum: one flipped bit in
    the stored numbers fails the read with a ResultError naming the file
    (without the checksum it reads back as another number)."""
    path = tmp_path / "result.h5"
    _write(path)
    with h5py.File(path, "r") as h5:
        arrays = []
        h5.visititems(
            lambda name, item: (
                arrays.append(item)
                if isinstance(item, h5py.Dataset) and item.ndim
                else None
            )
        )
        assert arrays and all(item.fletcher32 for item in arrays)
        offset = h5["mesh/points"].id.get_chunk_info(0).byte_offset
    data = bytearray(path.read_bytes())
    data[offset + 3] ^= 0x10  # a bit of the first number
    path.write_bytes(bytes(data))
    with pytest.raises(ResultError, match=f"{path}: not a readable result.h5"):
        read_result(path)


def test_write_rows_acts_on_a_held_signal_every_chunk_of_rows(tmp_path):
    """A signal held back while a set of files is written stops a long
    table after at most ROWS_PER_CHECKPOINT more rows, not at its end."""
    consumed = []

    def rows():
        for k in range(5 * ROWS_PER_CHECKPOINT):
            if k == 10:
                os.kill(os.getpid(), signal.SIGINT)
            consumed.append(k)
            yield [str(k)]

    with pytest.raises(KeyboardInterrupt), interrupt.deferred():
        write_rows(tmp_path / "t.csv", ["k"], rows())
    assert 10 < len(consumed) <= ROWS_PER_CHECKPOINT + 1


def test_result_h5_root_attributes(tmp_path):
    path = tmp_path / "result.h5"
    _write(path)
    with h5py.File(path, "r") as h5:
        attrs = dict(h5.attrs)
    assert attrs["format_version"] == 1
    assert attrs["xfemslip_version"] == __version__
    assert attrs["case_toml"] == 'name = "synthetic"\n'
    assert bool(attrs["converged"]) is True
    assert attrs["load_steps"] == 2
    assert attrs["newton_iterations"] == 9
    assert attrs["wall_time_s"] == pytest.approx(0.25)
    np.testing.assert_array_equal(attrs["newton_iterations_per_step"], [4, 5])
    assert attrs["status_codes"] == "0 open, 1 stick, 2 slip"


def test_result_h5_steps_written_when_several(tmp_path):
    path = tmp_path / "result.h5"
    _, _, steps = _write(path, load_steps=2)
    with h5py.File(path, "r") as h5:
        assert sorted(h5["steps"]) == ["0001", "0002"]
        for step in steps:
            group = h5[f"steps/{step.step:04d}"]
            assert group.attrs["load_factor"] == step.load_factor
            assert group.attrs["newton_iterations"] == step.newton_iterations
            assert group["fields/displacement"].attrs["units"] == "m"
            np.testing.assert_array_equal(
                group["fields/displacement"][()], step.displacement
            )
            _check_fracture(group["fractures/0"], step.fractures[0])


def test_result_h5_no_steps_group_for_single_step(tmp_path):
    path = tmp_path / "result.h5"
    _write(path, load_steps=1, steps=[_step(1)])
    with h5py.File(path, "r") as h5:
        assert "steps" not in h5
        assert "fields" in h5 and "fractures" in h5


def test_result_h5_mesh_only_without_converged_step(tmp_path):
    path = tmp_path / "result.h5"
    _write(path, load_steps=2, steps=[])
    with h5py.File(path, "r") as h5:
        assert set(h5) == {"mesh"}
        assert h5["mesh/points"].shape == (9, 2)


def test_result_h5_inputs_not_mutated(tmp_path):
    points, cells = _mesh()
    steps = [_step(1), _step(2)]
    attrs = _attrs(2)
    before = copy.deepcopy((points, cells, steps, attrs))
    write_result(
        tmp_path / "result.h5",
        points=points,
        cells=cells,
        steps=steps,
        attrs=attrs,
        load_steps=2,
    )
    np.testing.assert_array_equal(points, before[0])
    np.testing.assert_array_equal(cells, before[1])
    for step, old in zip(steps, before[2], strict=True):
        for name in ("displacement", "stress", "stress_zz", "principal_stress"):
            np.testing.assert_array_equal(getattr(step, name), getattr(old, name))
        for name in FRACTURE_UNITS.keys() - {"contact_pressure"}:
            np.testing.assert_array_equal(
                getattr(step.fractures[0], name), getattr(old.fractures[0], name)
            )
    assert attrs.keys() == before[3].keys()


def test_result_h5_is_deterministic(tmp_path):
    _write(tmp_path / "a.h5")
    _write(tmp_path / "b.h5")
    assert (tmp_path / "a.h5").read_bytes() == (tmp_path / "b.h5").read_bytes()


def _high_level_dataset(group, name, value, units, nan=False):
    """A data set as h5py's high-level calls write it: the reference of
    the writer's own calls."""
    dataset = group.create_dataset(
        name, data=value, track_times=False, fletcher32=np.ndim(value) > 0
    )
    dataset.attrs["units"] = units
    return dataset.id


@pytest.mark.parametrize("content", ["steps", "mesh"])
def test_result_h5_is_the_file_of_h5pys_high_level_calls(
    tmp_path, monkeypatch, content
):
    """result.h5 is, to the byte, the file that h5py's create_dataset (with
    track_times=False and a Fletcher-32 checksum on arrays) and attrs write:
    the same chunks, filters and attributes.  ``steps``: two load steps with
    their fracture fields and event sizes (float64, int8, NaN); ``mesh``: a
    300 x 300 mesh alone, whose points span several chunks."""
    from xfemslip.io import hdf5

    if content == "steps":
        points, cells = _mesh()
        steps = [_step(1), _step(2)]
        events = _events([[np.nan], [3.0e6]])
    else:
        xs, ys = np.meshgrid(np.linspace(0, 1, 301), np.linspace(0, 1, 301))
        points = np.column_stack([xs.ravel(), ys.ravel()])
        ij = np.arange(301 * 300).reshape(301, 300)[:300]
        cells = np.stack([ij, ij + 1, ij + 302, ij + 301], axis=-1).reshape(-1, 4)
        steps, events = [], None
    common = dict(
        points=points,
        cells=cells.astype(np.int64),
        steps=steps,
        attrs=_attrs(2),
        load_steps=2,
        events=events,
    )
    write_result(tmp_path / "a.h5", **common)
    monkeypatch.setattr(hdf5, "_dataset", _high_level_dataset)
    write_result(tmp_path / "b.h5", **common)
    with h5py.File(tmp_path / "b.h5") as h5:
        chunks = h5["mesh/points"].chunks
        assert h5["mesh/points"].fletcher32 and h5["mesh/cells"].attrs["units"] == "-"
    if content == "mesh":
        assert chunks[0] < points.shape[0]  # several chunks
    assert (tmp_path / "a.h5").read_bytes() == (tmp_path / "b.h5").read_bytes()


def test_result_h5_rejects_wrong_shapes(tmp_path):
    points, cells = _mesh()
    bad = _step(1)
    bad.stress = bad.stress[:, :2]
    with pytest.raises(ValueError, match="stress"):
        write_result(
            tmp_path / "result.h5",
            points=points,
            cells=cells,
            steps=[bad],
            attrs=_attrs(1),
            load_steps=1,
        )
    assert not (tmp_path / "result.h5").exists()
    assert os.listdir(tmp_path) == []


def _events(drop) -> EventTable:
    """An /events table of 2 steps by 1 fracture with the stress drops
    ``drop`` (2, 1)."""
    ones = np.ones((2, 1))
    return EventTable(
        slipped=np.array([[False], [True]]),
        max_slip=ones * [[0.0], [1e-3]],
        slipping_length=ones * [[0.0], [0.5]],
        moment_per_length=ones * [[0.0], [2e6]],
        stress_drop=np.asarray(drop, float),
        extent=ones * [[0.0], [0.5]],
        extent_given=False,
        max_slip_increment=ones * [[0.0], [1e-3]],
        moment_per_length_increment=ones * [[0.0], [2e6]],
    )


def test_undefined_stress_drop_is_stored_as_nan(tmp_path):
    """/events/stress_drop holds NaN where the crack model is undefined (no
    slipping length) and reads back as NaN; inf is refused all the same."""
    points, cells = _mesh()
    common = dict(
        points=points,
        cells=cells,
        steps=[_step(1), _step(2)],
        attrs=_attrs(2),
        load_steps=2,
    )
    write_result(tmp_path / "result.h5", events=_events([[np.nan], [3.0e6]]), **common)
    with h5py.File(tmp_path / "result.h5") as h5:
        drop = h5["events/stress_drop"][()]
    assert np.isnan(drop[0, 0]) and drop[1, 0] == 3.0e6
    read = xfemslip.read_result(tmp_path / "result.h5").events.stress_drop
    assert np.isnan(read[0, 0]) and read[1, 0] == 3.0e6
    with pytest.raises(OutputError, match="stress_drop"):
        write_result(tmp_path / "bad.h5", events=_events([[np.inf], [3.0e6]]), **common)
    assert not (tmp_path / "bad.h5").exists()


# --------------------------------------------------------------------------- vtu


def test_write_bulk_round_trip(tmp_path):
    vis = _vis()
    stress = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0]])
    stress_zz = np.array([10.0, 20.0, 30.0])
    before = copy.deepcopy(vis)
    path = tmp_path / "result.vtu"
    write_bulk(path, vis, {"stress": stress, "stress_zz": stress_zz})

    mesh = meshio.read(path)
    assert mesh.points.shape == (10, 3)
    np.testing.assert_array_equal(mesh.points[:, :2], vis.points)
    np.testing.assert_array_equal(mesh.points[:, 2], 0.0)
    disp = mesh.point_data["displacement"]
    assert disp.shape == (10, 3)
    np.testing.assert_array_equal(disp[:, :2], vis.displacement)
    np.testing.assert_array_equal(disp[:, 2], 0.0)
    assert [block.type for block in mesh.cells] == ["quad", "triangle"]
    np.testing.assert_array_equal(mesh.cells[0].data, vis.quads)
    np.testing.assert_array_equal(mesh.cells[1].data, vis.triangles)
    quad_stress, tri_stress = mesh.cell_data["stress"]
    np.testing.assert_array_equal(quad_stress, stress[[0, 1]])
    np.testing.assert_array_equal(tri_stress, stress[[2, 2]])
    np.testing.assert_array_equal(mesh.cell_data["stress_zz"][1], [30.0, 30.0])
    np.testing.assert_array_equal(mesh.cell_data["cell_id"][0], [0, 1])
    np.testing.assert_array_equal(mesh.cell_data["cell_id"][1], [2, 2])
    np.testing.assert_array_equal(vis.points, before.points)
    np.testing.assert_array_equal(vis.displacement, before.displacement)


def test_write_bulk_skips_empty_block(tmp_path):
    vis = _vis()
    vis.triangles = np.zeros((0, 3), dtype=np.int64)
    vis.triangle_cell = np.zeros(0, dtype=np.int64)
    path = tmp_path / "result.vtu"
    write_bulk(path, vis, {"stress_zz": np.array([1.0, 2.0, 3.0])})
    mesh = meshio.read(path)
    assert [block.type for block in mesh.cells] == ["quad"]
    np.testing.assert_array_equal(mesh.cell_data["stress_zz"][0], [1.0, 2.0])


def test_write_fractures_round_trip(tmp_path):
    first = _fracture(1.0)
    # second fracture given out of order in s: the writer sorts it
    second = _fracture(2.0)
    order = np.array([2, 0, 1])
    second = FractureFields(
        **{
            name: getattr(second, name)[order]
            for name in FRACTURE_UNITS.keys() - {"contact_pressure"}
        }
    )
    single = FractureFields(
        **{
            name: getattr(first, name)[:1]
            for name in FRACTURE_UNITS.keys() - {"contact_pressure"}
        }
    )
    path = tmp_path / "fractures.vtu"
    assert write_fractures(path, [(0, first), (2, second), (3, single)])

    mesh = meshio.read(path)
    assert mesh.points.shape == (7, 3)
    np.testing.assert_array_equal(mesh.points[:, 2], 0.0)
    lines = np.concatenate([b.data for b in mesh.cells if b.type == "line"])
    vertices = np.concatenate([b.data for b in mesh.cells if b.type == "vertex"])
    np.testing.assert_array_equal(lines, [[0, 1], [1, 2], [3, 4], [4, 5]])
    np.testing.assert_array_equal(vertices, [[6]])
    data = mesh.point_data
    np.testing.assert_array_equal(data["fracture"], [0, 0, 0, 2, 2, 2, 3])
    np.testing.assert_array_equal(data["s"], [0.1, 0.7, 1.3] * 2 + [0.1])
    np.testing.assert_array_equal(data["slip"][3:6], 2.0 * first.slip)
    np.testing.assert_array_equal(data["state"][:3], first.state)
    np.testing.assert_array_equal(
        data["contact_pressure"][:3], np.maximum(-first.normal_traction, 0.0)
    )
    for name in ("opening", "normal_traction", "shear_traction"):
        np.testing.assert_array_equal(data[name][:3], getattr(first, name))
    np.testing.assert_array_equal(mesh.points[:3, :2], first.points)


def test_write_fractures_without_points_writes_nothing(tmp_path):
    path = tmp_path / "fractures.vtu"
    assert write_fractures(path, []) is False
    assert not path.exists()


def test_write_pvd_lists_files(tmp_path):
    path = tmp_path / "result.pvd"
    entries = [
        (0.5, "steps/result_0001.vtu"),
        (0.5, "steps/fractures_0001.vtu"),
        (1.0, "steps/result_0002.vtu"),
        (1.0, "a&b.vtu"),
    ]
    write_pvd(path, entries)
    root = ET.parse(path).getroot()
    assert root.tag == "VTKFile" and root.attrib["type"] == "Collection"
    datasets = root.findall("./Collection/DataSet")
    assert [
        (float(d.attrib["timestep"]), d.attrib["file"]) for d in datasets
    ] == entries
    assert [d.attrib["part"] for d in datasets] == ["0", "1", "0", "1"]


# --------------------------------------------------------------------------- atomic


@pytest.mark.parametrize(
    "text",
    ["plain", 'a"b', "a'b", "a\"'b<&>", "x\ny\tz\rw", "&quot;", "", "]]>"],
)
def test_xdmf_names_read_back_by_an_xml_parser(text):
    """The XDMF writer's own escaping: an attribute value and character data
    parse back to the text (line ends in character data normalised to \\n,
    as XML does)."""
    from xfemslip.io.xdmf import _attr, _text

    element = ET.fromstring(f"<a n={_attr(text)}>{_text(text)}</a>")
    assert element.get("n") == text
    assert (element.text or "") == text.replace("\r", "\n")


def test_atomic_path_leaves_nothing_when_body_raises(tmp_path):
    final = tmp_path / "result.h5"
    with pytest.raises(RuntimeError, match="boom"), atomic_path(final) as tmp:
        tmp.write_bytes(b"partial")
        raise RuntimeError("boom")
    assert os.listdir(tmp_path) == []


def test_atomic_path_keeps_old_file_when_body_raises(tmp_path):
    final = tmp_path / "result.h5"
    final.write_bytes(b"old")
    with pytest.raises(KeyboardInterrupt), atomic_path(final) as tmp:
        tmp.write_bytes(b"partial")
        raise KeyboardInterrupt
    assert os.listdir(tmp_path) == ["result.h5"]
    assert final.read_bytes() == b"old"


def test_atomic_path_replaces_on_success(tmp_path):
    final = tmp_path / "result.pvd"
    final.write_text("old")
    with atomic_path(final) as tmp:
        assert tmp.parent == final.parent and tmp != final
        tmp.write_text("new")
        assert final.read_text() == "old"
    assert final.read_text() == "new"
    assert os.listdir(tmp_path) == ["result.pvd"]


def test_unwritable_location_gives_output_error(tmp_path):
    not_a_dir = tmp_path / "file"
    not_a_dir.write_text("")
    target = not_a_dir / "result.h5"
    with pytest.raises(OutputError, match="result.h5") as info:
        _write(target)
    assert "\n" not in str(info.value)
    with pytest.raises(OutputError, match="result.vtu"):
        write_bulk(not_a_dir / "result.vtu", _vis(), {})


@pytest.mark.skipif(
    not hasattr(os, "geteuid") or os.geteuid() == 0,
    reason="needs POSIX permissions and a non-root user",
)
def test_read_only_directory_gives_output_error(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    out.chmod(0o500)
    try:
        with pytest.raises(OutputError, match="result.pvd"):
            write_pvd(out / "result.pvd", [(1.0, "result.vtu")])
    finally:
        out.chmod(0o700)


def test_a_non_finite_field_is_refused_by_its_path(tmp_path):
    """NaN or inf in a fracture field: OutputError naming the data set's
    path in the file (built only then; the last step's copy at the root is
    written first), and no file written."""
    step = _step(2)
    step.fractures[0].slip[1] = np.inf
    with pytest.raises(OutputError, match=r"write /fractures/0/slip: 1 non-finite"):
        _write(tmp_path / "a.h5", steps=[_step(1), step])
    assert not (tmp_path / "a.h5").exists()
