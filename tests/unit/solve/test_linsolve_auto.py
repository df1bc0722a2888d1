"""The "auto" linear-solver rule (xfemslip.solve.linear.choose, system_facts) and
the bounded fall-back from AMG to SuperLU."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from tests.support.casegen import sweep_member
from xfemslip.case import build, loads_case
from xfemslip.simulation import build_model, run_case
from xfemslip.solve import linear as linsolve
from xfemslip.solve.linear import LinearSolver, choose, system_facts
from xfemslip.solve.newton import NewtonSolver

ROOT = Path(__file__).resolve().parents[3]
CASE = ROOT / "cases" / "reservoir_depletion.toml"
pytest.importorskip("pyamg")


@pytest.fixture(autouse=True)
def _without_mkl(monkeypatch):
    """The rule of an install without the mkl extra (with it, "auto" takes
    PARDISO from AUTO_PARDISO_MIN_DOFS on: test_pardiso.py)."""
    monkeypatch.setattr(linsolve.pardiso, "available", lambda: False)


def _reservoir(n) -> str:
    """The shipped reservoir case on n x n cells."""
    return build.case_text(build.file_case(CASE, **{"mesh.elements": [n, n]}))


def _grid(n, sx=1.0, sy=1.0):
    g = np.linspace(0.0, 1.0, n + 1)
    return np.column_stack([np.repeat(g, n + 1) * sx, np.tile(g, n + 1) * sy])


def test_rule_on_constructed_inputs():
    """Each input of the rule on its own side of its limit."""
    square, stretched = _grid(10), _grid(10, sy=5.0)  # cells 1:1 and 5:1
    n = linsolve.AUTO_AMG_MIN_DOFS
    top = linsolve.AUTO_AMG_MAX_BAND
    assert choose("auto", n, square, 0.0) == "amg"
    assert choose("auto", n, square, top) == "amg"
    assert choose("auto", n, square, np.nextafter(top, 1.0)) == "superlu"
    assert choose("auto", 10 * n, square, 0.9) == "superlu"  # network, any size
    assert choose("auto", n - 1, square, 0.0) == "superlu"  # small
    assert choose("auto", n, stretched, 0.0) == "superlu"  # elongated cells
    assert choose("auto", n, None, 0.0) == "superlu"  # no coordinates
    # an explicit choice is kept whatever the inputs
    assert choose("amg", 10, None, 1.0) == "amg"
    assert choose("superlu", 10 * n, square, 0.0) == "superlu"


def test_planned_solver_follows_the_rule_on_grid_lines():
    """planned_solver (grid lines, before the mesh) gives what choose gives on
    the same mesh's nodes, on both sides of each limit, and asks for the band
    share only when it decides between AMG and SuperLU."""
    n = linsolve.AUTO_AMG_MIN_DOFS
    top = linsolve.AUTO_AMG_MAX_BAND
    g = np.linspace(0.0, 1.0, 11)
    calls = []

    def share(value):
        def ask():
            calls.append(value)
            return value

        return ask

    for sy in (1.0, 5.0):  # cells 1:1 and 5:1
        nodes = _grid(10, sy=sy)
        for n_free in (n - 1, n, 10 * n):
            for band in (0.0, top, np.nextafter(top, 1.0)):
                calls.clear()
                planned = linsolve.planned_solver(
                    "auto", n_free, g, sy * g, share(band)
                )
                asked = len(calls)
                assert planned == choose("auto", n_free, nodes, band)
                assert planned == choose("auto", n_free, nodes, share(band))
                assert asked == (1 if sy == 1.0 and n_free >= n else 0)
    assert linsolve.planned_solver("auto", n, g, g) == "amg"  # band not known: 0
    assert linsolve.planned_solver("superlu", 10 * n, g, g, share(0.0)) == "superlu"
    assert linsolve.grid_aspect_ratio(g, 5.0 * g) == pytest.approx(5.0)
    assert linsolve.grid_aspect_ratio(g, 5.0 * g) == linsolve.cell_aspect_ratio(
        _grid(10, sy=5.0)
    )


def test_system_facts_on_a_chain():
    """A chain matrix (tridiagonal): the band of L layers around the enriched
    dofs is those dofs and the L before them, in the numbering of the free
    dofs (global dof 0 is fixed)."""
    n_nodes, n_enr = 10, 4  # 20 standard dofs, enriched global dofs 20..23
    free = np.arange(1, 2 * n_nodes + n_enr)  # 23 free dofs
    m = free.size
    K = sp.diags([-np.ones(m - 1), 2.0 * np.ones(m), -np.ones(m - 1)], [-1, 0, 1])
    node_xy = np.zeros((n_nodes, 2))
    layers = linsolve.AMG_BAND_LAYERS
    facts = system_facts(K.tocsr(), free, node_xy)
    assert facts["n_free"] == m
    assert facts["enriched_share"] == pytest.approx(n_enr / m, rel=1e-15)
    assert facts["band_share"] == pytest.approx((n_enr + layers) / m, rel=1e-15)
    band = linsolve.band_mask(K, free >= 2 * n_nodes, 1)
    assert np.nonzero(band)[0].tolist() == list(range(m - n_enr - 1, m))


def test_solver_weighs_the_band(monkeypatch):
    """LinearSolver("auto") computes the band share of its own matrix and
    follows the rule on both sides of the limit (the reservoir case on 30 x 30
    cells)."""
    monkeypatch.setattr(linsolve, "AUTO_AMG_MIN_DOFS", 100)
    model = build_model(loads_case(_reservoir(30)))
    newton = NewtonSolver(model.problem, 1e-8, 30, "consistent", "superlu")
    K, free, xy = newton.K_ff, newton.free, model.mesh.nodes
    share = system_facts(K, free, xy)["band_share"]
    assert 0.0 < share < 1.0
    monkeypatch.setattr(linsolve, "AUTO_AMG_MAX_BAND", share)
    assert LinearSolver(K, "auto", free, xy).method == "amg"
    monkeypatch.setattr(linsolve, "AUTO_AMG_MAX_BAND", 0.99 * share)
    assert LinearSolver(K, "auto", free, xy).method == "superlu"


# the shipped DFN sweep's seed-1 case (30 fractures) on 30 x 30 cells
NETWORK = sweep_member(**{"mesh.elements": [30, 30], "network.tip": "ramp"})


def test_auto_picks_per_case_end_to_end(tmp_path, monkeypatch, caplog):
    """A whole run with linear_solver = "auto" logs its choice: the
    one-fracture reservoir case on 40 x 40 cells (AMG band: 44 % of the free
    dofs) goes to AMG, a 30-fracture generated network on 30 x 30 cells (over
    90 %) to SuperLU.  The size floor is lowered so that both are small."""
    monkeypatch.setattr(linsolve, "AUTO_AMG_MIN_DOFS", 1000)
    single = loads_case(_reservoir(40), CASE)
    network = loads_case(NETWORK, "network.toml")
    chosen = {}
    for name, spec in (("single", single), ("network", network)):
        assert spec.solver.linear_solver == "auto"
        caplog.clear()
        with caplog.at_level(logging.DEBUG, logger="xfemslip"):
            run_case(spec, tmp_path / name)
        lines = [r.getMessage() for r in caplog.records]
        picks = [m for m in lines if m.startswith("linear solver: ")]
        assert len(picks) == 1, lines
        chosen[name] = picks[0].split()[2]
        assert "(auto: " in picks[0]
        assert (tmp_path / name / "result.h5").exists()
    assert chosen == {"single": "amg", "network": "superlu"}


def test_stalled_gmres_stops_at_the_first_check():
    """GMRES(5) without a preconditioner on diag(1 .. 1e4), cap 50: the
    restart cycles run in one scipy call, and at STALL_CHECK = 20 iterations
    the residual's fall, extrapolated at its mean rate, needs more than the
    50 left, so give_up stops there; without it all 50 are used, neither
    converging."""
    n = 2000
    A = sp.diags(np.linspace(1.0, 1.0e4, n)).tocsr()
    b = np.ones(n)
    M = spla.LinearOperator(A.shape, matvec=lambda v: v, dtype=float)
    x1, ok1, its1, ratio1 = linsolve._gmres(A, b, M, 5, 50, give_up=True)
    x2, ok2, its2, rel2 = linsolve._gmres(A, b, M, 5, 50, give_up=False)
    assert not ok1 and not ok2
    assert its1 == linsolve.STALL_CHECK and its2 == 50
    assert 1 + linsolve._projected(its1 - 1, ratio1) > 50
    assert rel2 == pytest.approx(np.linalg.norm(A @ x2 - b) / np.sqrt(n), rel=1e-12)
    assert linsolve.KRYLOV_RTOL < rel2 < 1.0


def test_stall_stop_within_the_first_cycle_and_not_on_a_slow_convergence():
    """GMRES(60), cap 150, no preconditioner.  diag(1 .. 1e4): after 20
    iterations the residual has fallen by 0.1 only, which at that rate needs
    about 200 more: stopped at STALL_CHECK = 20 (without the stop: all 150
    iterations, not converged).  diag(1 .. 100) converges in 114 iterations,
    through a restart, with and without the stop alike."""
    n = 2000
    b = np.ones(n)
    M = spla.LinearOperator((n, n), matvec=lambda v: v, dtype=float)
    A = sp.diags(np.linspace(1.0, 1.0e4, n)).tocsr()
    _, ok, its, ratio = linsolve._gmres(A, b, M, 60, 150, give_up=True)
    assert not ok and its == linsolve.STALL_CHECK
    assert 1 + linsolve._projected(its - 1, ratio) > 150
    _, ok, its, _ = linsolve._gmres(A, b, M, 60, 150, give_up=False)
    assert not ok and its == 150
    A = sp.diags(np.linspace(1.0, 100.0, n)).tocsr()
    runs = [linsolve._gmres(A, b, M, 60, 150, give_up=g) for g in (True, False)]
    for x, ok, its, rel in runs:
        assert ok and 60 < its < 150 and rel <= linsolve.KRYLOV_RTOL
        np.testing.assert_allclose(x, 1.0 / np.linspace(1.0, 100.0, n), rtol=1e-8)
    assert runs[0][2] == runs[1][2]


def test_gmres_converges_with_the_stop_on():
    """The check after each restart cycle does not stop a GMRES(5) that
    converges (diag(1 .. 2))."""
    n = 2000
    b = np.ones(n)
    M = spla.LinearOperator((n, n), matvec=lambda v: v, dtype=float)
    A = sp.diags(np.linspace(1.0, 2.0, n)).tocsr()
    x, ok, its, rel = linsolve._gmres(A, b, M, 5, 100, give_up=True)
    assert ok and rel <= linsolve.KRYLOV_RTOL
    np.testing.assert_allclose(x, 1.0 / np.linspace(1.0, 2.0, n), rtol=1e-9)


def test_amg_fallback_is_counted_timed_and_logged(monkeypatch, caplog):
    """An AMG-GMRES capped at 2 iterations cannot converge: the system is
    solved by SuperLU (agreeing with spsolve), the lost time is recorded and
    is part of the solve time, the warning names the iterations and the time,
    and the next system goes straight to SuperLU."""
    monkeypatch.setattr(linsolve, "AMG_MAX_ITERATIONS", 2)
    model = build_model(loads_case(_reservoir(20)))
    newton = NewtonSolver(model.problem, 1e-8, 30, "consistent", "amg")
    ls = newton.linear
    rng = np.random.default_rng(2)
    n = newton.free.size
    Kc = sp.random(n, n, density=0.0, format="csr")
    with caplog.at_level(logging.WARNING, logger="xfemslip"):
        for _ in range(2):
            r = rng.standard_normal(n)
            x = ls.solve(Kc, r)
            x_ref = spla.spsolve(newton.K_ff.tocsc(), r)
            assert np.linalg.norm(x - x_ref) <= 1e-8 * np.linalg.norm(x_ref)
    st = ls.stats
    assert st["method"] == "amg" and ls.method == "superlu"
    assert st["amg_fallbacks"] == 1 and st["factorizations"] == 1
    assert st["krylov_iterations"] == 2
    assert 0.0 < st["amg_fallback_time"] < st["solve_time"]
    warnings = [r.getMessage() for r in caplog.records]
    assert len(warnings) == 1
    assert "did not converge (2 iterations" in warnings[0]
    assert "s lost" in warnings[0]
