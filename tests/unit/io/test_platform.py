"""Windows is refused with one clear line (the output lock needs POSIX file
locks); Linux and macOS run."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from tests.support.golden import ROOT
from xfemslip.cli import cli
from xfemslip.cli import env as cli_env
from xfemslip.errors import UsageError
from xfemslip.io import lock


@pytest.mark.parametrize("platform", ["linux", "darwin"])
def test_linux_and_macos_pass(platform):
    cli_env.check_platform(platform)


def test_windows_is_refused_at_cli_start(monkeypatch, tmp_path):
    monkeypatch.setattr(cli_env.sys, "platform", "win32")
    result = CliRunner().invoke(
        cli,
        [
            "run",
            str(ROOT / "cases" / "reservoir_depletion.toml"),
            "-o",
            str(tmp_path / "o"),
        ],
    )
    assert result.exit_code == 2
    lines = result.stderr.splitlines()
    assert lines == [f"Error: {lock.UNSUPPORTED_PLATFORM}"]
    assert "WSL" in lines[0] and "Linux and macOS" in lines[0]
    assert not (tmp_path / "o").exists()


def test_lock_without_fcntl_refuses_before_writing(monkeypatch, tmp_path):
    """The library (run_case with an output folder) says the same."""
    monkeypatch.setattr(lock, "fcntl", None)
    final = tmp_path / "out"
    with pytest.raises(UsageError, match="runs on Linux and macOS"):
        with lock.folder_lock(final, final):
            pass
    assert list(tmp_path.iterdir()) == []
