"""The NumPy kernels (kernels/vectorized.py) against the Numba kernels, and the
backend choice.

The two backends are independent implementations of the same formulas (loops
over cells and points in Numba; whole-array products in NumPy), so each is the
other's reference (house style, kernels rule 8); the Numba kernels are also
tested against the closed forms and dense references of test_kernels_*.py.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.support.casegen import sweep_member
from xfemslip import kernels
from xfemslip.case import build, load_case, loads_case
from xfemslip.conventions import OPEN, SLIP, STICK, TANGENT_CONSISTENT, TANGENT_SECANT
from xfemslip.fem.assembly import _enriched_matrices
from xfemslip.fem.enrichment import build_enriched_cells, find_candidates
from xfemslip.fem.material import elasticity_matrix
from xfemslip.kernels import vectorized
from xfemslip.simulation import _geometry, build_model, kernel_work
from xfemslip.solve.newton import NewtonSolver

ROOT = Path(__file__).resolve().parents[3]
NUMBA = kernels.backend("numba")


def _rel(a, b):
    return np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300)


def test_rectangle_stiffness_agrees():
    rng = np.random.default_rng(1)
    hx, hy = rng.uniform(0.05, 3.0, 7), rng.uniform(0.05, 3.0, 7)
    D = elasticity_matrix(7.0e9, 0.27, "plane_strain")
    want = NUMBA.rectangle_stiffness(hx, hy, D)
    got = vectorized.rectangle_stiffness(hx, hy, D)
    assert _rel(got, want) < 1e-14
    # and a physical fact both must share: rigid translations have no energy
    assert np.max(np.abs(got @ np.tile([1.0, 0.0], 4))) < 1e-6 * np.max(np.abs(got))


def _enriched_both(text, folder):
    """(K, Bbar) of every enriched cell of a case, by each backend, through
    the assembly's own call (assembly._enriched_matrices)."""
    spec = loads_case(text, folder / "case.toml")
    mesh, fractures = _geometry(spec)
    ec = build_enriched_cells(mesh, fractures, find_candidates(mesh, fractures))
    D = elasticity_matrix(spec.material.E, spec.material.nu, spec.material.model)
    return tuple(
        _enriched_matrices(mesh, ec, D, None, backend=name)
        for name in ("numba", "numpy")
    )


@pytest.mark.parametrize(
    "case, elements",
    [("reservoir_depletion.toml", [17, 23]), ("fracture_network.toml", [40, 40])],
    ids=["branch-tip", "network-junctions"],
)
def test_enriched_cell_matrices_agree(case, elements, tmp_path):
    shipped = build.file_case(ROOT / "cases" / case, **{"mesh.elements": elements})
    text = build.case_text(shipped)
    (K0, B0), (K1, B1) = _enriched_both(text, tmp_path)
    assert K1.shape == K0.shape and B1.shape == B0.shape
    assert K0.shape[0] > 50  # the case has enriched cells to compare
    assert _rel(K1, K0) < 1e-13
    assert _rel(B1, B0) < 1e-13


def test_numpy_cell_matrices_do_not_depend_on_their_batches(tmp_path, monkeypatch):
    """The NumPy kernel's batched products (cells of one rule together, at
    most BATCH_CELLS cells and BATCH_POINTS points a batch): one cell a batch
    gives the same K and Bbar, bit for bit, on a case whose cells have rules
    of several sizes."""
    shipped = build.file_case(
        ROOT / "cases" / "reservoir_depletion.toml", **{"mesh.elements": [17, 23]}
    )
    spec = loads_case(build.case_text(shipped), tmp_path / "case.toml")
    mesh, fractures = _geometry(spec)
    ec = build_enriched_cells(mesh, fractures, find_candidates(mesh, fractures))
    D = elasticity_matrix(spec.material.E, spec.material.nu, spec.material.model)
    assert np.unique(np.diff(ec.qp_offsets)).size > 1  # several rules
    K0, B0 = _enriched_matrices(mesh, ec, D, None, backend="numpy")
    monkeypatch.setattr(vectorized, "BATCH_CELLS", 1)
    K1, B1 = _enriched_matrices(mesh, ec, D, None, backend="numpy")
    monkeypatch.setattr(vectorized, "BATCH_CELLS", 1000)
    monkeypatch.setattr(vectorized, "BATCH_POINTS", 100)  # below one rule's size
    K2, B2 = _enriched_matrices(mesh, ec, D, None, backend="numpy")
    np.testing.assert_array_equal(K1, K0)
    np.testing.assert_array_equal(K2, K0)
    np.testing.assert_array_equal(B1, B0)
    np.testing.assert_array_equal(B2, B0)


def _contact_points(rng, n=600, J=3):
    dofs = rng.integers(0, 40, size=(n, 2 * J))
    dofs[rng.random((n, 2 * J)) < 0.15] = -1
    angle = rng.uniform(0, np.pi, n)
    normal = np.column_stack([np.cos(angle), np.sin(angle)])
    tangent = np.column_stack([-normal[:, 1], normal[:, 0]])
    friction = rng.uniform(0.0, 0.8, n)
    cohesion = rng.uniform(0.0, 1e6, n) * (rng.random(n) < 0.5)
    # two thirds of the points weaken (friction, and cohesion on half of
    # those), over slip distances of a few penalty slips, from accumulated
    # slips before, within and past the weakening range
    weak = rng.random(n) < 2.0 / 3.0
    distance = np.where(weak, rng.uniform(2e-6, 5e-5, n), np.inf)
    return dict(
        ip_dofs=dofs.astype(np.int64),
        ip_coef=rng.uniform(-2.0, 2.0, (n, J)),
        ip_normal=normal,
        ip_tangent=tangent,
        ip_weight=rng.uniform(0.01, 0.1, n),
        pn0=-rng.uniform(0.0, 2e7, n),
        slip_old=rng.normal(0.0, 1e-5, n),
        accumulated_old=np.where(weak, rng.uniform(0.0, 1.2, n) * distance, 0.0),
        kn=rng.uniform(1e12, 1e14, n),
        kt=rng.uniform(1e12, 1e14, n),
        friction=friction,
        cohesion=cohesion,
        friction_dynamic=np.where(weak, friction * rng.uniform(0.3, 1.0, n), friction),
        cohesion_dynamic=np.where(weak & (rng.random(n) < 0.5), 0.0, cohesion),
        slip_distance=distance,
    )


def _respond(impl, u, pts, mode, pt_prev, gt_prev):
    n, J2 = pts["ip_dofs"].shape
    out = dict(
        out_f=np.zeros((n, J2)),
        out_K=np.zeros((n, J2, J2)),
        out_gn=np.zeros(n),
        out_gt=np.zeros(n),
        out_pn=np.zeros(n),
        out_pt=np.zeros(n),
        out_state=np.zeros(n, np.int8),
        out_slip=np.zeros(n),
        out_accumulated=np.zeros(n),
    )
    impl.contact_response(u, **pts, tangent_mode=mode, pt_prev=pt_prev,
                          gt_prev=gt_prev, **out)  # fmt: skip
    return out


@pytest.mark.parametrize("mode", [TANGENT_CONSISTENT, TANGENT_SECANT])
def test_contact_response_agrees(mode):
    rng = np.random.default_rng(7)
    pts = _contact_points(rng)
    u = rng.normal(0.0, 2e-5, 40)
    n = pts["ip_dofs"].shape[0]
    pt_prev = rng.normal(0.0, 1e6, n)
    gt_prev = rng.normal(0.0, 1e-5, n)
    gt_prev[:20] = np.nan  # replaced below by the point's own g_T (no secant)
    want = _respond(NUMBA, u, pts, mode, pt_prev, gt_prev)
    gt_prev[:20] = want["out_gt"][:20]
    want = _respond(NUMBA, u, pts, mode, pt_prev, gt_prev)
    got = _respond(vectorized, u, pts, mode, pt_prev, gt_prev)
    states = want["out_state"]
    # the sample covers the three states
    assert {OPEN, STICK, SLIP} <= set(np.unique(states).tolist())
    np.testing.assert_array_equal(got["out_state"], states)
    for key in want:
        if key != "out_state":
            assert _rel(got[key], want[key]) < 1e-13, key


def test_block_triplets_identical():
    rng = np.random.default_rng(3)
    dofs = rng.integers(0, 500, size=(80, 12)).astype(np.int64)
    dofs[rng.random(dofs.shape) < 0.4] = -1
    blocks = rng.normal(size=(80, 12, 12))
    for a, b in zip(
        NUMBA.block_triplets(dofs, blocks),
        vectorized.block_triplets(dofs, blocks),
        strict=True,
    ):
        assert a.dtype == b.dtype
        np.testing.assert_array_equal(a, b)


def test_choose(monkeypatch):
    monkeypatch.delenv(kernels.ENV_OVERRIDE, raising=False)
    limit = kernels.AUTO_NUMPY_MAX_WORK
    assert kernels.choose("auto", limit) == "numpy"
    assert kernels.choose("auto", 1.01 * limit) == "numba"
    assert kernels.choose("numba", 1.0) == "numba"
    assert kernels.choose("numpy", 1e12) == "numpy"
    monkeypatch.setenv(kernels.ENV_OVERRIDE, "numba")
    assert kernels.choose("auto", 1.0) == "numba"
    assert kernels.choose("numpy", 1.0) == "numpy"  # a case's own choice wins
    with pytest.raises(ValueError):
        kernels.choose("cuda", 1.0)


@pytest.mark.slow  # compiles the Numba kernels in a fresh process
def test_shipped_reservoir_case_is_numpy_and_the_dfn_limit_is_numba(
    monkeypatch, tmp_path
):
    """Where the measured rule puts the shipped cases (docs/performance.md, *Kernel
    backends*): the 50 x 50 reservoir case and the 15-fracture network below
    the limit, 100 generated fractures on 200 x 200 cells above it."""
    monkeypatch.delenv(kernels.ENV_OVERRIDE, raising=False)
    for case in ("reservoir_depletion.toml", "fracture_network.toml"):
        spec = load_case(ROOT / "cases" / case)
        mesh, fractures = _geometry(spec)
        ec = build_enriched_cells(mesh, fractures, find_candidates(mesh, fractures))
        assert kernels.choose("auto", kernel_work(ec)) == "numpy", case
    dfn = sweep_member(**{"mesh.elements": [200, 200], "network.generate.count": 100})
    spec = loads_case(dfn, tmp_path / "dfn.toml")
    mesh, fractures = _geometry(spec)
    ec = build_enriched_cells(mesh, fractures, find_candidates(mesh, fractures))
    assert kernels.choose("auto", kernel_work(ec)) == "numba"


def _small_case(backend: str, steps=3, friction=0.3, formats=("h5", "vtu")) -> str:
    keys = {
        "mesh.elements": [24, 24],
        "fractures.0.friction": friction,
        "loading.steps": steps,
        "solver.kernels": backend,
        "output.formats": formats,
    }
    case = build.file_case(ROOT / "cases/reservoir_depletion.toml", **keys)
    return build.case_text(case)


def test_whole_runs_agree(tmp_path):
    """The same case through both backends: same contact states in every step,
    fields equal to round-off of the converged solve (eta <= 1e-8)."""
    results = {}
    for backend in ("numba", "numpy"):
        model = build_model(loads_case(_small_case(backend), tmp_path / "c.toml"))
        assert model.kernels == model.contact.kernels == backend
        solver = NewtonSolver(model.problem, 1e-12, 60, "consistent")
        results[backend] = solver.run(3)
    for a, b in zip(results["numba"], results["numpy"], strict=True):
        np.testing.assert_array_equal(a.contact.state, b.contact.state)
        assert _rel(b.u, a.u) < 1e-9
        assert _rel(b.contact.pt, a.contact.pt) < 1e-9
    assert np.any(results["numpy"][-1].contact.state == SLIP)


def test_a_small_run_never_imports_numba(tmp_path):
    """The point of the NumPy backend: `xfemslip run` of a small case loads
    no Numba at all (no import, no target set-up, no compilation); nor
    scipy.spatial (0.2 s), which only a pressure field from a file needs."""
    case = tmp_path / "small.toml"
    case.write_text(_small_case("auto", steps=1, formats=["h5"]))
    code = (
        "import sys\n"
        "from xfemslip.cli import cli\n"
        "try:\n"
        f"    cli(['run', '-q', {str(case)!r}, '-o', {str(tmp_path / 'out')!r}])\n"
        "except SystemExit as e:\n"
        "    assert not e.code, e.code\n"
        "jit = ('numba', 'llvmlite')\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in jit))\n"
        "print('scipy.spatial' in sys.modules)\n"
    )
    env = {k: v for k, v in os.environ.items() if k != kernels.ENV_OVERRIDE}
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=ROOT
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.strip().splitlines()[-2:] == ["[]", "False"]
    import h5py

    with h5py.File(tmp_path / "out" / "result.h5") as f:
        assert f.attrs["kernels"] == "numpy"


def test_both_backends_provide_every_kernel():
    """A model's backend name gives a namespace with every kernel the package
    calls (KERNELS); "auto" is a choice (kernels.choose), not a backend."""
    for name in ("numba", "numpy"):
        namespace = kernels.backend(name)
        missing = [
            k for k in kernels.KERNELS if not callable(getattr(namespace, k, None))
        ]
        assert missing == [], (name, missing)
    with pytest.raises(ValueError, match="unknown kernel backend 'auto'"):
        kernels.backend("auto")


def test_cell_subtriangles_agree_on_random_lines():
    """Random cells cut by 0-6 random lines (some through corners, along edges
    or within the tolerance of a vertex), with and without apexes on a
    vertex: both backends give the same triangles, bit for bit, and they tile
    each cell (areas sum to the cell's)."""
    rng = np.random.default_rng(11)
    nc = 300
    x0, y0 = rng.uniform(-1.0, 1.0, nc), rng.uniform(-1.0, 1.0, nc)
    hx, hy = rng.uniform(0.01, 0.2, nc), rng.uniform(0.01, 0.2, nc)
    bounds = np.column_stack([x0, x0 + hx, y0, y0 + hy])
    counts = rng.integers(0, 7, nc)
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    cell = np.repeat(np.arange(nc), counts)
    centre = np.column_stack(
        [x0[cell] + rng.uniform(0, 1, cell.size) * hx[cell], y0[cell]]
    )
    centre[:, 1] += rng.uniform(0, 1, cell.size) * hy[cell]
    corner = rng.random(cell.size) < 0.2  # lines through a corner
    centre[corner, 0] = x0[cell[corner]]
    centre[corner, 1] = y0[cell[corner]]
    angle = rng.uniform(0.0, np.pi, cell.size)
    angle[rng.random(cell.size) < 0.1] = 0.0  # along an edge
    normal = np.column_stack([-np.sin(angle), np.cos(angle)])
    tol = 1e-9
    apex_counts = rng.integers(0, 2, nc)
    apex_off = np.concatenate([[0], np.cumsum(apex_counts)]).astype(np.int64)
    apexes = bounds[np.repeat(np.arange(nc), apex_counts)][:, [1, 3]]  # (x1, y1)
    args = (bounds, offsets, centre, normal, apex_off, apexes, tol)
    off_a, tris_a = NUMBA.cell_subtriangles(*args)
    off_b, tris_b = vectorized.cell_subtriangles(*args)
    np.testing.assert_array_equal(off_a, off_b)
    np.testing.assert_array_equal(tris_a, tris_b)
    e1 = tris_a[:, 1] - tris_a[:, 0]
    e2 = tris_a[:, 2] - tris_a[:, 0]
    area = 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    assert area.min() > 0.0
    per_cell = np.add.reduceat(area, off_a[:-1]) if area.size else area
    np.testing.assert_allclose(per_cell, hx * hy, rtol=1e-12)
    # a cell with an apex fans every piece holding it from the apex
    with_apex = np.nonzero(apex_counts)[0]
    for e in with_apex:
        t = tris_a[off_a[e] : off_a[e + 1]]
        at = np.all(np.abs(t - apexes[apex_off[e]]) <= tol, axis=2)
        assert not at[:, 1:].any()  # never vertex 1 or 2
        assert at[:, 0].any()


def test_enriched_cells_agree_between_backends():
    """The enriched cells of the shipped network (junctions, branch tips,
    crossings) built with either backend's sub-cells: the same arrays, bit
    for bit."""
    spec = load_case(ROOT / "cases" / "fracture_network.toml")
    mesh, fractures = _geometry(spec)
    cand = find_candidates(mesh, fractures)
    a = build_enriched_cells(mesh, fractures, cand, "numba")
    b = build_enriched_cells(mesh, fractures, cand, "numpy")
    for name in a.__dataclass_fields__:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), name)
    assert a.tris.shape[0] > a.cells.size  # cut cells
