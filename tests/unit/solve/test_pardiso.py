"""The MKL PARDISO path (xfemslip.pardiso, linear_solver = "pardiso"): the
fixed-pattern assembly equals K_ff + K_c, PARDISO solves the Newton systems of
real runs (SPD, unsymmetric with friction, stuck, sliding) to the backward-error
bound and agrees with SuperLU, analyses once per mode and run, and falls back
to SuperLU when it fails; "auto" takes it when it is installed and says what
it would gain when it is not."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from tests.support.newton_systems import solve_like_spsolve
from xfemslip.case import load as case_load
from xfemslip.case import loads_case
from xfemslip.errors import CaseError
from xfemslip.fem.assembly import coo_block
from xfemslip.simulation import build_model
from xfemslip.solve import linear as linsolve
from xfemslip.solve import pardiso
from xfemslip.solve.linear import LU_BACKWARD_ERROR, LinearSolver
from xfemslip.solve.newton import NewtonSolver

CASE = Path(__file__).resolve().parents[3] / "cases" / "reservoir_depletion.toml"
needs_mkl = pytest.mark.skipif(not pardiso.available(), reason="pypardiso missing")


def _text(n, steps=1, fracture=True, friction=0.1):
    text = CASE.read_text().replace("elements = [50, 50]", f"elements = [{n}, {n}]")
    text = text.replace("steps = 1", f"steps = {steps}")
    text = text.replace("friction = 0.1", f"friction = {friction}")
    if not fracture:
        start, end = text.index("[[fractures]]"), text.index("[loading]")
        text = text[:start] + text[end:]
    return text


def _newton_systems(n=24, steps=3, friction=0.1):
    """Every Newton system (blocks, r) of the reservoir case, in order, and
    the solver that made them (SuperLU)."""
    model = build_model(loads_case(_text(n, steps, friction=friction), CASE))
    solver = NewtonSolver(
        model.problem, 1e-10, 30, "consistent", "superlu", predictor=False
    )
    systems = []
    solve = solver._solve

    def record(res, r, k, it, eta):
        systems.append((res.blocks.copy(), r.copy(), res.state.copy()))
        return solve(res, r, k, it, eta)

    solver._solve = record
    solver.run(steps)
    return solver, systems


def test_fixed_pattern_equals_the_assembled_sum():
    """Random blocks on random dofs (with -1 entries and repeated dofs) on
    a random sparse symmetric K: the fixed-pattern matrix equals K + coo_block
    entry by entry (to the round-off of the order of summation), and its
    upper-triangle view is the upper triangle."""
    rng = np.random.default_rng(3)
    n = 60
    K = sp.random(n, n, density=0.05, random_state=4)
    K = (K + K.T + sp.identity(n)).tocsr()
    dofs = rng.integers(-1, n, size=(15, 4))
    pattern = pardiso.FixedPattern.from_blocks(K, dofs)
    for _ in range(2):  # the same pattern for new values
        blocks = rng.standard_normal((15, 4, 4))
        A = pattern.matrix(pattern.data(pattern.values(blocks)))
        ref = (K + coo_block(dofs, blocks, n, "numpy")).toarray()
        # equal up to the order of summation of repeated entries
        np.testing.assert_allclose(
            A.toarray(), ref, rtol=0, atol=1e-14 * abs(ref).max()
        )
        upper = sp.csr_matrix(
            (A.data[pattern.upper], pattern.indices_upper, pattern.indptr_upper),
            shape=(n, n),
        )
        np.testing.assert_array_equal(upper.toarray(), np.triu(A.toarray()))
    # zero blocks keep their entries stored: the pattern does not change
    A0 = pattern.matrix(pattern.data(pattern.values(np.zeros((15, 4, 4)))))
    assert A0.nnz == A.nnz


def test_symmetry_tests():
    rng = np.random.default_rng(5)
    B = rng.standard_normal((3, 4, 4))
    assert pardiso.symmetric_blocks(B + B.transpose(0, 2, 1))
    assert not pardiso.symmetric_blocks(B)
    assert pardiso.symmetric_blocks(np.zeros((0, 4, 4)))
    K = sp.csr_matrix(B[0] + B[0].T)
    assert pardiso.matrix_symmetric(K)
    assert not pardiso.matrix_symmetric(sp.csr_matrix(B[0]))


@needs_mkl
@pytest.mark.parametrize("mode", ["schur", "pattern"])
@pytest.mark.parametrize(
    ("friction", "slips"), [(0.1, True), (10.0, False)], ids=["sliding", "stuck"]
)
def test_newton_systems_match_superlu(friction, slips, mode, monkeypatch):
    """The Newton systems of a 3-step run solved by one PARDISO LinearSolver
    as a run does: backward error <= LU_BACKWARD_ERROR against the exact
    matrix and agreement with spsolve to 1e-8.

    schur (the default for a few contact dofs): one SPD factorization of
    K_ff for the whole run, one dense LU per change of the contact tangent.
    pattern (SCHUR_MAX_DOFS = 0): sliding systems are unsymmetric (mtype 11),
    stuck ones SPD only, one factorization for the whole run."""
    if mode == "pattern":
        monkeypatch.setattr(pardiso, "SCHUR_MAX_DOFS", 0)
    newton, seq = _newton_systems(friction=friction)
    ls = LinearSolver(newton.K_ff, "pardiso", newton.free, None, newton.c_dofs)
    changes, asym = solve_like_spsolve(
        newton, ((b, r) for b, r, _ in seq), ls, newton.linear.kernels
    )
    st = ls.stats
    assert st["method"] == "pardiso" and st["pardiso_fallbacks"] == 0
    assert (max(asym) > 1e-6) == slips  # the slip tangent is not symmetric
    if mode == "schur":
        assert st["pardiso_schur"] == len(seq)
        assert st["pardiso_analyses"] == 1 and st["factorizations"] == 1
        # a dense LU for each system whose tangent differs from the last one
        assert st["schur_factorizations"] == changes
        return
    assert st["pardiso_spd"] + st["pardiso_unsym"] == len(seq)
    if slips:
        assert st["pardiso_unsym"] >= 1
        assert st["pardiso_analyses"] == 1 + (st["pardiso_spd"] > 0)
    else:
        assert st["pardiso_unsym"] == 0 and st["pardiso_spd"] == len(seq)
        assert st["pardiso_analyses"] == 1
        assert st["factorizations"] == 1


@needs_mkl
def test_no_fracture_is_spd_and_back_solves():
    model = build_model(loads_case(_text(20, fracture=False), CASE))
    newton = NewtonSolver(model.problem, 1e-10, 30, "consistent", "pardiso")
    rng = np.random.default_rng(1)
    ls = newton.linear
    for _ in range(3):
        r = rng.standard_normal(newton.free.size)
        x = ls.solve(None, r)
        x_ref = spla.spsolve(newton.K_ff.tocsc(), r)
        assert np.linalg.norm(x - x_ref) <= 1e-9 * np.linalg.norm(x_ref)
    st = ls.stats
    assert st["factorizations"] == 1 and st["pardiso_analyses"] == 1
    assert st["pardiso_spd"] == 3


@needs_mkl
def test_whole_run_without_fracture():
    """A run without a contact set (no blocks at all) through PARDISO gives
    SuperLU's displacement; the SPD mode, one factorization."""
    u = {}
    for method in ("superlu", "pardiso"):
        model = build_model(loads_case(_text(16, fracture=False), CASE))
        newton = NewtonSolver(model.problem, 1e-10, 30, "consistent", method)
        u[method] = newton.run(1)[-1].u
    st = newton.linear.stats
    assert st["pardiso_spd"] >= 1 and st["factorizations"] == 1
    ref = np.abs(u["superlu"]).max()
    assert ref > 0.0
    assert np.abs(u["pardiso"] - u["superlu"]).max() <= 1e-9 * ref


@needs_mkl
def test_sparse_contact_tangent_through_solve():
    """solve(Kc, r) with a sparse Kc (the general interface) on PARDISO: a
    symmetric and an unsymmetric Kc on the same pattern share the pattern."""
    newton, seq = _newton_systems(n=16, steps=2)
    ls = LinearSolver(newton.K_ff, "pardiso", newton.free)
    for blocks, r, _ in seq:
        Kc = coo_block(newton.c_dofs, blocks, newton.free.size, newton.linear.kernels)
        x = ls.solve(Kc, r)
        x_ref = spla.spsolve((newton.K_ff + Kc).tocsc(), r)
        assert np.linalg.norm(x - x_ref) <= 1e-8 * np.linalg.norm(x_ref)
    assert ls.stats["pardiso_fallbacks"] == 0


@needs_mkl
def test_analysis_once_per_run_across_steps(monkeypatch):
    """A 4-step sliding run: PARDISO's phase 11 and 22 are called once for the
    run, whatever the number of Newton systems (the Schur mode); each new
    contact tangent costs a dense LU of the Schur complement."""
    phases = []
    call = pardiso.Handle._call

    def counting(self, phase, data, b=None, x=None):
        phases.append((self.mtype, phase))
        return call(self, phase, data, b, x)

    monkeypatch.setattr(pardiso.Handle, "_call", counting)
    model = build_model(loads_case(_text(20, steps=4), CASE))
    newton = NewtonSolver(model.problem, 1e-10, 30, "consistent", "pardiso")
    steps = newton.run(4)
    analyses = [p for p in phases if p[1] == 11]
    assert len(analyses) == 1  # the Schur mode: one SPD handle
    assert sum(s.iterations for s in steps) >= 4
    assert newton.linear.stats["solves"] >= 4
    assert sum(p[1] == 22 for p in phases) == newton.linear.stats["factorizations"] == 1
    st = newton.linear.stats
    assert 1 <= st["schur_factorizations"] <= st["solves"]


@needs_mkl
def test_failure_falls_back_to_superlu(monkeypatch, caplog):
    """A PARDISO error: logged, the system and the rest of the run on
    SuperLU, same answer."""
    newton, seq = _newton_systems(n=16, steps=2)

    def broken(self, data):
        raise pardiso.PardisoError(22, -4)

    monkeypatch.setattr(pardiso.Handle, "factor", broken)
    ls = LinearSolver(newton.K_ff, "pardiso", newton.free, None, newton.c_dofs)
    with caplog.at_level(logging.WARNING, logger="xfemslip.solve.linear"):
        for blocks, r, _ in seq:
            Kc = coo_block(
                newton.c_dofs, blocks, newton.free.size, newton.linear.kernels
            )
            x = ls.solve_contact(blocks, r)
            x_ref = spla.spsolve((newton.K_ff + Kc).tocsc(), r)
            assert np.linalg.norm(x - x_ref) <= 1e-8 * np.linalg.norm(x_ref)
    assert ls.stats["pardiso_fallbacks"] == 1
    assert ls.method == "superlu"
    assert "PARDISO phase 22 failed with error -4" in caplog.text
    assert "SuperLU solves this" in caplog.text


@needs_mkl
def test_singular_matrix_is_reported():
    """A matrix with a zero-energy mode ends in RuntimeError as on SuperLU
    (PARDISO's perturbed pivots give a solve far above the backward-error
    bound, then SuperLU finds the singularity) or an answer that is no
    solution."""
    model = build_model(loads_case(_text(8, fracture=False), CASE))
    n_std = 2 * model.mesh.n_nodes
    K = sp.csr_matrix(model.problem.K[:n_std][:, :n_std])  # nothing fixed
    r = np.zeros(n_std)
    r[-1] = 1.0
    ls = LinearSolver(K, "pardiso", np.arange(n_std), model.mesh.nodes)
    with pytest.raises(RuntimeError):
        x = ls.solve(None, r)
        if np.linalg.norm(K @ x - r) > 1e-6:
            raise RuntimeError("no solution")


def test_auto_takes_pardiso_when_installed(monkeypatch):
    n = linsolve.AUTO_PARDISO_MIN_DOFS
    g = np.linspace(0.0, 1.0, 11)
    square = np.column_stack([np.repeat(g, 11), np.tile(g, 11)])
    monkeypatch.setattr(pardiso, "available", lambda: True)
    assert linsolve.choose("auto", n, square) == "pardiso"
    assert linsolve.choose("auto", n - 1, square) == "superlu"
    assert linsolve.choose("superlu", n, square) == "superlu"
    monkeypatch.setattr(pardiso, "available", lambda: False)
    assert linsolve.choose("auto", n - 1, square) == "superlu"
    assert linsolve.choose("auto", linsolve.AUTO_AMG_MIN_DOFS, square) == "amg"


def test_auto_says_what_pardiso_would_gain(monkeypatch, caplog):
    """Without the extra, from PARDISO_HINT_MIN_DOFS free dofs on, one line
    names the install command and the measured factor; below it, none."""
    monkeypatch.setattr(pardiso, "available", lambda: False)
    n = linsolve.PARDISO_HINT_MIN_DOFS
    with caplog.at_level(logging.INFO, logger="xfemslip.solve.linear"):
        LinearSolver(sp.identity(n - 1, format="csr"), "auto")
        assert "xfemslip[mkl]" not in caplog.text
        LinearSolver(sp.identity(n, format="csr"), "auto")
    lines = [r for r in caplog.records if "xfemslip[mkl]" in r.getMessage()]
    assert len(lines) == 1
    low, high = linsolve.PARDISO_GAIN
    assert f"1/{low:.1f} to 1/{high:.1f}" in lines[0].getMessage()


def test_case_refuses_pardiso_when_not_installed(monkeypatch):
    monkeypatch.setattr(case_load.options, "pardiso_installed", lambda: False)
    text = CASE.read_text().replace(
        "max_iterations = 30", 'max_iterations = 30\nlinear_solver = "pardiso"'
    )
    with pytest.raises(CaseError) as err:
        loads_case(text, "case.toml")
    msg = str(err.value)
    assert "solver.linear_solver" in msg and "pip install 'xfemslip[mkl]'" in msg
    monkeypatch.setattr(case_load.options, "pardiso_installed", lambda: True)
    assert loads_case(text, "case.toml").solver.linear_solver == "pardiso"


@needs_mkl
def test_schur_complement_of_the_bulk_matrix():
    """PARDISO's dense Schur complement on the contact dofs equals
    K_cc - K_ci K_ii^-1 K_ic computed with SuperLU."""
    newton, _ = _newton_systems(n=12, steps=1)
    K = newton.K_ff.tocsr()
    dofs = newton.c_dofs
    k = dofs.shape[1]
    shape = (dofs.shape[0], k, k)
    rows = np.broadcast_to(dofs[:, :, None], shape)
    cols = np.broadcast_to(dofs[:, None, :], shape)
    stats = dict.fromkeys(("factorizations", "pardiso_analyses"), 0)
    stats.update(schur_factorizations=0, factor_time=0.0)
    systems = pardiso.SchurSystems(K, rows, cols, LU_BACKWARD_ERROR, stats)
    c = systems.c
    assert c.size == np.unique(dofs[dofs >= 0]).size
    systems._factor(np.zeros(systems.flat.size))
    i = np.setdiff1d(np.arange(K.shape[0]), c)
    K_ic = K[i][:, c].toarray()
    ref = K[c][:, c].toarray() - K_ic.T @ spla.splu(K[i][:, i].tocsc()).solve(K_ic)
    S = systems.handle.schur_matrix
    np.testing.assert_allclose(S, ref, rtol=0, atol=1e-11 * abs(ref).max())
    systems.release()


@needs_mkl
def test_the_library_is_found_without_walking_the_environment(monkeypatch):
    """MKL's library comes from the mkl distribution's file list, and the
    entry point loaded from it solves like the one pypardiso loads: a small
    SPD system through both, the same answer to round-off."""
    path = pardiso._mkl_rt_path()
    assert path is not None and "mkl_rt" in Path(path).name and Path(path).is_file()
    monkeypatch.setenv("PYPARDISO_MKL_RT", "/nowhere/libmkl_rt.so")
    assert pardiso._mkl_rt_path() == "/nowhere/libmkl_rt.so"
    monkeypatch.delenv("PYPARDISO_MKL_RT")
    n = 40
    K = sp.diags([-1.0, 2.5, -1.0], [-1, 0, 1], shape=(n, n), format="csr")
    b = np.linspace(1.0, 2.0, n)
    x_ref = spla.spsolve(K.tocsc(), b)
    answers = []
    for fresh in (True, False):
        monkeypatch.setattr(pardiso, "_LIB", None)
        if not fresh:  # the library not where the distribution says
            monkeypatch.setattr(pardiso, "_mkl_rt_path", lambda: None)
        upper = sp.triu(K, format="csr")
        h = pardiso.Handle(2, upper.indptr, upper.indices)
        h.factor(upper.data)
        answers.append(h.solve(b))
        h.release()
    for x in answers:
        assert np.linalg.norm(x - x_ref) <= 1e-12 * np.linalg.norm(x_ref)


def test_row_sums_match_scipy_with_empty_rows():
    """The per-row sums the Schur set-up uses: scipy's row sums, empty rows
    (5 of 50 here, and a leading and trailing one) included."""
    from xfemslip.solve.pardiso import _row_sums

    A = sp.random(50, 50, density=0.05, format="csr", random_state=1)
    assert (np.diff(A.indptr) == 0).sum() > 0
    assert np.allclose(_row_sums(A.data, A.indptr), np.asarray(A.sum(axis=1)).ravel())
    counts = _row_sums(np.ones(3) > 0, np.array([0, 0, 2, 3, 3]))
    assert counts.tolist() == [0, 2, 1, 0]


@needs_mkl
@pytest.mark.parametrize("where", ["last", "scattered"])
def test_schur_solve_takes_the_schur_unknowns_from_its_caller(where):
    """Handle.solve_schur: the callback gets the forward-eliminated
    right-hand side b_s - A_si A_ii^-1 b_i, and whatever it returns is x_s
    in x_i = A_ii^-1 (b_i - A_is x_s) (dense formulas), x_s = 0 included."""
    rng = np.random.default_rng(3)
    n = 70
    A = sp.random(n, n, density=0.08, random_state=4)
    A = (A + A.T + 12.0 * sp.identity(n)).tocsr()
    A.sort_indices()
    s = np.arange(n - 9, n) if where == "last" else np.sort(rng.choice(n, 9, False))
    i = np.setdiff1d(np.arange(n), s)
    up = sp.triu(A, format="csr")
    up.sort_indices()
    h = pardiso.Handle(pardiso.MTYPE_SPD, up.indptr, up.indices, schur=s)
    h.factor(up.data)
    D = A.toarray()
    A_ii, A_is, A_si = D[np.ix_(i, i)], D[np.ix_(i, s)], D[np.ix_(s, i)]
    b = rng.standard_normal(n)
    rhs_ref = b[s] - A_si @ np.linalg.solve(A_ii, b[i])
    xs = rng.standard_normal(s.size)
    seen = []

    def given(rhs):
        seen.append(rhs)
        return xs

    x = h.solve_schur(b, given)
    np.testing.assert_allclose(seen[0], rhs_ref, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(
        x[i], np.linalg.solve(A_ii, b[i] - A_is @ xs), rtol=1e-12, atol=1e-12
    )
    np.testing.assert_array_equal(x[s], xs)
    x0 = h.solve_schur(b, np.zeros_like)
    np.testing.assert_allclose(
        x0[i], np.linalg.solve(A_ii, b[i]), rtol=1e-12, atol=1e-12
    )
    assert not x0[s].any()
