"""The elimination order of SuperLU's factorizations: nested dissection of
the structured grid.

Every dof belongs to a node of the (nx + 1) x (ny + 1) grid (an enriched
dof to the node it enriches), and two nodes share matrix entries only when
they share a cell (or a contact patch along a fracture).  A line of nodes
therefore separates the grid in two: eliminating the two halves first and
the line last keeps the fill of each half to itself.  Applied recursively
(George 1973, "Nested dissection of a regular finite element mesh", SIAM J.
Numer. Anal. 10, 345-363) the factor of a 2-D grid has O(n log n) entries
and costs O(n^1.5) operations, the best an ordering can do there.  SuperLU's
own choice, minimum degree on A^T + A, knows nothing of the grid; measured
on the uncracked 200 x 200 stiffness (81k dofs, one BLAS thread): 17.3M
entries in L + U and 1.18-1.57 s against 12.3M and 0.52-0.83 s in this
order (MKL PARDISO's SPD factor-and-solve: 0.44 s on two threads); at
400 x 400 (321k dofs) 96.8M entries and 10.2 s against 58.4M and 3.7 s.
Contact patches couple nodes along a fracture across a separator, and
enriched nodes carry more dofs on its lines: the order stays valid, but
where many dofs are enriched (networks) minimum degree does better, so
the solver takes this order only with few (linear.GRID_ORDER_MAX_ENRICHED).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

# Largest side, in nodes, of a box ordered row by row instead of being cut
# again (on the uncracked 200 x 200 stiffness 4 gave the least fill, 12.3M
# entries against 13.7M at 8 and 16.7M at 16, and the fastest
# factorization, 0.52 against 0.66 and 0.90 s).
LEAF = 4


def grid_dissection(nx: int, ny: int, leaf: int = LEAF) -> np.ndarray:
    """(n_nodes,) the position of each node of the (nx + 1) x (ny + 1) grid
    (node j (nx + 1) + i at column i, row j) in a nested-dissection order:
    a box of nodes is cut across its longer side by its middle line of
    nodes, the two halves come first (each cut again), the line last."""
    if nx < 0 or ny < 0 or leaf < 1:
        raise ValueError(f"grid_dissection: nx, ny >= 0, leaf >= 1: {nx, ny, leaf}")
    boxes = []  # (i0, i1, j0, j1) inclusive, in elimination order
    # an explicit stack of box tuples, a box's line pushed below its halves
    # so that it comes after them; the nodes of all boxes are made in one
    # pass below (a recursion making each box's nodes as arrays took 2 s at
    # 1000 x 1000 cells, this 0.2 s)
    stack = [(0, nx, 0, ny, False)]
    while stack:
        i0, i1, j0, j1, line = stack.pop()
        w, h = i1 - i0 + 1, j1 - j0 + 1
        if line or (w <= leaf and h <= leaf):
            boxes.append((i0, i1, j0, j1))
        elif w >= h:
            m = (i0 + i1) // 2
            stack += [(m, m, j0, j1, True), (m + 1, i1, j0, j1, False)]
            stack += [(i0, m - 1, j0, j1, False)] if m > i0 else []
        else:
            m = (j0 + j1) // 2
            stack += [(i0, i1, m, m, True), (i0, i1, m + 1, j1, False)]
            stack += [(i0, i1, j0, m - 1, False)] if m > j0 else []
    b = np.array(boxes, dtype=np.int64).reshape(-1, 4)
    width = b[:, 1] - b[:, 0] + 1
    count = width * (b[:, 3] - b[:, 2] + 1)
    box = np.repeat(np.arange(b.shape[0]), count)
    local = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
    i = b[box, 0] + local % width[box]
    j = b[box, 2] + local // width[box]
    rank = np.empty((nx + 1) * (ny + 1), np.int64)
    rank[j * (nx + 1) + i] = np.arange(i.size)
    return rank


def node_grid(node_xy) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The rectilinear grid of the nodes (n_nodes, 2): its distinct x and y
    lines, increasing, and each node's column and row on them (the ranks of
    its x and y)."""
    xy = np.asarray(node_xy, dtype=float)
    x, col = np.unique(xy[:, 0], return_inverse=True)
    y, row = np.unique(xy[:, 1], return_inverse=True)
    return x, y, col.ravel(), row.ravel()


def grid_order(dof_node, node_xy) -> np.ndarray:
    """The elimination order (a permutation of the dofs) of the nested
    dissection of the grid (grid_dissection), a node's dofs together in
    their own order.  dof_node : (n,) the node of each dof; node_xy :
    (n_nodes, 2) the coordinates of the rectilinear grid's nodes
    (node_grid)."""
    _, _, col, row = node_grid(node_xy)
    nx, ny = int(col.max(initial=0)), int(row.max(initial=0))
    rank = grid_dissection(nx, ny)[row * (nx + 1) + col]
    return np.argsort(rank[np.asarray(dof_node, dtype=np.int64)], kind="stable")


def permuted(A, order: np.ndarray) -> sp.csc_matrix:
    """A[order][:, order] as CSC: the columns picked, the row indices
    renumbered and sorted (the row then column fancy indexing of scipy
    copies the matrix twice)."""
    order = np.asarray(order, dtype=np.int64)
    inverse = np.empty_like(order)
    inverse[order] = np.arange(order.size)
    B = sp.csc_matrix(A)[:, order]
    B.indices = inverse[B.indices].astype(B.indices.dtype, copy=False)
    B.has_sorted_indices = False
    B.sort_indices()
    return B
