"""OpenBLAS on one thread while MKL PARDISO solves.

MKL's OpenMP threads and OpenBLAS's threads both keep spinning for a while
after their work, waiting for more.  With as many cores as either pool has
threads, a dense product right after a PARDISO phase waits for the cores
MKL's threads still hold, and the next PARDISO phase for those OpenBLAS's
threads hold.  A Newton solve on PARDISO alternates the two hundreds of
times (partial solves between the low-rank updates' dense LUs and products,
the vector norms of the residual), so there OpenBLAS (NumPy's and SciPy's)
runs on one thread and leaves the cores to MKL.  Measured on the 100-fracture
network (200 x 200 cells, 2 cores, no thread variable set, whole processes
alternated, 3 runs each): 19.1-20.9 s with OpenBLAS's default of 2 threads,
13.7-17.2 s with one thread during the Newton solve (CPU 26-27 -> 17-21 s);
the single fracture at 700 x 700 cells (Schur path, dense LU of the contact
block) unchanged within the machine's noise, 11.2-13.6 against 11.7-12.8 s.
A user's own OPENBLAS_NUM_THREADS is a ceiling the limit stays under.
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
