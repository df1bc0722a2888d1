#!/usr/bin/env python3
"""Accuracy against run time: what every digit of the slip costs.

Three studies, printed as markdown tables (``--markdown FILE`` also writes
them to a file) plus a Pareto plot of error against wall time (``--plot``):

1. tips: the frictional inclined crack of ``xfemslip verify`` (a = 0.5 m at
   30 deg in a 2 m box, exact Westergaard displacements on the edges, f = 0.1,
   kn = kt = 100 E / h) for every tip option and h = a/4 .. a/64: slip L2
   error, K_II error (interaction integral), normal-traction oscillation,
   dofs, Newton iterations, the in-process time (build + solve, median of
   ``--runs``) and the whole-process time of ``xfemslip run`` (warm Numba
   cache, h5 output only, median of ``--runs``);
2. penalty: the same problem at h = a/20 with kn*h/E = kt*h/E from 1 to 1e6:
   slip error, K_II error, Newton iterations;
3. ogs: the OpenGeoSys peer problem (benchmarks/../shared/peers/ogs): a 20 m
   box, remote stress sxx = -20, syy = -40 MPa applied as edge tractions, a
   2 m crack at 45 deg through the centre, f = 0.1, E = 5 GPa, nu = 0.3,
   kn = kt = 5e12 Pa/m.  xfemslip solves the same box with the same
   tractions on the top, left and right edges; its bottom edge is a roller
   (uy = 0 plus the x traction), because a case must prescribe a displacement
   on an edge (OGS pins two corner points).  The mesh is a structured
   rectilinear grid, uniform (size h) over the crack's square and growing
   geometrically (ratio 1.2) to the box edges; its lines are shifted off the
   crack's centre so the mesh never follows the crack.  Both codes are
   compared with the same infinite-plane closed form.

    python benchmarks/accuracy_vs_time.py [--runs 3] [--max-aoh 64]
        [--markdown FILE] [--plot pareto.png] [--skip tips,penalty,ogs]

Run from the project root with xfemslip importable (PYTHONPATH or installed);
the subprocesses inherit the environment.
"""

from __future__ import annotations

import argparse
import math
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import h5py
import mdtable
import numpy as np
from xfem_process import timed_run

from xfemslip.case import build
from xfemslip.case.fractures import TIP_KINDS
from xfemslip.errors import XfemslipError
from xfemslip.reference import closed_form as cf
from xfemslip.verify import problems as V

AOH = (4, 8, 16, 32, 64)
PENALTIES = (1.0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6)


def whole_process(case: Path, out: Path) -> float:
    """Wall time of one ``xfemslip run`` process [s]."""
    return timed_run(case, out)[0]


def measure_case(case: Path, prob, runs: int, processes: bool):
    """Median in-process and whole-process times, and the measured row."""
    times, solved = [], None
    for _ in range(runs):
        solved = V.solve_case(case)
        times.append(solved.wall_s)
    row = V.measure(solved, prob, 0)
    row.wall_s = statistics.median(times)
    proc = math.nan
    if processes:
        proc = statistics.median(
            whole_process(case, case.parent / "out") for _ in range(runs)
        )
    return row, proc


def study_tips(work: Path, runs: int, max_aoh: int, log) -> list[dict]:
    rows = []
    prob = V.PROBLEMS[0]
    for tip in TIP_KINDS:
        for aoh in (a for a in AOH if a <= max_aoh):
            n = int(round(2 * V.HALF_BOX * aoh / V.HALF_LENGTH))
            case = V.write_case(work / f"{tip}_{aoh}", n, prob, tip, V.PENALTY)
            log(f"tips: {tip} a/{aoh}")
            row, proc = measure_case(case, prob, runs, processes=True)
            rows.append(dict(tip=tip, aoh=aoh, row=row, process_s=proc))
    return rows


def study_penalty(work: Path, runs: int, log) -> list[dict]:
    rows = []
    prob = V.PROBLEMS[0]
    for ratio in PENALTIES:
        case = V.write_case(work / f"pen_{ratio:g}", 80, prob, None, ratio)
        log(f"penalty: kn h / E = {ratio:g}")
        try:
            row, _ = measure_case(case, prob, 1, processes=False)
        except XfemslipError as exc:  # a very stiff penalty may not converge
            row = V.Row(problem="penalty", a_over_h=20, note=str(exc)[:120])
        rows.append(dict(ratio=ratio, row=row))
    return rows


# ---------------------------------------------------------------- OGS problem

OGS = dict(L=20.0, a=1.0, theta=45.0, E=5e9, nu=0.3, k=5e12, f=0.1)
GROWTH = 1.2  # size ratio of neighbouring cells outside the crack's square


def graded_lines(h: float, offset: float, core: float, half: float) -> np.ndarray:
    """Node lines: spacing h on [-core, core] (shifted by offset), then growing
    by GROWTH per cell to +/- half."""
    k0 = math.ceil((-core - offset) / h)
    k1 = math.floor((core - offset) / h)
    inner = offset + h * np.arange(k0, k1 + 1)

    def grow(start, sign):
        pts, step, x = [], h, start
        while abs(x) < half:
            step *= GROWTH
            x = x + sign * step
            pts.append(x)
        pts[-1] = sign * half
        if len(pts) > 1 and abs(pts[-1] - pts[-2]) < 0.5 * step / GROWTH:
            pts.pop(-2)  # merge a sliver last cell into its neighbour
        return pts

    right = grow(inner[-1], +1.0)
    left = grow(inner[0], -1.0)
    return np.array(sorted([*left, *inner, *right]))


def ogs_case(folder: Path, aoh: int) -> Path:
    """The OGS peer problem as an xfemslip case on a graded structured grid."""
    folder.mkdir(parents=True, exist_ok=True)
    a, half = OGS["a"], OGS["L"] / 2
    h = a / aoh
    core = a * math.cos(math.radians(OGS["theta"])) + 3 * h
    x = graded_lines(h, 0.37 * h, core, half)
    y = graded_lines(h, 0.71 * h, core, half)
    text = build.case_text(
        {
            "name": f"ogs-peer-{aoh}",
            "mesh": {"x": x, "y": y},
            "material": {"E": OGS["E"], "nu": OGS["nu"], "model": "plane_strain"},
            "fractures": [
                {
                    "center": [0.0, 0.0],
                    "length": 2 * a,
                    "angle": OGS["theta"],
                    "friction": OGS["f"],
                    "cohesion": 0.0,
                    "kn": OGS["k"],
                    "kt": OGS["k"],
                }
            ],
            "loading": {
                "stress": {"xx": -20.0e6, "yy": -40.0e6, "xy": 0.0},
                "steps": 1,
            },
            "boundary": {
                "bottom": {"uy": 0.0, "traction": True},
                "top": "traction",
                "left": "traction",
                "right": "traction",
            },
            "output": {"formats": ["h5"]},
        }
    )
    path = folder / "case.toml"
    path.write_text(text)
    return path


def ogs_slip_error(h5: Path) -> tuple[float, float, int]:
    """Relative L2 slip error (all, inner 90 %) and dofs of an xfemslip result."""
    with h5py.File(h5) as f:
        s = f["fractures/0/s"][()]
        slip = f["fractures/0/slip"][()]
        dofs = int(f.attrs["n_dofs"])
    a = OGS["a"]
    exact = cf.slip_profile(
        s,
        a,
        OGS["E"],
        OGS["nu"],
        "plane_strain",
        (-20e6, -40e6, 0.0),
        OGS["theta"],
        OGS["f"],
    )
    inner = np.abs(s - a) <= 0.9 * a
    return (
        cf.relative_l2(s, slip, exact),
        cf.relative_l2(s[inner], slip[inner], exact[inner]),
        dofs,
    )


# the OGS venv and the peer script (../shared/peers/ogs beside the repository);
# override with --ogs-python / --ogs-script
OGS_PYTHON = Path("/work/ogs-venv/bin/python")
OGS_SCRIPT = Path("/work/shared/peers/ogs/ogs_lie_slip.py")
OGS_H_FRAC = (0.01, 0.005, 0.0025)


def run_peer(work: Path, h_frac: float, k: int) -> dict:
    """One OpenGeoSys run of the peer script (Quad4); its summary.json."""
    import json

    folder = work / f"peer_{h_frac:g}_{k}"
    proc = subprocess.run(
        [
            str(OGS_PYTHON),
            str(OGS_SCRIPT),
            "--h-frac",
            repr(h_frac),
            "--quads",
            "--workdir",
            str(folder),
        ],
        capture_output=True,
        text=True,
    )
    if proc.returncode != 0:
        sys.exit(f"OGS peer failed: {proc.stderr.strip()[-400:]}")
    return json.loads((folder / "summary.json").read_text())


OGS_AOH = (8, 10, 16, 20, 32)


def study_ogs(work: Path, runs: int, log) -> tuple[list[dict], list[dict]]:
    """The OGS problem in xfemslip and, when its venv is there, in OpenGeoSys.

    The repetitions are interleaved (every xfemslip mesh, then every OGS mesh,
    ``runs`` times), so both codes see the same load on a shared machine.
    """
    peer_ok = OGS_PYTHON.exists() and OGS_SCRIPT.exists()
    if not peer_ok:
        log("OGS peer: no venv or script, skipped")
    cases = {aoh: ogs_case(work / f"ogs_{aoh}", aoh) for aoh in OGS_AOH}
    t_x = {aoh: [] for aoh in OGS_AOH}
    t_p = {h: [] for h in OGS_H_FRAC}
    sums = {}
    for rep in range(runs):
        for aoh, case in cases.items():
            log(f"ogs problem, xfemslip h = a/{aoh} (run {rep + 1}/{runs})")
            t_x[aoh].append(whole_process(case, case.parent / "out"))
        for h in OGS_H_FRAC if peer_ok else ():
            log(f"ogs problem, OGS h_frac = {h:g} (run {rep + 1}/{runs})")
            sums[h] = run_peer(work, h, rep)
            t_p[h].append(sums[h]["run"]["wall_s"])
    rows = []
    for aoh, case in cases.items():
        err, err_inner, dofs = ogs_slip_error(case.parent / "out" / "result.h5")
        rows.append(
            dict(
                aoh=aoh,
                dofs=dofs,
                error=err,
                inner=err_inner,
                process_s=statistics.median(t_x[aoh]),
            )
        )
    peer = [
        dict(
            h_frac=h,
            dofs=sums[h]["mesh"]["dofs"],
            error=sums[h]["result"]["err_L2_rel"],
            inner=sums[h]["result"]["err_L2_rel_inner90"],
            process_s=statistics.median(t_p[h]),
        )
        for h in sums
    ]
    return rows, peer


# ---------------------------------------------------------------- output


def md_tips(rows) -> str:
    out = [
        "| tip | h | dofs | slip L2 error | K_II error | \\|K_I\\|/K_II | "
        "p_N oscillation | Newton | in-process [s] | `xfemslip run` [s] |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in rows:
        w = r["row"]
        out.append(
            f"| {r['tip']} | a/{r['aoh']} | {w.dofs:,} | {100 * w.slip_error:.3g} % "
            f"| {100 * w.kii_error:.3g} % | {100 * w.ki_ratio:.3g} % "
            f"| {100 * w.oscillation:.3g} % | {w.newton} | {w.wall_s:.2f} "
            f"| {r['process_s']:.2f} |"
        )
    return "\n".join(out)


def md_penalty(rows) -> str:
    out = [
        "| kn h / E | slip L2 error | K_II error | p_N oscillation | Newton | note |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for r in rows:
        w = r["row"]
        out.append(
            f"| {r['ratio']:g} | {100 * w.slip_error:.3g} % | "
            f"{100 * w.kii_error:.3g} % | {100 * w.oscillation:.3g} % | "
            f"{w.newton} | {w.note} |"
        )
    return "\n".join(out)


def md_ogs(rows) -> str:
    out = [
        "| h on the crack | dofs | slip L2 error | inner 90 % | `xfemslip run` [s] |",
        "| --- | --- | --- | --- | --- |",
    ]
    out += [
        f"| a/{r['aoh']} = {OGS['a'] / r['aoh']:.3g} m | {r['dofs']:,} "
        f"| {100 * r['error']:.3g} % | {100 * r['inner']:.3g} % "
        f"| {r['process_s']:.2f} |"
        for r in rows
    ]
    return "\n".join(out)


def md_peer(rows) -> str:
    out = [
        "| OGS h_frac | dofs | slip L2 error | inner 90 % | `ogs` process [s] |",
        "| --- | --- | --- | --- | --- |",
    ]
    out += [
        f"| {r['h_frac']:g} m | {r['dofs']:,} | {100 * r['error']:.3g} % "
        f"| {100 * r['inner']:.3g} % | {r['process_s']:.2f} |"
        for r in rows
    ]
    return "\n".join(out)


def pareto_plot(tips, ogs, path: Path, ogs_peer=None) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker

    fig, ax = plt.subplots(figsize=(7, 5))
    for k, tip in enumerate(dict.fromkeys(r["tip"] for r in tips)):
        seq = [r for r in tips if r["tip"] == tip]
        ax.loglog(
            [r["process_s"] for r in seq],
            [r["row"].slip_error for r in seq],
            "o-",
            color=f"C{k}",
            label=f"xfemslip tip={tip} (exact-BC box)",
        )
        for r in seq:
            ax.annotate(
                f"a/{r['aoh']}",
                (r["process_s"], r["row"].slip_error),
                fontsize=7,
                xytext=(3, 3),
                textcoords="offset points",
            )
    if ogs:
        ax.loglog(
            [r["process_s"] for r in ogs],
            [r["error"] for r in ogs],
            "s-",
            color="C3",
            label="xfemslip, OGS problem (20 m box)",
        )
    if ogs_peer:
        ax.loglog(
            [p["process_s"] for p in ogs_peer],
            [p["error"] for p in ogs_peer],
            "^--",
            color="k",
            label="OpenGeoSys LIE (Quad4), same problem",
        )
    ax.axhline(0.01, color="grey", lw=0.8)
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.set_xlabel("whole-process wall time [s] (warm cache, median)")
    ax.set_ylabel("relative L2 slip error")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("accuracy against run time")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def markdown(parts: list[str], runs: int, loads) -> str:
    """docs/performance/accuracy_vs_time.md: the studies' tables, then how
    they were measured."""
    return (
        "\n\n".join(parts)
        + "\n"
        + mdtable.note(
            f"Times: medians of {runs} runs (in-process: build + solve; `xfemslip "
            "run`: the whole process, warm caches, h5 output only)",
            loads,
        )
    )


def main() -> int:
    global OGS_PYTHON, OGS_SCRIPT
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--max-aoh", type=int, default=64)
    mdtable.add_option(ap, "docs/performance/accuracy_vs_time.md")
    ap.add_argument("--plot", type=Path)
    ap.add_argument("--skip", default="", help="comma list of tips,penalty,ogs")
    ap.add_argument("--ogs-python", type=Path, default=OGS_PYTHON)
    ap.add_argument("--ogs-script", type=Path, default=OGS_SCRIPT)
    args = ap.parse_args()
    skip = set(filter(None, args.skip.split(",")))
    OGS_PYTHON, OGS_SCRIPT = args.ogs_python, args.ogs_script
    start = time.perf_counter()

    def log(msg):
        print(
            f"[{time.perf_counter() - start:7.1f} s] {msg}", file=sys.stderr, flush=True
        )

    parts, loads = [], [mdtable.load()]

    def emit(table):
        parts.append(table)
        loads.append(mdtable.load())
        print(table + "\n", flush=True)
        if args.markdown:  # after each study, so that a stopped run keeps them
            args.markdown.parent.mkdir(parents=True, exist_ok=True)
            args.markdown.write_text(markdown(parts, args.runs, loads))

    with tempfile.TemporaryDirectory(prefix="xfemslip-bench-") as tmp:
        work = Path(tmp)
        V.solve_case(V.write_case(work / "warm", 8, V.PROBLEMS[0], None, 100.0))
        whole_process(work / "warm" / "case.toml", work / "warm" / "out")
        tips = [] if "tips" in skip else study_tips(work, args.runs, args.max_aoh, log)
        if tips:
            emit(md_tips(tips))
        if "penalty" not in skip:
            emit(md_penalty(study_penalty(work, args.runs, log)))
        ogs, peer = ([], []) if "ogs" in skip else study_ogs(work, args.runs, log)
        if ogs:
            emit(md_ogs(ogs))
        if peer:
            emit(md_peer(peer))
    if args.plot and (tips or ogs):
        pareto_plot(tips, ogs, args.plot, peer)
    return 0


if __name__ == "__main__":
    sys.exit(main())
