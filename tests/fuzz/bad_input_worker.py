"""Worker process of the bad-input suite: runs many inputs through the CLI
in one interpreter (click's CliRunner), each under a time bound.

Usage: ``python bad_input_worker.py INPUTS.json RESULTS.jsonl``.  INPUTS is a
JSON list of ``{"id", "cwd", "argv", "env", "timeout", "stdin"}`` (stdin as
hex, or null); for each, one JSON
line ``{"id", "exit_code", "stdout", "stderr", "exception", "traceback",
"status", "seconds", "rss_before", "rss_after"}`` is appended to RESULTS and
flushed, so that the harness keeps every answer given before a crash.

The process limits its own address space (``MEMORY_CAP``): an input that
makes memory grow without bound ends in MemoryError, reported as a failure
of that input, instead of taking the machine down.  Each input runs under
``setitimer``; an input still running at its time bound is reported as
``"timeout"``.
"""

from __future__ import annotations

import json
import os
import resource
import signal
import sys
import time
import traceback

MEMORY_CAP = 4 * 2**30  # bytes of address space; a run of the suite needs < 1 GB


class HarnessTimeout(BaseException):
    """The time bound of one input passed (not an Exception: nothing in the
    CLI may swallow it)."""


def _alarm(signum, frame):
    raise HarnessTimeout


def _maxrss() -> int:
    """Peak resident memory of this process so far [bytes]."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def _run_one(runner, cli, item: dict) -> dict:
    os.chdir(item["cwd"])
    before = _maxrss()
    start = time.perf_counter()
    out = {"id": item["id"], "status": "done", "rss_before": before}
    signal.setitimer(signal.ITIMER_REAL, item["timeout"])
    try:
        stdin = item.get("stdin")
        result = runner.invoke(
            cli,
            item["argv"],
            env=item["env"],
            input=None if stdin is None else bytes.fromhex(stdin),
        )
        signal.setitimer(signal.ITIMER_REAL, 0)
        exc = result.exception
        out.update(
            exit_code=result.exit_code,
            stdout=result.stdout,
            stderr=result.stderr,
            exception=None if exc is None or isinstance(exc, SystemExit) else repr(exc),
            traceback=(
                "".join(traceback.format_exception(*result.exc_info))
                if exc is not None and not isinstance(exc, SystemExit)
                else ""
            ),
        )
    except HarnessTimeout:
        out.update(status="timeout", exit_code=None, stdout="", stderr="")
    except MemoryError:
        signal.setitimer(signal.ITIMER_REAL, 0)
        out.update(status="memory", exit_code=None, stdout="", stderr="")
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
    out["seconds"] = time.perf_counter() - start
    out["rss_after"] = _maxrss()
    return out


def main(inputs_path: str, results_path: str) -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_CAP, MEMORY_CAP))
    signal.signal(signal.SIGALRM, _alarm)
    from click.testing import CliRunner

    from xfemslip.cli import cli

    try:  # click < 8.2 mixes stderr into stdout unless told otherwise
        runner = CliRunner(mix_stderr=False)
    except TypeError:
        runner = CliRunner()
    with open(inputs_path, encoding="utf-8") as fh:
        items = json.load(fh)
    with open(results_path, "a", encoding="utf-8") as out:
        for item in items:
            out.write(json.dumps(_run_one(runner, cli, item)) + "\n")
            out.flush()


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
