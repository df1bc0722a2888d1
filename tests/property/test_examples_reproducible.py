"""The property tests draw the same examples whatever modules are loaded
(tests/conftest.py): a module imported between two runs of one derandomized
test, with literals of its own, changes none of its examples."""

from __future__ import annotations

import importlib
import sys

from hypothesis import given, settings
from hypothesis import strategies as st


def _drawn() -> list[tuple[float, int]]:
    """The examples of one derandomized test, in the order drawn."""
    seen = []

    @settings(max_examples=200, derandomize=True, database=None)
    @given(st.floats(0.0, 1.0), st.integers(0, 10**6))
    def probe(x, n):
        seen.append((x, n))

    probe()
    return seen


def test_a_module_loaded_between_runs_changes_no_example(tmp_path, monkeypatch):
    first = _drawn()
    assert len(first) == 200 and len(set(first)) > 150
    (tmp_path / "literals_probe.py").write_text("A = 0.123456789\nB = 654321\n")
    monkeypatch.syspath_prepend(tmp_path)
    try:
        importlib.import_module("literals_probe")
        assert _drawn() == first
    finally:
        sys.modules.pop("literals_probe", None)
