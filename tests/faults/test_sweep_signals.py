"""A signal stops a sweep and its workers; the members that finished are kept
and a rerun reuses them.

Real ``xfemslip sweep`` processes (``-j 2``, an uncertainty study evaluated
by XFEM or by the closed form, a Dask-backed sweep on a local cluster) get
SIGINT, SIGTERM (to the sweep alone, or to its whole process group as a
terminal's Ctrl-C does) or SIGKILL once some members have finished.  Then:

- the sweep ends with the signal's exit code and one ``Error: interrupted``
  line (SIGKILL: no line);
- every process it started is gone (checked by pid, under the harness's
  bound), and none holds a file of the sweep folder open;
- no member finishes after the signal beyond the two that were running
  (without the fix every member ran to its end);
- the members that finished are whole, and the same command again skips
  exactly them and runs the others, leaving no staging folder behind.

The time from the signal to the end is measured in
``benchmarks/interrupt_latency.py``, not asserted here.
"""

from __future__ import annotations

import contextlib
import os
import re
import signal
import subprocess
import threading
import time
from pathlib import Path

import pytest

from tests.faults import harness
from xfemslip.case import build

MEMBERS = 8
GONE_WITHIN = 10.0  # s: the harness's bound on processes outliving the sweep


# --------------------------------------------------------------------------- #
# Processes
# --------------------------------------------------------------------------- #


def _parents() -> dict[int, list[int]]:
    """ppid -> pids of every process now running (from /proc)."""
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        with contextlib.suppress(OSError, IndexError, ValueError):
            stat = (entry / "stat").read_text()
            fields = stat.rsplit(")", 1)[1].split()
            if fields[0] != "Z":  # a zombie has ended
                children.setdefault(int(fields[1]), []).append(int(entry.name))
    return children


def descendants(pid: int) -> set[int]:
    """Pids of every process below ``pid``."""
    children, found, todo = _parents(), set(), [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            found.add(child)
            todo.append(child)
    return found


def alive(pids) -> set[int]:
    """Those of ``pids`` still running (not ended, not zombies)."""
    out = set()
    for pid in pids:
        with contextlib.suppress(OSError, IndexError):
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
            if state != "Z":
                out.add(pid)
    return out


def holders(folder: Path) -> set[int]:
    """Pids of the processes holding a file under ``folder`` open."""
    root = str(folder.resolve())
    found = set()
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        with contextlib.suppress(OSError):
            for fd in (entry / "fd").iterdir():
                with contextlib.suppress(OSError):
                    if os.readlink(fd).startswith(root):
                        found.add(int(entry.name))
    return found


def wait_gone(pids, within: float = GONE_WITHIN) -> set[int]:
    """The pids still alive once they all ended, or ``within`` passed."""
    deadline = time.monotonic() + within
    left = alive(pids)
    while left and time.monotonic() < deadline:
        time.sleep(0.05)
        left = alive(left)
    return left


class Sweep:
    """A ``xfemslip sweep`` process whose stderr is read as it goes."""

    def __init__(self, args, cwd: Path, env: dict | None = None, group=False):
        def child_setup() -> None:
            harness.interactive_signals()
            if group:
                os.setpgrp()  # a process group of its own, as a terminal's job

        self.proc = subprocess.Popen(
            harness.command("sweep", *args),
            cwd=cwd,
            env=env or harness.environment(),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
            preexec_fn=child_setup,
        )
        self.lines: list[str] = []
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self) -> None:
        for line in self.proc.stderr:
            self.lines.append(line.rstrip("\n"))

    def finished(self) -> list[str]:
        """Ids of the members reported done (``[k/N] <id>: ok (...)``)."""
        found = []
        for line in list(self.lines):
            match = re.match(r"\[\d+/\d+\] (\S+): ok \(", line)
            if match:
                found.append(match[1])
        return found

    def wait_for(self, done: int) -> list[str]:
        """Block until ``done`` members have finished (bounded)."""
        deadline = time.monotonic() + harness.TIMEOUT
        while len(self.finished()) < done:
            assert self.proc.poll() is None, "\n".join(self.lines)
            assert time.monotonic() < deadline, "\n".join(self.lines)
            time.sleep(0.05)
        return self.finished()

    def signal(self, sig: int, group: bool = False) -> None:
        if group:
            os.killpg(self.proc.pid, sig)
        else:
            self.proc.send_signal(sig)

    def end(self) -> int:
        code = self.proc.wait(timeout=harness.TIMEOUT)
        self.reader.join(timeout=harness.TIMEOUT)
        return code

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()


# --------------------------------------------------------------------------- #
# Sweeps
# --------------------------------------------------------------------------- #


def sweep_files(folder: Path, *, uncertainty: str | None = None) -> Path:
    """A sweep of MEMBERS cases of a fraction of a second each (the
    reservoir case at 20 x 20 cells, 4 load steps), or an uncertainty study
    of as many samples on a depleting case."""
    folder.mkdir(parents=True, exist_ok=True)
    if uncertainty is None:
        (folder / "base.toml").write_text(harness.case_text(20, 4))
        values = ", ".join(f"{0.1 + 0.02 * k:g}" for k in range(MEMBERS))
        text = (
            'name = "s"\nbase = "base.toml"\n\n[vary]\n'
            f'"fractures[0].friction" = [{values}]\n'
        )
    else:
        base = build.file_case(
            harness.ROOT / "cases" / "depleting_reservoir.toml",
            **{"mesh.elements": [40, 25], "loading.steps": 4},
        )
        (folder / "base.toml").write_text(build.case_text(base))
        samples = MEMBERS if uncertainty == "xfem" else 1_000_000
        text = (
            f'name = "u"\nbase = "base.toml"\n\n[uncertainty]\nsamples = {samples}\n'
            f'seed = 3\nevaluate = "{uncertainty}"\n'
            "levels = { start = 0.0, stop = -20.0e6, num = 5 }\n\n"
            "[uncertainty.inputs]\n"
            '"fractures[0].friction" = { distribution = "uniform", low = 0.45, '
            "high = 0.75 }\n"
        )
    path = folder / "sweep.toml"
    path.write_text(text)
    return path


def members(out: Path) -> set[str]:
    """Members whose folder holds a result (a whole set: swapped in)."""
    return {p.parent.name for p in out.glob("[0-9]*/result.h5")}


def _interrupt_and_rerun(
    tmp_path, args, sig, *, group=False, env=None, pids=None, rerun=None
):
    """Run the sweep, signal it once two members finished, check the end,
    the processes, the folder, and the rerun (``rerun``: its arguments,
    default ``args``); returns the members kept and the rerun's lines."""
    sweep = Sweep(args, tmp_path, env=env, group=group)
    try:
        sweep.wait_for(2)
        started: set[int] = set()
        deadline = time.monotonic() + harness.TIMEOUT
        while not started and time.monotonic() < deadline:  # a member runs
            started = descendants(sweep.proc.pid) | set(pids() if pids else ())
        sweep.signal(sig, group=group)
        code = sweep.end()
    finally:
        sweep.kill()
    out = tmp_path / "out"
    expected = {signal.SIGINT: 130, signal.SIGTERM: 143, signal.SIGKILL: -9}[sig]
    assert code == expected, "\n".join(sweep.lines)
    if sig != signal.SIGKILL:
        assert sweep.lines[-1].startswith("Error: interrupted ("), sweep.lines[-3:]
    assert not any("Traceback" in line for line in sweep.lines), sweep.lines
    assert started, "the sweep started no process"
    assert wait_gone(started) == set(), [harness_cmdline(p) for p in started]
    assert holders(out) == set()
    finished = set(sweep.finished())
    kept = members(out)
    # what finished is kept; at most the two members that were running when
    # the signal came finished as well
    assert finished <= kept and len(kept) <= len(finished) + 2, (finished, kept)
    assert len(kept) < MEMBERS
    again = subprocess.run(
        harness.command("sweep", *(rerun or args)),
        cwd=tmp_path,
        env=env or harness.environment(),
        capture_output=True,
        text=True,
        timeout=harness.TIMEOUT,
        check=False,
    )
    assert again.returncode == 0, again.stderr[-2000:]
    assert "Traceback" not in again.stderr
    return kept, again.stderr.splitlines()


def harness_cmdline(pid: int) -> str:
    with contextlib.suppress(OSError):
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
    return "?"


def _skipped(lines: list[str]) -> set[str]:
    return {
        m[1] for line in lines if (m := re.match(r"\[\d+/\d+\] (\S+): skipped", line))
    }


LOCAL = ("-j", "2", "sweep.toml", "-o", "out")
RERUN = ("-j", "1", "sweep.toml", "-o", "out")  # in-process: no workers to start


@pytest.mark.parametrize(
    ("sig", "group"),
    [
        pytest.param(signal.SIGTERM, False, id="SIGTERM"),
        pytest.param(signal.SIGINT, False, id="SIGINT", marks=pytest.mark.slow),
        pytest.param(signal.SIGINT, True, id="Ctrl-C", marks=pytest.mark.slow),
        pytest.param(signal.SIGKILL, False, id="SIGKILL", marks=pytest.mark.slow),
    ],
)
def test_a_signal_stops_a_local_sweep_and_its_workers(tmp_path, sig, group):
    sweep_files(tmp_path)
    kept, lines = _interrupt_and_rerun(tmp_path, LOCAL, sig, group=group, rerun=RERUN)
    assert _skipped(lines) == kept
    assert f"({MEMBERS} done, {len(kept)} of them skipped" in lines[-1], lines[-1]
    assert harness.leftovers(tmp_path / "out") == []


@pytest.mark.slow
@pytest.mark.parametrize(
    "sig", [signal.SIGTERM, signal.SIGKILL], ids=["SIGTERM", "SIGKILL"]
)
def test_a_signal_stops_an_xfem_uncertainty_study(tmp_path, sig):
    sweep_files(tmp_path, uncertainty="xfem")
    kept, lines = _interrupt_and_rerun(tmp_path, LOCAL, sig, rerun=RERUN)
    assert _skipped(lines) == kept
    assert harness.leftovers(tmp_path / "out") == []


@pytest.mark.slow  # a million samples (test_writers checks the writer itself)
def test_a_signal_stops_a_screen_study_while_it_writes(tmp_path):
    """A million samples by the closed form: the signal comes while
    uncertainty.csv is written (its temporary file is there); the study
    ends within the harness's bound (writing the whole table takes
    minutes), writes nothing, and leaves no temporary file."""
    sweep_files(tmp_path, uncertainty="screen")
    proc = subprocess.Popen(
        harness.command("sweep", "sweep.toml", "-o", "out"),
        cwd=tmp_path,
        env=harness.environment(),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=harness.interactive_signals,
    )
    try:
        out = tmp_path / "out"
        deadline = time.monotonic() + harness.TIMEOUT
        while not list(out.glob(".uncertainty.csv.tmp-*")):
            assert proc.poll() is None, proc.stderr.read()
            assert time.monotonic() < deadline
            time.sleep(0.02)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 130, err
    assert err.strip().splitlines()[-1].startswith("Error: interrupted (SIGINT)")
    assert "Traceback" not in err
    assert sorted(p.name for p in out.iterdir()) == []


@pytest.mark.slow  # a scheduler and two worker processes
@pytest.mark.parametrize(
    "sig", [signal.SIGINT, signal.SIGKILL], ids=["SIGINT", "SIGKILL"]
)
def test_a_signal_stops_a_dask_sweep_and_its_tasks(tmp_path, sig, monkeypatch):
    """On a Dask cluster each member runs in a child process of a Dask
    worker; the signal (or the sweep's death) cancels the tasks, and the
    children are gone while the cluster's workers stay up for others."""
    from distributed import Client, LocalCluster

    sweep_files(tmp_path)
    env = harness.environment()
    monkeypatch.setenv("PYTHONPATH", str(harness.ROOT))  # the cluster's workers
    with (
        LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        Client(cluster) as client,
    ):
        workers = list(client.run(os.getpid).values())

        def tasks() -> set[int]:
            return {
                pid
                for worker in workers
                for pid in descendants(worker)
                if "xfemslip.studies.workers" in harness_cmdline(pid)
            }

        args = ("sweep.toml", "-o", "out", "--scheduler", cluster.scheduler_address)
        kept, lines = _interrupt_and_rerun(tmp_path, args, sig, env=env, pids=tasks)
        assert alive(workers) == set(workers)  # the cluster is not ours to stop
    assert _skipped(lines) == kept
