"""Numba settings shared by every kernel, read once from the environment.

XFEMSLIP_NUMBA_CACHE=0 turns the on-disk cache off (default on: compile once
per install).  fastmath stays off everywhere: the contact law relies on exact
sign tests and max(0, .).
"""

import os

NUMBA_CACHE = os.environ.get("XFEMSLIP_NUMBA_CACHE", "1") != "0"

# |Delta g_T| below this (m) has no usable secant; the elastic k_T is used
# (both backends).
SECANT_MIN_INCREMENT = 1.0e-300


def numba_settings() -> list[tuple[str, str]]:
    """Numba's threading layer, thread count, cache dir and JIT switch (for `info`)."""
    import numba

    # numba.config sets these from the environment when it is imported
    config = vars(numba.config)
    cache_dir = config["CACHE_DIR"] or "default (__pycache__ next to the sources)"
    return [
        ("numba threading layer", str(config["THREADING_LAYER"])),
        ("NUMBA_NUM_THREADS", str(config["NUMBA_NUM_THREADS"])),
        ("numba cache dir", str(cache_dir)),
        ("NUMBA_DISABLE_JIT", str(config["DISABLE_JIT"])),
        (
            "xfemslip numba cache",
            "on" if NUMBA_CACHE else "off (XFEMSLIP_NUMBA_CACHE=0)",
        ),
    ]
