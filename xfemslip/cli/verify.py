"""Command ``xfemslip verify``: the verification problems against closed forms.

Checks the options, prints progress and the table; the problems, the
measures and the targets are in :mod:`xfemslip.verify.problems`.
"""

from __future__ import annotations

import time
from pathlib import Path

import click

from xfemslip.case.fractures import TIP_KINDS
from xfemslip.cli.common import (
    EXIT_FAILURE,
    PathParam,
    debug_option,
    reported_errors,
)
from xfemslip.errors import UsageError


@click.command()
@click.option("--quick", is_flag=True, help="CI-sized: fewer problems and meshes.")
@click.option(
    "--tip",
    default=None,
    help="Crack-tip treatment, e.g. branch or ramp [default: the case default].",
)
@click.option(
    "--plot",
    type=PathParam(dir_okay=False, path_type=Path, empty_ok=False),
    help="Write error vs h and error vs wall time (.png or .pdf).",
)
@click.option(
    "--csv",
    "csv_path",
    type=PathParam(dir_okay=False, path_type=Path, empty_ok=False),
    help="Write the table as CSV.",
)
@click.option(
    "--penalty",
    default="100",
    show_default=True,
    help="kn h / E of the problems, or auto: leave kn, kt to the case default.",
)
@debug_option
def verify(quick, tip, plot, csv_path, penalty, debug) -> None:
    """Run the verification problems against closed forms; exit 1 if a target
    is missed (see docs/verification.md)."""
    with reported_errors(debug):
        ratio = _checked_options(tip, plot, penalty)
        # the library is imported here: `xfemslip --help` does not load NumPy
        from xfemslip.verify.problems import run_verification
        from xfemslip.verify.report import format_table, write_outputs

        start = time.perf_counter()

        def progress(msg):
            click.echo(f"[{time.perf_counter() - start:6.1f} s] {msg}", err=True)

        report = run_verification(
            quick=quick, tip=tip, penalty=ratio, progress=progress
        )
        click.echo(format_table(report))
        write_outputs(report, csv_path, plot)
        if report.failures:
            raise click.exceptions.Exit(EXIT_FAILURE)


def _checked_options(tip, plot, penalty) -> float | None:
    """UsageError for a bad --plot suffix, --tip or --penalty; the penalty
    ratio kn h / E (None: the case default)."""
    if plot is not None and Path(plot).suffix.lower() not in (".png", ".pdf"):
        raise UsageError(f"--plot {plot}: expected a .png or .pdf file name")
    if tip is not None and tip not in TIP_KINDS:
        raise UsageError(f"--tip {tip}: expected one of {', '.join(TIP_KINDS)}")
    if penalty == "auto":
        return None
    try:
        ratio = float(penalty)
    except ValueError:
        ratio = -1.0
    if not ratio > 0.0:
        raise UsageError(
            f"--penalty {penalty}: expected a positive number (kn h / E) or auto"
        )
    return ratio
