"""OpenBLAS on one thread while MKL PARDISO solves.

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
"""

from __future__ import annotations

import contextlib


def one_openblas_thread() -> contextlib.AbstractContextManager:
    """A context in which every OpenBLAS loaded in the process (NumPy's and
    SciPy's own copies) runs on one thread; the thread counts come back on
    exit.  Other BLAS (MKL's) and OpenMP pools are left alone; nothing to
    do where no OpenBLAS is loaded."""
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController().select(internal_api="openblas").limit(limits=1)
