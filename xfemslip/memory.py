"""Memory estimate of a run, checked before each large allocation.

The peak resident memory of a run is modelled from the sizes that set it
(a ``Footprint``), term by term, in bytes:

- ``base``: the interpreter with NumPy, SciPy, h5py and meshio (BASE_NUMPY),
  plus Numba and its compiled kernels when the Numba backend runs
  (BASE_NUMBA);
- ``enriched``: the enriched-cell quadrature (enrichment.EnrichedCells), per
  quadrature point its position and weight and the sub-triangles' vertex
  values (padded to S, the slots of the widest cell): QP_BYTES +
  QP_PAD_BYTES * S per point, and F and grad F of every column of a cell
  (the functions its slots take, one per group and function) at every
  point of the cell (QP_COLUMN_BYTES each);
- ``assembly``, while the stiffness is assembled: the padded element
  matrices of the enriched cells, (8 + 2 S)^2 doubles each, for at most
  assembly.enriched_chunk cells at a time, the intact
  cells summed into the grid's CSR (GRID_BYTES per node), the COO triplets
  of the enriched cells' entries with their conversion to CSR
  (TRIPLET_BYTES per entry) and, on the NumPy kernels, the shape-function
  gradients of a chunk's quadrature points (NUMPY_QP_FUNCTION_BYTES per
  point and function, 4 + S functions; an upper bound, the kernel takes
  them in smaller batches);
- ``solver``: what the linear solver the run will take holds at once
  (xfemslip.solve.linear: planned_solver states the choice, solver_bytes
  the bytes of its matrices, factorizations -- with the Schur complement
  of the contact dofs, or of the patches' jumps on networks -- or AMG
  hierarchy and Krylov vectors);
- ``contact tangents``, during the Newton iterations: the contact tangent
  blocks of every patch, padded to the widest (8 B per entry), NEWTON_BLOCKS
  arrays of them at once (the iterate's, the next one's -- a line-search
  trial or a local branch search's -- and the scratch one of the
  evaluations whose tangent is not used; one more on the NumPy kernels,
  which form the product before copying it in place), and the COO triplets
  of their non-empty entries (TRIPLET_BYTES each).  Before the interface
  points exist the widest block is taken as 2 S (measured 0.65 to 1.2 times
  the real one on generated networks);
- ``steps``: every converged load step is kept until the output is written:
  the displacement, the contact force and the displacement of the last
  contact evaluation (3 x 8 B per dof), per contact patch its jumps,
  tractions and state (48 B), and the written fields (per node 16 B, per
  cell 48 B, 80 B more with pore pressure, per contact point 80 B).

peak = base + enriched + max(assembly, solver + contact tangents + steps).

The resident memory is what is in use only if freed memory goes back to
the system: the command line fixes glibc's allocator thresholds for that
(configure_allocator; with glibc's defaults a crowded network whose Newton
solve ran long peaked at 1.7 times this estimate).

It is evaluated three times, each before what it guards: from the case alone
(``check_memory(spec)``, before the mesh: a lower estimate of the enrichment),
from the fractures and their node enrichments (``enriched_footprint``, before
the enriched cells are built: the slots per cell exactly, their quadrature
points estimated), and from the built model (``model_footprint``, before the
first solve: everything but the LU fill exact).  Measured against the peak
resident memory (ru_maxrss) of whole runs by benchmarks/memory_estimate.py
(table in docs/robustness.md, *Memory*): the last two estimates lie
between 0.90 and 1.34 times the measured peak on shipped cases, crowded
networks (failing after a long Newton solve, or converging), long runs and
large meshes.

The limit is the machine's physical memory (``SC_PHYS_PAGES * SC_PAGE_SIZE``),
or the environment variable ``XFEMSLIP_MEMORY_LIMIT`` in bytes (suffixes k, M,
G, T allowed, e.g. ``500M``), which tests and shared machines use.
"""

from __future__ import annotations

import ctypes
import logging
import math
import os
from dataclasses import dataclass

import numpy as np

from xfemslip.case.specs import CaseSpec
from xfemslip.errors import MeshError, UsageError

logger = logging.getLogger(__name__)

ENV_LIMIT = "XFEMSLIP_MEMORY_LIMIT"
BASE_NUMPY = 92e6  # measured 92 MB: a 10 x 10 case on the NumPy kernels [B]
BASE_NUMBA = 202e6  # measured 201 MB: the same case on the Numba kernels [B]
QP_BYTES = 48.0  # per enriched-cell quadrature point: xy, w, triangle share [B]
QP_COLUMN_BYTES = 24.0  # per column and point of its cell: F, grad F [B]
QP_PAD_BYTES = 4.0  # per point and slot of the widest cell: vertex values [B]
TRIPLET_BYTES = 48.0  # per COO entry: rows, cols, values and the CSR copy [B]
# per grid node while the intact cells are summed into the grid's CSR
# (assembly.grid_stiffness: 36 values per node in planes, their read-out with
# int32 columns, the CSR and its sum with the enriched cells' part); measured
# 750 B per node at 1000 x 1000 (peak 856 MB of the uncracked build) [B]
GRID_BYTES = 800.0
# per enriched-cell quadrature point and shape function, NumPy kernels only:
# gradients, weighted gradients and their gathered cell data [B]
NUMPY_QP_FUNCTION_BYTES = 56.0
NEWTON_BLOCKS = 3  # contact tangent-block arrays held at once (+1 on NumPy)
NNZ_PER_ENTRY = 0.56  # CSR non-zeros per COO entry (shared nodes summed)
# Enriched-cell quadrature points, estimated before the cells are cut: a
# cell crossed by p fracture pieces has about QP_CELL + QP_PIECE p +
# QP_PIECE2 p^2 points (its sub-triangles times 7), a cell near a branch
# enriched tip QP_BRANCH more (the collapsed Duffy rule); measured 20, 38, 63,
# 96, 146 points for p = 0..4 on a 200-fracture network, 109 near a tip.
QP_CELL, QP_PIECE, QP_PIECE2, QP_BRANCH = 20.0, 20.0, 5.0, 90.0
# Before the mesh is built: enriched dofs per unit fracture length / h (a cut
# cell enriches ~2 nodes with 2 dofs each, ~1.4 cut cells per h of length;
# the tip functions add 4 functions x 2 dofs on ~50 nodes, radius 4 cells).
_ENRICHED_PER_CELL_LENGTH = 8.0
_TIP_DOFS = 400
_SUFFIX = {"": 1.0, "k": 1e3, "m": 1e6, "g": 1e9, "t": 1e12}


@dataclass(frozen=True)
class Footprint:
    """The sizes that set a run's peak memory (counts, not bytes)."""

    n_nodes: int
    n_cells: int
    n_dofs: int
    nnz: float  # stiffness non-zeros
    steps: int  # kept load steps
    numba: bool = False  # the Numba kernels are loaded
    pore: bool = False  # pore-pressure fields are written
    enriched_cells: int = 0
    slots: int = 0  # enrichment slots of the widest enriched cell (padding)
    entries: float = 0.0  # COO entries of all cells, sum of (8 + 2 s)^2
    enriched_entries: float = 0.0  # of them, those of the enriched cells
    qp: float = 0.0  # enriched-cell quadrature points
    # F values stored: the points of each enriched cell times its columns
    # (None: every point with S columns, an upper bound)
    qp_columns: float | None = None
    patches: float = 0.0  # contact patches
    block: float = 0.0  # dofs of the widest patch's tangent block (2 J)
    contact_entries: float = 0.0  # non-empty entries of the tangent blocks
    points: float = 0.0  # contact integration points
    linear: str = "superlu"  # the linear solver "auto" resolves to
    contact_dofs: float = 0.0  # distinct dofs of the contact patches


def estimate_terms(fp: Footprint) -> dict[str, float]:
    """The terms of the module docstring [B] and their ``total``."""
    base = BASE_NUMBA if fp.numba else BASE_NUMPY
    qp_columns = fp.qp * fp.slots if fp.qp_columns is None else fp.qp_columns
    enriched = (
        fp.qp * (QP_BYTES + QP_PAD_BYTES * fp.slots) + QP_COLUMN_BYTES * qp_columns
    )
    from xfemslip.fem.assembly import enriched_chunk

    chunk = min(fp.enriched_cells, enriched_chunk(fp.slots))
    share = chunk / fp.enriched_cells if fp.enriched_cells else 1.0
    gradients = (
        0.0 if fp.numba else NUMPY_QP_FUNCTION_BYTES * share * fp.qp * (4 + fp.slots)
    )
    triplets = GRID_BYTES * fp.n_nodes + TRIPLET_BYTES * fp.enriched_entries
    assembly = chunk * (8 + 2 * fp.slots) ** 2 * 8.0
    assembly += max(gradients, triplets)  # one after the other
    from xfemslip.solve.linear import solver_bytes

    solver = solver_bytes(fp.linear, fp.nnz, fp.n_dofs, fp.contact_dofs, fp.patches)
    arrays = NEWTON_BLOCKS + (0 if fp.numba else 1)
    tangents = arrays * 8.0 * fp.patches * fp.block**2
    tangents += TRIPLET_BYTES * fp.contact_entries
    per_step = (
        24.0 * fp.n_dofs
        + 48.0 * fp.patches
        + 16.0 * fp.n_nodes
        + (128.0 if fp.pore else 48.0) * fp.n_cells
        + 80.0 * fp.points
    )
    steps = fp.steps * per_step
    total = base + enriched + max(assembly, solver + tangents + steps)
    return {
        "total": total,
        "base": base,
        "enriched cells": enriched,
        "assembly": assembly,
        "solver": solver,
        "contact tangents": tangents,
        "steps": steps,
    }


def estimate_dofs(spec: CaseSpec) -> int:
    """Upper estimate of the number of dofs of a validated case."""
    nx, ny = spec.mesh.x.size - 1, spec.mesh.y.size - 1
    h = float(min(np.diff(spec.mesh.x).min(), np.diff(spec.mesh.y).min()))
    enriched = 0.0
    for fr in spec.fractures:
        length = float(np.linalg.norm(np.diff(fr.points, axis=0), axis=1).sum())
        enriched += _ENRICHED_PER_CELL_LENGTH * (length / h + 2.0) + 2 * _TIP_DOFS
    enriched = min(enriched, 16.0 * (nx + 1) * (ny + 1))
    return int(2 * (nx + 1) * (ny + 1) + enriched)


def case_footprint(spec: CaseSpec) -> Footprint:
    """From the case alone (before the mesh): the standard part exactly, the
    enrichment from the fracture lengths (no slots, no quadrature: a lower
    estimate for crowded fractures, which enriched_footprint refines)."""
    nx, ny = spec.mesh.x.size - 1, spec.mesh.y.size - 1
    n_nodes, n_cells = (nx + 1) * (ny + 1), nx * ny
    n_dofs = estimate_dofs(spec)
    h = float(min(np.diff(spec.mesh.x).min(), np.diff(spec.mesh.y).min()))
    length = sum(
        float(np.linalg.norm(np.diff(fr.points, axis=0), axis=1).sum())
        for fr in spec.fractures
    )
    pieces = min(1.5 * length / h, float(n_cells))
    entries = 64.0 * n_cells  # the enriched cells' wider blocks are not known yet
    patches = _patches(spec, length, h, 4 * pieces)
    return Footprint(
        n_nodes=n_nodes,
        n_cells=n_cells,
        n_dofs=n_dofs,
        # the band of the enriched dofs is not known yet: AMG if large enough
        linear=_linear(spec, spec.mesh.x, spec.mesh.y, n_dofs),
        nnz=NNZ_PER_ENTRY * entries + 20.0 * (n_dofs - 2 * n_nodes),
        steps=spec.loading.steps,
        entries=entries,
        pore=spec.pore_pressure is not None,
        patches=patches,
        block=16.0,
        contact_entries=256.0 * patches,
        # the jumps are interpolated from the enriched dofs alone
        contact_dofs=float(n_dofs - 2 * n_nodes),
        points=4 * pieces,
    )


def _patches(spec: CaseSpec, length: float, h: float, points: float) -> float:
    """Contact patches: one per contact_patch cells of fracture, or per point."""
    cells = spec.solver.contact_patch
    return points if cells <= 0 else min(points, length / (cells * h) + 2.0)


def enriched_footprint(spec: CaseSpec, mesh, fractures, cand) -> Footprint:
    """From the built fractures and their node enrichments (enrichment.
    Candidates), before the enriched cells are cut: the enriched cells and
    their slots exactly (the cells around each enriched node, as
    enrichment.build_enriched_cells takes them), the quadrature points from
    the fracture pieces per cell (QP_CELL ...)."""
    from xfemslip.fem.enrichment import HEAVISIDE
    from xfemslip.kernels import choose

    nx = mesh.nx
    i, j = cand.node % (nx + 1), cand.node // (nx + 1)
    di, dj = np.array([-1, 0, -1, 0]), np.array([-1, -1, 0, 0])
    ci, cj = i[:, None] + di, j[:, None] + dj
    inside = (ci >= 0) & (ci < nx) & (cj >= 0) & (cj < mesh.ny)
    cell = (cj * nx + ci)[inside]
    slots = np.bincount(cell, minlength=mesh.n_cells)
    # the cells' columns: their distinct (group, function) pairs, as
    # enrichment.build_enriched_cells shares them
    k = np.nonzero(inside)[0]
    _, function = np.unique(
        cand.groups()[k] * 4 + cand.function_index()[k], return_inverse=True
    )
    width = int(function.max(initial=0)) + 1
    pairs = np.unique(cell * width + function.ravel())
    columns = np.bincount(pairs // width, minlength=mesh.n_cells)
    branch = np.zeros(mesh.n_cells, bool)
    branch[(cj * nx + ci)[inside & (cand.func != HEAVISIDE)[:, None]]] = True
    pieces = np.zeros(mesh.n_cells)
    for fr in fractures:
        np.add.at(pieces, np.unique(fr.piece_cell), 1.0)
    enr = slots > 0
    p = pieces[enr]
    qp_cell = QP_CELL + QP_PIECE * p + QP_PIECE2 * p * p + QP_BRANCH * branch[enr]
    qp = float(np.sum(qp_cell))
    qp_columns = float(np.sum(qp_cell * columns[enr]))
    S = int(slots.max(initial=0))
    enriched_entries = float(np.sum((8.0 + 2.0 * slots[enr]) ** 2))
    entries = 64.0 * (mesh.n_cells - enr.sum()) + enriched_entries
    n_points = 4.0 * sum(fr.piece_cell.size for fr in fractures)
    length = sum(float(fr.length.sum()) for fr in fractures)
    patches = _patches(spec, length, mesh.h_min, n_points)
    n_dofs = 2 * mesh.n_nodes + 2 * cand.node.size
    return Footprint(
        n_nodes=mesh.n_nodes,
        n_cells=mesh.n_cells,
        n_dofs=n_dofs,
        linear=_linear(
            spec, mesh.x, mesh.y, n_dofs, lambda: _band_share(mesh, cand, n_dofs)
        ),
        nnz=NNZ_PER_ENTRY * entries,
        steps=spec.loading.steps,
        # the points are estimated up to 20 % low (QP_CELL ...): near the
        # crossover, the larger base of the Numba kernels
        numba=choose(spec.solver.kernels, 1.25 * qp * (8 + 2 * S) ** 2) == "numba",
        pore=spec.pore_pressure is not None,
        enriched_cells=int(enr.sum()),
        slots=S,
        entries=entries,
        enriched_entries=enriched_entries,
        qp=qp,
        qp_columns=qp_columns,
        patches=patches,
        block=2.0 * S,
        # a patch's block holds the slots of about one cut cell
        contact_dofs=2.0 * cand.node.size,
        contact_entries=patches * float(np.mean((2.0 * slots[enr]) ** 2))
        if enr.any()
        else 0.0,
        points=n_points,
    )


def model_footprint(model) -> Footprint:
    """From the built model, before the first solve: exact but for the LU
    fill (the assembly, already done, is counted as it was)."""
    ec, contact = model.ec, model.contact
    S = ec.slot_node.shape[1]
    used = np.count_nonzero(ec.slot_cand >= 0, axis=1)
    enriched_entries = float(np.sum((8.0 + 2.0 * used) ** 2))
    entries = 64.0 * (model.mesh.n_cells - ec.cells.size) + enriched_entries
    dofs = np.count_nonzero(contact.dofs >= 0, axis=1)
    p = model.problem
    return Footprint(
        n_nodes=model.mesh.n_nodes,
        n_cells=model.mesh.n_cells,
        n_dofs=p.n_dofs,
        linear=_linear(
            model.spec,
            model.mesh.x,
            model.mesh.y,
            p.n_dofs,
            lambda: _problem_band_share(p),
        ),
        nnz=float(model.problem.K.nnz),
        steps=model.spec.loading.steps,
        numba=contact.kernels == "numba",
        pore=model.pore is not None,
        enriched_cells=int(ec.cells.size),
        slots=S,
        entries=entries,
        enriched_entries=enriched_entries,
        qp=float(ec.qp_w.size),
        qp_columns=float(ec.column_F.size),
        patches=float(contact.dofs.shape[0]),
        block=float(contact.dofs.shape[1]),
        contact_entries=float(np.sum(dofs.astype(float) ** 2)),
        contact_dofs=float(np.unique(contact.dofs[contact.dofs >= 0]).size),
        points=float(model.ip.n),
    )


# glibc's malloc (mallopt(3)): a block of at least M_MMAP_THRESHOLD bytes is
# mapped on its own and unmapped when freed; a smaller one comes from the
# heap, whose free space is given back only at its top, beyond
# M_TRIM_THRESHOLD.  By default glibc raises the threshold to the size of
# every mapped block freed, up to 32 MiB, so after the first large free the
# tangent blocks, the linear-system work arrays and SuperLU's factor arrays
# (4 of 30 x nnz entries per factorization, mostly unused) all land in the
# heap, where freed space stays resident between Newton iterations: a
# crowded network peaked at 0.63 GB with 0.35 GB in use.  Fixed thresholds
# keep the resident memory at what is in use (configure_allocator).  4 MiB:
# NumPy asks for transparent huge pages from 4 MiB on, so a mapped array
# costs few page faults; a free heap top of up to 8 MiB (twice that, glibc's
# own ratio) is kept for the smaller temporaries of an iteration (32 MiB
# raised the peak of the shipped cases by 10 MB).
M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3  # malloc.h
MMAP_THRESHOLD = 4 << 20  # [B]
TRIM_THRESHOLD = 8 << 20  # [B]
_MALLOC_ENV = {
    "MALLOC_MMAP_THRESHOLD_": MMAP_THRESHOLD,
    "MALLOC_TRIM_THRESHOLD_": TRIM_THRESHOLD,
}


def configure_allocator() -> bool:
    """Fix glibc's mmap and trim thresholds (MMAP_THRESHOLD, TRIM_THRESHOLD)
    in this process and, through the environment variables glibc reads at
    start, in the processes it starts (sweep workers).  The command line
    does this first; a program using the library may call it too.

    Returns whether it did: not on another C library, nor when the
    environment already sets a MALLOC_*_ threshold or a glibc.malloc
    tunable (the user's choice stands).
    """
    if any(name in os.environ for name in _MALLOC_ENV):
        return False
    if "glibc.malloc." in os.environ.get("GLIBC_TUNABLES", ""):
        return False
    try:
        if not (os.confstr("CS_GNU_LIBC_VERSION") or "").startswith("glibc"):
            return False
        mallopt = ctypes.CDLL(None).mallopt
    except (ValueError, OSError, AttributeError):  # not glibc
        return False
    mallopt.argtypes, mallopt.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
    if mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD) != 1:
        return False
    if mallopt(M_TRIM_THRESHOLD, TRIM_THRESHOLD) != 1:
        return False
    for name, value in _MALLOC_ENV.items():
        os.environ[name] = str(value)
    return True


def _linear(spec: CaseSpec, x, y, n_dofs, band_share=None) -> str:
    """The linear solver the run will take (linsolve.planned_solver) on a
    mesh with grid lines x, y and about n_dofs free dofs; ``band_share()``
    gives the share of them in the AMG band (None: not known yet)."""
    from xfemslip.solve.linear import planned_solver

    return planned_solver(spec.solver.linear_solver, n_dofs, x, y, band_share)


def _problem_band_share(problem) -> float:
    """Share of the Problem's dofs in the AMG band, as "auto" forms it."""
    from xfemslip.solve.linear import system_facts

    return system_facts(problem.K, np.arange(problem.n_dofs), problem.node_xy)[
        "band_share"
    ]


def _band_share(mesh, cand, n_dofs) -> float:
    """Share of the dofs in the AMG band before the stiffness exists."""
    from xfemslip.solve.linear import grid_band_share

    return grid_band_share((mesh.nx, mesh.ny), cand.node, n_dofs)


def available_bytes() -> tuple[float, str]:
    """The memory limit [B] and where it comes from."""
    text = os.environ.get(ENV_LIMIT, "").strip()
    if text:
        value = parse_bytes(text)
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


def parse_bytes(text: str) -> float | None:
    number, suffix = text, ""
    if text[-1:].lower() in "kmgt" and text[-1:].isalpha():
        number, suffix = text[:-1], text[-1].lower()
    try:
        value = float(number) * _SUFFIX[suffix]
    except (ValueError, KeyError):
        return None
    return value if math.isfinite(value) and value > 0 else None


def _gb(value: float) -> str:
    return f"{value / 1e9:.3g} GB"


def check_memory(spec: CaseSpec, footprint: Footprint | None = None) -> None:
    """Refuse a case whose memory estimate exceeds the limit (MeshError, one
    line naming the estimate, its largest terms and the limit).

    footprint : the sizes known so far (default: case_footprint(spec)).
    """
    fp = case_footprint(spec) if footprint is None else footprint
    terms = estimate_terms(fp)
    need = terms.pop("total")
    limit, source = available_bytes()
    logger.debug(
        "memory estimate %s for ~%d dofs (%s)",
        _gb(need),
        fp.n_dofs,
        ", ".join(f"{k} {_gb(v)}" for k, v in terms.items()),
    )
    if need <= limit:
        return
    nx, ny = spec.mesh.x.size - 1, spec.mesh.y.size - 1
    solve = ("solver", "contact tangents", "steps")
    if terms["assembly"] < sum(terms[k] for k in solve):
        del terms["assembly"]
    else:
        for k in solve:
            del terms[k]
    largest = [kv for kv in sorted(terms.items(), key=lambda kv: -kv[1]) if kv[1]]
    largest = largest[:3]
    parts = ", ".join(
        f"{fp.steps} kept load steps {_gb(v)}" if k == "steps" else f"{k} {_gb(v)}"
        for k, v in largest
    )
    raise MeshError(
        f"{spec.path}: mesh: {nx} x {ny} elements, {len(spec.fractures)} "
        f"fracture(s), ~{fp.n_dofs} dofs, {fp.steps} load step(s): need an "
        f"estimated {_gb(need)} of memory ({parts}), more than the "
        f"{_gb(limit)} available ({source}); use fewer elements, fractures or "
        f"load steps, or set {ENV_LIMIT} (bytes) to allow more"
    )


__all__ = [
    "ENV_LIMIT",
    "Footprint",
    "available_bytes",
    "case_footprint",
    "check_memory",
    "configure_allocator",
    "enriched_footprint",
    "estimate_dofs",
    "estimate_terms",
    "model_footprint",
]
