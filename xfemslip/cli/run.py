"""Commands ``xfemslip run | check | info``.

The library is imported inside each command, so that ``xfemslip --help`` and
``xfemslip info`` do not pay for NumPy, SciPy and h5py.
"""

from __future__ import annotations

import platform
import sys
from pathlib import Path

import click

from xfemslip import __version__
from xfemslip.cli.common import (
    EXIT_FAILURE,
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
    "--plot", is_flag=True, help="Also draw the figures into <output>/figures."
)
@debug_option
def run(
    case: Path,
    output: Path | None,
    overwrite: bool,
    verbose: bool,
    quiet: bool,
    plot: bool,
    debug: bool,
) -> None:
    """Run the case file CASE and write its results (CASE may be a pipe,
    such as <(...), or - for standard input).

    Ends with what happened on each fracture (slip, moment, magnitude), as
    ``xfemslip summary`` prints it; -q leaves that out.
    """
    with reported_errors(debug):
        configure_logging(verbose, quiet)
        spec = load_case_file(case)
        from xfemslip.simulation import run_case

        out_dir = output if output is not None else spec.output.directory
        summary = run_case(spec, out_dir, overwrite=overwrite)
        status = "converged" if summary.converged else "did NOT converge"
        click.echo(
            f"{spec.name}: {status} in {summary.load_steps} step(s), "
            f"{summary.newton_iterations} Newton iterations, "
            f"{summary.wall_time_s:.2f} s -> {summary.out_dir}"
        )
        if not quiet:  # what happened on the fractures
            from xfemslip.cli.summary import event_report

            for line in event_report(summary, spec):
                click.echo(line)
        if not summary.converged:
            raise click.exceptions.Exit(EXIT_FAILURE)
        if plot:  # matplotlib is imported only here
            from xfemslip.cli.studies import plot_run

            assert summary.out_dir is not None  # the command writes a folder
            plot_run(summary.out_dir)


@click.command()
@case_argument
@compression_option
@debug_option
def check(case: Path, compression_positive: bool, debug: bool) -> None:
    """Validate CASE and print its settings in engineering units (MPa, GPa,
    m, mm), stresses tension positive unless --compression-positive.

    Besides the keys, the geometry is checked (fractures against the mesh,
    boundary corners); nothing is assembled or solved.
    """
    with reported_errors(debug):
        configure_logging(False, True)  # warnings only: check prints the rest
        spec = load_case_file(case)
        from xfemslip.case import describe
        from xfemslip.simulation import check_geometry

        check_geometry(spec)
        click.echo(describe(spec, compression_positive))


@click.command()
def info() -> None:
    """Print versions and Numba settings."""
    from xfemslip.kernels import numba_settings

    rows = [("xfemslip", __version__), ("python", platform.python_version())]
    rows += [
        (name, _dist_version(name))
        for name in (
            *("numpy", "scipy", "numba", "h5py", "meshio", "click", "tomli-w"),
            "threadpoolctl",
            # optional: AMG, figures, Dask sweeps, MKL PARDISO (the mkl extra),
            # VTK (the tests read the ParaView files with it)
            *("pyamg", "matplotlib", "dask", "distributed", "pypardiso", "vtk"),
        )
    ]
    rows += numba_settings()
    rows += [("executable", sys.executable)]
    width = max(len(name) for name, _ in rows)
    for name, value in rows:
        click.echo(f"{name:<{width}}  {value}")


def _dist_version(name: str) -> str:
    """Installed version of a distribution, or 'not installed'."""
    import importlib.metadata  # only here: 0.05 s of imports that a run skips

    try:
        return importlib.metadata.version(name)
    except importlib.metadata.PackageNotFoundError:
        return "not installed"
