"""The threads of the process: OpenBLAS on one thread while MKL PARDISO
solves, and the compiled kernels' chunks spread over the cores.

MKL's OpenMP threads and OpenBLAS's threads both keep spinning for a while
after their work, waiting for more.  With as many cores as either pool has
threads, a dense product right after a PARDISO phase waits for the cores
MKL's threads still hold, and the next PARDISO phase for those OpenBLAS's
threads hold.  A Newton solve on PARDISO alternates the two hundreds of
times (partial solves between the low-rank updates' dense LUs and products,
the vector norms of the residual), so there OpenBLAS (NumPy's and SciPy's)
runs on one thread (whatever OPENBLAS_NUM_THREADS says) and leaves the
cores to MKL.  Measured on the 100-fracture network (200 x 200 cells, 2
cores, no thread variable set, whole processes alternated, 3 runs each):
16.1-18.6 s (CPU 23-26 s) with OpenBLAS's default of 2 threads, 12.4-16.8 s
(CPU 16-21 s) with one thread during the Newton solve; the single fracture
(Schur path, dense LU of the contact block) at 400 x 400 cells 3.94 against
4.43 s (medians of 5), at 700 x 700 the same within the machine's noise.

The model build's loops over chunks of enriched cells call Numba kernels
that release the GIL (``nogil=True``), so threads run the chunks on all the
cores (map_in_threads), each chunk's result written to its own slice: the
answer is the same to the bit on any number of threads.  OpenBLAS runs on
one thread meanwhile (the cell kernels' dense products are small; two
threads each wanting two BLAS threads on 2 cores ran slower than one thread
alone).  Measured on the 100-fracture network (200 x 200 cells, 3 runs
each): the enriched-cell entries 0.8-1.1 s on one thread, 0.45-0.7 s on 2.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Callable, Iterable
from concurrent.futures import ThreadPoolExecutor
from typing import TypeVar

T = TypeVar("T")
R = TypeVar("R")


def one_openblas_thread() -> contextlib.AbstractContextManager:
    """A context in which every OpenBLAS loaded in the process (NumPy's and
    SciPy's own copies) runs on one thread; the thread counts come back on
    exit.  Other BLAS (MKL's) and OpenMP pools are left alone; nothing to
    do where no OpenBLAS is loaded."""
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController().select(internal_api="openblas").limit(limits=1)


def process_cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


class _Share:
    """The kernel threads of a process that shares the cores with others
    (share_cores); None: the cores are all this process's."""

    threads: int | None = None


def share_cores(processes: int) -> None:
    """This process is one of ``processes`` working at once (a sweep's
    workers): its kernels take their share of the cores, at least one
    thread, unless NUMBA_NUM_THREADS says otherwise."""
    _Share.threads = max(1, process_cores() // max(1, int(processes)))


def kernel_threads() -> int:
    """Threads for the kernels' chunks: NUMBA_NUM_THREADS when set to a
    positive integer (the variable Numba's own threads follow), else this
    process's share of the cores (share_cores), else the cores this process
    may run on."""
    given = os.environ.get("NUMBA_NUM_THREADS", "").strip()
    if given.isdigit() and int(given) > 0:
        return int(given)
    if _Share.threads is not None:
        return _Share.threads
    return process_cores()


def map_in_threads(
    fn: Callable[[T], R], items: Iterable[T], threads: int | None = None
) -> list[R]:
    """[fn(item) for item in items], run by ``threads`` threads (default
    kernel_threads()), OpenBLAS on one thread in any case (so the results
    do not depend on the thread count: OpenBLAS's products round
    differently on one and two threads).  fn must write only what its item
    owns.  The first exception is raised once the running items are done;
    the items not started are dropped."""
    items = list(items)
    n = kernel_threads() if threads is None else threads
    with one_openblas_thread():
        if n <= 1 or len(items) <= 1:
            return [fn(item) for item in items]
        pool = ThreadPoolExecutor(min(n, len(items)))
        try:
            return list(pool.map(fn, items))
        finally:
            pool.shutdown(wait=True, cancel_futures=True)


# the kernel backend whose loops release the GIL (xfemslip.kernels: "numba")
COMPILED = "numba"


def backend_threads(backend: str) -> int:
    """Threads the kernel loops of ``backend`` run on: kernel_threads() for
    the compiled kernels; one for NumPy's, chosen for small models, where a
    pool would cost more than it saves."""
    return kernel_threads() if backend == COMPILED else 1


def map_kernels(backend: str, fn: Callable[[T], R], items: Iterable[T]) -> list[R]:
    """[fn(item) for item in items], a loop over the kernels of
    ``backend``: map_in_threads for the compiled kernels, in turn (OpenBLAS
    left alone) for NumPy's."""
    if backend != COMPILED:
        return [fn(item) for item in items]
    return map_in_threads(fn, items)
