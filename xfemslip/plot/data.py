"""What the figures need from a run, read from its documented output files.

``figure_data(path)`` reads ``result.h5`` (through
:func:`xfemslip.io.read.read_result`) and, when it lies beside it,
``result.vtu``: its split mesh (cut elements as triangles on each
side of the fracture, with their own points) is what lets a contour or a
deformed mesh show the displacement jump.  No matplotlib here.
"""

from __future__ import annotations

import logging
import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from xfemslip.errors import UsageError
from xfemslip.io.read import read_result

logger = logging.getLogger(__name__)


@dataclass
class FractureData:
    """One fracture of a result, ordered by arc length s."""

    index: int
    s: np.ndarray  # (K,) [m]
    points: np.ndarray  # (K, 2) [m]
    slip: np.ndarray  # (K,) tangential jump [m]
    slid: np.ndarray  # (K,) the slip that slid (FractureFields.slid) [m]
    # (K,) [Pa]: the effective normal traction sigma_n + p_f when the result
    # has pore pressure (what the Coulomb criterion sees), else sigma_n
    normal_traction: np.ndarray
    shear_traction: np.ndarray  # (K,) [Pa]
    state: np.ndarray  # (K,) 0 open, 1 stick, 2 slip
    theta: float  # chord angle, first to last point of the case file [deg]
    friction: float
    cohesion: float  # [Pa]


@dataclass
class ResultData:
    """A run's result, enough for every figure."""

    path: Path
    label: str  # the panel title: the case name, or a sweep case's parameters
    converged: bool
    points: np.ndarray  # (N, 2) [m]
    cells: np.ndarray  # (M, 4)
    displacement: np.ndarray  # (N, 2) [m]
    stress: np.ndarray  # (M, 3) [Pa]
    principal: np.ndarray  # (M, 2) [Pa] s_max, s_min
    stress_state: tuple[float, float, float]  # far field (xx, yy, xy) [Pa]
    stress_source: str  # "loading.stress" or "mean element stress"
    fractures: list[FractureData] = field(default_factory=list)
    # far-field pore pressure of the final step [Pa] ([pore_pressure]: initial,
    # plus the change when it acts in the whole model); 0 without one
    pore_pressure: float = 0.0
    # with a [pore_pressure] change: the state the fractures' Coulomb law
    # sees where the pressure changed, at the final step (changed_stress:
    # sigma + p I, its median over changed_cells cells), and the in-situ
    # effective stress (loading.initial_stress, else loading.stress, + p0 I)
    changed_stress: tuple[float, float, float] | None = None
    changed_cells: int = 0
    in_situ_stress: tuple[float, float, float] | None = None
    vis_points: np.ndarray | None = None  # (P, 2) split mesh from result.vtu
    vis_displacement: np.ndarray | None = None  # (P, 2)
    vis_triangles: np.ndarray | None = None  # (T, 3): quads split in two + cut
    vis_edges: np.ndarray | None = None  # (E, 2) point pairs: the element outlines
    name: str = ""  # the case's name (a sweep case: its base case's name)


# Display of the keys a sweep varies, by the last name of the key path (the
# name in a sweep case's id, ``002_angle=45``): (name shown, factor, unit).
PARAMETER_UNITS = {
    "E": ("E", 1e-9, "GPa"),
    "nu": ("\u03bd", 1.0, ""),
    "angle": ("angle", 1.0, "deg"),
    "friction": ("f", 1.0, ""),
    "cohesion": ("c", 1e-6, "MPa"),
    "kn": ("$k_N$", 1.0, "Pa/m"),
    "kt": ("$k_T$", 1.0, "Pa/m"),
    "length": ("length", 1.0, "m"),
    "change": ("$\\Delta p$", 1e-6, "MPa"),
    "initial": ("$p_0$", 1e-6, "MPa"),
    "xx": ("$\\sigma_{xx}$", 1e-6, "MPa"),
    "yy": ("$\\sigma_{yy}$", 1e-6, "MPa"),
    "xy": ("$\\sigma_{xy}$", 1e-6, "MPa"),
    "elements": ("elements", 1.0, ""),
}
_SWEEP_ID = re.compile(r"^\d+_(.+)$")
_PARAMETER = re.compile(r"([A-Za-z][A-Za-z0-9]*)=([^_]+)")


def parameter_label(text: str) -> str:
    """``E=5e9_friction=0.3`` (a sweep case id without its index) as
    ``E = 5 GPa, f = 0.3``: known keys in their engineering unit, others as
    written."""
    parts = []
    for key, value in _PARAMETER.findall(text):
        shown, factor, unit = PARAMETER_UNITS.get(key, (key, 1.0, ""))
        try:
            number = f"{float(value) * factor:.4g}"
        except ValueError:
            number = value
        parts.append(f"{shown} = {number} {unit}".rstrip())
    return ", ".join(parts) or text


def default_label(path: Path, case: dict) -> tuple[str, str]:
    """(label, name) of a result: a sweep case (its folder ``002_angle=45``,
    its name ``<base name>-002_angle=45``) is labelled by its parameters with
    units (``angle = 45 deg``) and named by its base case; any other result
    by the case's ``name`` (else its folder's)."""
    folder = path.resolve().parent.name
    name = str(case.get("name") or folder or path.stem)
    match = _SWEEP_ID.match(folder)
    if match and name.endswith(f"-{folder}"):
        return parameter_label(match[1]), name[: -len(folder) - 1]
    return name, name


def distinct_labels(results: list[ResultData]) -> None:
    """Make the labels of results that share one (runs of one case in
    several folders) tell them apart by their folder: ``tiny (angle = 45
    deg)`` for a folder named like a sweep case, else ``tiny (run-b)``."""
    count: dict[str, int] = {}
    for data in results:
        count[data.label] = count.get(data.label, 0) + 1
    for data in results:
        if count[data.label] > 1:
            folder = data.path.resolve().parent.name
            match = _SWEEP_ID.match(folder)
            where = parameter_label(match[1]) if match else folder
            data.label = f"{data.label} ({where})"


def _chord_angle(table: dict) -> float:
    """Fracture angle [deg] from the case table: ``angle`` or first->last point."""
    if "angle" in table:
        return float(table["angle"])
    pts = np.asarray(table.get("points", [[0, 0], [1, 0]]), dtype=float)
    d = pts[-1] - pts[0]
    return math.degrees(math.atan2(d[1], d[0]))


def _stress_state(case: dict, stress: np.ndarray, cell_area: np.ndarray):
    """Far-field stress: loading.stress, else the area-weighted mean stress."""
    given = case.get("loading", {}).get("stress")
    if isinstance(given, dict) and {"xx", "yy"} <= set(given):
        return (float(given["xx"]), float(given["yy"]), float(given.get("xy", 0.0))), (
            "loading.stress"
        )
    mean = (stress * cell_area[:, None]).sum(axis=0) / cell_area.sum()
    return tuple(float(v) for v in mean), "mean element stress"


def _far_pore_pressure(case: dict) -> float:
    """Pore pressure in the far field at the final step [Pa] (0 without one)."""
    pp = case.get("pore_pressure")
    if not isinstance(pp, dict):
        return 0.0
    change = pp.get("change", 0.0) if pp.get("region", "all") == "all" else 0.0
    return float(pp.get("initial", 0.0)) + float(change)


def _changed_state(case: dict, step) -> tuple[tuple | None, int, tuple | None]:
    """(sigma + p I where the pore pressure changed, at ``step``: the median
    of each component over those cells; their number; the in-situ
    effective stress), or (None, 0, None) without a pressure change.

    A cell counts as changed when its pore pressure moved by at least half
    the largest change (cut cells store their area mean, so a cell mostly
    outside the region does not count).  The median is the undisturbed
    value of the region's uniform part: the fractures disturb a few cells
    around them, which the mean would mix in.  sigma + p I and not
    sigma + alpha p I: the fractures see their full fluid pressure
    (Terzaghi, ``effective_normal_traction``)."""
    pp = case.get("pore_pressure")
    if not isinstance(pp, dict) or step.pore_pressure is None or step.stress is None:
        return None, 0, None
    p0 = float(pp.get("initial", 0.0))
    moved = np.abs(step.pore_pressure - p0)
    if not moved.max() > 0.0:
        return None, 0, None
    cells = moved >= 0.5 * moved.max()
    eff = step.stress[cells] + step.pore_pressure[cells, None] * np.array([1, 1, 0])
    loading = case.get("loading", {})
    start = loading.get("initial_stress") or loading.get("stress") or {}
    in_situ = tuple(
        float(start.get(k, 0.0)) + (p0 if k != "xy" else 0.0)
        for k in ("xx", "yy", "xy")
    )
    median = tuple(float(v) for v in np.median(eff, axis=0))
    return median, int(cells.sum()), in_situ


def _fracture_laws(result, case: dict, path: Path) -> list[tuple[float, float, float]]:
    """(theta [deg], friction, cohesion) of every fracture of the result, in
    its order: from the case the result carries, rebuilt beside the result
    (so [network] fractures, generated or from a CSV file, get their own
    values), else from the [[fractures]] tables and the [network] defaults,
    with a warning that says so."""
    from xfemslip.case import loads_case
    from xfemslip.errors import XfemslipError

    n = len(result.fractures)
    try:
        spec = loads_case(str(result.attrs.get("case_toml", "")), path)
        tables = case.get("fractures", [])
        laws = [
            (
                _chord_angle(tables[i] if i < len(tables) else {"points": fr.points}),
                fr.friction,
                fr.cohesion,
            )
            for i, fr in enumerate(spec.fractures)
        ]
        if len(laws) == n:
            return laws
    except XfemslipError as err:
        logger.warning(
            "%s: the case does not load here (%s); the network fractures' "
            "friction and cohesion are the [network] defaults",
            path,
            " ".join(str(err).split())[:120],
        )
    tables = case.get("fractures", [])
    net = case.get("network", {}) if isinstance(case.get("network"), dict) else {}
    laws = [
        (
            _chord_angle(t),
            float(t.get("friction", 0.0)),
            float(t.get("cohesion", 0.0)),
        )
        for t in tables[:n]
    ]
    for ff in result.fractures[len(laws) :]:
        theta = _chord_angle({"points": np.asarray(ff.points)[[0, -1]]})
        laws.append(
            (theta, float(net.get("friction", 0.0)), float(net.get("cohesion", 0.0)))
        )
    return laws


def _fracture_data(result, case: dict, path: Path) -> list[FractureData]:
    """Every fracture of the result ([[fractures]] and [network]), final step."""
    laws = _fracture_laws(result, case, path)
    out = []
    for i, (ff, (theta, friction, cohesion)) in enumerate(
        zip(result.fractures, laws, strict=True)
    ):
        out.append(
            FractureData(
                index=i,
                s=ff.s,
                points=ff.points,
                slip=ff.slip,
                slid=ff.slid,
                normal_traction=(
                    ff.effective_normal_traction
                    if ff.effective_normal_traction is not None
                    else ff.normal_traction
                ),
                shear_traction=ff.shear_traction,
                state=ff.state,
                theta=theta,
                friction=float(friction),
                cohesion=float(cohesion),
            )
        )
    return out


def _read_vtu(data: ResultData, path: Path) -> None:
    """Fill the split visualisation mesh from ``result.vtu`` (if readable)."""
    import meshio

    try:
        mesh = meshio.read(path)
    except Exception:  # a broken VTU only costs the jump in the plots
        return
    if "displacement" not in mesh.point_data or "cell_id" not in mesh.cell_data:
        return
    tris, edges = [], []
    pts = mesh.points[:, :2]
    for block, cell_id in zip(mesh.cells, mesh.cell_data["cell_id"], strict=True):
        if block.type == "quad":
            q = block.data
            tris += [q[:, [0, 1, 2]], q[:, [0, 2, 3]]]
            edges += [q[:, [k, (k + 1) % 4]] for k in range(4)]
        elif block.type == "triangle":
            tris.append(block.data)
            edges.append(_piece_outlines(pts, block.data, cell_id, data.fractures))
    if not tris:
        return
    data.vis_points = pts
    data.vis_displacement = mesh.point_data["displacement"][:, :2]
    data.vis_triangles = np.concatenate(tris).astype(np.int64)
    data.vis_edges = np.concatenate(edges).astype(np.int64)


def _side(points: np.ndarray, fractures: list[FractureData]) -> np.ndarray:
    """Side (+1 / -1) of each point w.r.t. the nearest fracture point's frame."""
    if not fractures:
        return np.ones(len(points))
    best = np.full(len(points), np.inf)
    side = np.ones(len(points))
    for fr in fractures:
        if len(fr.points) < 2:
            continue
        t = np.gradient(fr.points, axis=0)
        t /= np.linalg.norm(t, axis=1)[:, None]
        d = points[:, None, :] - fr.points[None, :, :]  # (P, K, 2)
        dist = np.linalg.norm(d, axis=2)
        k = np.argmin(dist, axis=1)
        rows = np.arange(len(points))
        cross = t[k, 0] * d[rows, k, 1] - t[k, 1] * d[rows, k, 0]
        closer = dist[rows, k] < best
        best[closer] = dist[rows, k][closer]
        side[closer] = np.where(cross[closer] >= 0.0, 1.0, -1.0)
    return side


def _piece_outlines(pts, tris, cell_id, fractures) -> np.ndarray:
    """Outline edges of the pieces of the split elements: the sub-triangles of
    one element on one side of the fracture, without their inner edges.

    Every sub-triangle has points of its own, so edges are matched by their
    (rounded) undeformed coordinates."""
    side = _side(pts[tris].mean(axis=1), fractures)
    scale = max(float(np.ptp(pts, axis=0).max()), 1e-300)
    key_of = np.round(pts / (1e-9 * scale)).astype(np.int64)
    count: dict = {}
    first: dict = {}
    for tri, cell, sd in zip(tris, cell_id, side, strict=True):
        for a, b in ((0, 1), (1, 2), (2, 0)):
            ka, kb = tuple(key_of[tri[a]]), tuple(key_of[tri[b]])
            key = (int(cell), sd, min(ka, kb), max(ka, kb))
            count[key] = count.get(key, 0) + 1
            first.setdefault(key, (tri[a], tri[b]))
    return np.array([first[k] for k, n in count.items() if n == 1]).reshape(-1, 2)


def figure_data(path: str | Path, label: str | None = None) -> ResultData:
    """What the figures need of ``result.h5`` (read by
    :func:`xfemslip.io.read.read_result`) and of ``result.vtu`` beside it.
    UsageError when the file is missing, not HDF5, or holds no converged
    fields."""
    path = Path(path)
    if path.is_dir():
        path = path / "result.h5"
    result = read_result(path)
    if not result.steps:
        raise UsageError(f"{path}: holds no converged load step to plot")
    case = tomllib.loads(str(result.attrs.get("case_toml", "")))
    points, cells = result.points, result.cells
    d1 = points[cells[:, 2]] - points[cells[:, 0]]
    d2 = points[cells[:, 3]] - points[cells[:, 1]]
    area = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
    state, source = _stress_state(case, result.stress, area)
    default, name = default_label(path, case)
    data = ResultData(
        path=path,
        label=label or default,
        name=name,
        converged=result.converged,
        points=points,
        cells=cells,
        displacement=result.displacement,
        stress=result.stress,
        principal=result.principal_stress,
        stress_state=state,
        stress_source=source,
        pore_pressure=_far_pore_pressure(case),
        fractures=_fracture_data(result, case, path.with_name("case.toml")),
    )
    data.changed_stress, data.changed_cells, data.in_situ_stress = _changed_state(
        case, result.final
    )
    vtu = path.with_name("result.vtu")
    if vtu.is_file() and _same_run(vtu, path, result.attrs.get("run_id")):
        _read_vtu(data, vtu)
    return data


def _same_run(vtu: Path, path: Path, run_id) -> bool:
    """Whether ``result.vtu`` was written by the run that wrote ``path``
    (the ``run_id`` both carry, output-format.md); if not, say so: the
    figures then draw result.h5's own mesh, without the split cells."""
    from xfemslip.io.vtu import read_run_id

    theirs = read_run_id(vtu)
    if run_id is not None and theirs == int(run_id):
        return True
    logger.warning(
        "%s is not of the run that wrote %s (run_id %s, not %s): it is not "
        "drawn; the figures show result.h5's mesh without the jump",
        vtu,
        path,
        "unreadable" if theirs is None else theirs,
        run_id,
    )
    return False
