"""run_case: case -> mesh -> fractures -> enrichment -> quadrature -> Newton -> output.

Testable without the CLI.  Output files follow ``output-format.md``; when a
load step fails, the steps already converged are written (``converged =
False``) before the ConvergenceError is passed on.  The files of a run are one
set, swapped into the output folder whole (:mod:`xfemslip.writers.folder`).
"""

from __future__ import annotations

import contextlib
import logging
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from xfemslip import __version__, interrupt, kernels
from xfemslip.assembly import BulkSystem, assemble_bulk
from xfemslip.boundary import dirichlet, hold_enriched, traction_load
from xfemslip.contact import ContactSet, build_contact
from xfemslip.conventions import OPEN, SLIP, STATE_CODES, STICK
from xfemslip.enrichment import EnrichedCells, build_enriched_cells, find_candidates
from xfemslip.errors import ConvergenceError, GeometryError
from xfemslip.geometry import build_fractures
from xfemslip.material import elasticity_matrix
from xfemslip.memory import check_memory, enriched_footprint, model_footprint
from xfemslip.mesh import Mesh, build_mesh
from xfemslip.poro import (
    Materials,
    PorePressure,
    body_load,
    build_materials,
    build_pore_pressure,
    fluid_pressure,
    fracture_load,
    make_contact_effective,
)
from xfemslip.post import bulk_fields, fracture_fields, vis_mesh
from xfemslip.predictor import stress_increment
from xfemslip.quadrature import InterfacePoints, interface_points
from xfemslip.solver import NewtonSolver, Problem, StepResult
from xfemslip.writers import StepFields

logger = logging.getLogger(__name__)

OUTPUT_FILES = ("result.h5", "result.vtu", "fractures.vtu", "result.pvd")


@dataclass
class Model:
    """Everything built from a case before solving."""

    spec: object
    mesh: Mesh
    D: np.ndarray
    fractures: tuple
    ec: EnrichedCells
    bulk: BulkSystem
    ip: InterfacePoints
    contact: ContactSet
    problem: Problem
    materials: Materials | None = None  # per-cell constants ([reservoir])
    pore: PorePressure | None = None  # [pore_pressure]


@dataclass
class RunSummary:
    out_dir: Path
    converged: bool
    load_steps: int
    newton_iterations: int
    iterations_per_step: list
    wall_time_s: float
    n_dofs: int


@contextlib.contextmanager
def _naming_the_file(spec):
    """Geometry errors found while building name the case file."""
    try:
        yield
    except GeometryError as err:
        raise GeometryError(f"{spec.path}: {err}") from None


def _geometry(spec):
    """Mesh and fractures (after the memory estimate: nothing large is
    allocated for a case that would not fit)."""
    check_memory(spec)
    mesh = build_mesh(spec.mesh.x, spec.mesh.y)
    box = np.array([mesh.x[0], mesh.x[-1], mesh.y[0], mesh.y[-1]])
    with _naming_the_file(spec):
        return mesh, build_fractures(mesh, spec.fractures, box)


def check_geometry(spec) -> None:
    """What ``xfemslip check`` adds to key validation: fractures against the
    mesh and the prescribed values at boundary corners (GeometryError)."""
    mesh, _ = _geometry(spec)
    with _naming_the_file(spec):
        dirichlet(mesh, spec.boundary)


def kernel_work(ec) -> float:
    """Size of the enriched-cell assembly for ``kernels.choose``: quadrature
    points of the enriched cells times (8 + 2 S)^2, S the slots per cell (the
    padded columns the NumPy backend multiplies)."""
    nd = 8 + 2 * ec.slot_node.shape[1]
    return float(ec.qp_w.size) * nd * nd


def build_model(spec) -> Model:
    """Build the discrete problem of a validated case."""
    mesh, fractures = _geometry(spec)
    mat = spec.material
    D = elasticity_matrix(mat.E, mat.nu, mat.model)
    cand = find_candidates(mesh, fractures)
    check_memory(spec, enriched_footprint(spec, mesh, fractures, cand))
    ec = build_enriched_cells(mesh, fractures, cand)
    kernel_backend = kernels.choose(spec.solver.kernels, kernel_work(ec))
    kernels.use(kernel_backend)
    ip = interface_points(fractures, mesh.h_min)
    materials = build_materials(spec, mesh, ec, fractures)
    if spec.reservoir is None:
        bulk = assemble_bulk(mesh, D, cand, ec, ip)
    else:
        bulk = assemble_bulk(
            mesh, materials.D, cand, ec, ip, materials.cell, materials.qp
        )
    pore = build_pore_pressure(spec, materials, ec, ip, mesh.h_min)
    contact = build_contact(
        mesh,
        fractures,
        ip,
        ec,
        cand,
        bulk.dofmap,
        spec.loading.initial_stress,
        mat.E,
        spec.solver.contact_patch,
    )
    contact.kernels = kernel_backend
    with _naming_the_file(spec):
        bc = hold_enriched(dirichlet(mesh, spec.boundary), cand, bulk.dofmap)
    F = traction_load(
        mesh, spec.boundary, spec.loading, ec, cand, bulk.dofmap, fractures
    )
    if pore is not None:  # Biot body load and fracture fluid load (xfemslip.poro)
        make_contact_effective(contact, pore)
        F = F + body_load(mesh, bulk, pore, ec) + fracture_load(contact, ip, pore)
    problem = Problem(
        K=bulk.K,
        F_unit=F,
        fixed=bc.dofs,
        fixed_values=bc.values,
        contact=contact,
        n_dofs=bulk.dofmap.n_dofs,
        floating=floating_parts(mesh, fractures, contact, bc),
        penalty_ratio=float(np.max(np.maximum(contact.kn, contact.kt), initial=0.0))
        * mesh.h_min
        / mat.E,
        node_xy=mesh.nodes,
        load_stress=stress_increment(spec.loading),
    )
    logger.info(
        "model: %d x %d cells, %d fracture(s), %d dofs (%d nodes enriched with %d "
        "functions), %d contact points, %s kernels",
        mesh.nx,
        mesh.ny,
        len(fractures),
        bulk.dofmap.n_dofs,
        np.unique(cand.node[bulk.dofmap.cand_dof >= 0]).size,
        bulk.dofmap.n_enriched_functions,
        ip.n,
        kernel_backend,
    )
    model = Model(
        spec=spec,
        mesh=mesh,
        D=D,
        fractures=fractures,
        ec=ec,
        bulk=bulk,
        ip=ip,
        contact=contact,
        problem=problem,
        materials=materials,
        pore=pore,
    )
    check_memory(spec, model_footprint(model))  # before the LU and the steps
    return model


def newton_solver(model: Model) -> NewtonSolver:
    """The Newton solver of a model, with the options of its [solver] table."""
    opt = model.spec.solver
    solver = NewtonSolver(
        model.problem,
        opt.tolerance,
        opt.max_iterations,
        opt.tangent,
        opt.linear_solver,
        max_step_cuts=opt.max_step_cuts,
    )
    _log_in_situ_release(model, solver.in_situ)
    return solver


def _log_in_situ_release(model: Model, zero) -> None:
    """Say, per fracture, where the in-situ traction is not admissible (shear
    above the friction limit, or tension) and how much of it the first load
    step releases (ContactSet.in_situ_force)."""
    c = model.contact
    if model.spec.loading.initial_stress is None or not np.any(zero.state != STICK):
        return
    pt_in_situ = c.kt * (0.0 - c.slip_committed)
    for fi, fr in enumerate(model.fractures):
        mine = c.fracture == fi
        slips = mine & (zero.state == SLIP)
        opens = mine & (zero.state == OPEN)
        total = float(c.weight[mine].sum())
        if slips.any():
            excess = np.abs(pt_in_situ[slips]) - np.abs(zero.pt[slips])
            logger.info(
                "fractures[%d]: the initial stress exceeds the friction limit on "
                "%.4g m of its %.4g m, by up to %.4g MPa of shear; the excess is "
                "released in load step 1 (the fracture slips by what it drives)",
                fr.index,
                float(c.weight[slips].sum()),
                total,
                float(excess.max()) / 1e6,
            )
        if opens.any():
            logger.info(
                "fractures[%d]: the initial stress pulls it open on %.4g m of its "
                "%.4g m, with up to %.4g MPa of tension; released in load step 1 "
                "(the fracture opens)",
                fr.index,
                float(c.weight[opens].sum()),
                total,
                float(c.pn0[opens].max()) / 1e6,
            )


def floating_parts(mesh, fractures, contact, bc):
    """Fractures cutting the domain in two, one part without prescribed dofs."""
    std = bc.dofs[bc.dofs < 2 * mesh.n_nodes]  # enrichment dofs are not nodes
    fixed_nodes = np.unique(std // 2)
    out = []
    for fi, fr in enumerate(fractures):
        if fr.tips or fr.junction_ends:
            continue
        side = fr.side(mesh.nodes[fixed_nodes]) if fixed_nodes.size else np.zeros(0)
        if not (np.any(side > 0) and np.any(side < 0)):
            out.append((fr.index, contact.fracture == fi))
    return out


def step_fields(model: Model, r: StepResult) -> StepFields:
    spec = model.spec
    mats, pore = model.materials, model.pore
    hetero = spec.reservoir is not None
    biot_p = None
    if pore is not None:
        p = pore.cell_pressure(r.load_factor)
        biot_p = (pore.biot * pore.initial, pore.biot * p)
    stress, szz, principal = bulk_fields(
        model.mesh,
        model.bulk,
        mats.D if hetero else model.D,
        r.u,
        spec.loading.initial_stress,
        mats.nu if hetero else spec.material.nu,
        spec.material.model,
        cell_material=mats.cell if hetero else None,
        biot_p=biot_p,
    )
    extra = {}
    fluid = None
    if pore is not None:
        extra = {
            "effective_stress": stress + biot_p[1][:, None] * [1.0, 1.0, 0.0],
            "pore_pressure": p,
        }
        fluid = fluid_pressure(model.ip, pore, r.load_factor)
    n_std = 2 * model.mesh.n_nodes
    return StepFields(
        step=r.step,
        load_factor=r.load_factor,
        newton_iterations=r.iterations,
        displacement=r.u[:n_std].reshape(-1, 2).copy(),
        stress=stress,
        stress_zz=szz,
        principal_stress=principal,
        fractures=fracture_fields(model.ip, r.contact, len(model.fractures), fluid),
        **extra,
    )


def run_case(
    spec, out_dir: Path | None = None, *, overwrite: bool = False
) -> RunSummary:
    """Solve a case and write its output; returns a summary.

    Raises ConvergenceError (after writing the converged steps) when a load
    step fails, UsageError when the output exists and overwrite is False.
    """
    start = time.perf_counter()
    done = solve_and_write(
        spec, out_dir, overwrite, lambda solver, _: solver.run(spec.loading.steps)
    )
    if done.failure is not None:
        raise done.failure
    iters = [r.iterations for r in done.results]
    logger.info("Newton iterations per load step: %s", iters)
    return RunSummary(
        out_dir=done.out_dir,
        converged=True,
        load_steps=spec.loading.steps,
        newton_iterations=int(sum(iters)),
        iterations_per_step=iters,
        wall_time_s=time.perf_counter() - start,
        n_dofs=done.model.problem.n_dofs,
    )


@dataclass
class Written:
    """What solve_and_write built, solved and wrote."""

    out_dir: Path
    model: Model
    results: list  # the converged StepResults (solver.completed)
    value: object  # what ``drive`` returned (None after a failure)
    failure: ConvergenceError | None


def solve_and_write(spec, out_dir, overwrite, drive, finish=None) -> Written:
    """The frame of every command that solves a case: take the output folder
    (:func:`xfemslip.writers.folder.output_folder`: locked, refused when it
    holds results and not ``overwrite``), build the model and its Newton
    solver, run ``drive(solver, model)``, and write the converged steps (also
    after a ConvergenceError, which is returned, not raised, with converged =
    False in result.h5).  ``finish(written, folder)`` may add files of its own
    to the set in ``folder``; the set replaces the folder's content whole."""
    from xfemslip.writers.folder import output_folder

    start = time.perf_counter()
    out_dir = Path(out_dir) if out_dir is not None else Path(spec.output.directory)
    with output_folder(out_dir, overwrite=overwrite, results=OUTPUT_FILES) as stage:
        model = build_model(spec)
        solver = newton_solver(model)
        value = failure = None
        try:
            value = drive(solver, model)
        except ConvergenceError as exc:
            failure = exc
        interrupt.checkpoint()  # a signal swallowed while solving ends it here
        results = solver.completed
        with interrupt.deferred():
            failure = (
                write_output(
                    model,
                    results,
                    stage.path,
                    converged=failure is None,
                    wall=time.perf_counter() - start,
                    iterations=[r.iterations for r in results],
                )
                or failure
            )
            done = Written(out_dir, model, results, value, failure)
            if finish is not None:
                finish(done, stage.path)
    return done


def write_output(model: Model, results, out_dir: Path, *, converged, wall, iterations):
    """Write result.h5 (+ VTU/PVD) of the converged steps into ``out_dir``
    (the staging folder of the set).  Returns a ConvergenceError when a step
    holds NaN or inf: the finite steps before it are written, converged =
    False."""
    from xfemslip.writers import hdf5, run_id

    spec = model.spec
    fields = [step_fields(model, r) for r in results]
    bad = _first_non_finite(fields)
    if bad is not None:  # never write NaN/inf: keep the finite steps only
        index, name = bad
        fields, results = fields[:index], results[:index]
        iterations, converged = list(iterations[:index]), False
    attrs = {
        "format_version": 1,
        "xfemslip_version": __version__,
        "case_toml": spec.text,
        "converged": bool(converged),
        "load_steps": int(spec.loading.steps),
        "newton_iterations": int(sum(iterations)),
        "newton_iterations_per_step": np.array(iterations, dtype=np.int64),
        # load-step bisections per written step (issue 4; 0 = not cut)
        "load_step_cuts_per_step": np.array([r.cuts for r in results], dtype=np.int64),
        "wall_time_s": float(wall),
        "tangent": spec.solver.tangent,
        "contact_patch_cells": float(spec.solver.contact_patch),
        "n_dofs": int(model.problem.n_dofs),
        "kernels": model.contact.kernels,
        "status_codes": STATE_CODES,
    }
    attrs["run_id"] = run_id(attrs, model.mesh.nodes, model.mesh.cells, fields)
    hdf5.write_result(
        out_dir / "result.h5",
        points=model.mesh.nodes,
        cells=model.mesh.cells,
        steps=fields,
        attrs=attrs,
        load_steps=spec.loading.steps,
    )
    if "vtu" in spec.output.formats and fields:
        _write_vtu(
            model, results, fields, out_dir, spec.loading.steps > 1, attrs["run_id"]
        )
    if bad is None:
        return None
    step = bad[0] + 1
    return ConvergenceError(
        f"load step {step} gave a non-finite {bad[1]} (NaN or inf), which is "
        f"not written; {len(fields)} finite step(s) kept. Lower the penalty "
        "stiffnesses kn/kt or use more load steps",
        step=step,
        iteration=0,
        residual=float("nan"),
    )


def _first_non_finite(fields):
    """(index, field name) of the first step holding NaN or inf, or None."""
    for index, f in enumerate(fields):
        arrays = {
            "displacement": f.displacement,
            "stress": f.stress,
            "stress_zz": f.stress_zz,
            "principal_stress": f.principal_stress,
        }
        for i, fr in enumerate(f.fractures):
            for name in ("slip", "opening", "normal_traction", "shear_traction"):
                arrays[f"fractures[{i}].{name}"] = getattr(fr, name)
        for name, value in arrays.items():
            if not np.all(np.isfinite(value)):
                return index, name
    return None


def _write_vtu(model, results, fields, out_dir, series, set_id) -> None:
    """Write the VTU (and PVD) files of the converged steps into ``out_dir``,
    each stamped with the set's ``run_id``."""
    from xfemslip.writers import vtu

    entries = []
    for r, f in zip(results, fields, strict=True):
        interrupt.checkpoint()  # between files: a deferred signal stops here
        vis = vis_mesh(model.mesh, model.ec, model.bulk, r.u)
        cell_data = {
            "stress": f.stress,
            "stress_zz": f.stress_zz,
            "principal_stress": f.principal_stress,
        }
        if f.effective_stress is not None:
            cell_data["effective_stress"] = f.effective_stress
            cell_data["pore_pressure"] = f.pore_pressure
        fr = [(model.fractures[i].index, ff) for i, ff in enumerate(f.fractures)]
        names = []
        if series:
            (out_dir / "steps").mkdir(exist_ok=True)
            names.append(f"steps/%s_{r.step:04d}.vtu")
            entries.append((r.load_factor, f"steps/result_{r.step:04d}.vtu"))
        if r is results[-1]:
            names.append("%s.vtu")
        for name in names:
            vtu.write_bulk(out_dir / (name % "result"), vis, cell_data, run_id=set_id)
            if fr:
                vtu.write_fractures(out_dir / (name % "fractures"), fr, run_id=set_id)
    if series:
        vtu.write_pvd(out_dir / "result.pvd", entries, run_id=set_id)
