"""``xfemslip verify``: verification problems against closed forms, with a table.

Every problem is a straight crack of half-length a = 0.5 m in a 2 m x 2 m box
whose four edges carry the exact displacements of the cracked infinite plane
(``closed_form.displacement``, written to per-edge CSV files, as in the
acceptance check ``check_inclined_crack.py``).  The box therefore behaves as a
window cut out of the infinite plane, and the closed form is exact for it:

- ``inclined``: frictional crack (several angles, friction, cohesion, plane
  strain and plane stress) -- slip profile and K_II = dtau sqrt(pi a);
- ``frictionless``: f = 0, c = 0, pure mode II;
- ``stick``: an orientation outside the slip window -- no point may slip and
  K_II = 0 (errors relative to the frictionless slip and K_II);
- ``window``: the slip window swept over angle -- each orientation is
  classified slipping when most of its points slip, and misclassified
  orientations are reported with their distance to the window's edges.

Measured per run: dofs, relative L2 slip error, K_II error (interaction
integral, worst tip), K_I (should be 0), normal-traction oscillation
max |p_N - mean| / |mean| over the inner 90 % of the crack, the observed
order of the slip error between consecutive meshes, and the wall time
(build + solve, in-process).  Targets: slip L2 <= 1 % at h = a/20,
observed order >= 1, K_II within 2 % at h = a/20, no misclassified
orientation farther than 2 degrees from the window's edges.

The module is one pipeline, read top to bottom: case text, window edges
written from the closed form, solve, measure, observed orders, the slip
window sweep, the targets.  Each stage is short and used only by the next;
it stays whole (about 520 lines) because split in two a reader would follow
one problem across both halves.
"""

from __future__ import annotations

import contextlib
import logging
import math
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from xfemslip.case import build, load_case
from xfemslip.contact.interface import ContactResult
from xfemslip.post.fields import fracture_fields
from xfemslip.post.jintegral import stress_intensity_factors
from xfemslip.reference import closed_form as cf
from xfemslip.simulation import Model, build_model, newton_solver

logger = logging.getLogger(__name__)

HALF_BOX = 1.0  # [m] the box is [-1, 1]^2
EDGE_NAMES = ("bottom", "top", "left", "right")  # boundary data: <edge>.csv
HALF_LENGTH = 0.5  # a [m]
CENTER = (0.0123, -0.0077)  # off the mesh lines, as in check_inclined_crack.py
STRESS = (-20.0e6, -40.0e6, 0.0)  # remote stress [Pa], the paper's state
E, NU = 5.0e9, 0.3
PENALTY = 100.0  # kn = kt = PENALTY * E / h, as in check_inclined_crack.py

# Accuracy targets
SLIP_TARGET = 0.01  # relative L2 slip error at h = a/20
KII_TARGET = 0.02  # relative K_II error at h = a/20
ORDER_TARGET = 1.0  # observed order of the slip error
WINDOW_TARGET = 2.0  # [deg] allowed misclassification distance to the edges
TARGET_H = 20  # a / h of the target mesh

QUICK_MESHES = (10, 20)  # a / h
FULL_MESHES = (5, 10, 20, 40)


@dataclass(frozen=True)
class Problem:
    """One verification problem (a straight crack with exact boundary data)."""

    name: str
    psi: float  # crack angle from +x [deg]
    friction: float = 0.1
    cohesion: float = 0.0  # [Pa]
    plane: str = "plane_strain"
    kind: str = "slip"  # "slip" | "stick"

    def driving_shear(self) -> float:
        return cf.driving_shear(STRESS, self.psi, self.friction, self.cohesion)


@dataclass
class Row:
    """One line of the table."""

    problem: str
    a_over_h: int
    dofs: int = 0
    slip_error: float = math.nan
    kii_error: float = math.nan
    ki_ratio: float = math.nan  # max |K_I| / |K_II exact|
    oscillation: float = math.nan
    order: float = math.nan
    wall_s: float = math.nan
    newton: int = 0
    note: str = ""
    extra: dict = field(default_factory=dict)


PROBLEMS = (
    Problem("inclined-30", 30.0),
    Problem("inclined-60", 60.0),
    Problem("cohesion-30", 30.0, friction=0.1, cohesion=2.0e6),
    Problem("friction0.2-30", 30.0, friction=0.2),
    Problem("stress-30", 30.0, plane="plane_stress"),
    Problem("frictionless-30", 30.0, friction=0.0),
    Problem("stick-80", 80.0, friction=0.3, kind="stick"),
)
QUICK_PROBLEMS = ("inclined-30", "stress-30", "frictionless-30", "stick-80")


def case_text(
    n: int,
    prob: Problem,
    tip: str | dict | None,
    penalty: float | None,
    *,
    steps: int = 1,
    solver: dict | None = None,
) -> str:
    """TOML of the problem on an n x n mesh of the box (edges from CSV files).

    tip : the tip kind or a tip table (``{"kind": "branch", "radius": r}``),
    None for the default.  penalty : kn h / E (= kt h / E), or None to leave
    kn and kt out (the case format's default).  steps : load steps; solver :
    keys of a [solver] table (None = none).
    """
    a = HALF_LENGTH
    p = math.radians(prob.psi)
    t = (math.cos(p), math.sin(p))
    p0 = [CENTER[0] - a * t[0], CENTER[1] - a * t[1]]
    p1 = [CENTER[0] + a * t[0], CENTER[1] + a * t[1]]
    kn = None if penalty is None else penalty * E / (2 * HALF_BOX / n)
    return build.case_text(
        {
            "name": f"verify-{prob.name}-{n}",
            "domain": {
                "size": [2 * HALF_BOX, 2 * HALF_BOX],
                "origin": [-HALF_BOX, -HALF_BOX],
            },
            "mesh": {"elements": [n, n]},
            "material": {"E": E, "nu": NU, "model": prob.plane},
            "fractures": [
                {
                    "points": [p0, p1],
                    "friction": prob.friction,
                    "cohesion": prob.cohesion,
                    "kn": kn,
                    "kt": kn,
                    "tip": tip or None,
                }
            ],
            "loading": {"steps": steps},
            "boundary": {e: {"file": f"{e}.csv"} for e in EDGE_NAMES},
            "output": {"formats": ["h5"]},
            "solver": solver or None,
        }
    )


def exact_kwargs(prob: Problem) -> dict:
    return dict(
        center=CENTER,
        a=HALF_LENGTH,
        E=E,
        nu=NU,
        plane=prob.plane,
        stress=STRESS,
        psi_deg=prob.psi,
        friction=prob.friction,
        cohesion=prob.cohesion,
    )


def box_edges(origin, size, n_per_edge) -> dict:
    """Points along the four edges of a box, n_per_edge + 1 each (corners included)."""
    x0, y0 = origin
    w, h = size
    kx = np.linspace(x0, x0 + w, n_per_edge + 1)
    ky = np.linspace(y0, y0 + h, n_per_edge + 1)
    return {
        "bottom": np.column_stack([kx, np.full_like(kx, y0)]),
        "top": np.column_stack([kx, np.full_like(kx, y0 + h)]),
        "left": np.column_stack([np.full_like(ky, x0), ky]),
        "right": np.column_stack([np.full_like(ky, x0 + w), ky]),
    }


def write_edge_csv(path: Path, points, values) -> None:
    """Boundary CSV (case-format.md): header x,y,ux,uy, one row per point."""
    with open(path, "w") as f:
        f.write("x,y,ux,uy\n")
        for (x, y), (ux, uy) in zip(points, values, strict=True):
            f.write(f"{x:.17g},{y:.17g},{ux:.17g},{uy:.17g}\n")


def write_case(
    folder: Path,
    n: int,
    prob: Problem,
    tip: str | dict | None,
    penalty: float | None,
    **options,
) -> Path:
    """Write case.toml and the four edge CSV files (8 points per element edge);
    ``options`` (steps, solver) go to case_text."""
    folder.mkdir(parents=True, exist_ok=True)
    box = (-HALF_BOX, -HALF_BOX), (2 * HALF_BOX, 2 * HALF_BOX)
    for name, pts in box_edges(*box, 8 * n).items():
        write_edge_csv(
            folder / f"{name}.csv", pts, cf.displacement(pts, **exact_kwargs(prob))
        )
    path = folder / "case.toml"
    path.write_text(case_text(n, prob, tip, penalty, **options))
    return path


@dataclass
class Solved:
    model: Model
    u: np.ndarray
    contact: ContactResult
    iterations: int
    wall_s: float


def solve_case(path: Path) -> Solved:
    """Build and solve a case in-process (no output files); timed."""
    start = time.perf_counter()
    spec = load_case(path)
    model = build_model(spec)
    results = newton_solver(model).run(spec.loading.steps)
    wall = time.perf_counter() - start
    last = results[-1]
    return Solved(
        model=model,
        u=last.u,
        contact=last.contact,
        iterations=int(sum(r.iterations for r in results)),
        wall_s=wall,
    )


def fracture_arrays(solved: Solved) -> dict:
    """s, slip, p_N, state of fracture 0, ordered by arc length (the fields
    that ``result.h5`` reports, from post.fracture_fields)."""
    model = solved.model
    ff = fracture_fields(model.ip, solved.contact, len(model.fractures))[0]
    return {
        "s": ff.s,
        "slip": ff.slip,
        "pn": ff.normal_traction,
        "state": ff.state,
    }


def oscillation(s, pn, a=HALF_LENGTH) -> float:
    """max |p_N - mean| / |mean| over the inner 90 % of the crack."""
    inner = np.abs(s - a) <= 0.9 * a
    mean = float(np.mean(pn[inner]))
    return float(np.max(np.abs(pn[inner] - mean)) / abs(mean))


def measure(solved: Solved, prob: Problem, a_over_h: int) -> Row:
    """The table row of one solved problem."""
    fa = fracture_arrays(solved)
    exact = cf.slip_profile(
        fa["s"],
        HALF_LENGTH,
        E,
        NU,
        prob.plane,
        STRESS,
        prob.psi,
        prob.friction,
        prob.cohesion,
    )
    k_exact = cf.k_ii(STRESS, prob.psi, HALF_LENGTH, prob.friction, prob.cohesion)
    sifs = stress_intensity_factors(solved.model, solved.u, solved.contact)
    k_ii = np.array([t.k_ii for t in sifs])
    k_i = np.array([t.k_i for t in sifs])
    row = Row(
        problem=prob.name,
        a_over_h=a_over_h,
        dofs=int(solved.model.problem.n_dofs),
        oscillation=oscillation(fa["s"], fa["pn"]),
        wall_s=solved.wall_s,
        newton=solved.iterations,
    )
    if prob.kind == "stick":
        # scale: the frictionless crack at this angle
        free = replace(prob, friction=0.0, cohesion=0.0)
        scale_slip = np.max(np.abs(cf.slip_profile(fa["s"], **profile_kwargs(free))))
        scale_k = abs(cf.k_ii(STRESS, prob.psi, HALF_LENGTH, 0.0, 0.0))
        row.slip_error = float(np.max(np.abs(fa["slip"])) / scale_slip)
        row.kii_error = float(np.max(np.abs(k_ii)) / scale_k)
        row.ki_ratio = float(np.max(np.abs(k_i)) / scale_k)
        n_slip = int(np.sum(fa["state"] == 2))
        row.note = f"{n_slip} slipping point(s)"
        row.extra["slipping_points"] = n_slip
    else:
        row.slip_error = cf.relative_l2(fa["s"], fa["slip"], exact)
        row.kii_error = float(np.max(np.abs(k_ii - k_exact)) / abs(k_exact))
        row.ki_ratio = float(np.max(np.abs(k_i)) / abs(k_exact))
    row.extra["k_ii"] = k_ii.tolist()
    row.extra["k_i"] = k_i.tolist()
    row.extra["k_ii_exact"] = k_exact
    return row


def profile_kwargs(prob: Problem) -> dict:
    """The keywords of closed_form.slip_profile: those of the field, no centre."""
    kw = exact_kwargs(prob)
    del kw["center"]
    return kw


def run_problem(
    prob: Problem,
    a_over_h: int,
    tip: str | None,
    penalty: float | None,
    workdir: Path,
) -> Row:
    """Write, solve and measure one problem on the mesh h = a / a_over_h."""
    n = int(round(2 * HALF_BOX * a_over_h / HALF_LENGTH))
    folder = workdir / f"{prob.name}_{a_over_h}"
    path = write_case(folder, n, prob, tip, penalty)
    return measure(solve_case(path), prob, a_over_h)


def observed_orders(rows: list[Row]) -> None:
    """Fill Row.order from consecutive meshes of the same problem (slip error)."""
    kinds = {p.name: p.kind for p in PROBLEMS}
    by: dict[str, list[Row]] = {}
    for r in rows:
        if kinds.get(r.problem, "slip") == "slip":  # a stuck crack has no order
            by.setdefault(r.problem, []).append(r)
    for seq in by.values():
        seq.sort(key=lambda r: r.a_over_h)
        for prev, cur in zip(seq[:-1], seq[1:], strict=True):
            if prev.slip_error > 0 and cur.slip_error > 0:
                cur.order = math.log(prev.slip_error / cur.slip_error) / math.log(
                    cur.a_over_h / prev.a_over_h
                )


@contextlib.contextmanager
def _workdir(keep: Path | None):
    if keep is not None:
        keep.mkdir(parents=True, exist_ok=True)
        yield keep
    else:
        with tempfile.TemporaryDirectory(prefix="xfemslip-verify-") as tmp:
            yield Path(tmp)


# --------------------------------------------------------------------------
# slip window sweep

WINDOW_FRICTION = 0.3  # window beta in (21.4, 51.9) deg for STRESS
WINDOW_MESH = 10  # a / h of the sweep
QUICK_OFFSETS = (-3.0, -1.5, -0.5, 0.5, 1.5, 3.0)  # deg from each edge
FULL_OFFSETS = (-5.0, -4.0, -3.0, -2.0, -1.0, -0.5, 0.5, 1.0, 2.0, 3.0, 4.0, 5.0)


@dataclass
class WindowPoint:
    beta: float  # angle between the crack and sigma_1 [deg]
    psi: float  # crack angle from +x [deg]
    slips_exact: bool
    slip_share: float  # share of contact points in SLIP
    distance: float  # to the nearest window edge [deg]

    @property
    def misclassified(self) -> bool:
        return (self.slip_share > 0.5) != self.slips_exact


def window_edges(friction=WINDOW_FRICTION):
    s1, s3, dir1 = cf.principal(STRESS)
    return cf.slip_window(s1, s3, friction), dir1


def run_window(
    offsets, tip, penalty, workdir: Path, progress: Callable | None = None
) -> list[WindowPoint]:
    """Sweep the crack angle across both edges of the slip window."""
    (lo, hi), dir1 = window_edges()
    betas = sorted({round(e + o, 3) for e in (lo, hi) for o in offsets})
    out = []
    for k, beta in enumerate(betas):
        psi = dir1 - beta  # a plane at beta from sigma_1
        prob = Problem(f"window-{beta:g}", psi, friction=WINDOW_FRICTION)
        if progress:
            progress(f"window beta = {beta:.2f} deg ({k + 1}/{len(betas)})")
        n = int(round(2 * HALF_BOX * WINDOW_MESH / HALF_LENGTH))
        path = write_case(workdir / f"window_{k}", n, prob, tip, penalty)
        fa = fracture_arrays(solve_case(path))
        out.append(
            WindowPoint(
                beta=beta,
                psi=psi,
                slips_exact=prob.driving_shear() != 0.0,
                slip_share=float(np.mean(fa["state"] == 2)),
                distance=min(abs(beta - lo), abs(beta - hi)),
            )
        )
    return out


# --------------------------------------------------------------------------
# the whole run: problems x meshes, targets, table, CSV, plot


@dataclass
class Report:
    rows: list[Row]
    window: list[WindowPoint]
    failures: list[str]
    tip: str | None


def order_between(rows: list[Row], problem: str, lo: int, hi: int) -> float:
    """Observed order of the slip error between a/h = lo and the finest <= hi."""
    seq = {r.a_over_h: r for r in rows if r.problem == problem}
    fine = [k for k in seq if lo < k <= hi]
    if lo not in seq or not fine:
        return math.nan
    f = max(fine)
    e0, e1 = seq[lo].slip_error, seq[f].slip_error
    return math.log(e0 / e1) / math.log(f / lo)


def check_targets(rows: list[Row], window: list[WindowPoint]) -> list[str]:
    """The issue's targets that are missed, one line each."""
    fails = []
    probs = {p.name: p for p in PROBLEMS}
    for r in rows:
        kind = probs[r.problem].kind if r.problem in probs else "slip"
        if kind == "stick" and r.extra.get("slipping_points", 0):
            fails.append(
                f"{r.problem} a/{r.a_over_h}: {r.extra['slipping_points']} "
                "point(s) slip on a crack that must stick"
            )
        if kind != "slip" or r.a_over_h != TARGET_H:
            continue
        if not r.slip_error <= SLIP_TARGET:
            fails.append(
                f"{r.problem} a/{TARGET_H}: slip L2 error {100 * r.slip_error:.2f} % "
                f"> {100 * SLIP_TARGET:.0f} %"
            )
        if not r.kii_error <= KII_TARGET:
            fails.append(
                f"{r.problem} a/{TARGET_H}: K_II error {100 * r.kii_error:.2f} % "
                f"> {100 * KII_TARGET:.0f} %"
            )
    for name in dict.fromkeys(r.problem for r in rows):
        if name in probs and probs[name].kind != "slip":
            continue
        meshes = {r.a_over_h for r in rows if r.problem == name}
        if not {10, 40} <= meshes:
            continue  # the target is for a/10 .. a/40 (not run with --quick)
        order = order_between(rows, name, 10, 40)
        if order < ORDER_TARGET:
            fails.append(
                f"{name}: observed order {order:.2f} between a/10 and a/40 "
                f"< {ORDER_TARGET:g}"
            )
    fails += [
        f"slip window: beta = {w.beta:.2f} deg misclassified "
        f"({w.distance:.2f} deg from the edge > {WINDOW_TARGET:g})"
        for w in window
        if w.misclassified and w.distance > WINDOW_TARGET
    ]
    return fails


def run_verification(
    *,
    quick: bool = False,
    tip: str | None = None,
    penalty: float | None = PENALTY,
    meshes=None,
    problems=None,
    window: bool = True,
    workdir: Path | None = None,
    progress: Callable | None = None,
) -> Report:
    """Run the verification problems on a mesh sequence and check the targets."""
    meshes = tuple(meshes or (QUICK_MESHES if quick else FULL_MESHES))
    names = problems or (QUICK_PROBLEMS if quick else [p.name for p in PROBLEMS])
    chosen = [p for p in PROBLEMS if p.name in names]
    rows = []
    total = len(chosen) * len(meshes)
    with _workdir(workdir) as wd:
        # one small solve first, so that no timed run pays for loading the
        # compiled kernels
        solve_case(write_case(wd / "warm-up", 8, PROBLEMS[0], tip, penalty))
        for i, prob in enumerate(chosen):
            for j, aoh in enumerate(meshes):
                if progress:
                    k = i * len(meshes) + j + 1
                    progress(f"{prob.name} h = a/{aoh} ({k}/{total})")
                rows.append(run_problem(prob, aoh, tip, penalty, wd))
        observed_orders(rows)
        sweep = (
            run_window(
                QUICK_OFFSETS if quick else FULL_OFFSETS, tip, penalty, wd, progress
            )
            if window
            else []
        )
    return Report(rows=rows, window=sweep, failures=check_targets(rows, sweep), tip=tip)
