"""OpenBLAS on one thread while PARDISO solves (xfemslip.solve.threads)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg  # noqa: F401  (loads SciPy's own OpenBLAS)
import scipy.sparse as sp
from threadpoolctl import ThreadpoolController

from xfemslip.case import loads_case
from xfemslip.simulation import run_case
from xfemslip.solve import pardiso
from xfemslip.solve.linear import LinearSolver
from xfemslip.solve.threads import one_openblas_thread

CASE = Path(__file__).resolve().parents[3] / "cases" / "reservoir_depletion.toml"


def _openblas() -> ThreadpoolController:
    ctl = ThreadpoolController().select(internal_api="openblas")
    if not ctl.lib_controllers:
        pytest.skip("no OpenBLAS loaded (NumPy and SciPy built on another BLAS)")
    return ctl


def _threads() -> list[int]:
    return [c.num_threads for c in _openblas().lib_controllers]


def test_one_thread_inside_and_the_counts_back_after():
    ctl = _openblas()
    with ctl.limit(limits=2):  # a known start, also on a one-core machine
        before = _threads()
        assert before == [2] * len(before)
        with one_openblas_thread():
            assert _threads() == [1] * len(before)
        assert _threads() == before


def test_only_the_pardiso_solver_limits_openblas():
    _openblas()
    K = sp.identity(4, format="csr")
    with _openblas().limit(limits=2):
        with LinearSolver(K, "superlu").blas_threads():
            assert set(_threads()) == {2}
        if pardiso.available():
            with LinearSolver(K, "pardiso").blas_threads():
                assert set(_threads()) == {1}


def test_a_run_solves_with_one_openblas_thread_on_pardiso(monkeypatch):
    """The run's Newton solves see one OpenBLAS thread on PARDISO and the
    process's count on SuperLU, which is back after the run; the slips
    agree to the solve tolerance."""
    if not pardiso.available():
        pytest.skip("pypardiso missing")
    seen: dict[str, set] = {}
    solve = LinearSolver.solve_contact

    def spy(self, blocks, r):
        seen[self.method].add(tuple(_threads()))
        return solve(self, blocks, r)

    monkeypatch.setattr(LinearSolver, "solve_contact", spy)
    slip = {}
    with _openblas().limit(limits=2):
        n = len(_threads())
        for method in ("superlu", "pardiso"):
            seen[method] = set()
            text = CASE.read_text().replace(
                "elements = [50, 50]", "elements = [16, 16]"
            )
            text = text.replace("[solver]", f'[solver]\nlinear_solver = "{method}"')
            result = run_case(loads_case(text, CASE))
            assert _threads() == [2] * n
            slip[method] = result.steps[-1].fractures[0].slip
    assert seen == {"superlu": {(2,) * n}, "pardiso": {(1,) * n}}
    ref = np.abs(slip["superlu"]).max()
    assert ref > 0.0
    assert np.abs(slip["pardiso"] - slip["superlu"]).max() <= 1e-8 * ref
