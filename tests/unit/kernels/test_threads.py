"""xfemslip.kernels.threads: OpenBLAS on one thread while PARDISO or the
bordered SuperLU factorization of a network solves, and the model build's
kernel chunks on threads (same arrays to the bit)."""

from __future__ import annotations

import os
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg  # noqa: F401  (loads SciPy's own OpenBLAS)
import scipy.sparse as sp
from threadpoolctl import ThreadpoolController

from xfemslip.case import loads_case
from xfemslip.fem import enrichment
from xfemslip.kernels.threads import kernel_threads, map_in_threads, one_openblas_thread
from xfemslip.simulation import build_model, run_case
from xfemslip.solve import pardiso
from xfemslip.solve.linear import LinearSolver

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


def test_pardiso_limits_openblas_and_superlu_without_a_network_does_not():
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


def test_the_bordered_superlu_network_solves_with_one_openblas_thread(monkeypatch):
    """A network on the one bordered SuperLU factorization (AugmentedLU:
    the shipped network with its contact dofs sent past the Schur limit)
    solves with one OpenBLAS thread, the count back after the run."""
    _openblas()
    monkeypatch.setattr(pardiso, "SCHUR_MAX_DOFS", 0)
    seen = []
    solve = LinearSolver.solve_contact

    def spy(self, blocks, r):
        x = solve(self, blocks, r)
        seen.append((self._augmented is not False, tuple(_threads())))
        return x

    monkeypatch.setattr(LinearSolver, "solve_contact", spy)
    text = NETWORK.read_text().replace(
        "[solver]", '[solver]\nlinear_solver = "superlu"'
    )
    assert 'linear_solver = "superlu"' in text
    with _openblas().limit(limits=2):
        n = len(_threads())
        run_case(loads_case(text, NETWORK))
        assert _threads() == [2] * n
    assert seen and set(seen) == {(True, (1,) * n)}


# --------------------------------------------------- the kernels' chunks on threads

NETWORK = Path(__file__).resolve().parents[3] / "cases" / "fracture_network.toml"


def test_map_in_threads_keeps_the_order_on_threads_with_one_openblas_thread():
    ctl = _openblas()
    seen = []

    def item(k):
        seen.append((threading.get_ident(), tuple(_threads())))
        time.sleep(0.002)  # long enough for the other thread to take one
        return k * k

    with ctl.limit(limits=2):
        n = len(_threads())
        assert map_in_threads(item, range(40), 2) == [k * k for k in range(40)]
        assert len({ident for ident, _ in seen}) == 2
        assert {counts for _, counts in seen} == {(1,) * n}
        seen.clear()
        assert map_in_threads(item, range(3), 1) == [0, 1, 4]  # serial
        assert {counts for _, counts in seen} == {(1,) * n}
        assert _threads() == [2] * n  # the count back after


def test_map_in_threads_raises_the_first_error_and_drops_the_rest():
    done = []

    def item(k):
        if k == 0:
            raise ValueError("item 0")
        time.sleep(0.01)
        done.append(k)

    with pytest.raises(ValueError, match="item 0"):
        map_in_threads(item, range(100), 2)
    assert len(done) < 10


def test_kernel_threads_follow_numba_num_threads(monkeypatch):
    monkeypatch.setenv("NUMBA_NUM_THREADS", "3")
    assert kernel_threads() == 3
    for unset in ("", "zero", "0"):
        monkeypatch.setenv("NUMBA_NUM_THREADS", unset)
        assert kernel_threads() == len(os.sched_getaffinity(0))


def _model_arrays(monkeypatch, threads: int) -> dict[str, np.ndarray]:
    """The arrays of the shipped network's model (compiled kernels) built
    with ``threads`` threads, the sub-cells cut in runs of 100 cells."""
    monkeypatch.setenv("NUMBA_NUM_THREADS", str(threads))
    monkeypatch.setattr(enrichment, "SUBCELL_THREAD_CELLS", 100)
    text = NETWORK.read_text().replace("[solver]", '[solver]\nkernels = "numba"')
    model = build_model(loads_case(text, NETWORK))
    K, ec = model.problem.K, model.ec
    return {
        "indptr": K.indptr,
        "indices": K.indices,
        "data": K.data,
        "F": model.problem.F_unit,
        "tri_offsets": ec.tri_offsets,
        "tris": ec.tris,
        "qp_xy": ec.qp_xy,
        "column_F": ec.column_F,
        "column_gradF": ec.column_gradF,
        "tri_F": ec.tri_F,
    }


def test_threaded_model_build_is_the_serial_one_to_the_bit(monkeypatch):
    """Sub-cells cut in runs of cells, groups evaluated and enriched-cell
    chunks assembled on 2 threads: the same arrays, bit for bit, as on one
    thread (premise: the network has more enriched cells than two runs)."""
    serial = _model_arrays(monkeypatch, 1)
    assert serial["tri_offsets"].size - 1 > 2 * enrichment.SUBCELL_THREAD_CELLS
    threaded = _model_arrays(monkeypatch, 2)
    for name, value in serial.items():
        assert np.array_equal(threaded[name], value), name


def _worker_threads(task) -> int:
    """A sweep worker's task: the kernel threads it would use."""
    return kernel_threads()


def test_sweep_workers_share_the_cores(monkeypatch):
    """Two local workers each take half the cores (at least one thread);
    NUMBA_NUM_THREADS still decides when it is set; this process keeps
    them all."""
    from xfemslip.kernels import threads
    from xfemslip.studies.workers import run_local

    monkeypatch.delenv("NUMBA_NUM_THREADS", raising=False)
    cores = threads.process_cores()
    got = list(run_local([0, 1], 2, _worker_threads, lambda task, why: why))
    assert got == [max(1, cores // 2)] * 2
    assert kernel_threads() == cores
    monkeypatch.setattr(threads._Share, "threads", None)
    threads.share_cores(3)
    assert kernel_threads() == max(1, cores // 3)
    monkeypatch.setenv("NUMBA_NUM_THREADS", "2")
    assert kernel_threads() == 2
