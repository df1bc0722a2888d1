"""What run and deplete log by default: one line per load step, bisection
trials labelled as such; the Newton iterations only with -v."""

from __future__ import annotations

import re

from click.testing import CliRunner

from tests.support.golden import ROOT
from xfemslip.case import build
from xfemslip.cli import cli

STEP = re.compile(r"^step (\d+)/(\d+): (converged in \d+ Newton iteration|bisection)")


def _case(tmp_path, name, **keys):
    path = tmp_path / f"{name}.toml"
    path.write_text(
        build.case_text(build.file_case(ROOT / "cases" / f"{name}.toml", **keys))
    )
    return path


def _step_lines(stderr: str) -> list[str]:
    return [ln for ln in stderr.splitlines() if ln.startswith("step ")]


def test_run_logs_one_line_per_load_step(tmp_path):
    case = _case(tmp_path, "reservoir_depletion", **{"loading.steps": 3})
    result = CliRunner().invoke(cli, ["run", str(case), "-o", str(tmp_path / "a")])
    assert result.exit_code == 0, result.stderr
    lines = _step_lines(result.stderr)
    assert [ln.split(":")[0] for ln in lines] == ["step 1/3", "step 2/3", "step 3/3"]
    assert all(STEP.match(ln) for ln in lines), lines
    assert "iteration 0" not in result.stderr
    verbose = CliRunner().invoke(
        cli, ["run", str(case), "-v", "-o", str(tmp_path / "b")]
    )
    assert verbose.exit_code == 0, verbose.stderr
    assert "step 1/3 iteration 0: eta = " in verbose.stderr


def test_deplete_labels_its_bisection_trials(tmp_path):
    """cases/depleting_reservoir.toml on a coarser mesh: ten load steps, each
    one line, and the trials of the bisection each one line naming its dp."""
    case = _case(tmp_path, "depleting_reservoir", **{"mesh.elements": [40, 25]})
    result = CliRunner().invoke(cli, ["deplete", str(case), "-o", str(tmp_path / "d")])
    assert result.exit_code == 0, result.stderr
    lines = _step_lines(result.stderr)
    assert all(STEP.match(ln) for ln in lines), lines
    converged = [ln for ln in lines if "converged in" in ln]
    trials = [ln for ln in lines if "bisection trial" in ln]
    assert [ln.split(":")[0] for ln in converged] == [
        f"step {k}/10" for k in range(1, 11)
    ]
    assert trials and all(
        re.search(r"bisection trial \d+ at dp = -?[\d.]+ MPa: ", ln) for ln in trials
    )
    assert not re.search(r"iteration \d+:", result.stderr)
