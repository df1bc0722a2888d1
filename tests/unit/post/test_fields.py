"""The stress as ParaView reads it: a symmetric tensor in VTK's order and
two invariants, against closed forms and read back from result.vtu."""

from __future__ import annotations

import math
from pathlib import Path

import meshio
import numpy as np
import pytest

import xfemslip
from xfemslip.post.fields import stress_for_paraview

CASE = Path(__file__).resolve().parents[3] / "cases" / "reservoir_depletion.toml"


@pytest.mark.parametrize(
    ("stress", "szz", "mean", "von_mises"),
    [
        ((-10.0, 0.0, 0.0), 0.0, -10.0 / 3, 10.0),  # uniaxial: |s|
        ((-7.0, -7.0, 0.0), -7.0, -7.0, 0.0),  # hydrostatic: no deviator
        ((0.0, 0.0, 4.0), 0.0, 0.0, math.sqrt(3.0) * 4.0),  # pure shear: sqrt(3) tau
        ((3.0, -3.0, 0.0), 0.0, 0.0, math.sqrt(27.0)),  # plane shear at 45 deg
    ],
)
def test_invariants_of_known_states(stress, szz, mean, von_mises):
    out = stress_for_paraview(np.array([stress]), np.array([szz]))
    assert out["mean_stress"][0] == pytest.approx(mean, abs=1e-12)
    assert out["von_mises"][0] == pytest.approx(von_mises, abs=1e-12)
    sxx, syy, sxy = stress
    np.testing.assert_array_equal(out["stress_tensor"][0], [sxx, syy, szz, sxy, 0, 0])


def test_von_mises_is_invariant_under_rotation():
    rng = np.random.default_rng(3)
    s = rng.normal(size=(50, 3)) * 1e6
    szz = rng.normal(size=50) * 1e6
    a = rng.uniform(0.0, math.pi, 50)
    c, n = np.cos(a), np.sin(a)
    sxx = c * c * s[:, 0] + n * n * s[:, 1] + 2 * c * n * s[:, 2]
    syy = n * n * s[:, 0] + c * c * s[:, 1] - 2 * c * n * s[:, 2]
    sxy = c * n * (s[:, 1] - s[:, 0]) + (c * c - n * n) * s[:, 2]
    rotated = np.column_stack([sxx, syy, sxy])
    one, two = stress_for_paraview(s, szz), stress_for_paraview(rotated, szz)
    np.testing.assert_allclose(one["von_mises"], two["von_mises"], rtol=1e-10)
    np.testing.assert_allclose(one["mean_stress"], two["mean_stress"], rtol=1e-10)


def test_result_vtu_carries_the_tensor_and_invariants(tmp_path):
    spec = xfemslip.load_case(CASE)
    result = xfemslip.run_case(spec, tmp_path / "out")
    vtu = meshio.read(tmp_path / "out" / "result.vtu")
    cell = np.concatenate(vtu.cell_data["cell_id"])
    tensor = np.concatenate(vtu.cell_data["stress_tensor"])
    assert tensor.shape == (cell.size, 6)
    final = result.final
    np.testing.assert_array_equal(tensor[:, [0, 1, 3]], final.stress[cell])
    np.testing.assert_array_equal(tensor[:, 2], final.stress_zz[cell])
    # von Mises from the in-plane principal stresses and szz
    s1, s2 = final.principal_stress[cell].T
    s3 = final.stress_zz[cell]
    expected = np.sqrt(0.5 * ((s1 - s2) ** 2 + (s2 - s3) ** 2 + (s3 - s1) ** 2))
    vm = np.concatenate(vtu.cell_data["von_mises"])
    np.testing.assert_allclose(vm, expected, rtol=1e-9)


@pytest.mark.parametrize(
    "polylines",
    [
        [[[0.2, 0.2], [0.8, 0.8]], [[0.2, 0.75], [0.75, 0.2]]],  # X junction
        [[[0.15, 0.3], [0.85, 0.62]], [[0.5, 0.46], [0.42, 0.85]]],  # T junction
    ],
    ids=["X", "T"],
)
def test_face_displacements_jump_by_slip_and_opening(polylines):
    """The two faces of every fracture (fractures.vtu's displacement and
    jump) evaluated on each side of the junction functions too: u+ - u-
    projected on t and n is the slip and the opening that the contact's own
    jump operators give."""
    from xfemslip.case import build, loads_case
    from xfemslip.post.fields import fracture_faces, fracture_fields
    from xfemslip.simulation import build_model, newton_solver

    text = build.case_text(
        {
            "domain": {"size": [1.0, 1.0]},
            "mesh": {"elements": [20, 20]},
            "material": {"E": 5.0e9, "nu": 0.3},
            "fractures": [
                {"points": p, "friction": 0.2, "kn": 5e12, "kt": 5e12, "tip": "ramp"}
                for p in polylines
            ],
            "loading": {"stress": {"xx": -20.0e6, "yy": -40.0e6, "xy": 5.0e6}},
            "boundary": {
                "bottom": {"uy": 0.0},
                "top": "traction",
                "left": "traction",
                "right": "traction",
            },
        }
    )
    model = build_model(loads_case(text, "faces.toml"))
    solver = newton_solver(model)
    solver.run(1)
    result = solver.completed[-1]
    faces = fracture_faces(model, result.u)
    fields = fracture_fields(model.ip, result.contact, len(model.fractures))
    assert max(np.abs(f.slip).max() for f in fields) > 1e-6  # they slip
    for fi, ((u_minus, u_plus), f) in enumerate(zip(faces, fields, strict=True)):
        t = np.subtract(*polylines[fi][::-1])
        t /= np.linalg.norm(t)
        n = np.array([-t[1], t[0]])
        jump = u_plus - u_minus
        scale = np.abs(f.slip).max()
        np.testing.assert_allclose(jump @ t, f.slip, atol=1e-9 * scale)
        np.testing.assert_allclose(jump @ n, f.opening, atol=1e-9 * scale)
