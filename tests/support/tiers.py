"""Which test tier runs: the default one, or the slow one too (``--run-slow``,
set by ``tests/conftest.py`` before the test modules are imported).

Property tests draw fewer examples in the default tier and all of them in
the slow one (``examples``)."""

from __future__ import annotations

SLOW = False


def examples(full: int) -> int:
    """Hypothesis examples of a property test: ``full`` in the slow tier, a
    fifth of them (at least 20) in the default one."""
    return full if SLOW else max(20, full // 5)
