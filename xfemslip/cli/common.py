"""What every command of the CLI shares: logging set-up, error reporting,
exit codes, parameter types and the common options.

Exit codes:

- 0: success;
- 1: the run failed (``ConvergenceError``, ``OutputError``, any other
  ``XfemslipError``);
- 2: bad input (``CaseError``, ``GeometryError`` and ``MeshError`` -- input
  that validates key by key but cannot be built, e.g. overlapping fractures --
  ``xfemslip.errors.UsageError``, a missing case file, bad command-line
  options);
- 130: interrupted (Ctrl-C, SIGINT); 143: terminated (SIGTERM, see
  ``xfemslip.interrupt``); the line says what the output folder holds.

A library error is reported as one line ``Error: <message>`` on stderr; the
traceback is shown only with ``--debug``.  Any other exception is a bug and
propagates with its traceback.
"""

from __future__ import annotations

import contextlib
import logging
import math
import traceback
from collections.abc import Iterator
from pathlib import Path

import click

from xfemslip.case.files import STDIN, path_problem
from xfemslip.errors import (
    CaseError,
    GeometryError,
    MeshError,
    UsageError,
    XfemslipError,
)
from xfemslip.interrupt import Terminated, sigterm_as_interrupt

EXIT_FAILURE = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130  # 128 + SIGINT, the shell convention
EXIT_TERMINATED = 143  # 128 + SIGTERM

_HANDLER_NAME = "xfemslip-cli"


class _EchoHandler(logging.Handler):
    """Log handler writing to the *current* ``sys.stderr`` through click.

    Resolving stderr at emit time keeps it working under ``CliRunner``, which
    swaps the streams for every invocation.
    """

    def emit(self, record: logging.LogRecord) -> None:
        try:
            click.echo(self.format(record), err=True)
        except Exception:  # logging must never raise
            self.handleError(record)


class _CompactFormatter(logging.Formatter):
    """``message`` alone below WARNING, ``LEVEL: message`` from WARNING up."""

    def format(self, record: logging.LogRecord) -> str:
        message = super().format(record)
        if record.levelno >= logging.WARNING:
            return f"{record.levelname}: {message}"
        return message


def configure_logging(verbose: bool, quiet: bool) -> None:
    """Log ``xfemslip.*`` to stderr: INFO by default, -q WARNING, -v DEBUG."""
    if verbose and quiet:
        raise UsageError("--verbose and --quiet cannot be used together")
    level = logging.DEBUG if verbose else logging.WARNING if quiet else logging.INFO
    package_logger = logging.getLogger("xfemslip")
    for handler in list(package_logger.handlers):
        if handler.get_name() == _HANDLER_NAME:
            package_logger.removeHandler(handler)
    handler = _EchoHandler()
    handler.set_name(_HANDLER_NAME)
    handler.setFormatter(_CompactFormatter("%(message)s"))
    package_logger.addHandler(handler)
    package_logger.setLevel(level)


def one_line(err: BaseException) -> str:
    """The error's message on one line (falls back to the class name)."""
    text = " ".join(str(err).split())
    return text or type(err).__name__


@contextlib.contextmanager
def reported_errors(debug: bool) -> Iterator[None]:
    """Turn library errors, Ctrl-C and SIGTERM into ``Error: ...`` and an exit
    code (``xfemslip.interrupt``: a signal always ends the command)."""
    try:
        with sigterm_as_interrupt():
            yield
    except XfemslipError as err:
        if debug:
            click.secho(traceback.format_exc().rstrip(), err=True, dim=True)
        click.echo(f"Error: {one_line(err)}", err=True)
        usage = isinstance(err, CaseError | UsageError | GeometryError | MeshError)
        raise click.exceptions.Exit(EXIT_USAGE if usage else EXIT_FAILURE) from None
    except KeyboardInterrupt as err:
        if debug:
            click.secho(traceback.format_exc().rstrip(), err=True, dim=True)
        term = isinstance(err, Terminated)
        # the notes say what each output folder holds (xfemslip.io.folder)
        left = "; ".join(getattr(err, "__notes__", ())) or (
            "no partial file is left under a final name"
        )
        click.echo(
            f"Error: interrupted ({'SIGTERM' if term else 'SIGINT'}); {left}",
            err=True,
        )
        raise click.exceptions.Exit(
            EXIT_TERMINATED if term else EXIT_INTERRUPTED
        ) from None


def load_case_file(case: Path):
    """Load and validate a case file, a pipe or standard input (``-``)
    (``CaseError`` on any problem); values that are valid but look like a
    mistake are logged as warnings (xfemslip.case.plausibility)."""
    from xfemslip.case import load_case

    problem = path_problem(case)
    if problem:
        raise UsageError(f"{shown_path(case)}: the path {problem}")
    if str(case) != STDIN and not case.exists():
        raise UsageError(f"{case}: no such file")
    if case.is_dir():
        raise UsageError(f"{case}: is a directory, expected a case file (.toml)")
    spec = load_case(case)
    from xfemslip.case.plausibility import plausibility_warnings

    for warning in plausibility_warnings(spec):
        logging.getLogger("xfemslip.case").warning("%s: %s", shown_path(case), warning)
    return spec


def shown_path(path) -> str:
    """A path for a message: NUL bytes escaped, cut to 80 characters."""
    text = repr(str(path))[1:-1]
    return text if len(text) <= 80 else text[:77] + "..."


class PathParam(click.Path):
    """``click.Path`` that refuses a path no file system can hold (a NUL byte,
    which click's own ``os.stat`` turns into a ValueError; a name over 255
    bytes) and, with ``empty_ok=False``, an empty path (``-o ""`` would write
    into the current folder)."""

    def __init__(self, *args, empty_ok: bool = True, **kwargs):
        super().__init__(*args, **kwargs)
        self.empty_ok = empty_ok

    def convert(self, value, param, ctx):
        if isinstance(value, str):
            if not value and not self.empty_ok:
                self.fail("the path is empty", param, ctx)
            problem = path_problem(value)
            if problem:
                self.fail(f"{shown_path(value)}: {problem}", param, ctx)
        return super().convert(value, param, ctx)


class FiniteFloat(click.FloatRange):
    """``click.FloatRange`` without NaN and infinities (``float("nan")``
    passes every range test)."""

    def convert(self, value, param, ctx):
        number = super().convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{number!r} is not a finite number", param, ctx)
        return number


def figure_path(ctx, param, value):
    """A figure file whose suffix matplotlib can write (checked before any
    work; matplotlib is imported only when a figure is asked for)."""
    if value is None:
        return value
    from matplotlib.backend_bases import FigureCanvasBase

    known = FigureCanvasBase.get_supported_filetypes()
    if value.suffix.lstrip(".").lower() not in known:
        raise click.BadParameter(
            f"{shown_path(value)}: the suffix must be one of "
            + ", ".join(f".{k}" for k in sorted(known))
        )
    return value


class OneLineUsageError(click.UsageError):
    """A click usage error shown as one line ``Error: ...`` (no usage block),
    like every other refusal of the CLI."""

    def show(self, file=None) -> None:
        hint = f" (see '{self.ctx.command_path} --help')" if self.ctx else ""
        message = " ".join(self.format_message().split())
        click.echo(f"Error: {message}{hint}", err=True)


@contextlib.contextmanager
def one_line_usage() -> Iterator[None]:
    """Re-raise click's usage errors (bad options, arguments) as one line."""
    try:
        yield
    except OneLineUsageError:
        raise
    except getattr(click.exceptions, "NoArgsIsHelpError", ()):
        raise  # `xfemslip` alone prints the help
    except click.UsageError as err:
        raise OneLineUsageError(err.format_message(), err.ctx) from None


class Group(click.Group):
    """The command group; its usage errors and its subcommands' are one line."""

    def make_context(self, info_name, args, parent=None, **extra):
        with one_line_usage():
            return super().make_context(info_name, args, parent, **extra)

    def invoke(self, ctx):
        with one_line_usage():
            return super().invoke(ctx)


debug_option = click.option(
    "--debug", is_flag=True, help="Show the traceback of a reported error."
)
case_argument = click.argument("case", type=PathParam(path_type=Path))
compression_option = click.option(
    "--compression-positive",
    is_flag=True,
    help="Print stresses and tractions compression positive and pore-pressure "
    "changes as depletions (a drop > 0) [default: tension positive, as the "
    "files are].",
)


def solve_options(command):
    """-o/--output, --overwrite, -v/--verbose and -q/--quiet: the options of
    every command that solves a case and writes its results (run, deplete)."""
    for option in reversed(
        [
            click.option(
                "-o",
                "--output",
                "output",
                type=PathParam(file_okay=False, path_type=Path, empty_ok=False),
                default=None,
                help="Output directory [default: output.directory of the case, "
                "else out/<name>].",
            ),
            click.option(
                "--overwrite",
                is_flag=True,
                help="Replace the results of an earlier run.",
            ),
            click.option("-v", "--verbose", is_flag=True, help="Log debug messages."),
            click.option(
                "-q", "--quiet", is_flag=True, help="Log warnings and errors only."
            ),
        ]
    ):
        command = option(command)
    return command
