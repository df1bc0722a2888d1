"""[pore_pressure] / [reservoir]: case keys, per-cell material, loads, output,
and the ``xfemslip deplete`` command (depletion)."""

from __future__ import annotations

import csv

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from xfemslip.case import build, loads_case
from xfemslip.cli import cli
from xfemslip.errors import CaseError
from xfemslip.fem.enrichment import find_candidates
from xfemslip.fem.poro import body_load
from xfemslip.simulation import build_model

BASE = {
    "domain": {"size": [100.0, 60.0]},
    "mesh": {"elements": [10, 6]},
    "material": {"E": 20.0e9, "nu": 0.25},
    "loading": {
        "initial_stress": {"xx": -44.0e6, "yy": -62.0e6},
        "stress": {"xx": -44.0e6, "yy": -62.0e6},
        "steps": 2,
    },
    "boundary": {
        "left": {"ux": 0.0},
        "right": {"ux": 0.0},
        "bottom": {"uy": 0.0},
        "top": "traction",
    },
}
PORE = {
    "pore_pressure": {"initial": 30.0e6, "change": -20.0e6, "region": "reservoir"},
    "reservoir": {"box": [0.0, 20.0, 100.0, 40.0], "E": 8.0e9, "nu": 0.2},
}
FRACTURE = {
    "fractures": [
        {"center": [51.0, 30.0], "length": 20.0, "angle": 60.0, "friction": 0.5}
    ]
}


def _case(*parts, **keys) -> str:
    """BASE with the tables of ``parts``, then the values at the dotted key
    paths ``keys`` set (None removes the key)."""
    table = dict(BASE)
    for part in parts:
        table.update(part)
    return build.case_text(build.with_keys(table, **keys))


def _problems(**keys):
    with pytest.raises(CaseError) as err:
        loads_case(_case(PORE, **keys), "p.toml")
    return dict(err.value.problems)


@pytest.mark.parametrize(
    "keys, key, words",
    [
        ({"pore_pressure.biot": 0.0}, "pore_pressure.biot", "0 <"),
        ({"pore_pressure.biot": 1.5}, "pore_pressure.biot", "<= 1"),
        (
            {
                "reservoir": None,
                "pore_pressure.initial": 1.0e6,
                "pore_pressure.change": -1.0e6,
            },
            "pore_pressure.region",
            "no [reservoir]",
        ),
        ({"reservoir.box": [50.0, 20.0, 10.0, 40.0]}, "reservoir.box", "x0 < x1"),
        (
            {"reservoir.boxes": [[0.0, 1.0, 2.0, 3.0]]},
            "reservoir",
            "exactly one of",
        ),
        ({"reservoir.box": [0.0, 20.0, 100.0]}, "reservoir.box", "4 numbers"),
        (
            {"reservoir.box": [200.0, 20.0, 300.0, 40.0]},
            "reservoir.box",
            "no element centre",
        ),
        ({"reservoir.nu": 0.5}, "reservoir.nu", "0.5"),
        (
            {"pore_pressure.change": None, "pore_pressure.chnage": -20.0e6},
            "pore_pressure.chnage",
            "did you mean 'change'",
        ),
        ({"pore_pressure.region": "res"}, "pore_pressure.region", "reservoir"),
    ],
)
def test_bad_keys_name_the_key(keys, key, words):
    problems = _problems(**keys)
    assert any(k == key and words in m for k, m in problems.items()), problems


def test_initial_pressure_needs_initial_stress():
    text = _case(PORE, **{"loading.initial_stress": None})
    with pytest.raises(CaseError) as err:
        loads_case(text, "p.toml")
    assert "loading.initial_stress" in str(err.value)
    assert "pore_pressure.initial" in str(err.value)


def test_absent_tables_change_nothing():
    """Without [pore_pressure] and [reservoir] the specs are None and the model
    is that of a case without pore pressure."""
    spec = loads_case(_case(FRACTURE), "p.toml")
    assert spec.pore_pressure is None and spec.reservoir is None
    model = build_model(spec)
    assert model.pore is None
    assert np.all(model.materials.cell == 0)


def test_reservoir_with_host_constants_gives_the_same_stiffness():
    """Per-cell material: a [reservoir] with the host's E, nu assembles the
    same K (intact and enriched cells), one with other constants does not."""
    plain = build_model(loads_case(_case(FRACTURE), "p.toml"))
    same = {"reservoir.E": 20.0e9, "reservoir.nu": 0.25}
    twin = build_model(loads_case(_case(FRACTURE, PORE, **same), "p.toml"))
    diff = abs(plain.bulk.K - twin.bulk.K).max()
    assert diff <= 1e-12 * abs(plain.bulk.K).max()
    soft = build_model(loads_case(_case(FRACTURE, PORE), "p.toml"))
    assert abs(plain.bulk.K - soft.bulk.K).max() > 0.1 * abs(plain.bulk.K).max()
    assert np.count_nonzero(soft.materials.cell) == 20  # 2 rows of 10 cells


def test_body_load_is_self_equilibrated_and_points_inwards():
    """F_body = int B^T m alpha dp: zero resultant, and under depletion the
    forces on the reservoir's top nodes point down, on its bottom nodes up."""
    model = build_model(loads_case(_case(FRACTURE, PORE), "p.toml"))
    F = body_load(model.mesh, model.bulk, model.pore, model.ec, model.kernels)
    n_std = 2 * model.mesh.n_nodes
    Fs = F[:n_std].reshape(-1, 2)
    assert abs(Fs[:, 0].sum()) < 1e-6 * np.abs(Fs).max()
    assert abs(Fs[:, 1].sum()) < 1e-6 * np.abs(Fs).max()
    y = model.mesh.nodes[:, 1]
    x = model.mesh.nodes[:, 0]
    away = np.abs(x - 51.0) > 20.0  # nodes of intact cells
    assert np.all(Fs[(y == 40.0) & away, 1] < 0.0)
    assert np.all(Fs[(y == 20.0) & away, 1] > 0.0)
    mid = (y == 30.0) & away
    inner = mid & (x > 0.0) & (x < 100.0)
    assert np.allclose(Fs[inner], 0.0, atol=1e-6 * np.abs(Fs).max())
    # on the domain's sides the reservoir edge is pulled inwards too
    assert Fs[mid & (x == 0.0), 0] > 0.0 and Fs[mid & (x == 100.0), 0] < 0.0


@pytest.fixture
def runner():
    try:
        return CliRunner(mix_stderr=False)
    except TypeError:
        return CliRunner()


def test_check_prints_the_new_tables(runner, tmp_path):
    case = tmp_path / "p.toml"
    case.write_text(_case(FRACTURE, PORE))
    result = runner.invoke(cli, ["check", str(case)])
    assert result.exit_code == 0, result.output
    assert "pore pressure: initial 30 MPa, change -20 MPa" in result.output
    assert "reservoir: E = 8 GPa, nu = 0.2 in box(es) [0, 20, 100, 40] m" in (
        result.output
    )


def test_check_prints_the_polygon_and_refuses_a_bad_one(runner, tmp_path):
    case = tmp_path / "p.toml"
    text = _case(FRACTURE, PORE, **L_POLYGON)
    case.write_text(text)
    result = runner.invoke(cli, ["check", str(case)])
    assert result.exit_code == 0, result.output
    assert (
        "in polygon [0, 20]; [100, 20]; [100, 40]; [30, 40]; [30, 60]; [0, 60] m"
        in (result.output)
    )
    crossed = [*L_POINTS[:4], L_POINTS[5], L_POINTS[4]]
    case.write_text(
        _case(FRACTURE, PORE, **{**L_POLYGON, "reservoir.polygon": crossed})
    )
    result = runner.invoke(cli, ["check", str(case)])
    assert result.exit_code == 2
    lines = [x for x in result.output.splitlines() if "reservoir.polygon" in x]
    assert len(lines) == 1 and "edges 3 and 5 cross" in lines[0], result.output


def test_bad_key_exits_2_with_one_line(runner, tmp_path):
    case = tmp_path / "bad.toml"
    case.write_text(_case(PORE, **{"reservoir.nu": 0.7}))
    result = runner.invoke(cli, ["run", str(case), "-o", str(tmp_path / "o")])
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "bad.toml" in lines[0] and "reservoir.nu" in lines[0]
    assert not (tmp_path / "o").exists()


def test_deplete_without_pore_pressure_exits_2(runner, tmp_path):
    case = tmp_path / "dry.toml"
    case.write_text(_case(FRACTURE))
    result = runner.invoke(cli, ["deplete", str(case), "-o", str(tmp_path / "o")])
    assert result.exit_code == 2
    assert "[pore_pressure]" in result.stderr
    assert not (tmp_path / "o").exists()


def test_deplete_writes_tables_and_fields(runner, tmp_path):
    case = tmp_path / "dep.toml"
    case.write_text(_case(FRACTURE, PORE))
    out = tmp_path / "out"
    result = runner.invoke(
        cli, ["deplete", str(case), "-o", str(out), "--tolerance", "5e4", "-q"]
    )
    assert result.exit_code == 0, result.output + result.stderr
    assert "critical depletion" in result.output
    rows = list(csv.DictReader((out / "critical_depletion.csv").open()))
    assert len(rows) == 1
    lo, hi = float(rows[0]["dp_lower_Pa"]), float(rows[0]["dp_upper_Pa"])
    assert -20.0e6 <= hi < lo < 0.0 and lo - hi <= 5.0e4
    table = list(csv.DictReader((out / "slip_vs_depletion.csv").open()))
    assert [float(r["dp_Pa"]) for r in table] == [0.0, -10.0e6, -20.0e6]
    with h5py.File(out / "result.h5", "r") as f:
        p = f["fields/pore_pressure"][()]
        assert set(np.round(p / 1e6, 9)) == {10.0, 30.0}
        eff, tot = f["fields/effective_stress"][()], f["fields/stress"][()]
        np.testing.assert_allclose(eff[:, :2], tot[:, :2] + p[:, None], rtol=1e-12)
        g = f["fractures/0"]
        pf = g["fluid_pressure"][()]
        np.testing.assert_allclose(
            g["effective_normal_traction"][()] - pf, g["normal_traction"][()]
        )
        assert f["fractures/0/fluid_pressure"].attrs["units"] == "Pa"
    again = runner.invoke(cli, ["deplete", str(case), "-o", str(out), "-q"])
    assert again.exit_code == 2  # output exists, no --overwrite


def test_plots_and_screen_use_the_effective_stress(runner, tmp_path):
    """The Mohr figure reads the effective normal traction, and ``screen``
    starts from the case's in-situ pore pressure p0 and follows its path."""
    from xfemslip.plot.data import figure_data

    case = tmp_path / "all.toml"
    case.write_text(_case(FRACTURE, PORE, **{"pore_pressure.region": "all"}))
    out = tmp_path / "out"
    assert runner.invoke(cli, ["run", str(case), "-o", str(out), "-q"]).exit_code == 0
    data = figure_data(out / "result.h5")
    assert data.pore_pressure == 10.0e6
    with h5py.File(out / "result.h5", "r") as f:
        eff = f["fractures/0/effective_normal_traction"][()]
    np.testing.assert_array_equal(data.fractures[0].normal_traction, eff)
    default = runner.invoke(cli, ["screen", str(case)])
    given = runner.invoke(cli, ["screen", str(case), "-p", "30.0e6"])
    assert default.exit_code == 0, default.output
    assert "pore pressure p = 30 MPa" in default.output
    assert default.output == given.output


def test_bisection_trial_falls_back_to_step_cutting(monkeypatch):
    """A bisection trial whose Newton solve fails is redone by the solver's
    step cutting from the committed state: same bracket, history untouched."""
    from xfemslip.errors import ConvergenceError
    from xfemslip.simulation import newton_solver
    from xfemslip.studies.depletion import critical_depletion

    def run(fail_call):
        model = build_model(loads_case(_case(FRACTURE, PORE), "p.toml"))
        solver = newton_solver(model)
        real, calls = solver._newton, []

        def newton(*args):
            calls.append(args)
            if len(calls) == fail_call:
                raise ConvergenceError("forced", step=2, iteration=0, residual=1.0)
            return real(*args)

        monkeypatch.setattr(solver, "_newton", newton)
        onsets, results = critical_depletion(solver, model, 2, 1.0e4)
        return onsets[0], results, model.contact, len(calls)

    plain, res_plain, c_plain, n_plain = run(fail_call=0)
    cut, res_cut, c_cut, n_cut = run(fail_call=3)  # steps 1, 2, then trial 1
    assert n_cut == n_plain + 1
    assert (cut.dp_lower, cut.dp_upper) == (plain.dp_lower, plain.dp_upper)
    assert len(res_cut) == len(res_plain) == 2
    np.testing.assert_array_equal(c_cut.slip_committed, c_plain.slip_committed)


def test_deplete_failure_keeps_the_converged_steps(runner, tmp_path, monkeypatch):
    """A load step that fails: exit 1, result.h5 of the converged steps with
    converged = false, and the tables written (like `run`)."""
    from xfemslip.errors import ConvergenceError
    from xfemslip.solve import newton as solver_module

    real = solver_module.NewtonSolver._newton

    def newton(self, u, lam, k, steps, contact=None):
        if k == 2:
            raise ConvergenceError(
                "load step 2 did not converge: forced",
                step=2,
                iteration=3,
                residual=1.0,
            )
        return real(self, u, lam, k, steps, contact)

    monkeypatch.setattr(solver_module.NewtonSolver, "_newton", newton)
    case = tmp_path / "dep.toml"
    case.write_text(_case(FRACTURE, PORE))
    out = tmp_path / "out"
    result = runner.invoke(cli, ["deplete", str(case), "-o", str(out), "-q"])
    assert result.exit_code == 1
    assert "load step 2 did not converge" in result.stderr
    with h5py.File(out / "result.h5", "r") as f:
        assert not bool(f.attrs["converged"])
        assert "fields/pore_pressure" in f
    rows = list(csv.DictReader((out / "slip_vs_depletion.csv").open()))
    assert [float(r["dp_Pa"]) for r in rows] == [0.0, -10.0e6]


# ------------------------------------------- per-QP regions in enriched cells
# A vertical fracture through the whole domain at x = 0.5, in the middle of
# the column 0.4 < x < 0.6; the reservoir box is the part left of it, so its
# edge x = 0.5 runs along the fracture, mid-cell.
def _split_case(E) -> str:
    """The case above with the reservoir's Young's modulus E [Pa]."""
    return build.case_text(
        {
            "mesh": {
                "x": [0.0, 0.2, 0.4, 0.6, 0.8, 1.0],
                "y": [0.0, 0.3, 0.6, 1.0],
            },
            "material": {"E": 20.0e9, "nu": 0.25},
            "reservoir": {"box": [0.0, 0.0, 0.5, 1.0], "E": E, "nu": 0.3},
            "pore_pressure": {
                "initial": 30.0e6,
                "change": -20.0e6,
                "biot": 0.7,
                "region": "reservoir",
            },
            "fractures": [{"points": [[0.5, 0.0], [0.5, 1.0]], "friction": 0.5}],
            "loading": {"initial_stress": {"xx": -44.0e6, "yy": -62.0e6}},
            "boundary": {"left": {"ux": 0.0}, "bottom": {"uy": 0.0}},
        }
    )


def _hat(nodes, v):
    """Values at v of the 1D hat functions of the sorted nodes."""
    return np.array(
        [np.interp(v, nodes, np.eye(nodes.size)[i]) for i in range(nodes.size)]
    )


def _hat_integral(nodes, lo, hi):
    """int_lo^hi of each 1D hat function (exact: trapezoid on refined nodes)."""
    t = np.unique(np.concatenate([nodes[(nodes > lo) & (nodes < hi)], [lo, hi]]))
    f = np.array([np.interp(t, nodes, row) for row in np.eye(nodes.size)])
    return np.sum(0.5 * (f[:, 1:] + f[:, :-1]) * np.diff(t), axis=1)


def test_body_load_splits_cut_cells_at_the_fracture(caplog):
    """Biot load of a region bounded by a fracture that cuts cells mid-cell,
    against the divergence theorem: int_R dN_a/dx dOmega = oint N_a n_x ds on
    the boundary of R = [0, 0.5] x [0, 1], with N_a = hat_i(x) hat_j(y); an
    enriched (Heaviside, shifted) dof of node a carries (H_R - H_a) times the
    same integral (H_R = +1: R is the fracture's + side).  Classifying the cut
    cells by their centre (x = 0.5, in neither part) drops their load."""
    model = build_model(loads_case(_split_case(20.0e9), "split.toml"))
    assert "not on a mesh line" not in caplog.text  # the fracture covers the edge
    mesh, pore = model.mesh, model.pore
    F = body_load(mesh, model.bulk, pore, model.ec, model.kernels)
    q = 0.7 * -20.0e6
    x, y = mesh.x, mesh.y
    ix = np.searchsorted(x, mesh.nodes[:, 0])
    iy = np.searchsorted(y, mesh.nodes[:, 1])
    fx = (_hat(x, 0.5) - _hat(x, 0.0))[ix] * _hat_integral(y, 0.0, 1.0)[iy]
    fy = (_hat(y, 1.0) - _hat(y, 0.0))[iy] * _hat_integral(x, 0.0, 0.5)[ix]
    ref = q * np.column_stack([fx, fy])
    n_std = 2 * mesh.n_nodes
    scale = np.abs(ref).max()
    np.testing.assert_allclose(F[:n_std].reshape(-1, 2), ref, atol=1e-12 * scale)
    cand, dofmap = find_candidates(mesh, model.fractures), model.bulk.dofmap
    H_a = np.where(model.fractures[0].side(mesh.nodes[cand.node]) >= 0, 1.0, -1.0)
    kept = dofmap.cand_dof >= 0
    assert kept.sum() == 8  # the 8 nodes of the cut column
    for k in np.nonzero(kept)[0]:
        d = dofmap.cand_dof[k]
        want = (1.0 - H_a[k]) * ref[cand.node[k]]
        np.testing.assert_allclose(F[d : d + 2], want, atol=1e-12 * scale)
    # the cut cells report half the change, the others all or nothing
    b = mesh.bounds
    cut = (b[:, 0] < 0.5) & (b[:, 1] > 0.5)
    np.testing.assert_allclose(pore.cell_fraction[cut], 0.5, rtol=1e-12)
    left = b[:, 1] <= 0.4
    np.testing.assert_array_equal(pore.cell_fraction[~cut], left[~cut])


def test_enriched_stiffness_takes_the_material_of_each_quadrature_point():
    """K_e of the cut cells = sum_q B_q^T D(x_q) B_q w_q, D of the reservoir
    left of the fracture and of the host right of it, against the point-by-
    point NumPy reference of test_kernels_bulk (not the D-difference form of
    assembly._enriched_matrices)."""
    from tests.support.bulk_reference import enriched_reference
    from xfemslip.fem.assembly import _enriched_matrices

    model = build_model(loads_case(_split_case(5.0e9), "split.toml"))
    ec, mats = model.ec, model.materials
    assert set(np.unique(mats.qp)) == {0, 1}
    K, _ = _enriched_matrices(
        model.mesh, ec, mats.D, mats.cell[ec.cells], mats.qp, backend=model.kernels
    )
    for e in range(ec.cells.size):
        q0, q1 = ec.qp_offsets[e], ec.qp_offsets[e + 1]
        K_ref = 0.0
        for q in range(q0, q1):
            K_ref = (
                K_ref
                + enriched_reference(
                    model.mesh.bounds[ec.cells[e]],
                    ec.qp_xy[q : q + 1],
                    ec.qp_w[q : q + 1],
                    *ec.qp_values([q]),
                    ec.slot_node[e],
                    ec.slot_fnode[e],
                    mats.D[mats.qp[q]],
                )[0]
            )
        np.testing.assert_allclose(K[e], K_ref, atol=1e-12 * np.abs(K_ref).max())
    # the QPs left of the fracture are reservoir, right of it host
    left = ec.qp_xy[:, 0] < 0.5
    assert np.all(mats.qp[left] == 1) and np.all(mats.qp[~left] == 0)


# ------------------------------------------------------------ polygon reservoir
L_POINTS = [
    [0.0, 20.0],
    [100.0, 20.0],
    [100.0, 40.0],
    [30.0, 40.0],
    [30.0, 60.0],
    [0.0, 60.0],
]
NO_BOX = {"reservoir.box": None}
L_BOXES = {
    **NO_BOX,
    "reservoir.boxes": [[0.0, 20.0, 100.0, 40.0], [0.0, 40.0, 30.0, 60.0]],
}
L_POLYGON = {**NO_BOX, "reservoir.polygon": L_POINTS}


@pytest.mark.parametrize(
    "keys, key, words",
    [
        (
            {**NO_BOX, "reservoir.polygon": [[0.0, 20.0], [100.0, 20.0]]},
            "reservoir.polygon",
            "at least 3",
        ),
        (
            {
                **NO_BOX,
                "reservoir.polygon": [[0.0, 20.0], [100.0, 20.0, 1.0], [50.0, 40.0]],
            },
            "reservoir.polygon[1]",
            "2 numbers",
        ),
        (
            {
                **NO_BOX,
                "reservoir.polygon": [
                    [0.0, 20.0],
                    [100.0, 40.0],
                    [100.0, 20.0],
                    [0.0, 40.0],
                ],
            },
            "reservoir.polygon",
            "edges 0 and 2 cross",
        ),
        (
            {**NO_BOX, "reservoir.polygon": [[0.0, 20.0], [50.0, 30.0], [100.0, 40.0]]},
            "reservoir.polygon",
            "zero area",
        ),
        (
            {
                **NO_BOX,
                "reservoir.polygon": [
                    [0.0, 20.0],
                    [0.0, 20.0],
                    [50.0, 30.0],
                    [0.0, 40.0],
                ],
            },
            "reservoir.polygon",
            "coincide",
        ),
        (
            {
                **NO_BOX,
                "reservoir.polygon": [[200.0, 0.0], [300.0, 0.0], [300.0, 50.0]],
            },
            "reservoir.polygon",
            "no element centre",
        ),
        (
            {**NO_BOX, "reservoir.polygon": [[0.0, 20.0], [100.0, 20.0], ["a", 40.0]]},
            "reservoir.polygon[2][0]",
            "",
        ),
        ({"reservoir.polygon": L_POINTS}, "reservoir", "exactly one of"),
    ],
)
def test_bad_polygon_names_the_key(keys, key, words):
    problems = _problems(**keys)
    assert any(k == key and words in m for k, m in problems.items()), problems


def test_polygon_equals_the_same_region_as_boxes():
    """An L-shaped polygon on mesh lines builds the same model as the union of
    two boxes: cell materials, stiffness, Biot and fracture loads."""
    models = [
        build_model(
            loads_case(
                _case(FRACTURE, PORE, **s),
                "p.toml",
            )
        )
        for s in (L_BOXES, L_POLYGON)
    ]
    a, b = models
    assert np.count_nonzero(a.materials.cell) == 2 * 10 + 2 * 3
    np.testing.assert_array_equal(a.materials.cell, b.materials.cell)
    np.testing.assert_array_equal(a.materials.qp, b.materials.qp)
    assert abs(a.bulk.K - b.bulk.K).max() == 0.0
    np.testing.assert_array_equal(a.problem.F_unit, b.problem.F_unit)
    np.testing.assert_array_equal(a.pore.point_ratio, b.pore.point_ratio)


def _clipped_area(bounds, p, n):
    """Area of the rectangle [x0, x1, y0, y1] on the side (x - p).n < 0."""
    x0, x1, y0, y1 = bounds
    poly = [np.array(v) for v in ((x0, y0), (x1, y0), (x1, y1), (x0, y1))]
    out = []
    for i, v in enumerate(poly):
        w = poly[(i + 1) % 4]
        dv, dw = (v - p) @ n, (w - p) @ n
        if dv < 0:
            out.append(v)
        if (dv < 0) != (dw < 0):
            out.append(v + dv / (dv - dw) * (w - v))
    P = np.array(out)
    return 0.5 * abs(
        np.sum(P[:, 0] * np.roll(P[:, 1], -1) - np.roll(P[:, 0], -1) * P[:, 1])
    )


def test_polygon_edge_along_an_inclined_fault(caplog):
    """A trapezoidal reservoir whose slanted edge runs along an inclined fault
    through the domain: the cut cells' pressure fraction is the exact area of
    the cell below the fault (half-plane clipping), no warning is logged for
    that edge, and one is for a slanted edge without a fault."""
    caplog.set_level("WARNING", logger="xfemslip.fem.poro")
    model = build_model(loads_case(_trapezoid_case(True), "tri.toml"))
    assert "polygon edge 0" not in caplog.text
    b = model.mesh.bounds
    p, t = np.array([0.0, 7.0]), np.array([100.0, 40.0]) / np.hypot(100.0, 40.0)
    n = np.array([-t[1], t[0]])
    cut = np.unique(model.fractures[0].piece_cell)
    area = (b[cut, 1] - b[cut, 0]) * (b[cut, 3] - b[cut, 2])
    want = np.array([_clipped_area(b[c], p, n) for c in cut]) / area
    assert np.all((want > 0.0) & (want < 1.0))
    np.testing.assert_allclose(model.pore.cell_fraction[cut], want, rtol=1e-10)
    np.testing.assert_allclose(model.pore.point_ratio, 0.5, rtol=0)
    caplog.clear()
    build_model(loads_case(_trapezoid_case(False), "tri.toml"))
    assert "polygon edge 0 is not on a mesh line" in caplog.text


def _trapezoid_case(fault):
    """Trapezoidal reservoir below the line (0, 7)-(100, 47), with or without a
    fault along that line."""
    trapezoid = [[0.0, 7.0], [100.0, 47.0], [100.0, 0.0], [0.0, 0.0]]
    fracture = {"points": [[0.0, 7.0], [100.0, 47.0]], "friction": 0.5}
    return _case(
        PORE,
        **NO_BOX,
        **{"reservoir.polygon": trapezoid, "fractures": [fracture] if fault else None},
    )
