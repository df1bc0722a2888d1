"""A signal always ends the command (xfemslip.interrupt).

An exception raised inside a destructor is printed as "Exception ignored" and
dropped by Python: a Ctrl-C in the first milliseconds of writing result.h5
(inside h5py's ``__dealloc__``) would end in exit 0 if the signal were acted
on there instead of held back until the data set is written.  These tests
send real signals to this process in the same situations.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

from tests.faults import harness
from xfemslip import interrupt
from xfemslip.errors import OutputError


class _SignalsInDestructor:
    """Sends ``sig`` to this process from ``__del__`` (the handler then runs
    inside the destructor, where its exception is swallowed)."""

    def __init__(self, sig: int) -> None:
        self.sig = sig

    def __del__(self) -> None:
        os.kill(os.getpid(), self.sig)
        for _ in range(1000):  # Python bytecode: the handler runs in here
            pass


@pytest.mark.parametrize(
    ("sig", "kind"),
    [(signal.SIGINT, KeyboardInterrupt), (signal.SIGTERM, interrupt.Terminated)],
)
def test_a_signal_swallowed_in_a_destructor_still_ends_the_block(
    sig, kind, monkeypatch
):
    ignored, ran_on = [], []
    monkeypatch.setattr(sys, "unraisablehook", lambda info: ignored.append(info))
    with pytest.raises(kind), interrupt.sigterm_as_interrupt():
        obj = _SignalsInDestructor(sig)
        del obj  # the exception is "ignored" here ...
        ran_on.append(True)  # ... so the block goes on
    assert ran_on == [True]
    assert [type(info.exc_value) for info in ignored] == [kind]  # premise


def test_deferred_signal_is_raised_at_the_checkpoint():
    reached = []
    with pytest.raises(KeyboardInterrupt), interrupt.sigterm_as_interrupt():
        with interrupt.deferred():
            os.kill(os.getpid(), signal.SIGINT)
            for _ in range(1000):
                pass
            reached.append("after the signal")
            interrupt.checkpoint()
            reached.append("after the checkpoint")
    assert reached == ["after the signal"]


def test_deferred_signal_is_raised_when_the_block_ends():
    with pytest.raises(interrupt.Terminated), interrupt.deferred():
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(0.01)
    assert interrupt.pending() is None
    assert signal.getsignal(signal.SIGTERM) == signal.SIG_DFL


def test_a_signal_wins_over_an_error_of_the_deferred_block():
    with pytest.raises(interrupt.Terminated) as info, interrupt.deferred():
        os.kill(os.getpid(), signal.SIGTERM)
        raise OutputError("disk full")
    assert isinstance(info.value.__context__, OutputError)


def test_no_stale_signal_in_a_later_block():
    with pytest.raises(KeyboardInterrupt), interrupt.sigterm_as_interrupt():
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(1)
    with interrupt.deferred():  # nothing recorded from the block above
        pass


@pytest.mark.parametrize(
    "args",
    [
        ["verify", "--quick"],
        ["deplete", str(harness.ROOT / "cases" / "depleting_reservoir.toml")],
    ],
    ids=["verify", "deplete"],
)
def test_sigterm_ends_every_command_in_one_line(tmp_path, args):
    """Not only ``run``: SIGTERM ends verify and deplete with exit 143 and one
    line, nothing written."""
    out = tmp_path / "out"
    extra = ["-o", str(out)] if args[0] == "deplete" else ["--csv", str(out)]
    proc = subprocess.Popen(
        [sys.executable, "-m", "xfemslip", *args, *extra],
        env=harness.environment(),
        cwd=tmp_path,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    first = proc.stderr.readline()  # working: its first progress line
    proc.send_signal(signal.SIGTERM)
    err = first + proc.communicate(timeout=harness.TIMEOUT)[1]
    assert proc.returncode == 143, err
    last = err.strip().splitlines()[-1]
    assert last.startswith("Error: interrupted (SIGTERM)")
    assert "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_a_signal_ignored_at_start_stays_ignored(tmp_path):
    """A run started with SIGINT ignored (``nohup``, a background job of a
    script, as Python itself keeps it) is not ended by SIGINT; SIGTERM still
    ends it."""
    case = harness.write_case(tmp_path, "case.toml", 8, 1)
    proc = subprocess.Popen(
        harness.command("run", "-q", case, "-o", tmp_path / "out"),
        env=harness.environment(XFEMSLIP_TEST_PAUSE="locked"),
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert proc.stderr.readline().startswith("xfemslip: test pause at locked")
    proc.send_signal(signal.SIGINT)
    with pytest.raises(subprocess.TimeoutExpired):  # still paused: ignored
        proc.wait(timeout=1.0)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=harness.TIMEOUT)
    assert proc.returncode == 143
    assert err.splitlines() == [
        f"Error: interrupted (SIGTERM); nothing was written to {tmp_path / 'out'}"
    ]
