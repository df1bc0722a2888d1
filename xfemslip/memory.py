"""Memory estimate of a run, checked before anything large is allocated.

The estimate comes from the number of dofs (2 per node plus the enriched dofs
of the fractures) and the fill of the sparse LU factorisation, which grows like
n_dofs * log2(n_dofs) for a 2D mesh with a fill-reducing ordering:

    bytes ~ BASE_BYTES + BYTES_PER_DOF_LOG * n_dofs * log2(n_dofs)

Calibrated on the reservoir case (peak resident memory of the whole process,
``ru_maxrss``): 47k dofs 341 MB, 183k dofs 835 MB, measured; the formula gives
420 MB and 1.0 GB, about 25 % above (an estimate that errs on the safe side).

The limit is the machine's physical memory (``SC_PHYS_PAGES * SC_PAGE_SIZE``),
or the environment variable ``XFEMSLIP_MEMORY_LIMIT`` in bytes (suffixes k, M,
G, T allowed, e.g. ``500M``), which tests and shared machines use.
"""

from __future__ import annotations

import logging
import math
import os

from xfemslip.errors import MeshError, UsageError

logger = logging.getLogger(__name__)

ENV_LIMIT = "XFEMSLIP_MEMORY_LIMIT"
BASE_BYTES = 200e6  # Python, NumPy, SciPy, Numba and the compiled kernels [B]
BYTES_PER_DOF_LOG = 250.0  # per dof and per factor log2(n_dofs) [B]
# Enriched dofs per unit fracture length / h: a cut cell enriches ~2 nodes
# with 2 dofs each, ~1.4 cut cells per h of length; the tip functions add
# 4 functions x 2 dofs on ~50 nodes (radius 4 cells).
_ENRICHED_PER_CELL_LENGTH = 8.0
_TIP_DOFS = 400
_SUFFIX = {"": 1.0, "k": 1e3, "m": 1e6, "g": 1e9, "t": 1e12}


def estimate_dofs(spec) -> int:
    """Upper estimate of the number of dofs of a validated case."""
    nx, ny = spec.mesh.x.size - 1, spec.mesh.y.size - 1
    h = float(min(min(_diffs(spec.mesh.x)), min(_diffs(spec.mesh.y))))
    enriched = 0.0
    for fr in spec.fractures:
        seg = fr.points[1:] - fr.points[:-1]
        length = float(sum(math.hypot(float(a), float(b)) for a, b in seg))
        enriched += _ENRICHED_PER_CELL_LENGTH * (length / h + 2.0) + 2 * _TIP_DOFS
    enriched = min(enriched, 16.0 * (nx + 1) * (ny + 1))
    return int(2 * (nx + 1) * (ny + 1) + enriched)


def _diffs(coords):
    return [float(b - a) for a, b in zip(coords[:-1], coords[1:], strict=True)]


def estimate_bytes(n_dofs: int) -> float:
    """Estimated peak memory [B] of a run with n_dofs unknowns."""
    return BASE_BYTES + BYTES_PER_DOF_LOG * n_dofs * math.log2(max(n_dofs, 2))


def available_bytes() -> tuple[float, str]:
    """The memory limit [B] and where it comes from."""
    text = os.environ.get(ENV_LIMIT, "").strip()
    if text:
        value = _parse_bytes(text)
        if value is None:
            raise UsageError(
                f"environment variable {ENV_LIMIT} = {text!r}: expected a number of "
                "bytes > 0, optionally with a suffix k, M, G or T (e.g. 500M)"
            )
        return value, ENV_LIMIT
    try:
        return (
            float(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")),
            "physical memory",
        )
    except (ValueError, OSError, AttributeError):  # not POSIX: no check
        return math.inf, "unknown"


def _parse_bytes(text: str) -> float | None:
    number, suffix = text, ""
    if text[-1:].lower() in "kmgt" and text[-1:].isalpha():
        number, suffix = text[:-1], text[-1].lower()
    try:
        value = float(number) * _SUFFIX[suffix]
    except (ValueError, KeyError):
        return None
    return value if math.isfinite(value) and value > 0 else None


def check_memory(spec) -> None:
    """Refuse a case whose memory estimate exceeds the limit (MeshError)."""
    n_dofs = estimate_dofs(spec)
    need = estimate_bytes(n_dofs)
    limit, source = available_bytes()
    logger.debug("memory estimate %.3g GB for ~%d dofs", need / 1e9, n_dofs)
    if need > limit:
        nx, ny = spec.mesh.x.size - 1, spec.mesh.y.size - 1
        raise MeshError(
            f"{spec.path}: mesh: {nx} x {ny} elements, ~{n_dofs} dofs, need an "
            f"estimated {need / 1e9:.3g} GB of memory, more than the "
            f"{limit / 1e9:.3g} GB available ({source}); use fewer elements, or set "
            f"{ENV_LIMIT} (bytes) to allow more"
        )
