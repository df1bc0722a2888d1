"""run_case: case -> mesh -> fractures -> enrichment -> quadrature -> Newton -> output.

Testable without the CLI.  Output files follow ``output-format.md``; when a
load step fails, the steps already converged are written (``converged =
False``) before the ConvergenceError is passed on.  The files of a run are one
set, swapped into the output folder whole (:mod:`xfemslip.io.folder`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import logging
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from xfemslip import __version__, interrupt, kernels
from xfemslip.case.record import case_of_record
from xfemslip.case.specs import CaseSpec
from xfemslip.contact.interface import ContactSet, build_contact
from xfemslip.contact.predictor import stress_increment
from xfemslip.conventions import OPEN, SLIP, STATE_CODES, STICK
from xfemslip.errors import ConvergenceError, GeometryError, UsageError
from xfemslip.fem.assembly import BulkSystem, assemble_bulk
from xfemslip.fem.boundary import dirichlet, hold_enriched, traction_load
from xfemslip.fem.enrichment import (
    Candidates,
    EnrichedCells,
    build_enriched_cells,
    find_candidates,
)
from xfemslip.fem.material import elasticity_matrix
from xfemslip.fem.mesh import Mesh, build_mesh
from xfemslip.fem.poro import (
    FACE_OFFSET,
    Materials,
    PorePressure,
    body_load,
    build_materials,
    build_pore_pressure,
    fracture_load,
    make_contact_effective,
)
from xfemslip.fem.quadrature import InterfacePoints, interface_points
from xfemslip.fem.zones import build_zones, in_situ_stress, loading_breaks
from xfemslip.geometry.fracture import Fracture
from xfemslip.geometry.junctions import build_fractures
from xfemslip.io.results import run_folder, write_results
from xfemslip.memory import check_memory, enriched_footprint, model_footprint
from xfemslip.post.events import event_inputs, event_table
from xfemslip.post.fields import (
    first_non_finite,
    fracture_properties,
    step_fields,
    vis_mesh_with_faces,
)
from xfemslip.post.hydraulics import add_permeability
from xfemslip.post.result import Result, run_id
from xfemslip.solve.newton import NewtonSolver, Problem
from xfemslip.solve.shared import active as sharing_active
from xfemslip.solve.shared import digest

logger = logging.getLogger(__name__)


@dataclass
class Model:
    """Everything built from a case before solving."""

    spec: CaseSpec
    mesh: Mesh
    D: np.ndarray
    fractures: tuple[Fracture, ...]
    ec: EnrichedCells
    bulk: BulkSystem
    ip: InterfacePoints
    contact: ContactSet
    problem: Problem
    kernels: str  # kernel backend ("numba" | "numpy", kernels.choose)
    materials: Materials | None = None  # per-cell constants ([reservoir])
    pore: PorePressure | None = None  # [pore_pressure]
    # per fracture, the arc lengths where the rock on a face changes
    # (xfemslip.fem.zones.loading_breaks)
    breaks: list[np.ndarray] | None = None


@contextlib.contextmanager
def _naming_the_file(spec: CaseSpec):
    """Geometry errors found while building name the case file."""
    try:
        yield
    except GeometryError as err:
        raise GeometryError(f"{spec.path}: {err}") from None


def _geometry(spec: CaseSpec) -> tuple[Mesh, tuple[Fracture, ...]]:
    """Mesh and fractures (after the memory estimate: nothing large is
    allocated for a case that would not fit)."""
    check_memory(spec)
    mesh = build_mesh(spec.mesh.x, spec.mesh.y)
    with _naming_the_file(spec):
        return mesh, build_fractures(mesh, spec.fractures, mesh.box)


def geometry_key(spec: CaseSpec) -> tuple:
    """What the mesh, the fractures' geometry and their enrichment are made
    of: the mesh lines, and per fracture its polyline and tip treatment
    (not its friction, cohesion or stiffness, which the model takes from
    the case: :func:`_shared_geometry`)."""
    return (
        spec.mesh.x.tobytes(),
        spec.mesh.y.tobytes(),
        tuple(
            (f.index, np.asarray(f.points, float).tobytes(), f.tip, f.tip_radius)
            for f in spec.fractures
        ),
    )


# Models of up to this many cells keep their geometry and bulk stiffness
# for the next case (xfemslip.solve.shared.sharing): the kept pieces of a
# 450 x 450 mesh are a few hundred MB.
MAX_SHARED_CELLS = 200_000


@dataclass
class _Geometry:
    """The pieces of a model that depend on its geometry only, kept between
    the samples of a study (xfemslip.solve.shared.kept_value)."""

    mesh: Mesh
    fractures: tuple[Fracture, ...]
    cand: Candidates
    ec: dict  # backend -> EnrichedCells
    bulk: dict  # (backends, E, nu, model, interface points) -> BulkSystem
    bbar: dict  # the Biot load's average strain operators (fem.poro.body_load)


def _shared_geometry(spec: CaseSpec) -> tuple[_Geometry, tuple[Fracture, ...]]:
    """The geometry of a case, kept between runs of the same geometry
    within xfemslip.solve.shared.sharing (made anew outside it), and its
    fractures with this case's friction, cohesion, stiffnesses and
    weakening."""
    from xfemslip.solve.shared import kept_value

    def make() -> _Geometry:
        mesh, fractures = _geometry(spec)
        return _Geometry(mesh, fractures, find_candidates(mesh, fractures), {}, {}, {})

    cells = (spec.mesh.x.size - 1) * (spec.mesh.y.size - 1)
    geo = (
        kept_value(("geometry", geometry_key(spec)), make)
        if cells <= MAX_SHARED_CELLS
        else make()  # not kept: a large model would double the next one's memory
    )
    check_memory(spec)
    own = tuple(
        dataclasses.replace(
            fr,
            friction=fs.friction,
            cohesion=fs.cohesion,
            kn=fs.kn,
            kt=fs.kt,
            weakening=fs.weakening,
        )
        for fr, fs in zip(geo.fractures, spec.fractures, strict=True)
    )
    return geo, own


def _contact_in_situ(spec, zones, ip, eps):
    """The in-situ stress the fractures start with: ``initial_stress`` (xx,
    yy, xy) when uniform (or None), else (n_ip, 3) [Pa] at every interface
    point, the mean of its two faces (xfemslip.fem.zones.in_situ_stress)."""
    if spec.loading.in_situ is None:
        return spec.loading.initial_stress
    faces = []
    for sign in (1.0, -1.0):
        xy = ip.xy + sign * eps * ip.normal
        faces.append(in_situ_stress(spec, zones, xy, zones.at(xy)))
    return 0.5 * (faces[0] + faces[1])


def check_geometry(spec: CaseSpec) -> None:
    """What ``xfemslip check`` adds to key validation: fractures against the
    mesh and the prescribed values at boundary corners (GeometryError)."""
    from xfemslip.solve.shared import active

    # within shared.sharing (a study), the geometry checked is kept for the
    # runs of the samples
    mesh = _shared_geometry(spec)[0].mesh if active() else _geometry(spec)[0]
    with _naming_the_file(spec):
        dirichlet(mesh, spec.boundary)


def kernel_work(ec) -> float:
    """Size of the enriched-cell assembly for ``kernels.choose``: quadrature
    points of the enriched cells times (8 + 2 S)^2, S the slots per cell (the
    padded columns the NumPy backend multiplies)."""
    nd = 8 + 2 * ec.slot_node.shape[1]
    return float(ec.qp_w.size) * nd * nd


def build_model(spec: CaseSpec) -> Model:
    """Build the discrete problem of a validated case (within
    xfemslip.solve.shared.sharing, the mesh, enrichment and bulk stiffness
    of an earlier case with the same geometry and rock are reused)."""
    geo, fractures = _shared_geometry(spec)
    mesh, cand = geo.mesh, geo.cand
    mat = spec.material
    D = elasticity_matrix(mat.E, mat.nu, mat.model)
    estimate = enriched_footprint(spec, mesh, fractures, cand)
    check_memory(spec, estimate)
    # the sub-cells are cut by the backend the estimate expects the model
    # to take (kernels.choose on the estimated kernel work)
    cut = "numba" if estimate.numba else "numpy"
    if cut not in geo.ec:
        geo.ec[cut] = build_enriched_cells(mesh, fractures, cand, cut)
    ec = geo.ec[cut]
    kernel_backend = kernels.choose(spec.solver.kernels, kernel_work(ec))
    zones = build_zones(spec)
    eps = FACE_OFFSET * mesh.h_min
    breaks = loading_breaks(zones, fractures, mesh.box, eps)
    ip = interface_points(fractures, mesh.h_min, breaks)
    materials = build_materials(spec, mesh, ec, fractures)
    rock = (cut, kernel_backend, mat.E, mat.nu, mat.model, digest(ip.cell, ip.ramp))
    if not spec.units:
        if rock not in geo.bulk:
            geo.bulk[rock] = assemble_bulk(
                mesh, D, cand, ec, ip, backend=kernel_backend
            )
        bulk = geo.bulk[rock]
    else:
        bulk = assemble_bulk(
            mesh,
            materials.D,
            cand,
            ec,
            ip,
            materials.cell,
            materials.qp,
            backend=kernel_backend,
        )
    pore = build_pore_pressure(spec, materials, mesh, ec, ip, spec.fractures)
    contact = build_contact(
        mesh,
        fractures,
        ip,
        ec,
        cand,
        bulk.dofmap,
        _contact_in_situ(spec, zones, ip, eps),
        mat.E,
        spec.solver.contact_patch,
        kernels=kernel_backend,
        breaks=breaks,
    )
    with _naming_the_file(spec):
        bc = hold_enriched(dirichlet(mesh, spec.boundary), cand, bulk.dofmap)
    F = traction_load(
        mesh, spec.boundary, spec.loading, ec, cand, bulk.dofmap, fractures
    )
    pieces = None
    if pore is not None:  # Biot body load and fracture fluid load (xfemslip.fem.poro)
        make_contact_effective(contact, pore, ip)
        if not pore.later:
            F = (
                F
                + body_load(mesh, bulk, pore, ec, kernel_backend, geo.bbar)
                + fracture_load(contact, ip, pore)
            )
        else:  # several fields from a file: reached in turn (PorePressure.weights)
            pieces = (
                pore.weights,
                [
                    body_load(mesh, bulk, p, ec, kernel_backend, geo.bbar)
                    + fracture_load(contact, ip, p)
                    for p in (pore, *pore.later)
                ],
            )
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
        dof_node=bulk.dofmap.dof_node(cand.node),
        load_stress=stress_increment(spec.loading),
        load_pieces=pieces,
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
        kernels=kernel_backend,
        materials=materials,
        pore=pore,
        breaks=breaks,
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
    if not model.spec.loading.has_in_situ or not np.any(zero.state != STICK):
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


def run_case(
    spec: CaseSpec, out_dir: Path | str | None = None, *, overwrite: bool = False
) -> Result:
    """Solve a case; returns its :class:`~xfemslip.post.result.Result`.

    Parameters
    ----------
    spec : CaseSpec
        A validated case (:func:`xfemslip.load_case`).
    out_dir : folder, optional
        Where to write the output set (``result.h5``, and the VTU/PVD files
        the case's ``output.formats`` call for), swapped in whole; None writes
        nothing (the command line passes ``-o`` or ``output.directory``).
    overwrite : bool
        Replace the results of an earlier run in ``out_dir``.

    Returns
    -------
    Result : the mesh, the fields of every load step and the run's attributes
    (those of ``result.h5``); ``out_dir`` is the folder written, or None.

    Raises
    ------
    ConvergenceError when a load step fails, after writing the converged
    steps (``converged = false``); its ``result`` holds them.  UsageError when
    ``spec`` is not a CaseSpec (a path, a dict, None: load it with
    :func:`xfemslip.load_case` first), or ``out_dir`` holds results and
    ``overwrite`` is False.
    """
    require_spec(spec, "run_case")
    done = solve_and_write(
        spec, out_dir, overwrite, lambda solver, _: solver.run(spec.loading.steps)
    )
    if done.failure is not None:
        done.failure.result = done.result  # the steps that converged
        raise done.failure
    logger.info("Newton iterations per load step: %s", done.result.iterations_per_step)
    return done.result


def require_spec(spec, function: str) -> None:
    """UsageError unless ``spec`` is a CaseSpec (the one thing the solve
    entry points take: a case that went through the case loader)."""
    if isinstance(spec, CaseSpec):
        return
    kind = type(spec).__name__
    shown = repr(spec) if isinstance(spec, str | Path) else kind
    hint = (
        f"; load it first: {function}(xfemslip.load_case({shown}))"
        if isinstance(spec, str | Path)
        else ""
    )
    raise UsageError(
        f"{function} needs a CaseSpec from xfemslip.load_case(path), got {kind}{hint}"
    )


@dataclass
class Written:
    """What solve_and_write built, solved and wrote."""

    out_dir: Path | None  # the output folder (None: nothing written)
    model: Model
    results: list  # the converged StepResults (solver.completed)
    value: object  # what ``drive`` returned (None after a failure)
    failure: ConvergenceError | None
    result: Result  # the fields of the results (those written)


def solve_and_write(
    spec, out_dir, overwrite, drive, finish=None, step_time=None, annotate=None
) -> Written:
    """The frame of every command that solves a case: take the output folder
    (:func:`xfemslip.io.results.run_folder`: locked, refused when it holds
    results and not ``overwrite``; ``out_dir`` None: no folder, nothing
    written), build the model and its Newton solver, run ``drive(solver,
    model)``, and write the converged steps (also after a ConvergenceError,
    which is returned, not raised, with converged = False in result.h5).
    ``finish(written, folder)`` may add files of its own to the set in
    ``folder``; the set replaces the folder's content whole.  ``step_time``
    maps a load factor to the time of the ParaView series (default: itself).
    ``annotate(result, model)`` may add to the result before it is written
    (what ``deplete`` found: ``Result.depletion``)."""
    start = time.perf_counter()
    spec = case_of_record(spec)  # a spec changed in Python records its own text
    folder = (
        run_folder(out_dir, overwrite)
        if out_dir is not None
        else contextlib.nullcontext()
    )
    with folder as stage:
        model = build_model(spec)
        if not sharing_active():  # kept for the next case within sharing
            # assembled and loaded: the solve and the output read the
            # enrichment's sub-triangles, not its values at the points
            model = dataclasses.replace(model, ec=model.ec.without_point_values())
        solver = newton_solver(model)
        value = failure = None
        try:
            with solver.linear.blas_threads():
                value = drive(solver, model)
        except ConvergenceError as exc:
            failure = exc
        interrupt.checkpoint()  # a signal swallowed while solving ends it here
        results = solver.completed
        with interrupt.deferred():
            result, bad = collect_result(
                model,
                results,
                converged=failure is None,
                wall=time.perf_counter() - start,
            )
            failure = bad or failure
            if annotate is not None:
                annotate(result, model)
            if stage is None:
                return Written(None, model, results, value, failure, result)
            write_results(
                stage.path,
                result,
                formats=spec.output.formats,
                vis_mesh=lambda i: vis_mesh_with_faces(model, results[i].u),
                fracture_ids=[fr.index for fr in model.fractures],
                step_time=step_time,
            )
            result.out_dir = Path(out_dir)
            done = Written(result.out_dir, model, results, value, failure, result)
            if finish is not None:
                finish(done, stage.path)
    return done


def _depth_datum(spec: CaseSpec) -> float | None:
    """The y [m] of zero depth of a case whose state varies with depth."""
    if spec.loading.in_situ is not None:
        return spec.loading.in_situ.datum
    pore = spec.pore_pressure
    if pore is not None and pore.gradient != 0.0:
        return pore.datum
    return None


def collect_result(model: Model, results, *, converged, wall):
    """The Result of the converged steps ``results`` and, when a step holds
    NaN or inf, the ConvergenceError that says so (the finite steps before it
    are kept, converged = False), else None."""
    spec = model.spec
    fields = [step_fields(model, r) for r in results]
    iterations = [r.iterations for r in results]
    cuts = [r.cuts for r in results]
    bad = first_non_finite(fields)
    if bad is not None:  # never write NaN/inf: keep the finite steps only
        index = bad[0]
        fields, iterations, cuts, converged = (
            fields[:index],
            iterations[:index],
            cuts[:index],
            False,
        )
    attrs = {
        "format_version": 1,
        "xfemslip_version": __version__,
        "case_toml": spec.text,
        "converged": bool(converged),
        # the case's steps, or more: the states of a followed path
        "load_steps": int(max(spec.loading.steps, len(fields))),
        "newton_iterations": int(sum(iterations)),
        "newton_iterations_per_step": np.array(iterations, dtype=np.int64),
        # load-step bisections per written step (0 = not cut)
        "load_step_cuts_per_step": np.array(cuts, dtype=np.int64),
        "wall_time_s": float(wall),
        "tangent": spec.solver.tangent,
        "contact_patch_cells": float(spec.solver.contact_patch),
        "n_dofs": int(model.problem.n_dofs),
        "kernels": model.kernels,
        "status_codes": STATE_CODES,
        "material_model": spec.material.model,
    }
    datum = _depth_datum(spec)
    if datum is not None:  # profiles give depths below it (xfemslip.post.profile)
        attrs["depth_datum"] = float(datum)
    attrs["run_id"] = run_id(attrs, model.mesh.nodes, model.mesh.cells, fields)
    result = Result(attrs, model.mesh.nodes, model.mesh.cells, fields)
    # of the case and derived from the fields, so outside run_id
    result.fracture_properties = fracture_properties(model)
    result.events = event_table(result, event_inputs(result, spec))
    add_permeability(result, spec)
    if bad is None:
        return result, None
    step = bad[0] + 1
    error = ConvergenceError(
        f"load step {step} gave a non-finite {bad[1]} (NaN or inf), which is "
        f"not written; {len(fields)} finite step(s) kept. Lower the penalty "
        "stiffnesses kn/kt or use more load steps",
        step=step,
        iteration=0,
        residual=float("nan"),
    )
    return result, error
