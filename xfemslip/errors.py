"""Exceptions of xfemslip.

Library code raises these; only :mod:`xfemslip.cli` turns them into messages
and exit codes (``CaseError`` and ``UsageError`` -> exit 2, the others -> exit 1).
"""

from __future__ import annotations

# Problems of a CaseError spelled out in its one-line message (all are kept
# in ``problems``).
MAX_SHOWN_PROBLEMS = 20


class XfemslipError(Exception):
    """Base class of every error xfemslip reports to a user."""


class CaseError(XfemslipError):
    """Invalid case file: every problem of the file, each with its key path.

    ``problems`` is a list of ``(key_path, message)``; ``str(err)`` is one line:
    ``case.toml: fractures[0].friction: must be >= 0, got -0.1`` or, with
    several problems, ``case.toml: 2 problems: a: ...; b: ...``.
    """

    def __init__(self, path, problems):
        self.path = str(path)
        self.problems = [(str(k), str(m)) for k, m in problems]
        parts = [f"{k}: {m}" if k else m for k, m in self.problems]
        if len(parts) > MAX_SHOWN_PROBLEMS:  # a file of 200,000 unknown keys
            hidden = len(parts) - MAX_SHOWN_PROBLEMS
            parts = [*parts[:MAX_SHOWN_PROBLEMS], f"and {hidden} more"]
        if len(parts) == 1:
            text = f"{self.path}: {parts[0]}"
        else:
            text = f"{self.path}: {len(self.problems)} problems: " + "; ".join(parts)
        super().__init__(text.replace("\n", " "))


class UsageError(XfemslipError):
    """A command-line usage problem found by the library (e.g. output exists)."""


class MeshError(XfemslipError):
    """A mesh that cannot be built or is not supported."""


class GeometryError(XfemslipError):
    """Fracture geometry that cannot be represented (names the case key)."""


class ConvergenceError(XfemslipError):
    """Newton did not converge in a load step.

    Fields: ``step`` (1-based), ``iteration``, ``residual`` (eta),
    ``increment`` (relative increment norm), ``flips`` (stick/slip switches in
    the last iteration), ``reason`` (why, without the step and residual
    figures of the message), ``retryable`` (False when a smaller load step
    cannot help, so the step is not bisected) and ``result`` (the
    :class:`~xfemslip.post.result.Result` of the steps that converged before,
    set by ``run_case``; None elsewhere).
    """

    def __init__(
        self,
        message,
        *,
        step,
        iteration,
        residual,
        increment=float("nan"),
        flips=0,
        reason="",
        retryable=True,
        result=None,
    ):
        self.step = step
        self.iteration = iteration
        self.residual = residual
        self.increment = increment
        self.flips = flips
        self.reason = reason
        self.retryable = retryable
        self.result = result
        super().__init__(message)


class OutputError(XfemslipError):
    """Output that cannot be written (unwritable directory, disk full, ...)."""


class ResultError(OutputError, UsageError):
    """A file read as a ``result.h5`` that is not one: missing, not HDF5,
    damaged (a checksum, a truncated file) or not what the output format
    says (a dataset missing, of the wrong shape, non-finite).

    It is an ``OutputError``, what :func:`xfemslip.read_result` promises,
    and a ``UsageError``: the file is bad input to the command that reads
    it, so the command-line reports it in one line with exit code 2.
    """
