"""Contact patches, branch radius and penalty on the inclined frictional crack.

Usage (from the project root)::

    python benchmarks/contact_patches.py [--quick]

The problem is that of ``check_inclined_crack.py`` and ``xfemslip verify``:
a crack of half-length a = 0.5 m through (0.0123, -0.0077) in a 2 m box,
remote stress (-20, -40, 0) MPa, E = 5 GPa, nu = 0.3, plane strain, with the
exact Westergaard displacements of the cracked infinite plane on every edge
(``xfemslip.closed_form``).  Printed as markdown tables:

1. contact patch length (``[solver] contact_patch``) x mesh: relative L2 slip
   error and normal-traction oscillation max |p_N - mean| / |mean| over the
   inner 90 % of the crack (slipping crack, psi = 30, f = 0.1);
2. penalty kn h / E = kt h / E from 1 to 1e6: slip error and Newton iterations
   of the slipping crack, max |slip| of a stuck one (psi = 45, f = 0.6) as a
   share of the slip it would have without friction, Newton iterations.

Wall times are not reported here (see accuracy_vs_time.py and scaling.py).
"""

from __future__ import annotations

import argparse
import logging
import math
import tempfile
from pathlib import Path

import h5py
import numpy as np

from xfemslip import closed_form as cf
from xfemslip.case import load_case
from xfemslip.simulation import run_case

A, HALF, CENTER = 0.5, 1.0, (0.0123, -0.0077)
STRESS, E, NU = (-20e6, -40e6, 0.0), 5e9, 0.3


def run(folder: Path, n, psi=30.0, friction=0.1, penalty=100.0, patch=None):
    """Solve; return (relative L2 slip error or max|slip|, oscillation, iterations)."""
    folder.mkdir(parents=True, exist_ok=True)
    field = dict(
        center=CENTER,
        a=A,
        E=E,
        nu=NU,
        plane="plane_strain",
        stress=STRESS,
        psi_deg=psi,
        friction=friction,
    )
    k = np.linspace(-HALF, HALF, 8 * n + 1)
    edges = {
        "bottom": np.column_stack([k, np.full_like(k, -HALF)]),
        "top": np.column_stack([k, np.full_like(k, HALF)]),
        "left": np.column_stack([np.full_like(k, -HALF), k]),
        "right": np.column_stack([np.full_like(k, HALF), k]),
    }
    for name, pts in edges.items():
        vals = cf.displacement(pts, **field)
        rows = "".join(
            f"{x:.17g},{y:.17g},{u:.17g},{v:.17g}\n"
            for (x, y), (u, v) in zip(pts, vals, strict=True)
        )
        (folder / f"{name}.csv").write_text("x,y,ux,uy\n" + rows)
    t = (math.cos(math.radians(psi)), math.sin(math.radians(psi)))
    p0 = [CENTER[0] - A * t[0], CENTER[1] - A * t[1]]
    p1 = [CENTER[0] + A * t[0], CENTER[1] + A * t[1]]
    kn = penalty * E / (2 * HALF / n)
    solver = "" if patch is None else f"contact_patch = {patch!r}\n"
    text = f"""
[domain]
size = [2.0, 2.0]
origin = [-1.0, -1.0]
[mesh]
elements = [{n}, {n}]
[material]
E = {E!r}
nu = {NU!r}
model = "plane_strain"
[[fractures]]
points = [{p0!r}, {p1!r}]
friction = {friction!r}
kn = {kn!r}
kt = {kn!r}
[boundary]
bottom = {{ file = "bottom.csv" }}
top = {{ file = "top.csv" }}
left = {{ file = "left.csv" }}
right = {{ file = "right.csv" }}
[solver]
{solver}[output]
formats = ["h5"]
"""
    case = folder / "case.toml"
    case.write_text(text)
    summary = run_case(load_case(case), folder / "out")
    with h5py.File(folder / "out" / "result.h5") as h:
        s, slip = h["fractures/0/s"][()], h["fractures/0/slip"][()]
        pn = h["fractures/0/normal_traction"][()]
        its = int(h.attrs["newton_iterations"])
    exact = cf.slip_profile(s, A, E, NU, "plane_strain", STRESS, psi, friction)
    inner = np.abs(s - A) < 0.9 * A
    osc = float(np.max(np.abs(pn[inner] - pn[inner].mean())) / abs(pn[inner].mean()))
    if np.any(exact):
        err = cf.relative_l2(s, slip, exact)
    else:
        _, tau = cf.crack_tractions(STRESS, psi)
        err = float(np.max(np.abs(slip)) / (4 * (1 - NU**2) / E * abs(tau) * A))
    del summary
    return err, osc, its


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="two meshes only")
    args = ap.parse_args()
    logging.disable(logging.WARNING)
    ns = (40, 80) if args.quick else (40, 80, 160)
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        print(
            "| contact_patch | "
            + " | ".join(f"a/{n // 4}: L2 slip error, p_N oscillation" for n in ns)
            + " |"
        )
        print("| --- |" + " --- |" * len(ns))
        for patch in (0.0, 0.5, 1.0, 1.5, 2.0):
            cells = [run(root / f"p{patch}-{n}", n, patch=patch) for n in ns]
            print(
                f"| {patch:g} | "
                + " | ".join(f"{100 * e:.2f} %, {100 * o:.2f} %" for e, o, _ in cells)
                + " |"
            )
        print()
        print(
            "| kn h / E | slipping: L2 slip error, iterations "
            "| stuck: max abs slip / frictionless peak, iterations |"
        )
        print("| --- | --- | --- |")
        for pen in (1.0, 10.0, 100.0, 1e3, 1e4, 1e5, 1e6):
            e, _, it = run(root / f"k{pen}", 80, penalty=pen)
            e2, _, it2 = run(root / f"ks{pen}", 80, psi=45.0, friction=0.6, penalty=pen)
            print(f"| {pen:g} | {100 * e:.3f} %, {it} | {e2:.1e}, {it2} |")


if __name__ == "__main__":
    main()
