"""The README's set-up section: the two commands .ci/run executes (a plain
install that runs a case, then the test extra and the tests), read the way
.ci/run reads them, and the supported platforms."""

from __future__ import annotations

import re

from tests.support.golden import ROOT

INSTALL_AND_RUN = (
    "python3 -m venv .venv && . .venv/bin/activate && pip install -e . && "
    "xfemslip run cases/reservoir_depletion.toml"
)
TESTS = (
    ". .venv/bin/activate && pip install -e '.[test]' && python -m pytest -q --run-slow"
)


def _setup_section() -> str:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    match = re.search(r"^## Set-up.*?(?=^## )", text, re.M | re.S)
    assert match, "README has no '## Set-up' section"
    return match.group(0)


def _commands(section: str) -> list[str]:
    """The non-empty lines of its ```bash fences (as .ci/run's awk reads)."""
    out, fence = [], False
    for line in section.splitlines():
        if line.startswith("```bash"):
            fence = True
        elif line.startswith("```"):
            fence = False
        elif fence and line.strip():
            out.append(line)
    return out


def test_two_commands_plain_install_first():
    assert _commands(_setup_section()) == [INSTALL_AND_RUN, TESTS]


def test_ci_reads_the_same_section():
    script = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert "/^## Set-up/" in script and '"${#commands[@]}" -ne 2' in script


def test_platforms_are_stated():
    section = _setup_section()
    assert "Linux and macOS" in section and "WSL" in section
