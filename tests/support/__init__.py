"""Helpers shared by the test tiers and the benchmarks: case builders
(``casegen``, ``harness``, ``depletion_cases``), the numerical stress matrix
(``matrix``), inputs whose cost is measured (``hardcases``) and point-by-point
references of the bulk kernels (``bulk_reference``).  Importable as
``tests.support`` from the project root (``pythonpath`` in pyproject.toml).
"""
