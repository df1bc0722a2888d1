"""Command ``xfemslip deplete``.

Parses arguments and prints; the work is in :mod:`xfemslip.studies.depletion`.
"""

from __future__ import annotations

import click

from xfemslip.cli.common import (
    FiniteFloat,
    case_argument,
    compression_option,
    configure_logging,
    debug_option,
    load_case_file,
    reported_errors,
    solve_options,
)


@click.command()
@case_argument
@solve_options
@click.option(
    "--tolerance",
    type=FiniteFloat(min=0.0, min_open=True),
    default=None,
    help="Bisection tolerance on the critical pore-pressure change [Pa] "
    "[default: 0.1 % of |pore_pressure.change|; a value below |change| x "
    "solver.tolerance, what the load steps resolve, is raised to it].",
)
@click.option(
    "--patch-length",
    type=FiniteFloat(min=0.0, min_open=True),
    default=None,
    metavar="M",
    help="Also find, per fracture, the pore-pressure change at which its "
    "slipping length first reaches M metres (bisection): the growth of slip, "
    "which converges under mesh refinement where the first slip at a corner "
    "does not.",
)
@click.option(
    "--plot",
    is_flag=True,
    help="Also draw slip_vs_depletion.png and depletion_field.png.",
)
@compression_option
@debug_option
def deplete(
    case,
    output,
    tolerance,
    patch_length,
    plot,
    overwrite,
    verbose,
    quiet,
    compression_positive,
    debug,
) -> None:
    """Critical depletion of every fracture of CASE: the pore-pressure change
    at which it first slips (bisection on the load), and slip vs depletion
    (result.h5, critical_depletion.csv, slip_vs_depletion.csv)."""
    with reported_errors(debug):
        configure_logging(verbose, quiet)
        spec = load_case_file(case)
        from xfemslip.studies.depletion import deplete as run_deplete
        from xfemslip.studies.depletion import format_report

        report = run_deplete(
            spec,
            output,
            tolerance=tolerance,
            plot=plot,
            overwrite=overwrite,
            patch_length=patch_length,
        )
        click.echo(format_report(report, compression_positive))
        for path in report.written:
            click.echo(str(path))
