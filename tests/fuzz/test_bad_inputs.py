"""About 1,800 generated bad and edge-case inputs, each through the real CLI.

The inputs come from ``tests/support/bad_inputs`` (fixed seed): mutated keys
of the shipped cases and of a small case (every key with the extremes of
every type, and random mutations that are run), TOML nested thousands of
levels deep, ``/dev/zero`` and FIFOs wherever a file is read, oversized
files, broken CSV files and sweeps, random networks whose derived sizes
overflow, geometry of thousands of vertices, depletion, command-line options
and environment variables, corrupted, truncated, partial and foreign result
files, distributions of uncertainty studies at their edges, post-processing
keys at their bounds, ``dfn --summary`` tables and cases on standard input.
The default run takes a deterministic sample of every family
(``bad_inputs.default_inputs``); ``--run-slow`` runs all the others.  They
run in batches in a worker process (``bad_input_worker.py``, click's
CliRunner, a per-input alarm and a cap on its address space); the few
whose environment Numba reads at import run in a fresh ``python -m
xfemslip`` each, under a subprocess timeout.

For every input the harness asserts what the CLI promises:

- it ends within its time bound (the alarm / the timeout: not a timed
  assertion) and without a memory blow-up (peak resident memory < 2 GB);
- with an allowed exit code: 0 run, 1 clean failure, 2 refusal;
- no traceback, and on exit 1 or 2 exactly one ``Error: ...`` line, the last
  one on stderr (any other line is a logged warning), naming the file and the
  key (or option, or variable) the input broke;
- on exit 2 nothing is written: the output folder does not exist or is empty,
  and no file appears beside the inputs;
- a run that exits 0 leaves a converged ``result.h5``, one that exits 1 no
  result claiming convergence.

``test_counts`` prints the inputs tried by outcome (run with ``-s``), and
``test_counts_of_the_slow_tier`` those of ``--run-slow``.
"""

from __future__ import annotations

import collections
import functools
import json
import os
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import pytest

from tests.support import bad_inputs
from tests.support.bad_inputs.base import Input, small, toml

WORKER = Path(__file__).with_name("bad_input_worker.py")
MEMORY_BOUND = 2 * 2**30  # peak resident memory an input may reach [bytes]
SUBPROCESS_CAP = 4 * 2**30  # address space of a `python -m xfemslip` input

INPUTS = bad_inputs.default_inputs()


def pytest_generate_tests(metafunc) -> None:
    """The slow tier's inputs, made only when it runs (``--run-slow``):
    generating them takes seconds."""
    if "slow_item" in metafunc.fixturenames:
        items = slow_inputs() if metafunc.config.getoption("--run-slow") else []
        metafunc.parametrize("slow_item", items, ids=[i.id for i in items])


@functools.cache
def slow_inputs() -> list[Input]:
    return bad_inputs.slow_inputs()


# --------------------------------------------------------------------------- #
# Materialising inputs
# --------------------------------------------------------------------------- #


def _write(folder: Path, name: str, content) -> None:
    path = folder / name
    if isinstance(content, str):
        path.write_text(content, encoding="utf-8")
    elif isinstance(content, bytes):
        path.write_bytes(content)
    elif content.kind == "fifo":
        os.mkfifo(path)
    elif content.kind == "dir":
        path.mkdir()
    elif content.kind == "symlink":
        path.symlink_to(content.arg)
    elif content.kind == "sparse":
        with open(path, "wb") as fh:
            fh.truncate(content.arg)
    elif content.kind == "lazy":
        path.write_bytes(content.arg())
    elif content.kind == "unreadable":
        path.write_bytes(content.arg)
        path.chmod(0)
    else:
        raise ValueError(content.kind)


def _listing(folder: Path) -> set[str]:
    return {str(p.relative_to(folder)) for p in folder.rglob("*")}


def _materialise(inputs: list[Input], root: Path) -> dict[str, Path]:
    folders = {}
    for k, item in enumerate(inputs):
        folder = root / f"{k:04d}"
        folder.mkdir(parents=True)
        for name, content in item.files.items():
            _write(folder, name, content)
        folders[item.id] = folder
    return folders


# --------------------------------------------------------------------------- #
# Running inputs
# --------------------------------------------------------------------------- #


def _run_in_worker(items: list[Input], folders: dict, scratch: Path) -> dict:
    """Outcomes of in-process inputs; a worker that dies is restarted after
    the input it died on (which is reported as 'crashed')."""
    results: dict[str, dict] = {}
    pending = list(items)
    attempt = 0
    while pending:
        attempt += 1
        spec = scratch / f"inputs-{attempt}.json"
        out = scratch / f"results-{attempt}.jsonl"
        spec.write_text(
            json.dumps(
                [
                    {
                        "id": i.id,
                        "cwd": str(folders[i.id]),
                        "argv": list(i.argv),
                        "env": i.env,
                        "timeout": i.timeout,
                        "stdin": None if i.stdin is None else i.stdin.hex(),
                    }
                    for i in pending
                ]
            )
        )
        budget = sum(i.timeout for i in pending) + 60.0
        proc = subprocess.run(
            [sys.executable, str(WORKER), str(spec), str(out)],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            timeout=budget,
            check=False,
        )
        done = [json.loads(line) for line in out.read_text().splitlines()]
        results.update((r["id"], r) for r in done)
        pending = pending[len(done) :]
        if pending:  # the worker died on pending[0]
            results[pending[0].id] = {
                "id": pending[0].id,
                "status": "crashed",
                "exit_code": None,
                "stdout": "",
                "stderr": proc.stderr.decode(errors="replace")[-2000:],
            }
            pending = pending[1:]
    return results


def _limit_memory() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (SUBPROCESS_CAP, SUBPROCESS_CAP))


def _run_in_subprocess(item: Input, folder: Path) -> dict:
    env = dict(os.environ)
    for name, value in item.env.items():
        if value is None:
            env.pop(name, None)
        else:
            env[name] = value
    start = time.perf_counter()
    try:
        proc = subprocess.run(
            [sys.executable, "-m", "xfemslip", *item.argv],
            cwd=folder,
            env=env,
            input=item.stdin or b"",
            capture_output=True,
            timeout=item.timeout,
            preexec_fn=_limit_memory,
            check=False,
        )
    except subprocess.TimeoutExpired:
        return {"id": item.id, "status": "timeout", "exit_code": None}
    return {
        "id": item.id,
        "status": "done",
        "exit_code": proc.returncode,
        "stdout": proc.stdout.decode(errors="replace"),
        "stderr": proc.stderr.decode(errors="replace"),
        "seconds": time.perf_counter() - start,
    }


def _run_all(inputs: list[Input], root: Path) -> dict:
    folders = _materialise(inputs, root / "inputs")
    before = {i.id: _listing(folders[i.id]) for i in inputs}
    scratch = root / "scratch"
    scratch.mkdir()
    outcomes = _run_in_worker([i for i in inputs if not i.subprocess], folders, scratch)
    for item in inputs:
        if item.subprocess:
            outcomes[item.id] = _run_in_subprocess(item, folders[item.id])
    for item in inputs:
        outcome = outcomes[item.id]
        outcome["folder"] = folders[item.id]
        outcome["new_files"] = sorted(_listing(folders[item.id]) - before[item.id])
    return outcomes


@pytest.fixture(scope="module")
def outcomes(tmp_path_factory) -> dict:
    return _run_all(INPUTS, tmp_path_factory.mktemp("bad-inputs"))


@pytest.fixture(scope="module")
def slow_outcomes(tmp_path_factory) -> dict:
    return _run_all(slow_inputs(), tmp_path_factory.mktemp("bad-inputs-slow"))


# --------------------------------------------------------------------------- #
# What every input must end in
# --------------------------------------------------------------------------- #


def _error_line(item: Input, outcome: dict) -> str:
    """The one ``Error:`` line, last on stderr; other lines are warnings."""
    lines = [line for line in outcome["stderr"].splitlines() if line.strip()]
    errors = [line for line in lines if line.startswith("Error: ")]
    assert len(errors) == 1 and lines[-1] == errors[0], outcome["stderr"][-3000:]
    if outcome["exit_code"] == 2:
        others = [line for line in lines[:-1] if not line.startswith("WARNING: ")]
        assert not others, outcome["stderr"][-3000:]
    return errors[0]


def _result_converged(folder: Path) -> bool | None:
    path = folder / "result.h5"
    if not path.exists():
        return None
    with h5py.File(path, "r") as f:
        return bool(f.attrs["converged"])


def check_outcome(item: Input, outcome: dict) -> None:
    status = outcome["status"]
    assert status == "done", f"{status}: {outcome.get('stderr', '')[-2000:]}"
    grew = outcome.get("rss_after", 0) > outcome.get("rss_before", 0)
    assert not grew or outcome["rss_after"] < MEMORY_BOUND, outcome["rss_after"]
    text = outcome["stdout"] + outcome["stderr"]
    assert not outcome.get("exception"), outcome.get("traceback", "")[-3000:]
    assert "Traceback" not in text, text[-3000:]
    code = outcome["exit_code"]
    assert code in item.expect, (code, outcome["stderr"][-3000:])
    folder = outcome["folder"]
    if code == 1 and item.argv[:1] == ("sweep",):
        # a sweep runs the cases it can: its last line sums up, the cases that
        # failed or were refused are named in their rows and warnings
        lines = [line for line in outcome["stderr"].splitlines() if line.strip()]
        last = lines[-1]
        # a sweep ends with its summary line, an uncertainty study with the
        # count of the samples left out
        assert last.startswith("summary: ") or (
            "sample(s) refused or failed" in last
        ), outcome["stderr"][-3000:]
        for name in item.names:
            assert name in outcome["stderr"], (name, outcome["stderr"][-3000:])
    elif code in (1, 2):
        line = _error_line(item, outcome)
        if code == 2:
            for name in item.names:
                assert name in line, (name, line)
    if code == 2:
        assert outcome["new_files"] == [], outcome["new_files"][:20]
    if item.out is not None and item.argv[:1] == ("run",):
        converged = _result_converged(folder / item.out)
        if code == 0:
            assert converged is True
        elif code == 1:
            assert converged is not True


@pytest.mark.parametrize("item", INPUTS, ids=[i.id for i in INPUTS])
def test_bad_input_ends_as_promised(item: Input, outcomes: dict) -> None:
    check_outcome(item, outcomes[item.id])


@pytest.mark.slow
def test_bad_input_ends_as_promised_in_the_slow_tier(
    slow_item: Input, slow_outcomes
) -> None:
    check_outcome(slow_item, slow_outcomes[slow_item.id])


def _counts(inputs: list[Input], results: dict) -> str:
    table = collections.Counter()
    for item in inputs:
        outcome = results[item.id]
        if outcome["status"] != "done":
            kind = outcome["status"]
        else:
            kind = {0: "ran", 1: "failed cleanly", 2: "refused"}.get(
                outcome["exit_code"], f"exit {outcome['exit_code']}"
            )
        table[(item.family, kind)] += 1
        table[("all", kind)] += 1
    kinds = sorted({k for _, k in table})
    families = sorted({f for f, _ in table} - {"all"}) + ["all"]
    rows = [f"{'family':<18}" + "".join(f"{k:>16}" for k in kinds)]
    rows += [
        f"{family:<18}" + "".join(f"{table[(family, k)]:>16}" for k in kinds)
        for family in families
    ]
    return "\n".join(rows)


def test_counts(outcomes: dict) -> None:
    """Every input has an outcome; the table of outcomes by family (-s)."""
    assert set(outcomes) == {i.id for i in INPUTS}
    print(f"\n{len(INPUTS)} generated inputs by outcome:\n" + _counts(INPUTS, outcomes))
    slowest = sorted(outcomes.values(), key=lambda o: -o.get("seconds", 0.0))[:8]
    print(
        "slowest: "
        + ", ".join(f"{o['id']} {o.get('seconds', 0):.1f} s" for o in slowest)
    )
    refused = sum(o["exit_code"] == 2 for o in outcomes.values())
    ran = sum(o["exit_code"] == 0 for o in outcomes.values())
    assert refused > 100 and ran > 20  # the sample holds both kinds


@pytest.mark.slow
def test_counts_of_the_slow_tier(slow_outcomes: dict) -> None:
    inputs = slow_inputs()
    assert set(slow_outcomes) == {i.id for i in inputs}
    print(
        f"\n{len(inputs)} generated inputs of the slow tier by outcome:\n"
        + _counts(inputs, slow_outcomes)
    )
    refused = sum(o["exit_code"] == 2 for o in slow_outcomes.values())
    ran = sum(o["exit_code"] == 0 for o in slow_outcomes.values())
    assert refused > 1000 and ran > 300


# --------------------------------------------------------------------------- #
# Signals while an input is read
# --------------------------------------------------------------------------- #


def _big_boundary_case(folder: Path) -> None:
    """A valid case whose boundary CSV is just under the size cap (~30 MB,
    600,000 rows): reading and checking it takes seconds."""
    doc = small(boundary={"bottom": {"uy": 0.0}, "left": {"file": "left.csv"}})
    (folder / "case.toml").write_text(toml(doc))
    n = 600_000
    rows = "".join(f"0.0,{i / (n - 1)!r},0.0,0.0\n" for i in range(n))
    (folder / "left.csv").write_text("x,y,ux,uy\n" + rows)


@pytest.mark.parametrize(
    ("sig", "code", "name"),
    [(signal.SIGTERM, 143, "SIGTERM"), (signal.SIGINT, 130, "SIGINT")],
)
def test_signal_while_reading_ends_the_run(tmp_path, sig, code, name):
    """`run -v` logs 'reading .../left.csv' just before it reads the file; the
    signal sent then must end the run within the harness's timeout, with one
    line, the signal's exit code and nothing written."""
    _big_boundary_case(tmp_path)
    proc = subprocess.Popen(
        [sys.executable, "-m", "xfemslip", "run", "-v", "case.toml", "-o", "out"],
        cwd=tmp_path,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=_limit_memory,
    )
    try:
        seen = []
        for line in proc.stderr:  # ends when the process does
            seen.append(line)
            if "reading" in line and "left.csv" in line:
                proc.send_signal(sig)
                break
        assert seen and "left.csv" in seen[-1], "".join(seen)
        stdout, rest = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == code, rest
    lines = [line for line in rest.splitlines() if line.strip()]
    assert lines[-1].startswith(f"Error: interrupted ({name})"), rest
    assert "Traceback" not in rest + stdout
    assert not (tmp_path / "out").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["case.toml", "left.csv"]
