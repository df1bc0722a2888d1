"""Regenerate the regression goldens: ``python tests/regression/regen.py [STEM ...]``.

Runs every ``cases/*.toml`` (or only the named stems) in a temporary folder and
writes ``tests/regression/golden/<stem>.json``.  Only do this when a change of
the physics or numerics is intended, and say why in the commit message.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

# a script: the project root on the path, for the tests.support package
sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
from tests.support.golden import case_files, key_scalars, run, write_golden  # noqa: E402


def main(argv: list[str]) -> int:
    cases = case_files()
    if argv:
        cases = [c for c in cases if c.stem in argv]
        missing = set(argv) - {c.stem for c in cases}
        if missing:
            print(f"no such case(s): {', '.join(sorted(missing))}")
            return 2
    with tempfile.TemporaryDirectory() as tmp:
        for case in cases:
            out = Path(tmp) / case.stem
            run(case, out)
            scalars = key_scalars(out)
            print(f"{write_golden(case, scalars)}: {scalars}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
