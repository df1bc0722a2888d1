#!/usr/bin/env python3
"""The displaced fault of Jansen, Singhal & Vossepoel (2019) on graded meshes:
the stuck fault's shear traction change against the inclusion closed form.

Reservoir 225 m high, throw 75 m, fault dip 70 degrees, nu = 0.15,
mu = 6.5 GPa, alpha = 0.9, dp = -25 MPa in both compartments, homogeneous
rock, in a 4 km x 3 km section (rollers on the sides, fixed bottom, constant
overburden on top; the compartments reach the rollers, so the reservoir is
laterally infinite as in the closed form).  The fault runs from 700 m below
to 700 m above the reservoir's centre and is held stuck (cohesion 1 GPa).
The mesh is the graded mesh of ``[mesh] size = h, growth = 1.2,
max_size = 100`` around the fault and the
reservoir's edges (xfemslip.geometry.grading), the reference
``xfemslip.reference.inclusion.fault_tractions``.

Printed per h: the mesh, the build and solve time, and the relative L2
error of the contact patches' shear traction change against the patch
averages of the closed form, over the patches farther than 0.05 H (H the
reservoir height) from the four corners where the reservoir's top and base
meet the fault (log singularities).

    python benchmarks/displaced_fault.py [--sizes 25,12.5,6.25]
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from xfemslip.case import build, loads_case
from xfemslip.reference.inclusion import displaced_fault, fault_tractions
from xfemslip.simulation import build_model, newton_solver

HEIGHT, THROW, DIP = 225.0, 75.0, 70.0
NU, MU, ALPHA, DP = 0.15, 6.5e9, 0.9, -25.0e6
HALF_W, HALF_H = 2000.0, 1500.0
S0 = (-40.0e6, -60.0e6)  # in-situ total stress (xx, yy), stuck by cohesion
FAULT_REACH = 700.0  # the fault's tips at y = -+700 m, in the host rock


def case_text(size: float) -> str:
    fault = displaced_fault(HEIGHT, THROW, DIP)
    cot = 1.0 / math.tan(math.radians(DIP))
    hw, fw = fault.hanging_wall[:, 1], fault.footwall[:, 1]
    hw0, hw1, fw0, fw1 = hw.min(), hw.max(), fw.min(), fw.max()

    def on(y):
        return [y * cot, y]

    # the union of the two compartments, cut at the rollers
    polygon = [
        [-HALF_W, hw0], on(hw0), on(fw0), [HALF_W, fw0],
        [HALF_W, fw1], on(fw1), on(hw1), [-HALF_W, hw1],
    ]  # fmt: skip
    return build.case_text(
        {
            "domain": {"size": [2 * HALF_W, 2 * HALF_H], "origin": [-HALF_W, -HALF_H]},
            "mesh": {"size": size, "growth": 1.2, "max_size": 100.0},
            "material": {"E": 2 * MU * (1 + NU), "nu": NU},
            "reservoir": {"polygon": polygon, "E": 2 * MU * (1 + NU), "nu": NU},
            "pore_pressure": {
                "initial": 30.0e6,
                "change": DP,
                "biot": ALPHA,
                "region": "reservoir",
            },
            "fractures": [
                {
                    "points": [on(-FAULT_REACH), on(FAULT_REACH)],
                    "friction": 0.6,
                    "cohesion": 1.0e9,
                }
            ],
            "loading": {
                "initial_stress": {"xx": S0[0], "yy": S0[1]},
                "stress": {"xx": S0[0], "yy": S0[1]},
            },
            "boundary": {
                "left": {"ux": 0.0},
                "right": {"ux": 0.0},
                "bottom": {"uy": 0.0},
                "top": "traction",
            },
            "output": {"formats": ["h5"]},
        }
    )


def shear_error(size: float) -> dict:
    spec = loads_case(case_text(size), "displaced_fault.toml")
    t0 = time.perf_counter()
    model = build_model(spec)
    solver = newton_solver(model)
    solver.run(1)
    elapsed = time.perf_counter() - t0
    res, ip, cs = solver.completed[-1].contact, model.ip, model.contact
    assert np.all(res.state == 1), "the fault must stay stuck"
    fault = displaced_fault(HEIGHT, THROW, DIP)
    t, n = fault.tangent, fault.normal
    tau0 = S0[0] * t[0] * n[0] + S0[1] * t[1] * n[1]
    ref = fault_tractions(fault, ip.xy[:, 1], DP, DP, NU, ALPHA).tau
    W = np.bincount(cs.patch, weights=ip.weight)
    ok = np.isfinite(ref)
    ref_patch = np.bincount(cs.patch, weights=np.where(ok, ip.weight * ref, 0.0)) / W
    yc = np.bincount(cs.patch, weights=ip.weight * ip.xy[:, 1]) / W
    half = 0.5 * W * abs(t[1])  # a patch's half extent in y
    dist = np.min(np.abs(yc[:, None] - fault.corners[None, :]), axis=1) - half
    keep = dist > 0.05 * HEIGHT
    err = (res.pt - tau0)[keep] - ref_patch[keep]
    return {
        "h": size,
        "mesh": f"{spec.mesh.x.size - 1} x {spec.mesh.y.size - 1}",
        "seconds": elapsed,
        "l2": math.sqrt(np.sum(err**2) / np.sum(ref_patch[keep] ** 2)),
        "patches": int(keep.sum()),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="25,12.5,6.25")
    args = parser.parse_args()
    print("| h [m] | mesh | build + solve [s] | patches | shear L2 error |")
    print("| --- | --- | --- | --- | --- |")
    for size in (float(s) for s in args.sizes.split(",")):
        r = shear_error(size)
        print(
            f"| {r['h']:g} | {r['mesh']} | {r['seconds']:.1f} | {r['patches']} | "
            f"{100 * r['l2']:.2f} % |"
        )


if __name__ == "__main__":
    main()
