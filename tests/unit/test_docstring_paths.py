"""What the package's docstrings and comments point to exists: file paths
under docs/, cases/, xfemslip/, benchmarks/ and tests/, and dotted names
xfemslip.module.attribute (imported and looked up)."""

from __future__ import annotations

import importlib
import re

import pytest

from tests.support.golden import ROOT

PACKAGE = ROOT / "xfemslip"
# a path: one of the project's folders, then path characters; a trailing
# dot or comma is punctuation
PATH = re.compile(r"(?<![\w./-])((?:docs|cases|xfemslip|benchmarks|tests)/[\w./-]*\w)")
DOTTED = re.compile(r"(?<![\w.])(xfemslip(?:\.\w+)+)")


def _mentions(pattern: re.Pattern) -> dict[str, list[str]]:
    found: dict[str, list[str]] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        for number, line in enumerate(text.splitlines(), 1):
            for match in pattern.finditer(line):
                where = f"{path.relative_to(ROOT)}:{number}"
                found.setdefault(match.group(1), []).append(where)
    return found


def _resolves(name: str) -> bool:
    """Whether ``xfemslip.a.b.c`` is a module, or an attribute of one."""
    parts = name.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ImportError:
            continue
        for attr in parts[k:]:
            if not hasattr(obj, attr):
                return False
            obj = getattr(obj, attr)
        return True
    return False


def test_the_scan_finds_paths_and_names():
    """The patterns see what the package names (so the checks below can fail)."""
    paths, names = _mentions(PATH), _mentions(DOTTED)
    assert "docs/case-format.md" in paths and len(paths) > 20
    assert "xfemslip.case" in names and len(names) > 50
    assert not _resolves("xfemslip.linsolve.lu_factor")  # a module that is gone
    assert _resolves("xfemslip.solve.linear.lu_factor")


def test_named_files_exist():
    missing = {
        path: where
        for path, where in _mentions(PATH).items()
        if not (ROOT / path).exists()
    }
    assert missing == {}


@pytest.mark.filterwarnings("ignore")
def test_named_modules_and_attributes_exist():
    missing = {
        name: where for name, where in _mentions(DOTTED).items() if not _resolves(name)
    }
    assert missing == {}
