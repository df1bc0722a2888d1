"""Command ``xfemslip dfn``: realize a case's fracture network without solving
(registered in :mod:`xfemslip.cli`).

Parses the arguments, prints, maps errors (through ``cli._reported_errors``);
the network is built by the case loader (:mod:`xfemslip.case_network`,
:mod:`xfemslip.dfn`), the figure by :mod:`xfemslip.dfn_plot`.
"""

from __future__ import annotations

from pathlib import Path

import click

from xfemslip.cli import (
    _case_argument,
    _debug_option,
    _figure_path,
    _load,
    _Path,
    _reported_errors,
)
from xfemslip.errors import OutputError, UsageError


def _write_text(path: Path, text: str) -> None:
    """Write ``text`` atomically (no partial file under the final name)."""
    from xfemslip.writers.atomic import atomic_path

    try:
        with atomic_path(path) as tmp:
            Path(tmp).write_text(text, encoding="utf-8")
    except OSError as exc:
        raise OutputError(f"{path}: cannot write: {exc.strerror or exc}") from None


@click.command()
@_case_argument
@click.option(
    "--csv",
    "csv_path",
    type=_Path(dir_okay=False, path_type=Path, empty_ok=False),
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
    type=_Path(dir_okay=False, path_type=Path, empty_ok=False),
    callback=_figure_path,
    help="Draw the network (.png or .pdf).",
)
@click.option(
    "--result",
    type=_Path(dir_okay=False, exists=True, path_type=Path),
    help="A result.h5 of this case: colour the figure by |slip|.",
)
@click.option(
    "--summary",
    type=_Path(dir_okay=False, exists=True, path_type=Path),
    help="A sweep's summary.csv: add the histogram of slipping fractures.",
)
@_debug_option
def dfn(case, csv_path, include_inline, plot, result, summary, debug) -> None:
    """Realize the fracture network of CASE (its [network] table) and print its
    statistics; optionally export it as CSV and draw it.  Nothing is solved."""
    with _reported_errors(debug):
        spec = _load(case)
        from xfemslip.dfn import network_stats, segments_csv_text

        (x0, y0), (w, h) = spec.origin, spec.size
        box = (x0, x0 + w, y0, y0 + h)
        chosen = [f for f in spec.fractures if include_inline or f.source]
        stats = network_stats([f.points for f in spec.fractures], box)
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
            _write_text(csv_path, segments_csv_text(chosen))
            click.echo(f"{len(chosen)} fractures -> {csv_path}")
        if plot is not None:
            from xfemslip.dfn_plot import figure_network, save

            save(figure_network(spec, result, summary), plot)
            click.echo(f"figure -> {plot}")
