"""The numerical stress matrix: case builders, one runner, references.

Shared by the tests in this folder (a fast subset) and ``benchmarks/stability.py``
(the whole matrix, written to ``docs/performance/stability.md``).  Every case either
converges or fails with a ``ConvergenceError`` whose message says why and what
to change; ``run`` records which, with the Newton iterations, the stick/slip
switches, the load-step cuts and ping-pong freezes, and max |slip|.

References (all independent of the XFEM code):

- ``crack``: a straight crack of half-length A in a 2 m box whose edges get the
  exact displacements of the cracked infinite plane (``xfemslip.reference.closed_form``,
  Westergaard mode II with friction and cohesion); the reference is the
  closed-form slip profile, compared as a relative L2 error along the crack;
  a crack that the closed form says sticks must show no SLIP point;
- ``reservoir``: the seed paper's reservoir case; the reference is the
  Mohr-Coulomb slip window (``closed_form.slip_window``);
- ``block``: a block on a through-going fault; rigid sliding once the driving
  shear exceeds f times the normal force plus the cohesion force (statics).
"""

from __future__ import annotations

import math
import tempfile
import time
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from xfemslip.case import build, loads_case
from xfemslip.conventions import OPEN, SLIP, STICK  # noqa: F401 (re-exported)
from xfemslip.errors import ConvergenceError
from xfemslip.reference import closed_form as cf
from xfemslip.simulation import build_model
from xfemslip.solve.newton import NewtonSolver

ROOT = Path(__file__).resolve().parents[2]
RESERVOIR = ROOT / "cases" / "reservoir_depletion.toml"

STRESS = (-20.0e6, -40.0e6, 0.0)  # far field of the crack cases [Pa]
# with shear, so that a horizontal crack (along element edges) slips:
# tau = 8 MPa > f |sigma_n| = 4 MPa at f = 0.1
SHEAR_STRESS = (-20.0e6, -40.0e6, 8.0e6)
A = 0.5  # crack half-length [m]
EDGE_FILES = ("bottom", "top", "left", "right")  # boundary data: <edge>.csv
H32_N = 32  # elements per side of the crack cases
E0 = 5.0e9  # Young's modulus of the crack cases [Pa]


@dataclass
class Outcome:
    """What one run of the matrix gave."""

    converged: bool
    iterations: int = 0  # Newton iterations, all steps
    switches: int = 0  # stick/slip/open switches, all iterations of all steps
    cuts: int = 0  # load-step bisections
    freezes: int = 0  # ping-pong freezes
    max_slip: float = math.nan  # max |[[u]].t| at the end [m]
    error: str = ""  # the ConvergenceError message
    steps: list = None  # StepResults
    model: object = None
    seconds: float = 0.0


def solve(text: str, path: Path, tangent="consistent", *, factors=None, **kw):
    """Build the case ``text`` (file name ``path``) and run Newton over the load
    path ``factors`` (default: proportional, ``[loading] steps``)."""
    spec = loads_case(text, path)
    model = build_model(spec)
    solver = NewtonSolver(
        model.problem,
        kw.get("tolerance", spec.solver.tolerance),
        kw.get("max_iterations", spec.solver.max_iterations),
        tangent,
        max_step_cuts=kw.get("max_step_cuts", spec.solver.max_step_cuts),
        predictor=kw.get("predictor", True),
    )
    if factors is None:
        n = spec.loading.steps
        factors = [k / n for k in range(1, n + 1)]
    start = time.perf_counter()
    error = ""
    try:
        solver.run_path(factors)
    except ConvergenceError as err:
        error = str(err)
    steps = solver.completed
    out = Outcome(
        converged=not error,
        iterations=sum(r.iterations for r in steps),
        switches=sum(sum(r.switches) for r in steps),
        cuts=sum(r.cuts for r in steps),
        freezes=sum(r.freezes for r in steps),
        error=error,
        steps=steps,
        model=model,
        seconds=time.perf_counter() - start,
    )
    if steps:
        final = steps[-1]
        assert np.all(np.isfinite(final.u)), "non-finite converged state"
        out.max_slip = float(
            np.max(np.abs(point_fields(final.contact)[0]), initial=0.0)
        )
    return out


# ----------------------------------------------------------------- crack cases


def _edge_csv(path: Path, points, values) -> None:
    with open(path, "w") as f:
        f.write("x,y,ux,uy\n")
        for (x, y), (ux, uy) in zip(points, values, strict=True):
            f.write(f"{x:.17g},{y:.17g},{ux:.17g},{uy:.17g}\n")


@dataclass
class Crack:
    """A straight crack in the 2 m box [-1, 1]^2 with exact boundary data."""

    psi: float = 30.0  # angle [deg]
    a: float = A  # half-length [m]
    center: tuple = (0.0123, -0.0077)
    n: int = 32  # elements per side
    E: float = E0
    nu: float = 0.3
    friction: float = 0.1
    cohesion: float = 0.0
    penalty: float = 100.0  # kn * h / E
    kt_kn: float = 1.0
    steps: int = 1
    tip: str = "branch"
    max_iterations: int = 30
    stress: tuple = STRESS  # far field (xx, yy, xy) [Pa]

    @property
    def h(self) -> float:
        return 2.0 / self.n

    def field(self) -> dict:
        return dict(
            center=self.center,
            a=self.a,
            E=self.E,
            nu=self.nu,
            plane="plane_strain",
            stress=self.stress,
            psi_deg=self.psi,
            friction=self.friction,
            cohesion=self.cohesion,
        )

    def write(self, folder: Path) -> tuple[str, Path]:
        folder.mkdir(parents=True, exist_ok=True)
        k = np.linspace(-1.0, 1.0, 8 * self.n + 1)
        edges = {
            "bottom": np.column_stack([k, np.full_like(k, -1.0)]),
            "top": np.column_stack([k, np.full_like(k, 1.0)]),
            "left": np.column_stack([np.full_like(k, -1.0), k]),
            "right": np.column_stack([np.full_like(k, 1.0), k]),
        }
        for name, pts in edges.items():
            _edge_csv(folder / f"{name}.csv", pts, cf.displacement(pts, **self.field()))
        p = math.radians(self.psi)
        t = (math.cos(p), math.sin(p))
        c = self.center
        p0 = [c[0] - self.a * t[0], c[1] - self.a * t[1]]
        p1 = [c[0] + self.a * t[0], c[1] + self.a * t[1]]
        kn = self.penalty * self.E / self.h
        text = build.case_text(
            {
                "domain": {"size": [2.0, 2.0], "origin": [-1.0, -1.0]},
                "mesh": {"elements": [self.n, self.n]},
                "material": {"E": self.E, "nu": self.nu},
                "fractures": [
                    {
                        "points": [p0, p1],
                        "friction": self.friction,
                        "cohesion": self.cohesion,
                        "kn": kn,
                        "kt": kn * self.kt_kn,
                        "tip": self.tip,
                    }
                ],
                "loading": {"steps": self.steps},
                "boundary": {e: {"file": f"{e}.csv"} for e in EDGE_FILES},
                "solver": {"max_iterations": self.max_iterations},
            }
        )
        return text, folder / "case.toml"

    def no_slip_cohesion(self) -> float:
        """Cohesion above which the closed form says the crack sticks [Pa]."""
        t_n, t_t = cf.crack_tractions(self.stress, self.psi)
        return max(0.0, abs(t_t) - self.friction * max(0.0, -t_n))


def point_fields(res) -> tuple[np.ndarray, np.ndarray]:
    """(slip [[u]].t, state) at every interface point.  ContactResult holds
    them per point, or per contact patch with ``point_*`` copies per point."""
    gt = getattr(res, "point_gt", None)
    state = getattr(res, "point_state", None)
    return (res.gt if gt is None else gt), (res.state if state is None else state)


def crack_error(crack: Crack, out: Outcome) -> tuple[float, str]:
    """(deviation, reference): relative L2 slip error against the closed form,
    or, for a crack that sticks, the SLIP share (must be 0)."""
    if not out.converged:
        return math.nan, "closed form"
    ip = out.model.ip
    gt, state = point_fields(out.steps[-1].contact)
    t = np.array([math.cos(math.radians(crack.psi)), math.sin(math.radians(crack.psi))])
    first = np.array(crack.center) - crack.a * t
    s = (ip.xy - first) @ t
    exact = cf.slip_profile(s, crack.a, **_profile_args(crack))
    if not np.any(exact):
        return float(np.mean(state == SLIP)), "sticks: SLIP share"
    # the slip as written to result.h5: the whole jump [[u]].t, penalty
    # compliance included
    return cf.relative_l2(s, gt, exact), "closed-form slip, rel. L2"


def _profile_args(crack: Crack) -> dict:
    return dict(
        E=crack.E,
        nu=crack.nu,
        plane="plane_strain",
        stress=crack.stress,
        psi_deg=crack.psi,
        friction=crack.friction,
        cohesion=crack.cohesion,
    )


def run_crack(crack: Crack, tangent="consistent", folder=None) -> tuple:
    """Solve a crack case; returns (Outcome, deviation, reference)."""
    with tempfile.TemporaryDirectory() as tmp:
        text, path = crack.write(Path(folder or tmp))
        out = solve(text, path, tangent)
    dev, ref = crack_error(crack, out)
    return out, dev, ref


# ------------------------------------------------------------- reservoir cases


def extra_fracture(points) -> dict:
    """A fracture with the keys of the reservoir case's one, on ``points``."""
    return {
        "points": points,
        "friction": 0.1,
        "cohesion": 0.0,
        "kn": 5.0e12,
        "kt": 5.0e12,
    }


def reservoir_text(
    *,
    n=20,
    angle=45.0,
    friction=0.1,
    cohesion=0.0,
    steps=1,
    points=None,
    extra_fractures=(),
    E=5.0e9,
    nu=0.3,
    initial_stress=None,
    max_iterations=30,
    kn=None,
) -> str:
    """The reservoir case on an n x n mesh with one fracture, plus one
    ``extra_fracture`` on each polyline of ``extra_fractures``; ``kn`` sets
    both penalties of the first fracture (None: the file's)."""
    doc = tomllib.loads(RESERVOIR.read_text())
    fracture = doc["fractures"][0]
    fracture.update(angle=float(angle), friction=float(friction))
    fracture["cohesion"] = float(cohesion)
    if kn is not None:
        fracture["kn"] = fracture["kt"] = kn
    if points is not None:
        for key in ("center", "length", "angle"):
            del fracture[key]
        fracture["points"] = points
    doc["fractures"] += [extra_fracture(p) for p in extra_fractures]
    doc["mesh"]["elements"] = [n, n]
    doc["material"].update(E=float(E), nu=float(nu))
    doc["loading"]["steps"] = steps
    if initial_stress is not None:
        xx, yy, xy = initial_stress
        doc["loading"]["initial_stress"] = {"xx": xx, "yy": yy, "xy": xy}
    doc["solver"]["max_iterations"] = max_iterations
    return build.case_text(doc)


def window_reference(angle: float, friction: float) -> tuple[bool, float]:
    """(inside the slip window, distance to its nearest edge [deg])."""
    sigma1, sigma3, dir1 = cf.principal(STRESS)
    window = cf.slip_window(sigma1, sigma3, friction)
    beta = cf.angle_to_sigma1(angle, dir1)
    if window is None:
        return False, math.inf
    lo, hi = window
    return lo < beta < hi, min(abs(beta - lo), abs(beta - hi))


# ------------------------------------------------------------------ the block


def block_text(
    *, shear, pressure=10.0e6, friction=0.5, cohesion=0.0, n=10, steps=1, kn=5.0e12
) -> str:
    """A 2 m x 1 m box cut by a horizontal fault at y = 0.55 (through-going):
    bottom edge fixed, top edge loaded by (shear, -pressure), sides free.  The
    top block is held by the fault alone."""
    return build.case_text(
        {
            "domain": {"size": [2.0, 1.0]},
            "mesh": {"elements": [2 * n, n]},
            "material": {"E": 5.0e9, "nu": 0.25},
            "fractures": [
                {
                    "points": [[0.0, 0.55], [2.0, 0.55]],
                    "friction": friction,
                    "cohesion": cohesion,
                    "kn": kn,
                    "kt": kn,
                }
            ],
            "loading": {
                "stress": {"xx": 0.0, "yy": -pressure, "xy": shear},
                "steps": steps,
            },
            "boundary": {
                "bottom": {"ux": 0.0, "uy": 0.0},
                "top": "traction",
                "left": "free",
                "right": "free",
            },
        }
    )


def block_threshold(pressure, friction, cohesion) -> float:
    """Shear traction on the top edge above which the top block slides rigidly:
    tau L > f p L + c L (L = fault length; statics of the top block) [Pa]."""
    return friction * pressure + cohesion
