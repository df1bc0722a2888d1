"""A pytest plugin that writes the CPU time of every test (this process and
the child processes it waited for: ``python -m xfemslip`` runs, sweep
workers) and its wall time, to choose the tests of the slow tier
(``tests/slow_tier.py``)::

    python -m pytest -p tests.support.cpu_times --cpu-times times.json

``times.json`` is a list of ``[node id, CPU seconds, wall seconds]``.
"""

from __future__ import annotations

import json
import resource
import time

import pytest

_ROWS: list[tuple[str, float, float]] = []


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--cpu-times", default=None, help="write per-test CPU times")


def _cpu() -> float:
    own = resource.getrusage(resource.RUSAGE_SELF)
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    cpu, wall = _cpu(), time.perf_counter()
    yield
    _ROWS.append((item.nodeid, _cpu() - cpu, time.perf_counter() - wall))


def pytest_sessionfinish(session, exitstatus) -> None:
    path = session.config.getoption("--cpu-times")
    if path:
        with open(path, "w", encoding="utf-8") as fh:
            json.dump(_ROWS, fh, indent=0)
