"""Substitutions with sparse triangular factors in CSC form (SuperLU's L and
U as SciPy returns them), for solves that stop part of the way.

SciPy's SuperLU solves only whole systems.  A Newton system of a crowded
network on the bordered factorization (xfemslip.solve.lowrank.AugmentedLU)
needs a forward substitution over the stuck matrix's columns, a small dense
solve on the patch jumps, and a backward substitution with those jumps held
fixed: one pass through the factors instead of two whole solves (measured
on the 100-fracture network's 55M factor entries: 32 ms forward and 57 ms
backward, against 62 ms per whole solve).

Both loops are column-oriented (a column's entries scattered into y), which
reads each factor once in storage order.  The factors' row indices need not
be sorted; SuperLU's U keeps its diagonal last in a column and L its unit
diagonal first, which the loops use when they find it there.

Numba only: with the NumPy kernels the callers use SuperLU's whole solves.
"""

from numba import njit

from xfemslip.kernels._config import NUMBA_CACHE


@njit(cache=NUMBA_CACHE, nogil=True)
def lower_unit_forward(indptr, indices, data, y, ncols):
    """y <- L^-1 y on the first ``ncols`` columns of the unit lower
    triangular L (CSC; stored diagonal entries are ignored): the rows past
    ``ncols`` receive the columns' contributions, y[j] - sum_{k < ncols}
    L[j, k] x[k], and are not divided."""
    for j in range(ncols):
        yj = y[j]
        if yj == 0.0:
            continue
        for k in range(indptr[j], indptr[j + 1]):
            i = indices[k]
            if i > j:
                y[i] -= data[k] * yj


# error_model="numpy": a division by zero gives inf/nan, as in NumPy, and no
# exception from inside the loop
@njit(cache=NUMBA_CACHE, nogil=True, error_model="numpy")
def upper_backward(indptr, indices, data, y, nfree):
    """y <- the backward substitution with the upper triangular U (CSC) in
    which the entries of y from ``nfree`` on are known values: their
    columns are subtracted from the rows above ``nfree``, then rows
    nfree - 1 .. 0 are solved.  A zero diagonal gives inf or nan (the
    caller's backward-error check refuses the solve)."""
    n = indptr.size - 1
    for j in range(n - 1, nfree - 1, -1):
        yj = y[j]
        if yj == 0.0:
            continue
        for k in range(indptr[j], indptr[j + 1]):
            i = indices[k]
            if i < nfree:
                y[i] -= data[k] * yj
    for j in range(nfree - 1, -1, -1):
        start, last = indptr[j], indptr[j + 1] - 1
        if last >= start and indices[last] == j:
            diag, end = data[last], last
        else:
            diag, end = 0.0, last + 1
            for k in range(start, end):
                if indices[k] == j:
                    diag = data[k]
        yj = y[j] / diag
        y[j] = yj
        if yj == 0.0:
            continue
        for k in range(start, end):
            i = indices[k]
            if i < j:
                y[i] -= data[k] * yj
