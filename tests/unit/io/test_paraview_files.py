"""The ParaView files of a run read back with VTK's own readers (the `vtk`
wheel): arrays, component counts and names, time values, and the fracture
displacement against the bulk mesh it must move with (output-format.md,
paraview.md)."""

from __future__ import annotations

import textwrap
import xml.etree.ElementTree as ET

import h5py
import meshio
import numpy as np
import pytest

vtk = pytest.importorskip("vtk")
from vtk.util.numpy_support import vtk_to_numpy  # noqa: E402

from xfemslip.case import load_case  # noqa: E402
from xfemslip.simulation import run_case  # noqa: E402
from xfemslip.studies.depletion import deplete  # noqa: E402

STEPS = 3

# An inclined fracture in a compressed block: it slips (friction 0.2 at 30
# degrees from the load) with a jump of about 1e-4 m.
CASE = textwrap.dedent(
    f"""
    name = "paraview-files"
    [domain]
    size = [1.0, 1.0]
    [mesh]
    elements = [24, 24]
    [material]
    E = 1.0e9
    nu = 0.25
    [[fractures]]
    points = [[0.3, 0.35], [0.7, 0.65]]
    friction = 0.2
    kn = 1.0e12
    kt = 1.0e12
    [loading]
    steps = {STEPS}
    [boundary]
    bottom = {{ ux = 0.0, uy = 0.0 }}
    top = {{ uy = -2.0e-3 }}
    """
)


def _read_vtu(path):
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    return reader.GetOutput()


def _array(data, name) -> tuple[np.ndarray, list]:
    array = data.GetArray(name)
    assert array is not None, name
    names = [array.GetComponentName(k) for k in range(array.GetNumberOfComponents())]
    return vtk_to_numpy(array), names


def _pvd(path) -> list[tuple[float, str]]:
    root = ET.parse(path).getroot()
    return [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("paraview") / "out"
    case = folder.parent / "case.toml"
    case.write_text(CASE)
    result = run_case(load_case(case), folder)
    slip = np.abs(result.steps[-1].fractures[0].slip).max()
    assert slip > 1e-5  # the fracture slips: the jump is worth warping
    return folder


def test_bulk_stress_arrays_are_named_tensors_and_invariants(run):
    cells = _read_vtu(run / "result.vtu").GetCellData()
    tensor, names = _array(cells, "stress_tensor")
    assert tensor.shape[1] == 6 and names == ["XX", "YY", "ZZ", "XY", "YZ", "XZ"]
    stress, names = _array(cells, "stress")
    assert names == ["XX", "YY", "XY"]
    principal, names = _array(cells, "principal_stress")
    assert names == ["max", "min"]
    szz, _ = _array(cells, "stress_zz")
    np.testing.assert_array_equal(tensor[:, [0, 1, 3]], stress)
    np.testing.assert_array_equal(tensor[:, 2], szz)
    # the invariants from the principal stresses (an independent route)
    s1, s2, s3 = principal[:, 0], principal[:, 1], szz
    mean, _ = _array(cells, "mean_stress")
    von_mises, _ = _array(cells, "von_mises")
    scale = np.abs(principal).max()
    np.testing.assert_allclose(mean, (s1 + s2 + s3) / 3, atol=1e-12 * scale)
    vm = np.sqrt(0.5 * ((s1 - s2) ** 2 + (s2 - s3) ** 2 + (s3 - s1) ** 2))
    np.testing.assert_allclose(von_mises, vm, atol=1e-9 * scale)


def test_fracture_faces_carry_the_jump_and_sit_on_the_bulk(run):
    fractures = _read_vtu(run / "fractures.vtu")
    points = fractures.GetPointData()
    mean, _ = _array(points, "displacement")
    jump, _ = _array(points, "displacement_jump")
    slip, _ = _array(points, "slip")
    opening, _ = _array(points, "opening")
    assert mean.shape[1] == 3 and jump.shape[1] == 3
    assert not mean[:, 2].any() and not jump[:, 2].any()
    t = np.array([0.4, 0.3]) / 0.5  # the fracture's tangent, first to last point
    n = np.array([-t[1], t[0]])
    np.testing.assert_allclose(jump[:, :2] @ t, slip, atol=1e-9 * np.abs(slip).max())
    np.testing.assert_allclose(jump[:, :2] @ n, opening, atol=1e-9 * np.abs(slip).max())
    # each face is where the bulk mesh's side of the fracture is: probe the
    # split cells of result.vtu just off the fracture on either side (1e-4 m,
    # 1/400 of a cell: closer, VTK's point location tolerance may pick the
    # cell on the other side)
    xyz = vtk_to_numpy(fractures.GetPoints().GetData())
    s, _ = _array(points, "s")
    sides = {}
    for sign in (1.0, -1.0):
        probe_points = vtk.vtkPoints()
        for p in xyz + sign * 1e-4 * np.append(n, 0.0):
            probe_points.InsertNextPoint(*p)
        probe_set = vtk.vtkPolyData()
        probe_set.SetPoints(probe_points)
        probe = vtk.vtkProbeFilter()
        probe.SetInputData(probe_set)
        probe.SetSourceData(_read_vtu(run / "result.vtu"))
        probe.Update()
        found = probe.GetOutput().GetPointData().GetArray("vtkValidPointMask")
        assert vtk_to_numpy(found).all()
        sides[sign] = _array(probe.GetOutput().GetPointData(), "displacement")[0]
    # The split cells interpolate linearly between their vertices on the
    # fracture, the XFEM field is bilinear (and ramped in the tip cells, where
    # the split cells show less of the jump): equal to a small part of the
    # jump, the faces two cells or more from a tip, the mean everywhere.
    tolerance = 0.02 * np.abs(jump).max()
    inner = (s > 2.0 / 24) & (s < 0.5 - 2.0 / 24)
    for sign, body in sides.items():
        face = mean + sign * 0.5 * jump
        assert np.abs(body - face)[inner].max() < tolerance
    both = 0.5 * (sides[1.0] + sides[-1.0])
    assert np.abs(both - mean).max() < tolerance


def test_two_series_over_every_step_timed_by_load_factor(run):
    with h5py.File(run / "result.h5") as h5:
        factors = [float(g.attrs["load_factor"]) for g in h5["steps"].values()]
    np.testing.assert_allclose(factors, np.arange(1, STEPS + 1) / STEPS)
    body, cracks = _pvd(run / "result.pvd"), _pvd(run / "fractures.pvd")
    assert [t for t, _ in body] == factors == [t for t, _ in cracks]
    assert [f for _, f in cracks] == [
        f"steps/fractures_{k:04d}.vtu" for k in range(1, STEPS + 1)
    ]
    for (_, b), (_, c) in zip(body, cracks, strict=True):
        reader = vtk.vtkXMLGenericDataObjectReader()
        reader.SetFileName(str(run / c))
        reader.Update()
        assert reader.GetOutput().GetPointData().GetArray("displacement") is not None
        assert _read_vtu(run / b).GetNumberOfCells() > 24 * 24  # split cells


def test_xdmf_opens_result_h5_with_vtk_and_meshio(run):
    mesh = meshio.read(run / "result.xdmf")
    with h5py.File(run / "result.h5") as h5:
        np.testing.assert_array_equal(mesh.points[:, :2], h5["mesh/points"][()])
        np.testing.assert_array_equal(mesh.cells_dict["quad"], h5["mesh/cells"][()])
        np.testing.assert_array_equal(
            mesh.point_data["displacement"], h5["fields/displacement"][()]
        )
        for name in ("stress", "stress_zz", "principal_stress"):
            np.testing.assert_array_equal(mesh.cell_data[name][0], h5["fields"][name])
        steps = [g["fields/displacement"][()] for g in h5["steps"].values()]
        factors = [float(g.attrs["load_factor"]) for g in h5["steps"].values()]
    reader = vtk.vtkXdmfReader()
    reader.SetFileName(str(run / "result_steps.xdmf"))
    reader.UpdateInformation()
    key = vtk.vtkStreamingDemandDrivenPipeline.TIME_STEPS()
    times = list(reader.GetOutputInformation(0).Get(key))
    np.testing.assert_allclose(times, factors)
    for time, expected in zip(times, steps, strict=True):
        reader.UpdateTimeStep(time)
        grid = reader.GetOutputDataObject(0)
        u, _ = _array(grid.GetPointData(), "displacement")
        assert u.shape == (expected.shape[0], 3)  # padded with z = 0 for warping
        np.testing.assert_array_equal(u[:, :2], expected)


DEPLETION = textwrap.dedent(
    """
    name = "paraview-depletion"
    [domain]
    size = [100.0, 100.0]
    [mesh]
    elements = [16, 16]
    [material]
    E = 10.0e9
    nu = 0.25
    [pore_pressure]
    initial = 20.0e6
    change = -8.0e6
    [[fractures]]
    center = [50.0, 50.0]
    length = 30.0
    angle = 60.0
    friction = 0.6
    [loading]
    initial_stress = { xx = -30.0e6, yy = -50.0e6, xy = 0.0 }
    stress = { xx = -30.0e6, yy = -50.0e6, xy = 0.0 }
    steps = 4
    [boundary]
    left = { ux = 0.0 }
    right = { ux = 0.0 }
    bottom = { uy = 0.0 }
    top = "traction"
    """
)


def test_depletion_series_are_timed_by_the_pore_pressure_change(tmp_path):
    case = tmp_path / "case.toml"
    case.write_text(DEPLETION)
    deplete(load_case(case), tmp_path / "out")
    # |dp| at steps 1..4 of -8 MPa: 2, 4, 6, 8 MPa, increasing as ParaView plays
    expected = [2.0e6, 4.0e6, 6.0e6, 8.0e6]
    for name in ("result.pvd", "fractures.pvd"):
        times = [t for t, _ in _pvd(tmp_path / "out" / name)]
        np.testing.assert_allclose(times, expected, rtol=1e-12)
    reader = vtk.vtkXdmfReader()
    reader.SetFileName(str(tmp_path / "out" / "result_steps.xdmf"))
    reader.UpdateInformation()
    key = vtk.vtkStreamingDemandDrivenPipeline.TIME_STEPS()
    times = reader.GetOutputInformation(0).Get(key)
    np.testing.assert_allclose(times, expected, rtol=1e-12)
