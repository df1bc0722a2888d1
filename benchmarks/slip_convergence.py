#!/usr/bin/env python3
"""Why the slip error on the OpenGeoSys peer problem stopped converging.

Usage (from the project root)::

    python benchmarks/slip_convergence.py candidates --h 0.025
    python benchmarks/slip_convergence.py mesh --h 0.1 0.05 0.025 0.0125
    python benchmarks/slip_convergence.py mesh --element q4 ...   # the former element
    python benchmarks/slip_convergence.py exact --aoh 10 20 40
    python benchmarks/slip_convergence.py box --h 0.1 0.05 0.025 0.0125 [--element q4]

The problem is that of ``benchmarks/ogs_compare.py`` (``xfemslip.reference.peer``): a
crack of half-length a = 1 m at 45 degrees through the centre of a square box,
remote stress (-20, -40, 0) MPa as edge tractions (bottom edge a roller),
f = 0.1, c = 0, kn = kt = 5e12 Pa/m, E = 5 GPa, nu = 0.3, plane strain, one
load step, on the rectilinear mesh ``peer.graded``: cells of size h on
[-fine, fine]^2 growing by ``growth`` per cell to the box edges at +-half
(ogs_compare: fine = 0.8, growth = 1.3; here half = 200 m unless varied, so
the box error is negligible).  Error: relative L2 norm of slip - exact slip
(``closed_form.slip_profile``, infinite plane) over the output points; "inner"
is the mean relative error of the slip over the inner half of the crack
(|s - a| <= a/2), which shows a uniform under-prediction.

- ``candidates``: one variable at a time against the base case at one h.
- ``mesh``: far-field grading (fine, growth) x h, default tip radius and a
  fixed one, with the shipped element or (``--element q4``) the plain Q4 for
  the intact cells (monkeypatched here; the library has no such option).
- ``box``: ogs_compare's own 20 m box (``--half 10``), whose finite size
  biases the slip against the infinite-plane closed form.
- ``exact``: the inclined crack of ``xfemslip verify`` (exact Westergaard
  displacements on a 2 m box, uniform mesh), default and fixed tip radius.

In-process solves (build + Newton, no output files).  Printed as markdown.
"""

from __future__ import annotations

import argparse
import logging
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from xfemslip import kernels
from xfemslip.case import build, loads_case
from xfemslip.fem import quadrature as Q
from xfemslip.post.fields import fracture_fields
from xfemslip.reference import peer as oc
from xfemslip.reference.closed_form import relative_l2, slip_profile
from xfemslip.simulation import build_model, newton_solver

HALF = 200.0  # [m] half-width of the box


def case_text(
    h,
    *,
    half=HALF,
    fine=0.8,
    growth=1.3,
    radius=None,
    tip=None,
    kn=5.0e12,
    patch=None,
    aligned=False,
):
    """xfemslip.reference.peer.case_table on the mesh graded(h, fine, half,
    growth), with one option changed.  aligned: the crack at 0 degrees (off the
    mesh lines by (0.3 h, 0.37 h)) under the stress that gives it the same
    normal and shear traction as the 45-degree crack: (-30, -30, 10) MPa."""
    case = oc.case_table(
        h, half=half, fine=fine, growth=growth, radius=radius, tip=tip, kn=kn
    )
    if aligned:
        cx, cy = 0.3 * h, 0.37 * h
        a = oc.A
        case["fractures"][0]["points"] = [[cx - a, cy], [cx + a, cy]]
        case["loading"]["stress"] = {"xx": -30.0e6, "yy": -30.0e6, "xy": 10.0e6}
    if patch is not None:
        case["solver"] = {"contact_patch": patch}
    return build.case_text(case)


def solve(txt, aligned=False) -> dict:
    """Build and solve in-process; slip errors against the closed form."""
    start = time.perf_counter()
    spec = loads_case(txt)
    model = build_model(spec)
    results = newton_solver(model).run(spec.loading.steps)
    ff = fracture_fields(model.ip, results[-1].contact, len(model.fractures))[0]
    stress, psi = ((-30e6, -30e6, 10e6), 0.0) if aligned else (oc.STRESS, oc.PSI)
    exact = slip_profile(ff.s, oc.A, oc.E, oc.NU, "plane_strain", stress, psi, oc.F)
    slip = (np.sign(np.sum(ff.slip * exact)) or 1.0) * ff.slip
    inner = np.abs(ff.s - oc.A) <= 0.5 * oc.A
    return {
        "dofs": int(model.problem.n_dofs),
        "err": relative_l2(ff.s, slip, exact),
        "inner": float(np.mean(slip[inner] / exact[inner] - 1.0)),
        "pn": float(np.mean(ff.normal_traction[inner])),
        "wall": time.perf_counter() - start,
    }


def q4_rectangle_stiffness(hx, hy, D):
    """The plain bilinear Q4 (2x2 Gauss) of the intact rectangles, as it was
    before the incompatible modes (for --element q4)."""
    g = np.array([-1.0, 1.0]) / math.sqrt(3.0)
    xi_a = np.array([-1.0, 1.0, 1.0, -1.0])
    eta_a = np.array([-1.0, -1.0, 1.0, 1.0])
    K = np.zeros((hx.size, 8, 8))
    for e in range(hx.size):
        for xi in g:
            for eta in g:
                dNx = 0.5 * xi_a * (1.0 + eta * eta_a) / hx[e]
                dNy = 0.5 * eta_a * (1.0 + xi * xi_a) / hy[e]
                B = np.zeros((3, 8))
                B[0, 0::2], B[1, 1::2] = dNx, dNy
                B[2, 0::2], B[2, 1::2] = dNy, dNx
                K[e] += B.T @ D @ B * 0.25 * hx[e] * hy[e]
    return K


def use_element(element: str) -> None:
    if element == "q4":  # in both backends: the case may choose either
        for backend in ("numba", "numpy"):
            kernels.backend(backend).rectangle_stiffness = q4_rectangle_stiffness


def pct(x):
    return f"{100 * x:.3f} %"


def study_candidates(h):
    """One variable at a time at mesh size h (default tip radius)."""

    def duffy(n):
        g, gw = np.polynomial.legendre.leggauss(n)
        Q._DS, Q._DV = np.meshgrid(0.5 * (g + 1), 0.5 * (g + 1), indexing="ij")
        Q._DW = np.outer(0.5 * gw, 0.5 * gw)

    def line(n):
        Q.LINE_POINTS, Q.LINE_WEIGHTS = np.polynomial.legendre.leggauss(n)

    rows = [
        ("base (fine 0.8, growth 1.3, half 200)", {}, None),
        ("far field: growth 1.1", {"growth": 1.1}, None),
        ("far field: growth 1.2", {"growth": 1.2}, None),
        ("far field: uniform core to +-2.0", {"fine": 2.0}, None),
        ("box half-width 2000 m", {"half": 2000.0}, None),
        ("box half-width 20 m", {"half": 20.0}, None),
        ("kn = kt = 1e15 Pa/m", {"kn": 1.0e15}, None),
        ("kn = kt = 5e11 Pa/m", {"kn": 5.0e11}, None),
        ("pointwise contact (contact_patch = 0)", {"patch": 0.0}, None),
        ("contact_patch = 3", {"patch": 3.0}, None),
        ("tip Duffy rule 16 x 16 (default 8 x 8)", {}, (duffy, 16, 8)),
        ("8 Gauss points per crack piece (default 4)", {}, (line, 8, 4)),
        ("branch radius 0.4 m fixed", {"radius": 0.4}, None),
        ("crack at 0 deg (rectangular cut cells)", {"aligned": True}, None),
    ]
    print(f"h = {h}\n")
    print("| variant | dofs | slip L2 error | inner mean slip error | mean p_N [MPa] |")
    print("| --- | --- | --- | --- | --- |")
    for label, kw, patch in rows:
        if patch is not None:
            patch[0](patch[1])
        r = solve(case_text(h, **kw), aligned=kw.get("aligned", False))
        if patch is not None:
            patch[0](patch[2])
        print(
            f"| {label} | {r['dofs']:,} | {pct(r['err'])} | {100 * r['inner']:+.3f} % "
            f"| {r['pn'] / 1e6:.3f} |",
            flush=True,
        )


def study_mesh(hs, element):
    grids = [(0.8, 1.3), (0.8, 1.2), (0.8, 1.1), (2.0, 1.1)]
    print(f"intact cells: {element}\n")
    head = " | ".join(f"h = {h:g}" for h in hs)
    print(f"| fine, growth | radius | {head} | order (last two) |")
    print("| --- | --- | " + " | ".join("---" for _ in hs) + " | --- |")
    for fine, growth in grids:
        for radius in (None, 0.4):
            errs, cells = [], []
            for h in hs:
                r = solve(case_text(h, fine=fine, growth=growth, radius=radius))
                errs.append(r["err"])
                cells.append(f"{pct(r['err'])} ({r['dofs'] / 1e3:.0f}k)")
            order = math.log(errs[-2] / errs[-1]) / math.log(hs[-2] / hs[-1])
            rad = "default" if radius is None else f"{radius:g} m"
            print(
                f"| {fine:g}, {growth:g} | {rad} | "
                + " | ".join(cells)
                + f" | {order:.2f} |",
                flush=True,
            )


def study_box(hs, element, half):
    """ogs_compare's own box (half = 10): error / inner mean slip error."""
    head = " | ".join(f"h = {h:g}" for h in hs)
    print(f"half = {half:g} m, intact cells: {element}\n")
    print(f"| mesh, radius | {head} |")
    print("| --- | " + " | ".join("---" for _ in hs) + " |")
    for growth, radius in ((1.3, None), (1.3, 0.4), (1.2, 0.4)):
        cells = []
        for h in hs:
            r = solve(case_text(h, half=half, growth=growth, radius=radius))
            cells.append(
                f"{pct(r['err'])} / {100 * r['inner']:+.3f} % ({r['dofs'] / 1e3:.0f}k)"
            )
        rad = "default" if radius is None else f"{radius:g} m"
        print(f"| growth {growth:g}, {rad} | " + " | ".join(cells) + " |", flush=True)


def study_exact(aohs):
    from xfemslip.verify import problems as V

    prob = next(p for p in V.PROBLEMS if p.name == "inclined-30")
    print("| radius | " + " | ".join(f"a/{n}" for n in aohs) + " |")
    print("| --- | " + " | ".join("---" for _ in aohs) + " |")
    with tempfile.TemporaryDirectory() as tmp:
        for radius in (None, 0.2):
            cells = []
            for aoh in aohs:
                n = int(round(2 * V.HALF_BOX * aoh / V.HALF_LENGTH))
                tip = None if radius is None else {"kind": "branch", "radius": radius}
                path = V.write_case(Path(tmp) / f"{radius}_{aoh}", n, prob, tip, 100.0)
                row = V.measure(V.solve_case(path), prob, aoh)
                cells.append(f"{pct(row.slip_error)} ({row.dofs / 1e3:.0f}k)")
            rad = "default" if radius is None else f"{radius:g} m"
            print(f"| {rad} | " + " | ".join(cells) + " |", flush=True)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("study", choices=("candidates", "mesh", "exact", "box"))
    p.add_argument("--h", type=float, nargs="+", default=[0.025])
    p.add_argument("--aoh", type=int, nargs="+", default=[10, 20, 40])
    p.add_argument("--element", choices=("im", "q4"), default="im")
    p.add_argument("--half", type=float, default=10.0, help="box half-width (box)")
    args = p.parse_args(argv)
    logging.basicConfig(level=logging.WARNING)
    use_element(args.element)
    if args.study == "candidates":
        for h in args.h:
            study_candidates(h)
    elif args.study == "mesh":
        study_mesh(args.h, args.element)
    elif args.study == "box":
        study_box(args.h, args.element, args.half)
    else:
        study_exact(args.aoh)
    return 0


if __name__ == "__main__":
    sys.exit(main())
