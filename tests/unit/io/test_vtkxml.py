"""The VTU writer (xfemslip.io.vtkxml): what it writes reads back bit for bit
with an independent reader (meshio's), across sizes that span one and many
compression blocks, every cell type and dtype it writes; with the field
data and component names in the file's text; bad shapes refused."""

from __future__ import annotations

import meshio
import numpy as np
import pytest

from xfemslip.io import vtkxml


@pytest.mark.parametrize("n_quads", [1, 7, 5000, 30000])
def test_round_trip_through_meshio(tmp_path, n_quads):
    rng = np.random.default_rng(n_quads)
    n_points = 4 * n_quads + 3
    points = np.column_stack([rng.standard_normal((n_points, 2)), np.zeros(n_points)])
    quads = rng.integers(0, n_points, (n_quads, 4))
    tris = rng.integers(0, n_points, (3, 3))
    lines = rng.integers(0, n_points, (2, 2))
    verts = rng.integers(0, n_points, (1, 1))
    cells = [("quad", quads), ("triangle", tris), ("line", lines), ("vertex", verts)]
    point_data = {
        "u": rng.standard_normal((n_points, 3)),
        "id": np.arange(n_points, dtype=np.int64),
        "f32": rng.standard_normal(n_points).astype(np.float32),
        "big_endian": rng.standard_normal(n_points).astype(">f8"),
    }
    cell_data = {
        "s": [rng.standard_normal((c.shape[0], 6)) for _, c in cells],
        "k": [np.full(c.shape[0], j, dtype=np.int32) for j, (_, c) in enumerate(cells)],
    }
    path = tmp_path / "g.vtu"
    vtkxml.write_vtu(
        path,
        points,
        cells,
        point_data,
        cell_data,
        {"run_id": 2**62 + 5},
        {"s": ["XX", "YY", "ZZ", "XY", "YZ", "XZ"]},
    )
    back = meshio.read(path)
    assert np.array_equal(back.points, points)
    assert [(b.type, b.data.tolist()) for b in back.cells] == [
        (t, c.tolist()) for t, c in cells
    ]
    for name, values in point_data.items():
        assert np.array_equal(back.point_data[name], values), name
    for name, blocks in cell_data.items():
        for got, want in zip(back.cell_data[name], blocks, strict=True):
            assert np.array_equal(got, want), name
    assert back.field_data["run_id"].tolist() == [2**62 + 5]
    head = path.read_bytes()[:2000]
    assert b'header_type="UInt64"' in head
    assert b'compressor="vtkZLibDataCompressor"' in head
    assert (
        b'Name="run_id" NumberOfTuples="1" format="ascii">\n4611686018427387909' in head
    )
    text = path.read_bytes()
    assert b'Name="s" NumberOfComponents="6" ComponentName0="XX"' in text
    assert b'ComponentName5="XZ"' in text


def test_many_blocks_compress_in_parallel_to_the_same_bytes(tmp_path, monkeypatch):
    """The thread pool and the serial path write the same file."""
    rng = np.random.default_rng(3)
    points = np.column_stack([rng.standard_normal((200_000, 2)), np.zeros(200_000)])
    cells = [("vertex", np.arange(200_000)[:, None])]
    a, b = tmp_path / "a.vtu", tmp_path / "b.vtu"
    vtkxml.write_vtu(a, points, cells, {"x": points[:, 0]})
    monkeypatch.setattr(vtkxml, "PARALLEL_BYTES", 1 << 60)
    vtkxml.write_vtu(b, points, cells, {"x": points[:, 0]})
    assert a.read_bytes() == b.read_bytes()


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"points": np.zeros((3, 2))}, "points must be"),
        ({"cells": [("hexahedron", np.zeros((1, 8), int))]}, "cell type"),
        ({"point_data": {"u": np.zeros(2)}}, "2 rows for 3 points"),
        ({"cell_data": {"c": [np.zeros(1), np.zeros(1)]}}, "2 blocks for 1"),
        ({"cell_data": {"c": [np.zeros(2)]}}, "2 rows for 1 cells"),
        ({"point_data": {"u": np.zeros((3, 2, 2))}}, "arrays must be"),
    ],
)
def test_bad_shapes_are_refused(tmp_path, kwargs, match):
    args = {
        "points": np.zeros((3, 3)),
        "cells": [("triangle", np.array([[0, 1, 2]]))],
    }
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        vtkxml.write_vtu(tmp_path / "x.vtu", **args)


def test_incompressible_arrays_are_stored_and_read_back(tmp_path):
    """An array whose first block does not shrink below STORE_RATIO (random
    float64) is written at zlib level 0, a regular one compressed; both read
    back exactly, and the file holds the random array at about its raw size
    and the regular one in far less."""
    rng = np.random.default_rng(5)
    n = 100_000
    noise = rng.standard_normal(n)
    ramp = np.arange(n, dtype=np.float64) % 7.0
    points = np.column_stack([np.arange(n, dtype=np.float64), np.zeros(n), np.zeros(n)])
    blocks = [memoryview(noise.tobytes())[: vtkxml.BLOCK_SIZE]] * 2
    assert vtkxml._level(blocks) == 0
    assert vtkxml._level([memoryview(ramp.tobytes())[: vtkxml.BLOCK_SIZE]] * 2) == 1
    path = tmp_path / "mixed.vtu"
    cells = [("vertex", np.arange(n)[:, None])]
    vtkxml.write_vtu(path, points, cells, {"noise": noise})
    back = meshio.read(path)
    assert np.array_equal(back.point_data["noise"], noise)
    size_noise = path.stat().st_size
    vtkxml.write_vtu(path, points, cells, {"noise": ramp})
    assert np.array_equal(meshio.read(path).point_data["noise"], ramp)
    # stored: the 800 kB of noise are all in the file; the ramp compresses
    assert size_noise - path.stat().st_size > 0.9 * noise.nbytes
