"""Solving the nonlinear problem: load stepping with Newton-Raphson and the linear
solves of its systems.

Modules:

- ``newton``: ``NewtonSolver`` and ``Problem``: load steps, bisection, Newton
  iterations;
- ``linear``: ``LinearSolver``: direct and AMG solves of the Newton systems,
  and the automatic choice among them;
- ``pardiso``: the MKL PARDISO path (the mkl extra): one SPD factorization
  with the Schur complement on the contact dofs, or a fixed pattern;
- ``lowrank``: the PARDISO path of networks: the stuck matrix factored once,
  each Newton system a low-rank change of it;
- ``backward``: the backward error every solve is checked against;
- ``threads``: OpenBLAS on one thread while PARDISO solves.

The subpackage imports nothing itself: import the module you need (``from
xfemslip.solve.newton import ...``)."""

__all__ = ["backward", "linear", "lowrank", "newton", "pardiso", "threads"]
