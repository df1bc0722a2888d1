"""An output folder holds one complete run: the earlier one or the new one.

Real processes are killed (SIGKILL, SIGTERM, SIGINT) while they write, at
points chosen by the writer's test hook (``XFEMSLIP_TEST_PAUSE``, see
``xfemslip.io.folder``: the process stops exactly between two renames
until the signal arrives) and at a sweep of delays over the write phase; two
runs race into one folder; disks fill; folders are read-only.  After each
fault the folder is compared, file by file, with the complete earlier and the
complete new result (``harness.classify``), every file of it carries one
``run_id``, and nothing temporary is left once the next run has cleaned up.
"""

from __future__ import annotations

import errno
import os
import shutil
import signal
import subprocess
from pathlib import Path

import h5py
import pytest

from tests.faults import harness
from xfemslip.case import build
from xfemslip.cli import cli
from xfemslip.io import folder as folder_module
from xfemslip.io.fileset import replace_files
from xfemslip.io.lock import folder_lock
from xfemslip.io.read import read_result


@pytest.fixture(scope="module")
def scenario(tmp_path_factory) -> harness.Scenario:
    """Case A (10 x 10, 3 steps) complete in ref-a; case B (24 x 24, 6 steps)
    in ref-b; both signatures."""
    return harness.Scenario(tmp_path_factory.mktemp("sets"), n=(10, 24), steps=(3, 6))


def _start(scenario, out: Path, point: str, *extra: str) -> subprocess.Popen:
    """Run case B into ``out`` paused at the test hook ``point``; returns once
    it is there."""
    env = harness.environment(scenario.code, XFEMSLIP_TEST_PAUSE=point)
    proc = subprocess.Popen(
        harness.command("run", "-q", scenario.case_b, "-o", out, *extra),
        env=env,
        preexec_fn=harness.interactive_signals,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    line = proc.stderr.readline()
    assert line.startswith(f"xfemslip: test pause at {point}"), line
    return proc


def _finish(proc: subprocess.Popen, sig: int) -> tuple[int, list[str]]:
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=harness.TIMEOUT)
    return proc.returncode, [line for line in err.splitlines() if line.strip()]


def _rerun(scenario, out: Path) -> list[str]:
    """Run B again over whatever is there; returns its stderr lines."""
    proc = subprocess.run(
        harness.command("run", "-q", scenario.case_b, "-o", out, "--overwrite"),
        env=scenario.env,
        capture_output=True,
        text=True,
        timeout=harness.TIMEOUT,
    )
    assert proc.returncode == 0, proc.stderr
    return proc.stderr.splitlines()


def _one_run_id(out: Path) -> int:
    ids = harness.run_ids(out)
    assert len(ids) == 1, ids
    return ids.pop()


# --------------------------------------------------------- between two renames


@pytest.mark.parametrize(("point", "expected"), [("staged", "old"), ("swapped", "new")])
def test_sigkill_between_renames_leaves_one_whole_run(scenario, point, expected):
    """SIGKILL with the new set complete beside the folder (before the swap)
    or just after the swap: the folder is the earlier or the new run, whole;
    the next run removes the leftovers and says so."""
    out = scenario.fresh_old(f"kill-{point}")
    proc = _start(scenario, out, point, "--overwrite")
    code, _ = _finish(proc, signal.SIGKILL)
    assert code == -signal.SIGKILL
    assert harness.classify(out, scenario.sig_a, scenario.sig_b) == expected
    _one_run_id(out)
    left = harness.leftovers(out)
    assert f".out.tmp-{proc.pid}" in left  # premise: the kill left its staging
    lines = _rerun(scenario, out)
    said = [line for line in lines if "left by an interrupted" in line]
    assert said == [
        f"WARNING: removed {out.parent / f'.out.tmp-{proc.pid}'}, left by an "
        f"interrupted xfemslip process (pid {proc.pid})"
    ]
    assert harness.classify(out, scenario.sig_a, scenario.sig_b) == "new"
    assert harness.leftovers(out) == []


@pytest.mark.parametrize(
    ("sig", "code", "name"),
    [
        (signal.SIGTERM, 143, "SIGTERM"),
        pytest.param(signal.SIGINT, 130, "SIGINT", marks=pytest.mark.slow),
    ],
)
@pytest.mark.parametrize(
    ("point", "expected", "says"),
    [
        ("locked", "old", "keeps its earlier content"),
        ("staged", "old", "keeps its earlier content"),
        ("swapped", "new", "holds the complete new result"),
    ],
)
def test_signal_at_each_point_says_what_the_folder_holds(
    scenario, sig, code, name, point, expected, says
):
    """SIGTERM/SIGINT before any work, with the new set complete but not yet
    swapped, and after the swap: exit 130/143, one line that says which run
    the folder holds, and it holds exactly that one; nothing temporary."""
    out = scenario.fresh_old(f"{name}-{point}")
    proc = _start(scenario, out, point, "--overwrite")
    returncode, lines = _finish(proc, sig)
    assert returncode == code, lines
    assert lines == [f"Error: interrupted ({name}); {out} {says}"]
    assert harness.classify(out, scenario.sig_a, scenario.sig_b) == expected
    assert harness.leftovers(out) == []


def test_sigterm_into_a_fresh_folder_writes_nothing(scenario, tmp_path):
    out = tmp_path / "new" / "out"
    proc = _start(scenario, out, "staged")
    returncode, lines = _finish(proc, signal.SIGTERM)
    assert returncode == 143
    assert lines == [f"Error: interrupted (SIGTERM); nothing was written to {out}"]
    assert not (tmp_path / "new").exists()


# ------------------------------------------------------------ kill delays


def _delay_sweep(scenario, sig: int, delays, tag: str) -> list[harness.Trial]:
    trials = []
    for k, delay in enumerate(delays):
        trial = scenario.kill_while_writing(f"{tag}-{sig}-{k}", sig, delay)
        assert trial.outcome in ("old", "new"), (delay, trial)
        assert trial.clean_exit, (delay, trial.stderr)
        if sig != signal.SIGKILL:
            assert trial.leftovers == [], (delay, trial)
            assert trial.returncode in (0, 128 + sig), (delay, trial)
            if trial.returncode == 0:  # the signal came after the end
                assert trial.outcome == "new"
        trials.append(trial)
    return trials


@pytest.mark.slow  # (test_signals_over_the_write_phase: 24 delays)
def test_sigkill_over_the_write_phase(scenario):
    """Four SIGKILLs spread over the write phase: old or new, never mixed."""
    trials = _delay_sweep(scenario, signal.SIGKILL, [0.0, 0.03, 0.08, 0.15], "few")
    assert {t.outcome for t in trials} <= {"old", "new"}


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM, signal.SIGINT])
def test_signals_over_the_write_phase(scenario, sig):
    """24 delays per signal from the last load step's convergence on: 12 of
    them 1 ms apart (a Ctrl-C in the first milliseconds of writing result.h5
    must end the run, never be swallowed), 12 spread over the write phase as
    measured on this machine now."""
    window = 1.2 * scenario.write_time()
    delays = [k * 0.001 for k in range(12)] + [window * k / 12 for k in range(1, 13)]
    trials = _delay_sweep(scenario, sig, delays, "many")
    if sig != signal.SIGKILL:
        assert any(t.returncode == 128 + sig for t in trials)  # premise: it hit


# ----------------------------------------------------------------- races


def test_a_second_run_into_a_folder_being_written_is_refused(scenario):
    """The first run holds the folder (paused after taking its lock); the
    second is refused at once with one line naming the holder, exit 2, with
    and without --overwrite; the folder is untouched."""
    out = scenario.fresh_old("race-lock")
    first = _start(scenario, out, "locked", "--overwrite")
    for extra in ([], ["--overwrite"]):
        second = subprocess.run(
            harness.command("run", "-q", scenario.case_a, "-o", out, *extra),
            env=scenario.env,
            capture_output=True,
            text=True,
            timeout=harness.TIMEOUT,
        )
        assert second.returncode == 2
        assert second.stderr.splitlines() == [
            f"Error: {out} is being written by another xfemslip process (pid "
            f"{first.pid}); wait for it to end or choose another output folder"
        ]
    code, _ = _finish(first, signal.SIGTERM)
    assert code == 143
    assert harness.classify(out, scenario.sig_a, scenario.sig_b) == "old"
    assert harness.leftovers(out) == []


def _races(scenario, overwrite, staggers, tag: str) -> None:
    for k, stagger in enumerate(staggers):
        name = f"{tag}-race-{overwrite}-{k}"
        trial = scenario.race(name, overwrite, stagger)
        assert trial.outcome in ("old", "new"), trial
        assert trial.leftovers == [], trial
        assert trial.clean_exit, trial.stderr
        refused = [line for line in trial.stderr.splitlines() if "Error" in line]
        assert all(
            "is being written by another xfemslip process" in line
            or "already holds" in line
            for line in refused
        ), refused
        _one_run_id(scenario.work / name / "out")


@pytest.mark.parametrize(
    "overwrite",
    [
        (False, False),
        pytest.param((True, True), marks=pytest.mark.slow),
        pytest.param((False, True), marks=pytest.mark.slow),
    ],
)
def test_racing_runs_leave_one_whole_run(scenario, overwrite):
    """Two runs started together into a fresh folder: exactly one whole run
    is there, every file with its run_id; a refused run says why in one line."""
    _races(scenario, overwrite, [0.0], "once")


@pytest.mark.slow
@pytest.mark.parametrize(
    "overwrite", [(False, False), (True, True), (False, True), (True, False)]
)
def test_racing_runs_at_many_offsets(scenario, overwrite):
    _races(scenario, overwrite, [0.005 * k for k in range(8)], "offsets")


def test_stale_lock_of_a_dead_process_does_not_block(scenario, tmp_path):
    out = tmp_path / "out"
    (tmp_path / ".out.lock").write_text("999999999\n")
    lines = _rerun(scenario, out)
    assert not any(line.startswith("Error") for line in lines)
    assert harness.classify(out, scenario.sig_a, scenario.sig_b) == "new"
    assert harness.leftovers(out) == []


def test_lock_held_in_process_refuses_run(runner, tmp_path, scenario):
    out = tmp_path / "out"
    out.mkdir()
    with folder_lock(out, out):
        result = runner.invoke(cli, ["run", "-q", str(scenario.case_a), "-o", str(out)])
    assert result.exit_code == 2
    assert f"(pid {os.getpid()})" in result.stderr
    assert list(out.iterdir()) == []
    assert harness.leftovers(out) == []


# ------------------------------------------------------- full and read-only


def _mount_tmpfs(path: Path, size: str) -> bool:
    path.mkdir(parents=True, exist_ok=True)
    if os.geteuid() != 0:
        return False
    proc = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(path)],
        capture_output=True,
    )
    return proc.returncode == 0


@pytest.fixture
def small_disk(tmp_path):
    """A 1 MB tmpfs (root only; skipped where it cannot be mounted)."""
    mount = tmp_path / "disk"
    if not _mount_tmpfs(mount, "1m"):
        pytest.skip("cannot mount a tmpfs here (needs root)")
    yield mount
    subprocess.run(["umount", "-l", str(mount)], check=False)


def test_a_really_full_disk_keeps_the_earlier_result(scenario, small_disk):
    """On a 1 MB file system the earlier result (about 0.1 MB) is there and
    case B's set does not fit: exit 1 with one line saying the disk is full,
    the earlier result untouched byte for byte, no temporary file, and a sweep
    would not take the folder as done."""
    out = small_disk / "out"
    shutil.copytree(scenario.work / "ref-a", out)
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    big = harness.write_case(scenario.work, "big.toml", 60, 12)
    proc = subprocess.run(
        harness.command("run", "-q", big, "-o", out, "--overwrite"),
        env=scenario.env,
        capture_output=True,
        text=True,
        timeout=harness.TIMEOUT,
    )
    assert proc.returncode == 1, proc.stderr
    (line,) = proc.stderr.splitlines()
    assert line.startswith(f"Error: cannot write {out}/")
    assert line.endswith("No space left on device")
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before
    assert harness.leftovers(out) == []


def test_read_only_folder_is_refused_untouched(scenario, tmp_path):
    """A folder on a read-only file system: refused before any work (exit 1,
    one line), the earlier files untouched."""
    mount = tmp_path / "ro"
    if not _mount_tmpfs(mount, "4m"):
        pytest.skip("cannot mount a tmpfs here (needs root)")
    try:
        out = mount / "out"
        shutil.copytree(scenario.work / "ref-a", out)
        before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
        subprocess.run(["mount", "-o", "remount,ro", str(mount)], check=True)
        proc = subprocess.run(
            harness.command("run", "-q", scenario.case_b, "-o", out, "--overwrite"),
            env=scenario.env,
            capture_output=True,
            text=True,
            timeout=harness.TIMEOUT,
        )
        assert proc.returncode == 1
        assert proc.stderr.splitlines() == [
            f"Error: cannot write {out}: Read-only file system"
        ]
        assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before
    finally:
        subprocess.run(["umount", "-l", str(mount)], check=False)


def test_output_path_that_is_a_file_is_refused_untouched(runner, scenario, tmp_path):
    """Named by -o (click refuses it) or by output.directory (one line)."""
    out = tmp_path / "out"
    out.write_text("mine")
    result = runner.invoke(cli, ["run", "-q", str(scenario.case_a), "-o", str(out)])
    assert result.exit_code == 2
    assert "is a file" in result.stderr.splitlines()[-1]
    case = tmp_path / "case.toml"
    keys = {"output.directory": out}
    case.write_text(build.case_text(build.file_case(scenario.case_a, **keys)))
    result = runner.invoke(cli, ["run", "-q", str(case)])
    assert result.exit_code == 2
    assert result.stderr.splitlines() == [f"Error: {out} exists and is not a directory"]
    assert out.read_text() == "mine"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["case.toml", "out"]


def test_current_directory_is_refused(runner, scenario, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(cli, ["run", "-q", str(scenario.case_a), "-o", "."])
    assert result.exit_code == 2
    assert "is (or holds) the current directory" in result.stderr
    assert list(tmp_path.iterdir()) == []


# --------------------------------------------------------- what is carried


def test_foreign_files_are_carried_and_outputs_replaced(runner, scenario, tmp_path):
    """A note and a folder of the user's survive a rerun (as the same files);
    earlier figures and stale step files do not."""
    out = tmp_path / "out"
    shutil.copytree(scenario.work / "ref-b", out)  # 6 steps
    (out / "notes.txt").write_text("keep me")
    (out / "mine").mkdir()
    (out / "mine" / "data.csv").write_text("1,2\n")
    (out / "figures").mkdir()
    (out / "figures" / "slip.png").write_bytes(b"old figure")
    inode = (out / "notes.txt").stat().st_ino
    result = runner.invoke(
        cli, ["run", "-q", str(scenario.case_a), "-o", str(out), "--overwrite"]
    )
    assert result.exit_code == 0, result.stderr
    assert harness.signature(out) == {
        **scenario.sig_a,
        "notes.txt": ("file", 7),
        "mine/data.csv": ("file", 4),
    }
    assert (out / "notes.txt").stat().st_ino == inode  # the same file, linked
    assert harness.leftovers(out) == []


def test_exchange_unavailable_falls_back_to_two_renames(
    runner, scenario, tmp_path, monkeypatch
):
    def unsupported(a, b):
        raise OSError(errno.EINVAL, os.strerror(errno.EINVAL))

    monkeypatch.setattr(folder_module, "_rename_exchange", unsupported)
    out = tmp_path / "out"
    shutil.copytree(scenario.work / "ref-a", out)
    args = ["run", "-q", str(scenario.case_b), "-o", str(out), "--overwrite"]
    assert runner.invoke(cli, args).exit_code == 0
    assert harness.classify(out, scenario.sig_a, scenario.sig_b) == "new"
    assert harness.leftovers(out) == []


@pytest.mark.parametrize("staged", [True, False])
def test_a_swap_cut_between_two_renames_is_finished(scenario, tmp_path, staged):
    """The fallback's window: DIR renamed away, the staging folder not yet
    renamed in, the killed process's pid in the lock file.  The next process
    to take the folder finishes the swap with the complete staged set, or,
    without one, restores the earlier set."""
    out = tmp_path / "out"
    shutil.copytree(scenario.work / "ref-a", tmp_path / ".out.old-4242")
    if staged:
        shutil.copytree(scenario.work / "ref-b", tmp_path / ".out.tmp-4242")
    (tmp_path / ".out.lock").write_text("4242\n")  # what the killed one left
    with folder_lock(out, out):
        pass
    expected = "new" if staged else "old"
    assert harness.classify(out, scenario.sig_a, scenario.sig_b) == expected
    assert harness.leftovers(out) == []


# --------------------------------------------------- the other commands


def test_sweep_reruns_a_member_whose_set_is_not_whole(tmp_path):
    """The done-test needs the whole set: a member with a converged result.h5
    but no result.vtu (a disk that filled before this rule) runs again; a
    whole member is skipped."""
    from xfemslip.studies.run import is_done, run_sweep
    from xfemslip.studies.sweep import load_sweep

    base = harness.write_case(tmp_path, "base.toml", 8, 2)
    sweep_file = tmp_path / "sweep.toml"
    sweep_file.write_text(
        f'name = "s"\nbase = "{base.name}"\n\n[vary]\n'
        '"fractures[0].friction" = [0.1, 0.2]\n'
    )
    sweep = load_sweep(sweep_file)
    rows = run_sweep(sweep, tmp_path / "runs")
    assert [r.status for r in rows] == ["ok", "ok"]
    member = tmp_path / "runs" / sweep.cases[0].case_id
    assert is_done(member, sweep.cases[0].text, sweep.cases[0].spec)
    (member / "result.vtu").unlink()
    assert not is_done(member, sweep.cases[0].text, sweep.cases[0].spec)
    rows = run_sweep(sweep, tmp_path / "runs")
    assert [r.status for r in rows] == ["ok", "skipped"]
    assert (member / "result.vtu").is_file()
    assert (member / "case.toml").is_file()  # carried into the new set
    # a step file that only the fractures' series names counts as well
    assert is_done(member, sweep.cases[0].text, sweep.cases[0].spec)
    (member / "steps" / "fractures_0002.vtu").unlink()
    assert not is_done(member, sweep.cases[0].text, sweep.cases[0].spec)
    assert harness.leftovers(member) == []
    assert sorted(p.name for p in tmp_path.glob(".*")) == []


def _flip(path: Path, offset: int) -> None:
    data = bytearray(path.read_bytes())
    data[offset] ^= 0x04
    path.write_bytes(bytes(data))


def test_sweep_recomputes_a_member_whose_files_are_damaged(tmp_path, runner):
    """A rerun over members whose result.h5 has a flipped bit (in a data
    set: its checksum; in the file's header) or whose result.pvd is cut
    short runs those members again, with a warning naming the file, and
    skips the whole one; no traceback."""
    base = harness.write_case(tmp_path, "base.toml", 8, 2)
    sweep_file = tmp_path / "sweep.toml"
    sweep_file.write_text(
        f'name = "s"\nbase = "{base.name}"\n\n[vary]\n'
        '"fractures[0].friction" = [0.1, 0.2, 0.3, 0.4]\n'
    )
    out = tmp_path / "runs"
    args = ["sweep", "-j", "1", str(sweep_file), "-o", str(out)]
    first = runner.invoke(cli, args)
    assert first.exit_code == 0, first.stderr
    folders = sorted(p for p in out.iterdir() if p.is_dir())
    data, header, pvd, whole = folders
    with h5py.File(data / "result.h5", "r") as h5:
        offset = h5["mesh/points"].id.get_chunk_info(0).byte_offset
    _flip(data / "result.h5", offset + 5)
    _flip(header / "result.h5", 0)  # the signature of the superblock
    text = (pvd / "result.pvd").read_text()
    (pvd / "result.pvd").write_text(text[: len(text) // 2])
    with h5py.File(whole / "result.h5", "r") as h5:
        whole_id = int(h5.attrs["run_id"])
    again = runner.invoke(cli, args)
    assert again.exit_code == 0, again.stderr
    assert "Traceback" not in again.stderr + again.stdout
    rows = (out / "summary.csv").read_text().splitlines()[1:]
    status = {row.split(",")[0]: row.split(",")[-2] for row in rows}
    assert {k: status[k.name] for k in folders} == {
        data: "ok",
        header: "ok",
        pvd: "ok",
        whole: "skipped",
    }
    warned = [ln for ln in again.stderr.splitlines() if ln.startswith("WARNING:")]
    assert any(str(data / "result.h5") in ln and "run again" in ln for ln in warned)
    for folder in (data, header, pvd):
        assert read_result(folder).converged
    with h5py.File(whole / "result.h5", "r") as h5:
        assert int(h5.attrs["run_id"]) == whole_id  # not run again
    assert harness.leftovers(out) == []


def test_replace_files_changes_nothing_when_one_file_fails(tmp_path):
    """verify --csv/--plot, plot figures, sweep summaries: a set of single
    files; a failure while writing any of them leaves every earlier file."""
    a, b = tmp_path / "a.csv", tmp_path / "sub" / "b.png"
    b.parent.mkdir()
    a.write_text("old a")
    b.write_text("old b")

    def full(tmp):
        Path(tmp).write_text("half")
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    with pytest.raises(Exception, match=f"cannot write {b}: No space left"):
        replace_files({a: lambda tmp: Path(tmp).write_text("new a"), b: full})
    assert (a.read_text(), b.read_text()) == ("old a", "old b")
    assert sorted(p.name for p in tmp_path.rglob(".*")) == []
    written = replace_files({a: lambda tmp: Path(tmp).write_text("new a"), b: None})
    assert written == [a]
    assert a.read_text() == "new a" and not b.exists()


def test_deplete_interrupted_while_writing_tables_keeps_the_earlier_set(
    runner, tmp_path, monkeypatch
):
    """deplete's CSVs are part of its set: Ctrl-C while they are written
    leaves the earlier folder as it was (exit 130)."""
    import xfemslip.studies.depletion as depletion

    root = harness.ROOT / "cases" / "depleting_reservoir.toml"
    text = root.read_text()
    case = tmp_path / "dep.toml"
    case.write_text(text)
    out = tmp_path / "out"
    first = runner.invoke(cli, ["deplete", "-q", str(case), "-o", str(out)])
    assert first.exit_code == 0, first.stderr
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    assert {"critical_depletion.csv", "result.h5"} <= {p.name for p in before}

    def interrupted(report, folder):
        raise KeyboardInterrupt

    monkeypatch.setattr(depletion, "write_tables", interrupted)
    args = ["deplete", "-q", str(case), "-o", str(out), "--overwrite"]
    again = runner.invoke(cli, args)
    assert again.exit_code == 130
    assert again.stderr.splitlines()[-1] == (
        f"Error: interrupted (SIGINT); {out} keeps its earlier content"
    )
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before
    assert harness.leftovers(out) == []


def test_result_h5_run_id_matches_every_file(scenario):
    out = scenario.work / "ref-b"
    with h5py.File(out / "result.h5", "r") as f:
        stamped = int(f.attrs["run_id"])
    assert harness.run_ids(out) == {stamped}
    assert len(list(out.rglob("*.vtu"))) == 2 + 2 * 6  # premise: every VTU seen


@pytest.mark.parametrize("length", [246, 250])
def test_a_name_too_long_for_the_hidden_files_is_refused(
    runner, scenario, tmp_path, length
):
    """A folder name that fits the file system but not with the lock or the
    staging folder beside it (``.NAME.lock``, ``.NAME.tmp-<pid>``): exit 2,
    one line, nothing written."""
    out = tmp_path / ("x" * length)
    result = runner.invoke(cli, ["run", "-q", str(scenario.case_a), "-o", str(out)])
    assert result.exit_code == 2
    (line,) = result.stderr.splitlines()
    assert line.startswith(f"Error: {out}: ") and "too long" in line
    assert list(tmp_path.iterdir()) == []
