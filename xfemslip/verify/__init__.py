"""``xfemslip verify``: the verification problems, solved and compared with
the closed forms of :mod:`xfemslip.reference`.

Modules:

- ``problems``: the verification problems, their runs and the errors
  against the references;
- ``report``: the table, the CSV file and the plot of a verification run.

Kept apart from :mod:`xfemslip.reference` because it runs the solver, which
the closed forms must not need.  The subpackage imports nothing itself:
import the module you need (``from xfemslip.verify.problems import ...``).
"""

__all__ = ["problems", "report"]
