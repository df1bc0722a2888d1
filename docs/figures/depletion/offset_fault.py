"""Figure offset_fault.png of the README (section Depletion): the vertical
fault through an offset reservoir, FE against the closed forms (J1), (J2) of
xfemslip.closed_form_depletion, h = 5 m (the verification tests' set-up: the
fault ON the pressure boundary x = 0, mid-cell).

    PYTHONPATH=. python docs/figures/depletion/offset_fault.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT / "tests" / "verification"))
from depletion_cases import offset_fault_case  # noqa: E402

from xfemslip.case import loads_case  # noqa: E402
from xfemslip.closed_form_depletion import (  # noqa: E402
    offset_fault_shear,
    offset_fault_slip,
)
from xfemslip.simulation import build_model, newton_solver, step_fields  # noqa: E402


def solve(**kw):
    text, corners, _ = offset_fault_case(h=5.0, **kw)
    model = build_model(loads_case(text, "fault.toml"))
    solver = newton_solver(model)
    solver.run(1)
    return step_fields(model, solver.completed[-1]).fractures[0], corners


def main():
    stuck, (a, b, c, d) = solve(friction=0.6, cohesion=1.0e9)
    free, _ = solve()
    y = np.linspace(-150.0, 180.0, 2001)
    mu = 10.0e9 / 2.5
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(9.0, 4.0), constrained_layout=True)
    ax1.plot(
        -offset_fault_shear(y, a, b, c, d, -10e6, 0.25) / 1e6,
        y,
        "k-",
        lw=1,
        label="closed form (J1)",
    )
    ax1.plot(
        stuck.shear_traction / 1e6,
        stuck.points[:, 1],
        ".",
        ms=3,
        label="xfemslip, stuck (patch tractions)",
    )
    ax1.set_xlim(-4, 4)
    ax1.set_xlabel("shear traction $p_T = -\\sigma_{xy}$ [MPa]")
    ax1.set_ylabel("y [m]")
    ax2.plot(
        offset_fault_slip(y, a, b, c, d, -10e6, 0.25, mu) * 1e3,
        y,
        "k-",
        lw=1,
        label="closed form (J2)",
    )
    ax2.plot(
        free.slip * 1e3, free.points[:, 1], ".", ms=3, label="xfemslip, frictionless"
    )
    ax2.set_xlabel("slip $u_y^{left} - u_y^{right}$ [mm]")
    for ax in (ax1, ax2):
        for v in (a, b, c, d):
            ax.axhline(v, color="0.8", lw=0.6)
        ax.set_ylim(-150, 180)
        ax.legend(fontsize=8, loc="lower right")
    fig.suptitle(
        "vertical fault through an offset reservoir (thickness 100 m, throw "
        "30 m), dp = -10 MPa, E = 10 GPa, nu = 0.25, h = 5 m,\nfault on the "
        "pressure boundary x = 0 (mid-cell)",
        fontsize=9,
    )
    out = Path(__file__).with_name("offset_fault.png")
    fig.savefig(out, dpi=100)
    print(out)


if __name__ == "__main__":
    main()
