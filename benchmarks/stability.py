"""The numerical stress matrix: every case, both tangents.

Writes a table (case, converged, Newton iterations, stick/slip switches,
load-step cuts / ping-pong freezes, max |slip|, result vs reference) to
docs/performance/stability.md (which docs/performance.md names) and prints
it; --no-write only prints.  The case builders and
references are tests/support/matrix.py.

Usage (from the project root):  python benchmarks/stability.py [--quick]
--quick skips the 1-degree angle sweep and the 1000-step runs.
"""

from __future__ import annotations

import argparse
import math
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # tests.support

from tests.support.matrix import (  # noqa: E402
    H32_N,
    RESERVOIR,
    SHEAR_STRESS,
    SLIP,
    STICK,
    Crack,
    block_text,
    block_threshold,
    reservoir_text,
    run_crack,
    solve,
    window_reference,
)
from xfemslip.case import loads_case  # noqa: E402
from xfemslip.errors import XfemslipError  # noqa: E402
from xfemslip.simulation import build_model  # noqa: E402

TANGENTS = ("consistent", "secant")
BEGIN, END = "<!-- stability:begin -->", "<!-- stability:end -->"
rows: list[str] = []
failures: list[str] = []


def fmt(x, spec=".3g") -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    return format(x, spec)


def row(group, case, tangent, out, ref, versus) -> None:
    conv = "yes" if out.converged else "**no**"
    extra = f"{out.cuts}/{out.freezes}"
    rows.append(
        f"| {group} | {case} | {tangent} | {conv} | {out.iterations} | {out.switches} "
        f"| {extra} | {fmt(out.max_slip)} | {ref} | {versus} |"
    )
    if not out.converged:
        why = out.error.partition(" did not converge: ")[2][:500]
        failures.append(f"- {group}, {case}, {tangent}: {why}")
    print(rows[-1], f"({out.seconds:.2f} s)", flush=True)


def pct(err) -> str:
    return "-" if err is None or math.isnan(err) else f"{100 * err:.2f} %"


def crack_rows(group, name, crack) -> None:
    for tangent in TANGENTS:
        out, err, ref = run_crack(crack, tangent)
        if ref.startswith("sticks"):
            versus = f"SLIP share {100 * err:.0f} %" if out.converged else "-"
        else:
            versus = pct(err)
        row(group, name, tangent, out, ref, versus)


def penalty() -> None:
    for kt_kn in (1.0, 1e-3):
        for p in (1e-1, 1.0, 1e2, 1e4, 1e6, 1e8):
            crack_rows(
                "penalty",
                f"kn h/E = {p:g}, kt/kn = {kt_kn:g}",
                Crack(penalty=p, kt_kn=kt_kn),
            )


def friction() -> None:
    for f in (0.0, 0.1, 0.3, 0.6, 1.0, 1.5):
        crack_rows("friction", f"f = {f:g} (30 deg)", Crack(friction=f))
    base = Crack(psi=50.0, friction=0.3)
    cstar = base.no_slip_cohesion()
    for frac in (0.0, 0.5, 0.9, 0.99, 1.01, 1.1, 1.2, 2.0):
        crack = Crack(psi=50.0, friction=0.3, cohesion=frac * cstar)
        crack_rows("cohesion", f"c = {frac:g} c* (c* = {cstar / 1e6:.2f} MPa)", crack)


def geometry() -> None:
    h = 2.0 / H32_N
    cases = {
        "through nodes (45 deg)": Crack(psi=45.0, center=(0.0, 0.0)),
        "tips on nodes (45 deg)": Crack(
            psi=45.0, center=(0.0, 0.0), a=math.sqrt(2) * 6 * h
        ),
        "along element edges": Crack(psi=0.0, center=(0.0, 0.0), stress=SHEAR_STRESS),
        "tips on edges": Crack(psi=0.0, center=(0.0, 0.5 * h), stress=SHEAR_STRESS),
        "1e-9 h from an edge": Crack(
            psi=0.0, center=(0.0, 1e-9 * h), stress=SHEAR_STRESS
        ),
        "tip 1e-9 h from an edge": Crack(
            psi=0.0, center=(1e-9 * h, 0.5 * h), stress=SHEAR_STRESS
        ),
        "tip one element from the boundary": Crack(
            psi=0.0, center=(0.0, 0.5 * h), a=1.0 - 1.5 * h, stress=SHEAR_STRESS
        ),
    }
    for name, crack in cases.items():
        crack_rows("geometry", name, crack)
    hh = 1.0 / 20
    d = hh / math.sqrt(2)
    two = reservoir_text(
        n=20,
        points=[[0.29 - d, 0.29 + d], [0.71 - d, 0.71 + d]],
        extra_fractures=[[[0.29 + d, 0.29 - d], [0.71 + d, 0.71 - d]]],
    )
    for tangent in TANGENTS:
        out = solve(two, RESERVOIR, tangent)
        row(
            "geometry",
            "two parallel fractures one element apart (reservoir 20x20)",
            tangent,
            out,
            "none (no closed form)",
            "both slip" if out.converged else "-",
        )
    cross = reservoir_text(n=20, extra_fractures=[[[0.29, 0.71], [0.71, 0.29]]])
    try:
        build_model(loads_case(cross, RESERVOIR))
        msg = "NOT refused"
    except XfemslipError as err:
        msg = "refused (exit 2): " + str(err).split(": ", 1)[1][:90]
    rows.append(f"| geometry | two crossing fractures | - | {msg} | | | | | | |")
    print(rows[-1])


def block() -> None:
    for f, c in ((0.5, 0.0), (0.5, 2.0e6), (1.5, 0.0), (0.0, 0.0)):
        thr = block_threshold(10.0e6, f, c)
        for frac in (0.5, 0.9, 0.95, 0.99, 1.01, 1.1):
            tau = frac * thr if thr > 0 else frac * 1.0e6
            for tangent in TANGENTS:
                out = solve(
                    block_text(shear=tau, friction=f, cohesion=c), RESERVOIR, tangent
                )
                if out.converged:
                    res = out.steps[-1].contact
                    w = out.model.contact.weight
                    versus = (
                        f"sum p_T w / (tau L) = {np.sum(w * res.pt) / (tau * 2.0):.7f}"
                    )
                else:
                    versus = "no equilibrium expected" if frac > 1 or thr == 0 else "-"
                label = (
                    f"tau = {frac:g} tau*" if thr > 0 else f"tau = {tau / 1e6:g} MPa"
                )
                row(
                    "block",
                    f"f = {f:g}, c = {c / 1e6:g} MPa, {label}",
                    tangent,
                    out,
                    "rigid sliding at tau* = f p + c",
                    versus,
                )


def material() -> None:
    for nu in (0.3, 0.45, 0.49, 0.499):
        crack_rows("material", f"nu = {nu:g} (plane strain)", Crack(nu=nu))
    for E in (1e6, 1e9, 1e12):
        crack_rows("material", f"E = {E:g} Pa (kn = 100 E/h)", Crack(E=E))


def load_steps(quick: bool) -> None:
    counts = (1, 10, 100) if quick else (1, 10, 100, 1000)
    for tangent in TANGENTS:
        ref = None
        for n in counts:
            out = solve(reservoir_text(n=16, steps=n), RESERVOIR, tangent)
            u = out.steps[-1].u
            ref = u if ref is None else ref
            diff = np.max(np.abs(u - ref)) / np.max(np.abs(ref))
            row(
                "load steps",
                f"{n} proportional step(s), reservoir 16x16",
                tangent,
                out,
                "1 step",
                f"max rel. diff {diff:.1e}",
            )
    for tangent in TANGENTS:
        text = reservoir_text(n=16, initial_stress=(-30e6, -30e6, 0.0), friction=0.3)
        out = solve(text, RESERVOIR, tangent, factors=[1, 0, 1, 0, 1, 0])
        if out.converged:
            s = out.steps
            resid = np.max(np.abs(s[1].contact.slip_plastic))
            drift = max(
                np.max(np.abs(s[0].u - s[4].u)), np.max(np.abs(s[1].u - s[5].u))
            ) / np.max(np.abs(s[0].u))
            stick = all(np.all(r.contact.state == STICK) for r in s[1::2])
            versus = (
                f"residual slip {resid * 1e3:.3f} mm, unloaded all stick: {stick}, "
                f"drift {drift:.1e}"
            )
        else:
            versus = "-"
        row(
            "hysteresis",
            "load/unload x3, in-situ 30 MPa, f = 0.3",
            tangent,
            out,
            "elastic unloading",
            versus,
        )


def sweep() -> None:
    for f in (0.1, 0.3):
        for tangent in TANGENTS:
            start = time.perf_counter()
            conv = its = sw = cuts = frz = 0
            wrong, failed, itmax = [], [], 0
            for angle in range(0, 181):
                out = solve(
                    reservoir_text(n=20, angle=angle, friction=f), RESERVOIR, tangent
                )
                if not out.converged:
                    failed.append(angle)
                    failures.append(
                        f"- sweep f = {f}, {angle} deg, {tangent}: {out.error[:200]}"
                    )
                    continue
                conv += 1
                its += out.iterations
                itmax = max(itmax, out.iterations)
                sw += out.switches
                cuts += out.cuts
                frz += out.freezes
                inside, dist = window_reference(angle, f)
                share = np.mean(out.steps[-1].contact.state == SLIP)
                if dist > 3.0 and (
                    (inside and share < 0.8) or (not inside and share > 0)
                ):
                    wrong.append(angle)
            rows.append(
                f"| angle sweep | f = {f:g}: 0..180 deg, 1-deg steps, reservoir 20x20 "
                f"| {tangent} | {conv}/181 | {its} (max {itmax}) | {sw} | {cuts}/{frz} "
                f"| - | slip window (3 deg margin) | misclassified: {wrong or 'none'} |"
            )
            print(rows[-1], f"({time.perf_counter() - start:.0f} s)", flush=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--no-write", action="store_true")
    args = ap.parse_args()
    start = time.perf_counter()
    penalty()
    friction()
    geometry()
    block()
    material()
    load_steps(args.quick)
    if not args.quick:
        sweep()
    wall = time.perf_counter() - start
    header = [
        "| group | case | tangent | converged | Newton iterations | switches "
        "| cuts/freezes | max abs(slip) [m] | reference | result vs reference |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    text = "\n".join(
        [
            BEGIN,
            "Command: `python benchmarks/stability.py"
            f"{' --quick' if args.quick else ''}`, {wall / 60:.1f} min on "
            f"{platform.machine()}, Python {platform.python_version()} "
            "(shared machine, so the times are not benchmarks).",
            "",
            *header,
            *rows,
            "",
            "Combinations that do not converge, and why "
            "(the ConvergenceError message):",
            "",
            *(failures or ["- none"]),
            END,
        ]
    )
    print(text)
    if not args.no_write:
        path = ROOT / "docs" / "performance" / "stability.md"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
