"""The package passes the type checker (mypy, configured in pyproject.toml
[tool.mypy]) with no error; the same configuration rejects a module with a
type error, so the check can fail."""

from __future__ import annotations

import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

import xfemslip

pytest.importorskip("mypy", reason="mypy is not installed (the test extra has it)")

ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "pyproject.toml"
PACKAGE = Path(xfemslip.__file__).parent


def mypy(*targets: Path, cache: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [
            sys.executable,
            "-m",
            "mypy",
            "--config-file",
            str(CONFIG),
            "--cache-dir",
            str(cache),
            *map(str, targets),
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=900,
    )


def test_configuration_silences_no_error():
    """No module is exempt: nothing sets ignore_errors, and an ignore
    comment must name the error it silences."""
    config = tomllib.loads(CONFIG.read_text(encoding="utf-8"))["tool"]["mypy"]
    tables = [config, *config.get("overrides", [])]
    assert not any(table.get("ignore_errors") for table in tables)
    assert "ignore-without-code" in config["enable_error_code"]


def test_package_has_no_type_error():
    done = mypy(PACKAGE, cache=ROOT / ".mypy_cache")
    assert done.returncode == 0, done.stdout + done.stderr
    assert "Success: no issues found" in done.stdout


def test_a_type_error_is_reported(tmp_path):
    """A None where a float is expected and an ignore comment without its
    error code: both reported, exit 1."""
    bad = tmp_path / "bad.py"
    bad.write_text(
        "def half(x: float) -> float:\n"
        "    return x / 2\n"
        "\n"
        "\n"
        "value: float | None = None\n"
        "half(value)\n"
        "count: int = 'three'  # type: ignore\n",
        encoding="utf-8",
    )
    done = mypy(bad, cache=tmp_path / "cache")
    assert done.returncode == 1, done.stdout + done.stderr
    assert "bad.py:6: error:" in done.stdout and "[arg-type]" in done.stdout
    assert "bad.py:7: error:" in done.stdout and "[ignore-without-code]" in done.stdout
