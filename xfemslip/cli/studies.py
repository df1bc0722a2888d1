"""Commands ``xfemslip sweep | plot | screen``.

These only parse arguments, print and map errors to exit codes
(through ``cli.common.reported_errors``); the work is in
:mod:`xfemslip.studies.sweep`, :mod:`xfemslip.studies.run`,
:mod:`xfemslip.plot.figures` and :mod:`xfemslip.reference.screen`.
matplotlib is imported only when a figure is drawn, Dask only with
``--scheduler``.
"""

from __future__ import annotations

import contextlib
import logging
import os
import sys
import time
from pathlib import Path

import click

from xfemslip.case.files import path_problem
from xfemslip.cli.common import (
    EXIT_FAILURE,
    FiniteFloat,
    PathParam,
    compression_option,
    configure_logging,
    debug_option,
    load_case_file,
    reported_errors,
    shown_path,
)
from xfemslip.errors import UsageError

# Each local worker holds its own interpreter, NumPy, SciPy and model
# (~0.2-1 GB); more than a few per CPU only adds memory.
MAX_JOBS = 4 * (os.cpu_count() or 1)
# A figure of a few inches at this resolution is already ~100 megapixels.
MAX_DPI = 2400.0
KINDS = (
    "displacement",
    "principal_stress",
    "deformed_mesh",
    "slip",
    "mohr",
    "profile",
)


# --------------------------------------------------------------------------- #
# sweep
# --------------------------------------------------------------------------- #


@click.command()
@click.argument("sweep_file", metavar="SWEEP", type=PathParam(path_type=Path))
@click.option(
    "-o",
    "--output",
    type=PathParam(file_okay=False, path_type=Path, empty_ok=False),
    default=None,
    help="Sweep folder [default: output.directory of the sweep, else "
    "out/sweeps/<name>].",
)
@click.option(
    "-j",
    "--jobs",
    type=click.IntRange(min=1, max=MAX_JOBS),
    default=None,
    help="Local worker processes [default: the number of CPUs, at most "
    f"{MAX_JOBS} = 4 x CPUs]; 1 runs the cases in this process.",
)
@click.option(
    "--scheduler",
    metavar="ADDRESS",
    default=None,
    help="Run on an existing Dask cluster (e.g. tcp://host:8786) instead of "
    "local processes; needs `pip install xfemslip[dask]`.",
)
@click.option("--force", is_flag=True, help="Rerun cases that already have a result.")
@click.option("-v", "--verbose", is_flag=True, help="Log every case's messages.")
@debug_option
def sweep(sweep_file, output, jobs, scheduler, force, verbose, debug) -> None:
    """Run the cases of the sweep file SWEEP (base case + varied parameters).

    Each case writes into <folder>/<case id>/; cases with a converged result
    of the same case text are skipped, cases that cannot be built are
    reported and not run.  A table of the results is printed and written to
    <folder>/summary.csv.  Exit 1 if a case failed or was refused.

    A sweep file with an [uncertainty] table instead of [vary] draws samples
    of uncertain inputs and writes the probability that each fracture slips
    against the pore-pressure change (docs/uncertainty.md).
    """
    with reported_errors(debug):
        configure_logging(verbose, not verbose)
        problem = path_problem(sweep_file)
        if problem:
            raise UsageError(f"{shown_path(sweep_file)}: the path {problem}")
        if not sweep_file.is_file():
            raise UsageError(f"{sweep_file}: no such file")
        from xfemslip.studies.run import format_table, require_dask, run_sweep
        from xfemslip.studies.sweep import load_sweep
        from xfemslip.studies.uncertainty import is_uncertainty_file

        if scheduler:
            require_dask()
        if is_uncertainty_file(sweep_file):  # docs/sweep-format.md, Uncertainty
            from xfemslip.cli.uncertainty import run_uncertainty

            run_uncertainty(
                sweep_file, output, jobs or os.cpu_count() or 1, scheduler, force
            )
            return
        spec = load_sweep(sweep_file)
        folder = output or spec.directory
        n_jobs = jobs or os.cpu_count() or 1
        where = f"Dask at {scheduler}" if scheduler else f"{n_jobs} local process(es)"
        click.echo(
            f"{spec.name}: {len(spec.cases)} case(s) -> {folder} ({where})", err=True
        )
        with _progress(spec.name, len(spec.cases)) as progress:
            rows = run_sweep(
                spec,
                folder,
                jobs=n_jobs,
                scheduler=scheduler,
                force=force,
                progress=progress,
            )
        click.echo(format_table(spec.keys, rows))
        _print_dfn_aggregate(spec.keys, rows)
        failed = sum(r.status == "failed" for r in rows)
        refused = sum(r.status == "refused" for r in rows)
        skipped = sum(r.status == "skipped" for r in rows)
        click.echo(
            f"summary: {folder / 'summary.csv'} ({len(rows) - failed - refused} "
            f"done, {skipped} of them skipped as already done, "
            f"{failed} failed, {refused} refused)",
            err=True,
        )
        if failed or refused:
            raise click.exceptions.Exit(EXIT_FAILURE)


@contextlib.contextmanager
def _progress(label: str, total: int):
    """A callback per finished case: a progress bar on a terminal; elsewhere
    (a pipe, a log file, CI) one line per case, so a long sweep reports as it
    goes instead of one line and then silence."""
    if sys.stderr.isatty():
        with click.progressbar(
            length=total,
            label=label,
            file=sys.stderr,  # click.get_text_stream is deprecated (Click 8.2)
        ) as bar:
            yield lambda row: bar.update(1)
        return
    start, done = time.monotonic(), 0

    def line(row) -> None:
        nonlocal done
        done += 1
        elapsed = time.monotonic() - start
        click.echo(
            f"[{done}/{total}] {row.case_id}: {row.status} ({elapsed:.1f} s)",
            err=True,
        )

    yield line


def _print_dfn_aggregate(keys, rows) -> None:
    """Over network realizations: the aggregate table of dfn_summary.csv."""
    from xfemslip.studies.dfn_summary import aggregate, format_aggregate, is_dfn_sweep

    if is_dfn_sweep(keys):
        click.echo("\nover the realizations (dfn_summary.csv):")
        click.echo(format_aggregate(aggregate(rows)))


# --------------------------------------------------------------------------- #
# plot
# --------------------------------------------------------------------------- #


def _default_figure_dir(results: list[Path]) -> Path:
    """One result: <its folder>/figures; several: <their common folder>/figures."""
    folders = [(p if p.is_dir() else p.parent).resolve() for p in results]
    if len(folders) == 1:
        return folders[0] / "figures"
    return Path(os.path.commonpath(folders)) / "figures"


@click.command()
@click.argument("results", nargs=-1, required=False, type=PathParam(path_type=Path))
@click.option(
    "--case",
    "case",
    type=PathParam(path_type=Path, dir_okay=False),
    default=None,
    help="Draw this case file before it runs: geometry, mesh, fractures, "
    "boundary conditions and loads, as <case file name>.png/.pdf [default "
    "folder: the case file's].",
)
@click.option(
    "-o",
    "--output",
    type=PathParam(file_okay=False, path_type=Path, empty_ok=False),
    default=None,
    help="Folder for the figures [default: <result folder>/figures, or the "
    "results' common folder /figures].",
)
@click.option(
    "--figure",
    "kinds",
    multiple=True,
    type=click.Choice((*KINDS, "network", "permeability")),
    help="Draw only this figure (repeatable) [default: all but network and "
    "permeability]; network: slip and contact state of every fracture of the "
    "first result; permeability: apertures and the permeability ratio of the "
    "first result (a case with [permeability]).",
)
@click.option(
    "--format",
    "formats",
    multiple=True,
    type=click.Choice(("png", "pdf")),
    help="File format (repeatable) [default: png and pdf].",
)
@click.option(
    "--label",
    "labels",
    multiple=True,
    help="Legend label of each result, in order (repeatable).",
)
@click.option(
    "--scale",
    type=FiniteFloat(min=0.0, min_open=True),
    default=None,
    help="Displacement magnification of the deformed mesh [default: auto].",
)
@click.option(
    "--dpi",
    type=FiniteFloat(min=10.0, max=MAX_DPI),
    default=110.0,
    show_default=True,
    help="Resolution of the PNG files.",
)
@debug_option
def plot(results, case, output, kinds, formats, labels, scale, dpi, debug) -> None:
    """Draw the paper's figures of one or several RESULTS (result.h5 files or
    their folders); several results are drawn side by side or overlaid.
    With --case, draw a case file before it runs (the paper's Fig. 5)."""
    with reported_errors(debug):
        configure_logging(False, True)  # the warnings; the paths are printed
        # and one line per figure on stderr: a large result takes a minute
        logging.getLogger("xfemslip.plot.figures.progress").setLevel(logging.INFO)
        if case is not None:
            spec = load_case_file(case)
            from xfemslip.plot.case import plot_case

            out_dir = output or Path(case).parent
            for path in plot_case(spec, out_dir, formats or ("png", "pdf"), dpi):
                click.echo(str(path))
            if not results:
                return
        elif not results:
            raise UsageError(
                "plot needs RESULTS (result.h5 files or folders) or --case"
            )
        from xfemslip.plot.figures import plot_results

        out_dir = output or _default_figure_dir(list(results))
        written = plot_results(
            list(results),
            out_dir,
            kinds=kinds or KINDS,
            formats=formats or ("png", "pdf"),
            labels=labels or None,
            scale=scale,
            dpi=dpi,
        )
        for path in written:
            click.echo(str(path))


def plot_run(out_dir: Path) -> None:
    """``xfemslip run --plot``: every figure of the run into <out_dir>/figures."""
    from xfemslip.plot.figures import plot_results

    for path in plot_results([out_dir / "result.h5"], out_dir / "figures"):
        click.echo(str(path))


# --------------------------------------------------------------------------- #
# screen
# --------------------------------------------------------------------------- #


@click.command()
@click.argument("case", required=False, type=PathParam(path_type=Path))
@click.option(
    "--stress",
    nargs=3,
    type=FiniteFloat(),
    default=None,
    metavar="XX YY XY",
    help="Total far-field stress [Pa], tension positive [default: CASE's "
    "in-situ stress: loading.initial_stress with a [pore_pressure] change, "
    "else loading.stress].",
)
@click.option(
    "-p",
    "--pore-pressure",
    type=FiniteFloat(),
    default=None,
    help="Pore pressure p [Pa]; effective stress = stress + p I "
    "[default: pore_pressure.initial of CASE, else 0].",
)
@click.option(
    "--friction",
    type=FiniteFloat(min=0.0),
    default=None,
    help="Friction coefficient f [default: the first fracture's].",
)
@click.option(
    "--cohesion",
    type=FiniteFloat(min=0.0),
    default=None,
    help="Cohesion c [Pa] [default: the first fracture's, else 0].",
)
@click.option(
    "--angle",
    "angles",
    multiple=True,
    type=FiniteFloat(),
    help="A fracture angle to screen [deg, CCW from +x] (repeatable) "
    "[default: the fractures of CASE].",
)
@click.option(
    "--step",
    type=FiniteFloat(min=0.1, max=90.0),
    default=5.0,
    show_default=True,
    help="Angle step of the orientation table [deg].",
)
@click.option(
    "--csv",
    "csv_path",
    type=PathParam(dir_okay=False, path_type=Path, empty_ok=False),
    default=None,
    help="Also write the orientation table as CSV.",
)
@click.option(
    "--plot",
    "plot_dir",
    type=PathParam(file_okay=False, path_type=Path, empty_ok=False),
    default=None,
    help="Also draw the Mohr diagram into this folder.",
)
@click.option(
    "--format",
    "formats",
    multiple=True,
    type=click.Choice(("png", "pdf")),
    help="Format of the --plot files (repeatable) [default: png and pdf].",
)
@compression_option
@debug_option
def screen(
    case,
    stress,
    pore_pressure,
    friction,
    cohesion,
    angles,
    step,
    csv_path,
    plot_dir,
    formats,
    compression_positive,
    debug,
) -> None:
    """Closed-form slip screening of every orientation (and of the fractures of
    CASE): slip tendency, Coulomb margin, the band that slips and the
    pore-pressure change at which each fracture slips or opens, along CASE's
    own stress path when it changes the pore pressure (else at constant
    total stress, the pressure rising).  Options in Pa; the report in MPa,
    tension positive unless --compression-positive (the CSV keeps Pa)."""
    with reported_errors(debug):
        from xfemslip.reference import screen as scr
        from xfemslip.studies.slip_screen import screen_plan

        configure_logging(False, True)  # the warnings; the report is printed
        spec = load_case_file(case) if case is not None else None
        fractures = _screen_planes(spec, stress, friction, cohesion, angles)
        plan = screen_plan(spec, fractures, stress, pore_pressure)
        if plan.refused:
            _warn_path_refused(case, plan.refused)
        f0, c0 = fractures[0][2], fractures[0][3]
        screened = [
            scr.screen_fracture(
                label, theta, plan.stress, plan.pore_pressure, f, c, found
            )
            for (label, theta, f, c, _), found in zip(
                fractures, plan.onsets, strict=True
            )
            if label
        ]
        click.echo(
            scr.format_report(
                plan.stress,
                plan.pore_pressure,
                f0,
                c0,
                step,
                screened,
                plan.text,
                compression_positive,
            )
        )
        if csv_path is not None:
            _write_screen_csv(
                csv_path,
                scr.orientation_table(
                    plan.stress, plan.pore_pressure, f0, c0, _angles(step)
                ),
            )
        if plot_dir is not None:
            from xfemslip.plot.figures import plot_screen

            for path in plot_screen(
                plot_dir,
                plan.stress,
                plan.pore_pressure,
                f0,
                c0,
                [(s.label, s.theta, s.friction, s.cohesion) for s in screened],
                formats or ("png", "pdf"),
            ):
                click.echo(str(path), err=True)


def _angles(step: float):
    import numpy as np

    return np.arange(0.0, 180.0, step)


def _warn_path_refused(case, why: str) -> None:
    """The case changes the pore pressure along a path the closed form cannot
    follow: say why, what the screen did instead, and what answers it."""
    logging.getLogger("xfemslip.reference.screen").warning(
        "%s: the closed form cannot follow this case's stress path (%s); this "
        "screen keeps the total stress fixed instead, so its dp to slip is not "
        "the case's (xfemslip deplete %s solves the poroelastic path)",
        case,
        why,
        case,
    )


def _screen_planes(spec, stress, friction, cohesion, angles):
    """[(label, theta, f, c, ends)] from the case's spec (or None) and the
    options; a fracture-less entry (label "") carries the defaults of f and c."""
    loading = None if spec is None else spec.loading
    if stress is None and (
        loading is None or (loading.stress is None and loading.initial_stress is None)
    ):
        raise UsageError("screen needs --stress XX YY XY or a CASE with loading.stress")
    if angles:
        fractures = [(f"angle {a:g}", a, friction, cohesion, None) for a in angles]
    elif spec is not None and spec.fractures:
        from xfemslip.reference.screen import case_fractures

        fractures = case_fractures(spec)
    else:
        fractures = [("", 0.0, friction, cohesion, None)]
    f0 = friction if friction is not None else fractures[0][2]
    if f0 is None:
        raise UsageError("screen needs --friction (or a CASE with a fracture)")
    c0 = cohesion if cohesion is not None else (fractures[0][3] or 0.0)
    return [  # --friction and --cohesion replace every fracture's
        (
            lab,
            th,
            f0 if friction is not None or f is None else f,
            c0 if cohesion is not None or c is None else c,
            ends,
        )
        for lab, th, f, c, ends in fractures
    ]


def _write_screen_csv(path: Path, table: dict) -> None:
    from xfemslip.io.csv import write_csv

    names = list(table)
    rows = (
        [
            f"{table[n][i]:.9g}" if n != "slips" else str(bool(table[n][i])).lower()
            for n in names
        ]
        for i in range(len(table[names[0]]))
    )
    write_csv(path, names, rows)
