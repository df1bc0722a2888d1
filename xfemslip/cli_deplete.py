"""Command ``xfemslip deplete`` (registered in :mod:`xfemslip.cli`).

Parses arguments and prints; the work is in :mod:`xfemslip.depletion`.
"""

from __future__ import annotations

import click

from xfemslip.cli import (
    _case_argument,
    _configure_logging,
    _debug_option,
    _FiniteFloat,
    _load,
    _reported_errors,
    _solve_options,
)


@click.command()
@_case_argument
@_solve_options
@click.option(
    "--tolerance",
    type=_FiniteFloat(min=0.0, min_open=True),
    default=None,
    help="Bisection tolerance on the critical pore-pressure change [Pa] "
    "[default: 0.1 % of |pore_pressure.change|; a value below |change| x "
    "solver.tolerance, what the load steps resolve, is raised to it].",
)
@click.option(
    "--plot",
    is_flag=True,
    help="Also draw slip_vs_depletion.png and depletion_field.png.",
)
@_debug_option
def deplete(case, output, tolerance, plot, overwrite, verbose, quiet, debug) -> None:
    """Critical depletion of every fracture of CASE: the pore-pressure change
    at which it first slips (bisection on the load), and slip vs depletion
    (result.h5, critical_depletion.csv, slip_vs_depletion.csv)."""
    with _reported_errors(debug):
        _configure_logging(verbose, quiet)
        spec = _load(case)
        from xfemslip.depletion import deplete as run_deplete
        from xfemslip.depletion import format_report

        report = run_deplete(
            spec, output, tolerance=tolerance, plot=plot, overwrite=overwrite
        )
        click.echo(format_report(report))
        for path in report.written:
            click.echo(str(path))
