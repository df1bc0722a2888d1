"""Command-line interface: ``xfemslip run | check | info | verify | sweep |
plot | screen | deplete | dfn | summary``.

The commands parse arguments, configure logging, call the library and map its
errors to messages and exit codes (:mod:`xfemslip.cli.common`); they do no
numerics.  One module per group of commands; nothing in the library imports
this package.
"""

from __future__ import annotations

import click

from xfemslip import __version__, interrupt
from xfemslip.cli.common import EXIT_USAGE, Group, one_line
from xfemslip.cli.deplete import deplete
from xfemslip.cli.dfn import dfn
from xfemslip.cli.env import check_environment, check_platform
from xfemslip.cli.run import check, info, run
from xfemslip.cli.studies import plot, screen, sweep
from xfemslip.cli.summary import summary
from xfemslip.cli.verify import verify
from xfemslip.errors import UsageError

__all__ = ["cli", "main"]


@click.group(cls=Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="xfemslip")
def cli() -> None:
    """XFEM frictional contact on 2D fractures, driven by TOML case files."""
    try:  # not inside reported_errors: the command installs the signal handlers
        check_platform()
        check_environment()
    except UsageError as err:
        click.echo(f"Error: {one_line(err)}", err=True)
        raise click.exceptions.Exit(EXIT_USAGE) from None


for _command in (run, check, info, verify, sweep, plot, screen, deplete, dfn, summary):
    cli.add_command(_command)


def main() -> None:
    """Console-script entry point (``xfemslip``)."""
    # here, not at the top: memory imports NumPy, which --help and the
    # argument errors do not pay
    from xfemslip import memory

    # freed memory goes back to the system between Newton iterations, so the
    # peak is what memory.py estimates (see configure_allocator)
    memory.configure_allocator()
    interrupt.for_process()
    try:
        cli(prog_name="xfemslip")
    except KeyboardInterrupt as exc:
        # a signal whose Python handler ran while the command was already on
        # its way out (its SystemExit replaced): the command said what the
        # folder holds; end with the shell's code, not killed by the signal
        from xfemslip.cli.common import EXIT_INTERRUPTED, EXIT_TERMINATED

        term = isinstance(exc, interrupt.Terminated)
        raise SystemExit(EXIT_TERMINATED if term else EXIT_INTERRUPTED) from None
    finally:
        _forget_interrupted_string_exec()


def _forget_interrupted_string_exec() -> None:
    """Keep the exit code the command chose after a caught Ctrl-C.

    CPython records a KeyboardInterrupt that ends the evaluation of a source
    string (``exec``/``eval`` of a ``str``: a namedtuple or a dataclass being
    defined by a module imported on the way, say), even when a caller catches
    it; under ``python -m`` the interpreter then kills itself with SIGINT at
    exit, so a run that reported "interrupted" and chose 130 ends as killed
    by the signal.  Every string evaluation clears that record when it
    starts: an empty one here does, after the last place a signal handler
    can raise (the command has put SIG_IGN in place)."""
    exec("", {})
