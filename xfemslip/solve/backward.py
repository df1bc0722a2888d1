"""The normwise backward error of a linear solve, the accuracy check every
linear solver of the Newton systems applies (``linear``, ``pardiso``)."""

from __future__ import annotations

import numpy as np

__all__ = ["backward_error", "backward_error_of"]


def backward_error(A, x, b, norm_A=None) -> float:
    """Normwise backward error ||A x - b|| / (||A|| ||x|| + ||b||), infinity
    norms (0 for x = b = 0, inf for a non-finite x)."""
    if not np.all(np.isfinite(x)):
        return np.inf
    if norm_A is None:
        norm_A = abs(A).sum(axis=1).max()
    return backward_error_of(A @ x - b, x, b, norm_A)


def backward_error_of(residual, x, b, norm_A) -> float:
    """backward_error from the residual A x - b and ||A|| (infinity norms)."""
    if not np.all(np.isfinite(x)):
        return np.inf
    den = float(norm_A) * np.abs(x).max(initial=0.0) + np.abs(b).max(initial=0.0)
    r = np.abs(residual).max(initial=0.0)
    return float(r / den) if den > 0.0 else float(r)


def refined(solve, apply, r, norm_A, max_error: float, stats: dict):
    """x = solve(r) and its backward error against apply (x -> A x), with
    one step of iterative refinement when the error is above max_error
    (counted in stats["refinements"]): the check every factored solve of
    the contact systems makes."""
    x = solve(r)
    err = backward_error_of(apply(x) - r, x, r, norm_A)
    if not err <= max_error and np.isfinite(err):
        stats["refinements"] += 1
        x = x + solve(r - apply(x))
        err = backward_error_of(apply(x) - r, x, r, norm_A)
    return x, err
