"""Solving the nonlinear problem: load stepping with Newton-Raphson and the linear
solves of its systems.

Modules:

- ``newton``: ``NewtonSolver`` and ``Problem``: load steps, bisection, Newton
  iterations;
- ``linear``: ``LinearSolver``: direct and AMG solves of the Newton systems.

The subpackage imports nothing itself: import the module you need (``from
xfemslip.solve.newton import ...``)."""

__all__ = ["linear", "newton"]
