"""Initial guesses for a sequence of linear systems from the earlier solutions.

The Newton systems of a run (every iteration, load step and ``deplete``
bisection) share the bulk stiffness and differ only in the contact tangent,
and with proportional loading their right-hand sides repeat the same few
directions.  A Krylov solve started from zero pays its full iteration count
on every one of them.  Started from the best combination of the last few
solutions instead (the projection of Fischer, "Projection techniques for
iterative solution of Ax = b with successive right-hand sides", Comput.
Methods Appl. Mech. Engrg. 163 (1998) 193-204, here in its least-squares
form because the friction tangent is not symmetric),

    x0 = X c,   c = argmin || A X c - b ||,

a system whose answer lies in the span of the kept solutions is solved
without any iteration, and one near it in a few.  The cost is one matrix
product per kept vector and a least-squares solve of m unknowns.
"""

from __future__ import annotations

from collections import deque

import numpy as np

__all__ = ["KEEP", "PreviousSolutions"]

# solutions kept (the memory is KEEP vectors of the free dofs: 6 x 16 MB at
# 2M dofs); a load step adds one or two
KEEP = 6
# singular values of A X below this share of the largest are dropped (a
# solution repeated, or one the others already span)
RCOND = 1.0e-12


class PreviousSolutions:
    """The last :data:`KEEP` solutions of a sequence of systems of one size,
    each scaled to unit norm."""

    def __init__(self, keep: int = KEEP):
        self.vectors: deque[np.ndarray] = deque(maxlen=keep)

    def __len__(self) -> int:
        return len(self.vectors)

    def add(self, x: np.ndarray) -> None:
        norm = float(np.linalg.norm(x))
        if norm > 0.0 and np.isfinite(norm):
            self.vectors.append(np.asarray(x, dtype=np.float64) / norm)

    def guess(self, A, b: np.ndarray) -> tuple[np.ndarray | None, float]:
        """(x0, ||A x0 - b||) minimising the residual over the span of the kept
        solutions; (None, ||b||) with none kept."""
        b = np.asarray(b, dtype=np.float64)
        if not self.vectors or not np.any(b):
            return None, float(np.linalg.norm(b))
        X = np.column_stack(self.vectors)
        W = np.asarray(A @ X)
        c = np.linalg.lstsq(W, b, rcond=RCOND)[0]
        if not np.all(np.isfinite(c)):
            return None, float(np.linalg.norm(b))
        return X @ c, float(np.linalg.norm(W @ c - b))
