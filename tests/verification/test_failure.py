"""A run that cannot converge fails at a known step and keeps what it had.

The reservoir case with 3 MPa cohesion and 5 load steps: by the far-field
Mohr-Coulomb closed form the 45-degree fracture sticks while
|tau| <= c + f |sigma_n|, i.e. up to load factor
lambda* = c / (|tau| - f |sigma_n|) = 3 / (10 - 3) = 0.43.  While everything
sticks the problem is linear and Newton converges in one iteration, so with
``[solver] max_iterations = 1`` and the secant tangent (the consistent one
with the stick/slip predictor converges the first slipping step in one
iteration too) steps 1 and 2 (lambda 0.2, 0.4) converge and
step 3 (lambda 0.6, the first with slip) fails: ConvergenceError with step 3,
iteration 1 and the residual eta; result.h5 exists with converged = False and
holds steps 1 and 2 (output-format.md, house style "the writers flush the steps
already completed").  The CLI turns it into exit code 1 and one line
"Error: ..." on stderr naming the step and the residual.

Measured (secant, after 6 cuts): eta = 8.63e-4 at step 3, iteration 1; 9
stick/slip switches.
"""

from __future__ import annotations

import math
import re
import subprocess
import sys
import tomllib
import xml.etree.ElementTree as ET
from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from tests.support.harness import STICK
from xfemslip.case import build, load_case
from xfemslip.cli import cli
from xfemslip.errors import ConvergenceError
from xfemslip.simulation import run_case

pytestmark = pytest.mark.verification

CASES = Path(__file__).resolve().parents[2] / "cases"
STEPS = 5
COHESION = 3.0e6


def expected_failing_step() -> int:
    """First load step whose load factor exceeds the closed-form onset of slip."""
    doc = tomllib.loads((CASES / "reservoir_depletion.toml").read_text())
    s = doc["loading"]["stress"]
    f = doc["fractures"][0]["friction"]
    theta = math.radians(doc["fractures"][0]["angle"])
    t = np.array([math.cos(theta), math.sin(theta)])
    n = np.array([-t[1], t[0]])
    sig = np.array([[s["xx"], s["xy"]], [s["xy"], s["yy"]]])
    sigma_n, tau = n @ sig @ n, t @ sig @ n
    onset = COHESION / (abs(tau) - f * abs(sigma_n))
    return math.floor(STEPS * onset) + 1


def write_case(folder: Path, *, steps=STEPS, cohesion=COHESION, formats=("h5", "vtu")):
    doc = tomllib.loads((CASES / "reservoir_depletion.toml").read_text())
    doc["loading"]["steps"] = steps
    doc["fractures"][0]["cohesion"] = cohesion
    # secant tangent: the stick/slip predictor (consistent tangent only)
    # would converge the first slipping step in one iteration
    doc["solver"] = {"max_iterations": 1, "tolerance": 1.0e-8, "tangent": "secant"}
    doc["output"] = {"formats": list(formats)}
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "failing.toml"
    path.write_text(build.case_text(doc))
    return path


def test_expected_step_from_closed_form():
    assert expected_failing_step() == 3


def test_run_case_raises_and_keeps_converged_steps(tmp_path):
    out = tmp_path / "out"
    with pytest.raises(ConvergenceError) as info:
        run_case(load_case(write_case(tmp_path)), out)
    err = info.value
    k = expected_failing_step()
    assert err.step == k
    assert err.iteration == 1
    assert math.isfinite(err.residual) and err.residual > 1.0e-8
    assert f"{err.residual:.3e}" in str(err)

    h5 = out / "result.h5"
    assert h5.is_file()
    with h5py.File(h5, "r") as f:
        assert not bool(f.attrs["converged"])
        assert int(f.attrs["load_steps"]) == STEPS
        assert (
            int(f.attrs["newton_iterations"]) == k - 1
        )  # one iteration per stuck step
        kept = sorted(f["steps"].keys())
        assert kept == [f"{i:04d}" for i in range(1, k)]
        # the root holds the last converged step
        np.testing.assert_array_equal(
            f["fields/displacement"][()],
            f[f"steps/{k - 1:04d}/fields/displacement"][()],
        )
        u1 = f["steps/0001/fields/displacement"][()]
        u2 = f["steps/0002/fields/displacement"][()]
        for i in range(1, k):
            assert np.all(f[f"steps/{i:04d}/fractures/0/state"][()] == STICK)
    # the kept steps are right: stuck steps are linear in the load
    np.testing.assert_allclose(u2, 2.0 * u1, rtol=0, atol=1e-9 * np.max(np.abs(u2)))
    # no file of a step that did not converge, and no temporary files left behind
    names = {p.name for p in out.rglob("*")}
    assert not any(f"{k:04d}" in name for name in names)
    assert not any(name.startswith(".") or name.endswith(".tmp") for name in names), (
        names
    )
    pvd = ET.parse(out / "result.pvd").getroot()
    files = [d.get("file") for d in pvd.iter("DataSet")]
    assert len(files) == k - 1
    assert all((out / name).is_file() for name in files)


def test_failure_in_first_step_writes_mesh_only(tmp_path):
    """No cohesion: the first step already slides and needs 2 iterations."""
    out = tmp_path / "out"
    with pytest.raises(ConvergenceError) as info:
        run_case(load_case(write_case(tmp_path, steps=1, cohesion=0.0)), out)
    assert info.value.step == 1
    with h5py.File(out / "result.h5", "r") as f:
        assert not bool(f.attrs["converged"])
        assert "mesh/points" in f and "mesh/cells" in f
        assert "fields" not in f and "steps" not in f


def _error_lines(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if line.startswith("Error:")]


def _check_error_line(line: str, step: int):
    assert re.search(rf"\bstep {step}\b", line), line
    assert re.search(r"residual[^0-9]*[0-9.]+e[-+][0-9]+", line), line


def console_script() -> list[str]:
    """The installed ``xfemslip`` script of this interpreter's environment
    (beside sys.executable, whether or not the environment is activated),
    else ``python -m xfemslip``."""
    script = Path(sys.executable).with_name("xfemslip")
    return [str(script)] if script.is_file() else [sys.executable, "-m", "xfemslip"]


def test_cli_exit_code_and_message(tmp_path):
    """The installed console script: exit 1, one 'Error:' line, last on stderr."""
    case = write_case(tmp_path)
    proc = subprocess.run(
        [*console_script(), "run", str(case), "-o", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 1, proc.stderr[-2000:]
    errors = _error_lines(proc.stderr)
    assert len(errors) == 1, proc.stderr[-2000:]
    assert proc.stderr.strip().splitlines()[-1] == errors[0]
    _check_error_line(errors[0], expected_failing_step())
    assert "Traceback" not in proc.stderr
    with h5py.File(tmp_path / "out" / "result.h5", "r") as f:
        assert not bool(f.attrs["converged"])


def test_cli_quiet_prints_only_the_error(tmp_path):
    case = write_case(tmp_path, formats=("h5",))
    try:  # click < 8.2 mixes stderr into stdout unless told otherwise
        runner = CliRunner(mix_stderr=False)
    except TypeError:
        runner = CliRunner()
    result = runner.invoke(cli, ["run", "-q", str(case), "-o", str(tmp_path / "out")])
    assert result.exit_code == 1, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("Error:"), result.stderr
    _check_error_line(lines[0], expected_failing_step())
    assert result.stdout == ""
