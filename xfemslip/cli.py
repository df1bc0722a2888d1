"""Command-line interface: ``xfemslip run | check | info | verify``.

This module parses arguments, configures logging, calls the library and maps
its errors to messages and exit codes.  It does no numerics.

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
import platform
import sys
import traceback
from collections.abc import Iterator
from pathlib import Path

import click

from xfemslip import __version__
from xfemslip.case_files import path_problem
from xfemslip.errors import (
    CaseError,
    GeometryError,
    MeshError,
    UsageError,
    XfemslipError,
)
from xfemslip.interrupt import Terminated, sigterm_as_interrupt

logger = logging.getLogger(__name__)

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


def _configure_logging(verbose: bool, quiet: bool) -> None:
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


def _one_line(err: BaseException) -> str:
    """The error's message on one line (falls back to the class name)."""
    text = " ".join(str(err).split())
    return text or type(err).__name__


@contextlib.contextmanager
def _reported_errors(debug: bool) -> Iterator[None]:
    """Turn library errors, Ctrl-C and SIGTERM into ``Error: ...`` and an exit
    code (``xfemslip.interrupt``: a signal always ends the command)."""
    try:
        with sigterm_as_interrupt():
            yield
    except XfemslipError as err:
        if debug:
            click.secho(traceback.format_exc().rstrip(), err=True, dim=True)
        click.echo(f"Error: {_one_line(err)}", err=True)
        usage = isinstance(err, CaseError | UsageError | GeometryError | MeshError)
        raise click.exceptions.Exit(EXIT_USAGE if usage else EXIT_FAILURE) from None
    except KeyboardInterrupt as err:
        if debug:
            click.secho(traceback.format_exc().rstrip(), err=True, dim=True)
        term = isinstance(err, Terminated)
        # the notes say what each output folder holds (xfemslip.writers.folder)
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


def _load(case: Path):
    """Load and validate a case file (``CaseError`` on any problem)."""
    from xfemslip.case import load_case

    problem = path_problem(case)
    if problem:
        raise UsageError(f"{_shown_path(case)}: the path {problem}")
    if not case.exists():
        raise UsageError(f"{case}: no such file")
    if case.is_dir():
        raise UsageError(f"{case}: is a directory, expected a case file (.toml)")
    return load_case(case)


def _shown_path(path) -> str:
    """A path for a message: NUL bytes escaped, cut to 80 characters."""
    text = repr(str(path))[1:-1]
    return text if len(text) <= 80 else text[:77] + "..."


class _Path(click.Path):
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
                self.fail(f"{_shown_path(value)}: {problem}", param, ctx)
        return super().convert(value, param, ctx)


class _FiniteFloat(click.FloatRange):
    """``click.FloatRange`` without NaN and infinities (``float("nan")``
    passes every range test)."""

    def convert(self, value, param, ctx):
        number = super().convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{number!r} is not a finite number", param, ctx)
        return number


def _figure_path(ctx, param, value):
    """A figure file whose suffix matplotlib can write (checked before any
    work; matplotlib is imported only when a figure is asked for)."""
    if value is None:
        return value
    from matplotlib.backend_bases import FigureCanvasBase

    known = FigureCanvasBase.get_supported_filetypes()
    if value.suffix.lstrip(".").lower() not in known:
        raise click.BadParameter(
            f"{_shown_path(value)}: the suffix must be one of "
            + ", ".join(f".{k}" for k in sorted(known))
        )
    return value


class _OneLineUsageError(click.UsageError):
    """A click usage error shown as one line ``Error: ...`` (no usage block),
    like every other refusal of the CLI."""

    def show(self, file=None) -> None:
        hint = f" (see '{self.ctx.command_path} --help')" if self.ctx else ""
        message = " ".join(self.format_message().split())
        click.echo(f"Error: {message}{hint}", err=True)


@contextlib.contextmanager
def _one_line_usage() -> Iterator[None]:
    """Re-raise click's usage errors (bad options, arguments) as one line."""
    try:
        yield
    except _OneLineUsageError:
        raise
    except getattr(click.exceptions, "NoArgsIsHelpError", ()):
        raise  # `xfemslip` alone prints the help
    except click.UsageError as err:
        raise _OneLineUsageError(err.format_message(), err.ctx) from None


class _Group(click.Group):
    """The command group; its usage errors and its subcommands' are one line."""

    def make_context(self, info_name, args, parent=None, **extra):
        with _one_line_usage():
            return super().make_context(info_name, args, parent, **extra)

    def invoke(self, ctx):
        with _one_line_usage():
            return super().invoke(ctx)


_debug_option = click.option(
    "--debug", is_flag=True, help="Show the traceback of a reported error."
)
_case_argument = click.argument("case", type=_Path(path_type=Path))


@click.group(cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="xfemslip")
def cli() -> None:
    """XFEM frictional contact on 2D fractures, driven by TOML case files."""
    from xfemslip.cli_env import check_environment

    try:  # not inside _reported_errors: the command installs the signal handlers
        check_environment()
    except UsageError as err:
        click.echo(f"Error: {_one_line(err)}", err=True)
        raise click.exceptions.Exit(EXIT_USAGE) from None


def _solve_options(command):
    """-o/--output, --overwrite, -v/--verbose and -q/--quiet: the options of
    every command that solves a case and writes its results (run, deplete)."""
    for option in reversed(
        [
            click.option(
                "-o",
                "--output",
                "output",
                type=_Path(file_okay=False, path_type=Path, empty_ok=False),
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


@cli.command()
@_case_argument
@_solve_options
@click.option(
    "--plot", is_flag=True, help="Also draw the figures into <output>/figures."
)
@_debug_option
def run(
    case: Path,
    output: Path | None,
    overwrite: bool,
    verbose: bool,
    quiet: bool,
    plot: bool,
    debug: bool,
) -> None:
    """Run the case file CASE and write its results."""
    with _reported_errors(debug):
        _configure_logging(verbose, quiet)
        spec = _load(case)
        from xfemslip.simulation import run_case

        summary = run_case(spec, output, overwrite=overwrite)
        status = "converged" if summary.converged else "did NOT converge"
        click.echo(
            f"{spec.name}: {status} in {summary.load_steps} step(s), "
            f"{summary.newton_iterations} Newton iterations, "
            f"{summary.wall_time_s:.2f} s -> {summary.out_dir}"
        )
        if not summary.converged:
            raise click.exceptions.Exit(EXIT_FAILURE)
        if plot:  # matplotlib is imported only here
            from xfemslip.cli_studies import plot_run

            plot_run(summary.out_dir)


@cli.command()
@_case_argument
@_debug_option
def check(case: Path, debug: bool) -> None:
    """Validate CASE and print its settings in SI units.

    Besides the keys, the geometry is checked (fractures against the mesh,
    boundary corners); nothing is assembled or solved.
    """
    with _reported_errors(debug):
        spec = _load(case)
        from xfemslip.case import describe
        from xfemslip.simulation import check_geometry

        check_geometry(spec)
        click.echo(describe(spec))


@cli.command()
def info() -> None:
    """Print versions and Numba settings."""
    from xfemslip.kernels._config import numba_settings

    rows = [("xfemslip", __version__), ("python", platform.python_version())]
    rows += [
        (name, _dist_version(name))
        for name in ("numpy", "scipy", "numba", "pyamg", "h5py", "meshio", "click")
    ]
    rows += numba_settings()
    rows += [("executable", sys.executable)]
    width = max(len(name) for name, _ in rows)
    for name, value in rows:
        click.echo(f"{name:<{width}}  {value}")


@cli.command()
@click.option("--quick", is_flag=True, help="CI-sized: fewer problems and meshes.")
@click.option(
    "--tip",
    default=None,
    help="Crack-tip treatment, e.g. branch or ramp [default: the case default].",
)
@click.option(
    "--plot",
    type=_Path(dir_okay=False, path_type=Path, empty_ok=False),
    help="Write error vs h and error vs wall time (.png or .pdf).",
)
@click.option(
    "--csv",
    "csv_path",
    type=_Path(dir_okay=False, path_type=Path, empty_ok=False),
    help="Write the table as CSV.",
)
@click.option(
    "--penalty",
    default="100",
    show_default=True,
    help="kn h / E of the problems, or auto: leave kn, kt to the case default.",
)
@_debug_option
def verify(quick, tip, plot, csv_path, penalty, debug) -> None:
    """Run the verification problems against closed forms; exit 1 if a target
    is missed (see README, Verification)."""
    with _reported_errors(debug):
        from xfemslip.verify import main as verify_main

        if not verify_main(
            quick=quick, tip=tip, plot=plot, csv_path=csv_path, penalty=penalty
        ):
            raise click.exceptions.Exit(EXIT_FAILURE)


def _dist_version(name: str) -> str:
    """Installed version of a distribution, or 'not installed'."""
    import importlib.metadata  # only here: 0.05 s of imports that a run skips

    try:
        return importlib.metadata.version(name)
    except importlib.metadata.PackageNotFoundError:
        return "not installed"


# sweep | plot | screen: their code is in cli_studies, which imports the helpers
# above (so this import stays below them).
from xfemslip.cli_studies import plot, screen, sweep  # noqa: E402

cli.add_command(sweep)
cli.add_command(plot)
cli.add_command(screen)

# deplete: its code is in cli_deplete (issue 6, depletion)
from xfemslip.cli_deplete import deplete  # noqa: E402

cli.add_command(deplete)

from xfemslip.cli_dfn import dfn  # noqa: E402  (random fracture networks)

cli.add_command(dfn)


def main() -> None:
    """Console-script entry point (``xfemslip``)."""
    from xfemslip import interrupt, memory

    # freed memory goes back to the system between Newton iterations, so the
    # peak is what memory.py estimates (see configure_allocator)
    memory.configure_allocator()
    interrupt.for_process()
    cli(prog_name="xfemslip")
