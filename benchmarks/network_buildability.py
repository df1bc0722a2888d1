#!/usr/bin/env python3
"""How many generated networks can be built, and built right.

For each network table below, every seed in the range is realized and
validated (``case.loads_case``) and its geometry built as ``xfemslip check``
does (``simulation.check_geometry``: clipping, junctions, cell pieces).  A
seed is *refused* when either raises a ``CaseError`` or ``GeometryError``.

A seed that builds is checked independently of the junction code's own
tests, on the snapped segments (``geometry.find_junctions`` on the clipped
fractures, as ``build_fractures`` calls it); it is *inconsistent* when (each
seed is counted once, under the first of these found, in this order)

- two snapped fractures overlap: they touch and lie within 1e-9 h of each
  other's line over a common stretch (one was snapped onto the other), or
- two snapped fractures touch or cross (``dfn.intersecting_pairs``) with no
  junction between them, or
- two fractures crossed or touched as drawn (before snapping) and have no
  junction (snapping parted them), or
- a junction point is off one of its two fractures (by more than 1e-6 h).

    python benchmarks/network_buildability.py [--seeds 500] [--dfn-seeds 1000]
        [--src DIR]

``--src DIR`` measures the xfemslip package in ``DIR/xfemslip`` (another
version, e.g. ``git archive COMMIT xfemslip | tar -x -C DIR``) with the same
tables and checks, instead of the installed one.

Networks:

- ``test table``: the network of
  ``tests/unit/case/test_case_network.py::test_allow_network_that_crosses_is_built
  _with_a_junction_per_crossing``: 40 fractures of 0.2 m, uniform
  orientation, ``intersections = "allow"``, in a 2 x 1 m domain of 20 x 10
  cells (h = 0.1 m);
- ``DFN sweep base``: the ``[base]`` of ``cases/sweeps/dfn_realizations.toml``
  (30 fractures, two sets, power-law lengths 0.12-0.4 m, 50 x 50 cells on
  the unit square), with its own count and with ``count = 100``.

Not a test: it prints the table of docs/networks.md, *Random networks*.
"""

from __future__ import annotations

import argparse
import copy
import logging
import sys
import time
import tomllib
from pathlib import Path


def _source_first(argv) -> None:
    """With --src DIR, import xfemslip from DIR: drop the finder of an
    editable install (it comes before sys.path) and put DIR first."""
    if "--src" in argv[:-1]:
        sys.meta_path = [f for f in sys.meta_path if "__editable__" not in repr(f)]
        sys.path.insert(0, str(Path(argv[argv.index("--src") + 1]).resolve()))


_source_first(sys.argv)

import numpy as np  # noqa: E402

from xfemslip.case import build, loads_case  # noqa: E402
from xfemslip.errors import CaseError, GeometryError  # noqa: E402
from xfemslip.fem.mesh import build_mesh  # noqa: E402
from xfemslip.geometry import fracture as geometry  # noqa: E402
from xfemslip.geometry import junctions  # noqa: E402
from xfemslip.geometry.dfn import intersecting_pairs  # noqa: E402
from xfemslip.simulation import check_geometry  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SWEEP = ROOT / "cases" / "sweeps" / "dfn_realizations.toml"

TEST_TABLE = {
    "domain": {"size": [2.0, 1.0]},
    "mesh": {"elements": [20, 10]},
    "material": {"E": 5.0e9, "nu": 0.3},
    "loading": {"stress": {"xx": -20.0e6, "yy": -40.0e6}},
    "boundary": {"bottom": {"uy": 0.0}, "top": "traction"},
    "network": {
        "friction": 0.5,
        "generate": {
            "seed": 0,
            "count": 40,
            "intersections": "allow",
            "orientation": {"distribution": "uniform"},
            "length": {"distribution": "constant", "value": 0.2},
        },
    },
}


def test_table() -> dict:
    """The test's case as a TOML document."""
    return copy.deepcopy(TEST_TABLE)


def dfn_base(count: int | None = None) -> dict:
    """The shipped DFN sweep's base case, optionally with another count."""
    document = copy.deepcopy(tomllib.loads(SWEEP.read_text())["base"])
    if count is not None:
        document["network"]["generate"]["count"] = count
    return document


def snapped(spec):
    """(segments (n, 2, 2) before and after snapping, junctions, h) of a case
    whose fractures are straight, as build_fractures finds them."""
    mesh = build_mesh(spec.mesh.x, spec.mesh.y)
    box = np.array([mesh.x[0], mesh.x[-1], mesh.y[0], mesh.y[-1]])
    h = mesh.h_min
    tol = geometry.GEOMETRY_TOL * h
    polylines, free = [], []
    for f in spec.fractures:
        pts, _ = geometry.clip_to_domain(np.asarray(f.points, float), box, tol, "")
        polylines.append(pts.copy())
        free.append([not geometry.on_boundary(p, box, tol) for p in pts[[0, -1]]])
    names = [f"fractures[{f.index}]" for f in spec.fractures]
    drawn = np.array(polylines)
    found = junctions.find_junctions(polylines, free, names, h, tol)
    return drawn, np.array(polylines), found, h


def _distance(p, a, b) -> float:
    """Distance of point p to segment a-b."""
    d = b - a
    t = np.clip((p - a) @ d / (d @ d), 0.0, 1.0)
    return float(np.linalg.norm(a + t * d - p))


def _overlap(s, r, tol) -> bool:
    """Segments s, r (2, 2) within tol of each other over more than tol."""
    u = (s[1] - s[0]) / np.linalg.norm(s[1] - s[0])
    along = sorted((r - s[0]) @ u)
    lo, hi = max(along[0], 0.0), min(along[1], float(np.linalg.norm(s[1] - s[0])))
    if hi - lo <= tol:
        return False
    ends = [s[0] + lo * u, s[0] + hi * u]  # the common stretch on s
    return all(_distance(p, *r) <= tol for p in ends)


def inconsistency(spec) -> tuple[str, str] | None:
    """(kind, message) of what is wrong with the snapped geometry of a case
    that builds, or None; kind is one of KINDS, checked in that order."""
    drawn, segments, found, h = snapped(spec)
    tol = geometry.GEOMETRY_TOL * h
    met = {tuple(sorted((main, sec))) for _, main, sec, _ in found}
    for i, j in intersecting_pairs(segments, tol):
        if _overlap(segments[i], segments[j], tol) or _overlap(
            segments[j], segments[i], tol
        ):
            return "overlap", f"fractures[{i}] and [{j}] overlap after snapping"
    for i, j in intersecting_pairs(segments, tol):
        if (i, j) not in met:
            return "no junction", f"fractures[{i}] and [{j}] meet with no junction"
    for i, j in intersecting_pairs(drawn, 0.0):
        if (i, j) not in met:
            return "parted", f"fractures[{i}] and [{j}] crossed before snapping"
    for kind, main, sec, point in found:
        for f in (main, sec):
            off = _distance(np.asarray(point), *segments[f])
            if off > 1e-6 * h:
                return "off", (
                    f"{kind} junction of fractures[{main}] and [{sec}] lies "
                    f"{off / h:.2g} h off [{f}]"
                )
    return None


def survey(document: dict, seeds) -> tuple[list, list]:
    """(refused, inconsistent): lists of (seed, message) and (seed, kind,
    message) over the seeds."""
    refused, wrong = [], []
    for seed in seeds:
        document["network"]["generate"]["seed"] = seed
        try:
            spec = loads_case(build.case_text(document), f"seed{seed}.toml")
            check_geometry(spec)
        except (CaseError, GeometryError) as err:
            refused.append((seed, " ".join(str(err).split())))
            continue
        problem = inconsistency(spec)
        if problem is not None:
            wrong.append((seed, *problem))
    return refused, wrong


KINDS = ("overlap", "no junction", "parted", "off")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument(
        "--seeds", type=int, default=500, help="seeds of the test table"
    )
    parser.add_argument("--dfn-seeds", type=int, default=1000, help="seeds of the DFN")
    parser.add_argument("--src", help="measure the xfemslip package in this folder")
    args = parser.parse_args(argv)
    import xfemslip

    print(f"xfemslip from {Path(xfemslip.__file__).parent}")
    logging.disable(logging.WARNING)  # the tip-mode notes of every seed
    rows = [
        ("test table (40 x 0.2 m, allow)", test_table(), args.seeds),
        ("DFN sweep base (count 30)", dfn_base(), args.dfn_seeds),
        ("DFN sweep base, count = 100", dfn_base(100), args.dfn_seeds),
    ]
    print(
        "| network | seeds | refused | built, overlapping | built, meeting "
        "without junction | built, a drawn crossing parted | built, a junction "
        "off its fracture | time |"
    )
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    messages = []
    for name, document, n in rows:
        start = time.perf_counter()
        refused, wrong = survey(document, range(n))
        wall = time.perf_counter() - start
        counts = [sum(1 for w in wrong if w[1] == k) for k in KINDS]
        cells = " | ".join(str(c) for c in counts)
        print(f"| {name} | 0-{n - 1} | {len(refused)} | {cells} | {wall:.0f} s |")
        if refused:
            seeds = ", ".join(str(s) for s, _ in refused[:8])
            messages.append(f"{name}: refused seeds {seeds}; {refused[0][1]}")
        for kind in KINDS:
            found = [w for w in wrong if w[1] == kind]
            if found:
                seeds = ", ".join(str(w[0]) for w in found[:8])
                messages.append(f"{name}: {kind} seeds {seeds}; {found[0][2]}")
    for text in messages:
        print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
