"""Faults: interruption (SIGINT, SIGTERM), a full or unwritable output
directory, an existing output directory, and a non-finite state.

Contract (output-format.md): a failed or interrupted run never leaves a
truncated file under a final name; the CLI says what happened in one line.
"""

from __future__ import annotations

import errno
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

import xfemslip.simulation as simulation
from xfemslip.case import build
from xfemslip.cli import cli
from xfemslip.errors import OutputError
from xfemslip.io import hdf5

ROOT = Path(__file__).resolve().parents[2]
RESERVOIR = ROOT / "cases" / "reservoir_depletion.toml"


def case_file(folder: Path, *, n=10, steps=3, formats=("h5", "vtu")) -> Path:
    keys = {"mesh.elements": [n, n], "loading.steps": steps, "output.formats": formats}
    text = build.case_text(build.file_case(RESERVOIR, **keys))
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "case.toml"
    path.write_text(text)
    return path


def _error_line(result) -> str:
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert lines and lines[-1].startswith("Error: "), result.stderr
    assert sum(line.startswith("Error: ") for line in lines) == 1
    assert "Traceback" not in result.stderr
    return lines[-1]


def _no_partial_files(out: Path) -> list[str]:
    """Names under out; none temporary (in it or beside it: the staging
    folder and the lock), every final .h5 complete."""
    names = (
        sorted(str(p.relative_to(out)) for p in out.rglob("*")) if out.exists() else []
    )
    assert not any(Path(n).name.startswith(".") for n in names), names
    beside = [p.name for p in out.parent.iterdir() if p.name.startswith(".")]
    assert beside == [], beside
    for name in names:
        if name.endswith(".h5"):
            with h5py.File(out / name, "r") as f:
                assert "mesh/points" in f
    return names


# ------------------------------------------------------------- interruption


@pytest.mark.parametrize(
    ("sig", "code", "name"),
    [(signal.SIGINT, 130, "SIGINT"), (signal.SIGTERM, 143, "SIGTERM")],
)
def test_signal_during_a_run_leaves_no_partial_file(tmp_path, sig, code, name):
    """A real process, interrupted while it iterates (many load steps, so it
    is still running when the signal arrives)."""
    case = case_file(tmp_path, n=30, steps=400)
    out = tmp_path / "out"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.Popen(
        [sys.executable, "-m", "xfemslip", "run", str(case), "-o", str(out)],
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        # SIGINT as in a terminal: a suite started in the background (a
        # script, CI) hands its children SIGINT ignored
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    lines = []
    deadline = time.monotonic() + 120
    for line in proc.stderr:  # wait until Newton is iterating
        lines.append(line)
        if "step 3/400" in line or time.monotonic() > deadline:
            break
    proc.send_signal(sig)
    _, rest = proc.communicate(timeout=120)
    stderr = "".join(lines) + rest
    assert proc.returncode == code, stderr[-2000:]
    last = stderr.strip().splitlines()[-1]
    assert last == f"Error: interrupted ({name}); nothing was written to {out}"
    assert "Traceback" not in stderr
    assert not out.exists()  # interrupted while solving: nothing
    _no_partial_files(out)


def test_interrupt_inside_a_string_exec_keeps_exit_130(tmp_path):
    """A Ctrl-C whose handler runs while a source string is evaluated (a
    module imported on the way defining a namedtuple or a dataclass), caught
    and reported by the command: ``python -m xfemslip`` ends with 130, not
    killed by SIGINT (CPython records such an interrupt for ``-m`` runs)."""
    (tmp_path / "interrupted_exec.py").write_text(
        "import xfemslip.cli as cli\n"
        "import click\n"
        "from xfemslip.cli.common import reported_errors\n"
        "@click.command()\n"
        "def command():\n"
        "    with reported_errors(False):\n"
        "        exec('raise KeyboardInterrupt', {})\n"
        "cli.cli = command\n"
        "cli.main()\n"
    )
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path), str(ROOT)]))
    proc = subprocess.run(
        [sys.executable, "-m", "interrupted_exec"],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
        timeout=120,
    )
    assert proc.returncode == 130, (proc.returncode, proc.stderr)
    assert _error_line(proc).startswith("Error: interrupted (SIGINT)")


def test_interrupt_while_writing_removes_the_file(tmp_path, runner, monkeypatch):
    """Ctrl-C in the middle of writing result.h5: no result.h5, no temporary."""
    calls = []

    def interrupted(group, name, value, units):
        calls.append(name)
        if len(calls) == 4:
            raise KeyboardInterrupt
        return original(group, name, value, units)

    original = hdf5._dataset
    monkeypatch.setattr(hdf5, "_dataset", interrupted)
    out = tmp_path / "out"
    result = runner.invoke(cli, ["run", "-q", str(case_file(tmp_path)), "-o", str(out)])
    assert result.exit_code == 130
    assert _error_line(result) == (
        f"Error: interrupted (SIGINT); nothing was written to {out}"
    )
    assert len(calls) == 4  # premise: it was writing
    assert _no_partial_files(out) == []


# ------------------------------------------------------- full / unwritable


def test_full_disk_is_a_clear_error_and_leaves_no_file(tmp_path, runner, monkeypatch):
    """ENOSPC raised by the HDF5 writer half-way through the file."""
    calls = []

    def full(group, name, value, units):
        calls.append(name)
        if len(calls) == 5:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return original(group, name, value, units)

    original = hdf5._dataset
    monkeypatch.setattr(hdf5, "_dataset", full)
    out = tmp_path / "out"
    result = runner.invoke(cli, ["run", "-q", str(case_file(tmp_path)), "-o", str(out)])
    assert result.exit_code == 1
    line = _error_line(result)
    assert f"cannot write {out / 'result.h5'}" in line
    assert "No space left on device" in line
    assert _no_partial_files(out) == []


@pytest.mark.parametrize("earlier", [False, True])
def test_full_disk_while_writing_vtu(tmp_path, runner, monkeypatch, earlier):
    """A disk that fills while the VTU is written leaves no result.h5 that
    claims completeness: the folder keeps the earlier result byte for byte,
    or there is none.  The disk fills in the middle of a file: the first
    data array's bytes raise ENOSPC after the header was written."""
    from xfemslip.io import vtkxml

    out = tmp_path / "out"
    before = {}
    if earlier:
        case = case_file(tmp_path / "earlier", steps=2)
        assert (
            runner.invoke(cli, ["run", "-q", str(case), "-o", str(out)]).exit_code == 0
        )
        before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
        # premise: h5, its 2 XDMF, 2 PVD, 2 VTU and 2 x 2 in steps/
        assert len(before) == 11

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(vtkxml, "_encode", full)
    args = ["run", "-q", str(case_file(tmp_path)), "-o", str(out), "--overwrite"]
    result = runner.invoke(cli, args)
    assert result.exit_code == 1
    line = _error_line(result)
    assert f"cannot write {out}/" in line and ".vtu: No space left on device" in line
    _no_partial_files(out)
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before


def test_output_under_a_file_is_a_clear_error(tmp_path, runner):
    blocker = tmp_path / "blocker"
    blocker.write_text("not a directory")
    out = blocker / "out"
    result = runner.invoke(cli, ["run", "-q", str(case_file(tmp_path)), "-o", str(out)])
    assert result.exit_code == 1
    line = _error_line(result)
    assert f"cannot create output directory {out}" in line
    assert blocker.read_text() == "not a directory"


def test_existing_output_is_refused_untouched(tmp_path, runner):
    """docs/output-format.md: an output folder holding results is refused
    (exit 2) unless --overwrite; the earlier files stay byte for byte."""
    case = case_file(tmp_path, steps=1, formats=["h5"])
    out = tmp_path / "out"
    first = runner.invoke(cli, ["run", "-q", str(case), "-o", str(out)])
    assert first.exit_code == 0
    before = (out / "result.h5").read_bytes()
    again = runner.invoke(cli, ["run", "-q", str(case), "-o", str(out)])
    assert again.exit_code == 2
    assert "--overwrite" in _error_line(again)
    assert (out / "result.h5").read_bytes() == before
    forced = runner.invoke(cli, ["run", "-q", str(case), "-o", str(out), "--overwrite"])
    assert forced.exit_code == 0
    assert _no_partial_files(out) == ["result.h5"]


# -------------------------------------------------------------- NaN / inf


def test_non_finite_state_is_a_convergence_error(tmp_path, runner, monkeypatch):
    """A non-finite field in step 2 of 3 (injected): exit 1, the message says
    so, result.h5 keeps step 1 only, converged = false, no NaN anywhere."""
    original = simulation.step_fields

    def poisoned(model, r):
        fields = original(model, r)
        if r.step == 2:
            fields.stress = fields.stress.copy()
            fields.stress[0, 0] = np.nan
        return fields

    monkeypatch.setattr(simulation, "step_fields", poisoned)
    out = tmp_path / "out"
    result = runner.invoke(cli, ["run", "-q", str(case_file(tmp_path)), "-o", str(out)])
    assert result.exit_code == 1
    line = _error_line(result)
    assert "load step 2 gave a non-finite stress" in line
    with h5py.File(out / "result.h5", "r") as f:
        assert not bool(f.attrs["converged"])
        assert sorted(f["steps"]) == ["0001"]
        for name in ("fields/stress", "fields/displacement"):
            assert np.all(np.isfinite(f[name][()]))
    assert not any(n.endswith("0002.vtu") for n in _no_partial_files(out))


def test_writers_refuse_nan(tmp_path):
    """The last line of defence: the HDF5 writer never writes NaN or inf."""
    with pytest.raises(OutputError, match="non-finite"):
        hdf5.write_result(
            tmp_path / "result.h5",
            points=np.array([[0.0, 0.0], [1.0, np.inf], [1.0, 1.0], [0.0, 1.0]]),
            cells=np.array([[0, 1, 2, 3]]),
            steps=[],
            attrs={
                "case_toml": "",
                "converged": False,
                "newton_iterations": 0,
                "wall_time_s": 0.0,
            },
            load_steps=1,
        )
    assert os.listdir(tmp_path) == []
