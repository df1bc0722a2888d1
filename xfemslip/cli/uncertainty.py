"""``xfemslip sweep`` of a sweep file with an ``[uncertainty]`` table.

Parses nothing itself: :mod:`xfemslip.studies.uncertainty` reads the file,
:mod:`xfemslip.studies.reactivation` evaluates the samples and
:mod:`xfemslip.studies.uncertainty_output` writes and formats the results.
"""

from __future__ import annotations

import time
from pathlib import Path

import click

from xfemslip.cli.common import EXIT_FAILURE


def run_uncertainty(sweep_file: Path, output, jobs: int, scheduler, force: bool):
    """Draw, evaluate, write, print; exit 1 when a sample was refused or failed."""
    from xfemslip.studies import reactivation
    from xfemslip.studies.run import connect, sweep_lock
    from xfemslip.studies.uncertainty import load_uncertainty
    from xfemslip.studies.uncertainty_output import format_summary, write_outputs

    spec = load_uncertainty(sweep_file)
    folder = Path(output or spec.directory)
    where = (
        "closed form"
        if spec.evaluate == "screen"
        else f"Dask at {scheduler}"
        if scheduler
        else f"{jobs} local process(es)"
    )
    click.echo(
        f"{spec.name}: {spec.samples} sample(s), evaluate = {spec.evaluate} -> "
        f"{folder} ({where})",
        err=True,
    )
    client = connect(scheduler) if scheduler and spec.evaluate == "xfem" else None
    try:
        with sweep_lock(folder):
            if spec.evaluate == "screen":
                result = reactivation.evaluate_screen(spec)
            else:
                result = reactivation.evaluate_xfem(
                    spec,
                    folder,
                    jobs=jobs,
                    client=client,
                    force=force,
                    progress=_progress(spec.samples),
                )
            written = write_outputs(result, folder)
    finally:
        if client is not None:
            client.close()
    click.echo(format_summary(result))
    for path in written:
        click.echo(str(path), err=True)
    bad = int(sum(s in ("refused", "failed") for s in result.status))
    if bad:
        click.echo(
            f"{bad} sample(s) refused or failed (see uncertainty.csv); the "
            "probabilities count the evaluated samples only",
            err=True,
        )
        raise click.exceptions.Exit(EXIT_FAILURE)


def _progress(total: int):
    """One line per finished sample on stderr, with the elapsed time."""
    start, done = time.monotonic(), 0

    def line(case_id: str, status: str) -> None:
        nonlocal done
        done += 1
        click.echo(
            f"[{done}/{total}] {case_id}: {status} ({time.monotonic() - start:.1f} s)",
            err=True,
        )

    return line
