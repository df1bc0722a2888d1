"""The platform, and the environment variables xfemslip and Numba read,
checked before a command runs (by the command group of :mod:`xfemslip.cli`).

Numba parses its variables when it is first imported: ``NUMBA_NUM_THREADS=0``
then raises ``ValueError`` from inside ``import numba``, and a value it cannot
parse (``NUMBA_NUM_THREADS=abc``) prints a warning holding a traceback.  The
xfemslip variables are read deep inside a run (the memory limit before the
mesh is built, the kernel choice when the model is assembled), where a typo
would be ignored or reported late.  Each is checked here, cheaply and without
importing Numba, and a bad value is one line naming the variable (exit 2).
"""

from __future__ import annotations

import os
import sys

from xfemslip.errors import UsageError
from xfemslip.io.lock import UNSUPPORTED_PLATFORM
from xfemslip.memory import parse_bytes


def _positive_int(text: str) -> bool:
    try:
        return int(text) >= 1  # int() is how Numba reads its integers
    except ValueError:
        return False


def _int(text: str) -> bool:
    try:
        int(text)
    except ValueError:
        return False
    return True


def _byte_count(text: str) -> bool:
    return not text.strip() or parse_bytes(text.strip()) is not None


def _kernels(text: str) -> bool:
    return text.strip().lower() in ("", "auto", "numba", "numpy")


# (variable, check of its text, what is expected)
ENVIRONMENT = (
    ("NUMBA_NUM_THREADS", _positive_int, "an integer >= 1 (Numba's thread count)"),
    ("NUMBA_DISABLE_JIT", _int, "an integer (0 or 1)"),
    (
        "XFEMSLIP_MEMORY_LIMIT",
        _byte_count,
        "a number of bytes > 0, optionally with a suffix k, M, G or T (e.g. 500M)",
    ),
    ("XFEMSLIP_KERNELS", _kernels, "numba, numpy or auto"),
)


def check_environment(environ=None) -> None:
    """UsageError naming the first variable of ENVIRONMENT with a bad value."""
    environ = os.environ if environ is None else environ
    for name, check, expected in ENVIRONMENT:
        value = environ.get(name)
        if value is not None and not check(value):
            shown = value if len(value) <= 40 else value[:37] + "..."
            raise UsageError(
                f"environment variable {name} = {shown!r}: expected {expected}"
            )


def check_platform(platform: str | None = None) -> None:
    """UsageError on a platform the command line does not run on (Windows:
    the output lock needs POSIX file locks); Linux and macOS pass."""
    if (sys.platform if platform is None else platform) == "win32":
        raise UsageError(UNSUPPORTED_PLATFORM)
