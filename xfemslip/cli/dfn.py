"""Command ``xfemslip dfn``: realize a case's fracture network without solving.

Parses the arguments, prints, maps errors (through ``cli.common.reported_errors``);
the network is built by the case loader (:mod:`xfemslip.case.network`,
:mod:`xfemslip.geometry.dfn`), the figure by :mod:`xfemslip.plot.dfn`.
"""

from __future__ import annotations

from pathlib import Path

import click

from xfemslip.cli.common import (
    PathParam,
    case_argument,
    debug_option,
    figure_path,
    load_case_file,
    reported_errors,
)
from xfemslip.errors import UsageError


@click.command()
@case_argument
@click.option(
    "--csv",
    "csv_path",
    type=PathParam(dir_okay=False, path_type=Path, empty_ok=False),
    help="Write the fractures as a CSV of segments (the network.file format).",
)
@click.option(
    "--all",
    "include_inline",
    is_flag=True,
    help="Export the [[fractures]] of the case too [default: [network] only].",
)
@click.option(
    "--plot",
    type=PathParam(dir_okay=False, path_type=Path, empty_ok=False),
    callback=figure_path,
    help="Draw the network (.png or .pdf).",
)
@click.option(
    "--result",
    type=PathParam(dir_okay=False, exists=True, path_type=Path),
    help="A result.h5 of this case: colour the figure by |slip|.",
)
@click.option(
    "--summary",
    type=PathParam(dir_okay=False, exists=True, path_type=Path),
    help="A sweep's summary.csv: add the histogram of slipping fractures.",
)
@debug_option
def dfn(case, csv_path, include_inline, plot, result, summary, debug) -> None:
    """Realize the fracture network of CASE (its [network] table) and print its
    statistics; optionally export it as CSV and draw it.  Nothing is solved."""
    with reported_errors(debug):
        spec = load_case_file(case)
        from xfemslip.geometry.dfn import network_stats, segments_csv_text
        from xfemslip.io.csv import write_text

        chosen = [f for f in spec.fractures if include_inline or f.source]
        stats = network_stats([f.points for f in spec.fractures], spec.box)
        click.echo(
            f"{spec.name}: {stats['count']} fractures "
            f"({len(spec.fractures) - sum(bool(f.source) for f in spec.fractures)}"
            f" from [[fractures]]); in the domain: P20 = {stats['p20']:.4g} 1/m^2, "
            f"P21 = {stats['p21']:.4g} m/m^2, length {stats['min_length']:.4g} .. "
            f"{stats['max_length']:.4g} m (mean {stats['mean_length']:.4g} m)"
        )
        if csv_path is not None and not chosen:
            raise UsageError(
                f"{case}: no [network] fractures to export (--all exports the "
                "[[fractures]] too)"
            )
        if csv_path is not None:
            write_text(csv_path, segments_csv_text(chosen))
            click.echo(f"{len(chosen)} fractures -> {csv_path}")
        if plot is not None:
            from xfemslip.plot.dfn import figure_network, save

            save(figure_network(spec, result, summary), plot)
            click.echo(f"figure -> {plot}")
