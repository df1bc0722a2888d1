"""Command ``xfemslip summary``: what happened in a run, from its result.h5.

The same per-fracture table and "what happened" line that end ``xfemslip
run`` (:func:`event_report`), for any result read back through
:func:`xfemslip.read_result`: the event sizes it stores, or, for a result
written without them, computed from what it stores
(:mod:`xfemslip.post.events`, which says what an older result lacks).
"""

from __future__ import annotations

from pathlib import Path

import click

from xfemslip import display
from xfemslip.cli.common import compression_option, debug_option, reported_errors

__all__ = ["event_report", "summary"]


def event_report(result, spec=None, every_step: bool = False) -> list[str]:
    """The lines printed for ``result``: its final converged step, or every
    one; ``spec`` the case when at hand (its events.extent), else what the
    result stores.  None without a converged step (the status line before
    says so)."""
    from xfemslip.post.events import (
        event_inputs,
        event_sizes,
        increment_line,
        summary_lines,
    )
    from xfemslip.post.hydraulics import permeability_lines, ratio_phrase

    if not result.steps:
        return []
    inputs = event_inputs(result, spec)
    sizes = event_sizes(result, inputs)
    shown = range(len(sizes)) if every_step else [len(sizes) - 1]
    lines = []
    for k in shown:
        step = result.steps[k]
        lines.append(
            f"fractures at step {step.step} of {result.load_steps} "
            f"(load factor {step.load_factor:.4g}), slip cumulative over the steps:"
        )
        perm = result.permeability
        lines += summary_lines(sizes[k], inputs, ratio_phrase(perm, k) if perm else "")
        lines += permeability_lines(result, k)
        if every_step:
            lines.append(increment_line(sizes[k], inputs))
    return lines


@click.command()
@click.argument("result_path", metavar="RESULT", type=click.Path(path_type=Path))
@click.option(
    "--steps",
    "every_step",
    is_flag=True,
    help="A table for every converged load step, not only the last, with "
    "what the step's own slip adds.",
)
@compression_option
@debug_option
def summary(
    result_path: Path, every_step: bool, compression_positive: bool, debug: bool
) -> None:
    """Print what happened in the run that wrote RESULT (a result.h5 or its
    folder): per fracture whether it slipped, max slip, slipping length,
    moment per unit length, stress drop and magnitude with its extent W; with
    [permeability], the apertures and the block's permeability change."""
    with reported_errors(debug):
        from xfemslip import read_result

        result = read_result(result_path)
        name = _case_name(result.attrs.get("case_toml", ""))
        status = "converged" if result.converged else "did NOT converge"
        click.echo(
            f"{name or result_path}: {status}, {len(result.steps)} converged "
            f"step(s), {result.newton_iterations} Newton iterations"
        )
        if not result.steps:
            click.echo("no converged load step: nothing to report on the fractures")
        else:
            click.echo(display.convention(compression_positive))
        for line in event_report(result, every_step=every_step):
            click.echo(line)
        if result.depletion is not None:
            from xfemslip.studies.depletion import depletion_lines

            for line in depletion_lines(result.depletion, compression_positive):
                click.echo(line)


def _case_name(text: str) -> str:
    """The case's ``name`` from its text ("" when it gives none)."""
    import tomllib

    try:
        name = tomllib.loads(str(text)).get("name", "")
    except tomllib.TOMLDecodeError:
        return ""
    return name if isinstance(name, str) else ""
