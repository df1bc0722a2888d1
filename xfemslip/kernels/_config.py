"""Numba settings shared by every kernel, read once from the environment.

XFEMSLIP_NUMBA_CACHE=0 turns the on-disk cache off (default on: compile once
per install).  fastmath stays off everywhere: the contact law relies on exact
sign tests and max(0, .).
"""

import os

NUMBA_CACHE = os.environ.get("XFEMSLIP_NUMBA_CACHE", "1") != "0"
NUMBA_FASTMATH = False
