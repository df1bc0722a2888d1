"""Shared pytest configuration: the ``--run-slow`` opt-in for ``slow`` tests
(marked where they are defined, or named in ``tests/slow_tier.py``), the
hypothesis profile of the suite, the ``xfemslip`` logger put back after each
test, and ``runner``, the CLI runner of the command tests."""

from __future__ import annotations

import contextlib
import logging
import warnings

import pytest
from click.testing import CliRunner
from hypothesis import settings
from hypothesis.internal.conjecture import providers


def _same_examples_whatever_is_loaded() -> None:
    """Every property test draws the same examples in every run: alone, with
    its folder or in the whole suite, in any order.

    ``derandomize`` seeds a test's examples from the test function alone, but
    hypothesis (since 6.131.1) also draws, now and then, literals it parses
    from the project's modules loaded at that moment (not the test files), so
    a test drew other examples when other test files had imported more of
    xfemslip.  No setting turns that off (6.170): its pool is emptied here,
    leaving hypothesis' own constants.  The profile makes the tests without
    an explicit ``derandomize`` reproducible too, with no example database;
    ``--hypothesis-profile`` still chooses another."""
    settings.register_profile(
        "xfemslip", derandomize=True, database=None, deadline=None, print_blob=True
    )
    settings.load_profile("xfemslip")
    if not callable(getattr(providers, "_get_local_constants", None)):
        # a newer hypothesis: the suite still runs, and
        # tests/property/test_examples_reproducible.py says whether the
        # examples now depend on the modules loaded
        warnings.warn(
            "hypothesis no longer has providers._get_local_constants: "
            "update tests/conftest.py",
            stacklevel=1,
        )
        return
    empty = providers.Constants()
    providers._get_local_constants = lambda: empty


_same_examples_whatever_is_loaded()


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption(
        "--run-slow",
        action="store_true",
        default=False,
        help="also run tests marked 'slow'",
    )


def pytest_configure(config: pytest.Config) -> None:
    from tests.support import tiers

    tiers.SLOW = bool(config.getoption("--run-slow"))


def pytest_collection_modifyitems(
    config: pytest.Config, items: list[pytest.Item]
) -> None:
    from tests.slow_tier import SLOW_TESTS

    for item in items:
        if item.nodeid in SLOW_TESTS or item.nodeid.split("[")[0] in SLOW_TESTS:
            item.add_marker(pytest.mark.slow)
    if config.getoption("--run-slow"):
        return
    skip_slow = pytest.mark.skip(reason="slow: run with --run-slow")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip_slow)


@contextlib.contextmanager
def _package_logging_kept():
    """Put back the level and the handlers of the ``xfemslip`` logger: a
    command run in-process (CliRunner) sets the level and adds its stderr
    handler, which later tests would otherwise see."""
    logger = logging.getLogger("xfemslip")
    level, handlers = logger.level, list(logger.handlers)
    try:
        yield
    finally:
        logger.setLevel(level)
        for handler in list(logger.handlers):
            if handler not in handlers:
                logger.removeHandler(handler)


@pytest.fixture(autouse=True, scope="module")
def _package_logging_per_module():
    """(module-scoped fixtures run commands too)"""
    with _package_logging_kept():
        yield


@pytest.fixture(autouse=True)
def _package_logging_per_test():
    with _package_logging_kept():
        yield


@pytest.fixture
def runner() -> CliRunner:
    """A CliRunner whose result keeps stdout and stderr apart."""
    try:  # click < 8.2 mixes stderr into stdout unless told otherwise
        return CliRunner(mix_stderr=False)
    except TypeError:
        return CliRunner()
