"""The memory estimate: refused before allocating, with the estimate named."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from click.testing import CliRunner

from xfemslip.case import load_case
from xfemslip.cli import cli
from xfemslip.errors import MeshError, UsageError
from xfemslip.memory import (
    ENV_LIMIT,
    available_bytes,
    check_memory,
    estimate_bytes,
    estimate_dofs,
)

CASE = Path(__file__).resolve().parents[2] / "cases" / "reservoir_depletion.toml"


@pytest.mark.parametrize(
    ("text", "value"), [("500M", 5e8), ("2g", 2e9), ("1e9", 1e9), ("123", 123.0)]
)
def test_limit_from_the_environment(monkeypatch, text, value):
    monkeypatch.setenv(ENV_LIMIT, text)
    assert available_bytes() == (value, ENV_LIMIT)


@pytest.mark.parametrize("text", ["abc", "-1G", "0", "nan", "1X", "inf"])
def test_bad_limit_is_a_usage_error(monkeypatch, text):
    monkeypatch.setenv(ENV_LIMIT, text)
    with pytest.raises(UsageError, match=ENV_LIMIT):
        available_bytes()


def test_physical_memory_is_the_default(monkeypatch):
    monkeypatch.delenv(ENV_LIMIT, raising=False)
    limit, source = available_bytes()
    assert source == "physical memory" and 1e8 < limit < math.inf


def test_estimate_counts_the_dofs():
    """50 x 50 reservoir: 5202 standard dofs plus the enriched ones (6128 in
    total, measured); the estimate is within 20 % and grows like n log n."""
    spec = load_case(CASE)
    n = estimate_dofs(spec)
    assert 2 * 51 * 51 < n and abs(n - 6128) < 0.2 * 6128
    assert estimate_bytes(4 * n) > 4 * (estimate_bytes(n) - 200e6)


def test_refused_before_building_with_the_estimate(monkeypatch, tmp_path):
    monkeypatch.setenv(ENV_LIMIT, "100M")
    spec = load_case(CASE)
    with pytest.raises(MeshError) as info:
        check_memory(spec)
    text = str(info.value)
    assert str(CASE) in text and "mesh: 50 x 50 elements" in text
    assert "GB of memory" in text and ENV_LIMIT in text
    out = tmp_path / "out"
    result = CliRunner().invoke(cli, ["run", str(CASE), "-o", str(out)])
    assert result.exit_code == 2
    assert not out.exists()
