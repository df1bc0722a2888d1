"""Contact patches, branch radius and penalty on the inclined frictional crack.

Usage (from the project root)::

    python benchmarks/contact_patches.py [--quick]
        [--markdown docs/performance/contact_patches.md]

The problem is that of ``check_inclined_crack.py`` and ``xfemslip verify``:
a crack of half-length a = 0.5 m through (0.0123, -0.0077) in a 2 m box,
remote stress (-20, -40, 0) MPa, E = 5 GPa, nu = 0.3, plane strain, with the
exact Westergaard displacements of the cracked infinite plane on every edge
(``xfemslip.reference.closed_form``).  Printed as markdown tables:

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
import tempfile
from pathlib import Path

import mdtable
import numpy as np

from xfemslip.reference import closed_form as cf
from xfemslip.verify import problems as V


def run(folder: Path, n, psi=30.0, friction=0.1, penalty=100.0, patch=None):
    """Solve; return (relative L2 slip error or max|slip|, oscillation, iterations).

    The case is ``xfemslip verify``'s (``verify.write_case``), with
    ``[solver] contact_patch`` added when ``patch`` is given.
    """
    prob = V.Problem(f"psi{psi:g}-f{friction:g}", psi, friction=friction)
    solver = None if patch is None else {"contact_patch": patch}
    path = V.write_case(folder, n, prob, None, penalty, solver=solver)
    solved = V.solve_case(path)
    fa = V.fracture_arrays(solved)
    s, slip = fa["s"], fa["slip"]
    exact = cf.slip_profile(s, **V.profile_kwargs(prob))
    if np.any(exact):
        err = cf.relative_l2(s, slip, exact)
    else:
        _, tau = cf.crack_tractions(V.STRESS, psi)
        err = float(
            np.max(np.abs(slip)) / (4 * (1 - V.NU**2) / V.E * abs(tau) * V.HALF_LENGTH)
        )
    return err, V.oscillation(s, fa["pn"]), solved.iterations


PATCHES = (0.0, 0.5, 1.0, 1.5, 2.0)
PENALTIES = (1.0, 10.0, 100.0, 1e3, 1e4, 1e5, 1e6)


def markdown(ns, patches: dict, penalties: dict) -> str:
    """The tables of docs/performance/contact_patches.md.  patches: {patch:
    [(slip error, oscillation, iterations) per n]}; penalties: {kn h / E:
    ((slipping error, its), (stuck slip ratio, its))}."""
    first = mdtable.table(
        ["contact_patch"] + [f"a/{n // 4}: L2 slip error, p_N oscillation" for n in ns],
        [
            [f"{patch:g}"] + [f"{100 * e:.2f} %, {100 * o:.2f} %" for e, o, _ in cells]
            for patch, cells in patches.items()
        ],
    )
    second = mdtable.table(
        [
            "kn h / E",
            "slipping: L2 slip error, iterations",
            "stuck: max abs slip / frictionless peak, iterations",
        ],
        [
            [f"{pen:g}", f"{100 * e:.3f} %, {it}", f"{e2:.1e}, {it2}"]
            for pen, ((e, it), (e2, it2)) in penalties.items()
        ],
    )
    return (
        first
        + "\n"
        + second
        + mdtable.note(
            "The inclined crack of `xfemslip verify` (psi = 30 deg, f = 0.1, "
            "kn = kt = 100 E/h unless varied; stuck: psi = 45 deg, f = 0.6) at "
            f"{', '.join(f'a/{n // 4}' for n in ns)}; the penalty at a/{80 // 4}; "
            "errors, not times: repeatable on any machine"
        )
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="two meshes only")
    mdtable.add_option(ap, "docs/performance/contact_patches.md")
    args = ap.parse_args()
    logging.disable(logging.WARNING)
    ns = (40, 80) if args.quick else (40, 80, 160)
    patches, penalties = {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        for patch in PATCHES:
            patches[patch] = [run(root / f"p{patch}-{n}", n, patch=patch) for n in ns]
            print(f"contact_patch {patch:g}: {patches[patch]}", flush=True)
        for pen in PENALTIES:
            e, _, it = run(root / f"k{pen}", 80, penalty=pen)
            e2, _, it2 = run(root / f"ks{pen}", 80, psi=45.0, friction=0.6, penalty=pen)
            penalties[pen] = ((e, it), (e2, it2))
    mdtable.write(args.markdown, markdown(ns, patches, penalties))


if __name__ == "__main__":
    main()
