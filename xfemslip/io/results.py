"""The output set of a run: ``result.h5`` and the ParaView files, in one folder.

``run_folder(out_dir, overwrite)`` takes the output folder (locked, refused
when it holds results of an earlier run and not ``overwrite``; the set is
swapped in whole, :mod:`xfemslip.io.folder`); ``write_results`` writes a
:class:`~xfemslip.post.result.Result` into its staging folder:

- ``result.h5`` (:mod:`xfemslip.io.hdf5`), always;
- with ``"csv"`` in ``output.formats``: ``profile.csv``, the profiles of
  the fractures at every step (:mod:`xfemslip.post.profile`), when the
  case has a fracture;
- with ``"vtu"`` in the case's ``output.formats`` (the ParaView files) and
  at least one converged step: ``result.xdmf`` (and ``result_steps.xdmf``
  with more than one load step) describing ``result.h5``
  (:mod:`xfemslip.io.xdmf`), ``result.vtu`` and ``fractures.vtu`` of the
  final step and, with more than one load step, ``steps/result_<kkkk>.vtu``
  (and fractures) per step and the series ``result.pvd`` (bulk) and
  ``fractures.pvd`` (:mod:`xfemslip.io.vtu`).

The time of the series is the load factor, or what ``step_time`` makes of it
(``deplete``: the pore-pressure change reached).

Every file carries the set's ``run_id``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

from xfemslip import interrupt
from xfemslip.io import hdf5
from xfemslip.io.csv import write_rows
from xfemslip.io.folder import RUN_FILES, output_folder
from xfemslip.post.fields import VisMesh, stress_for_paraview
from xfemslip.post.profile import PROFILE_COLUMNS, profile_rows
from xfemslip.post.result import Result

__all__ = ["OUTPUT_FILES", "run_folder", "write_results"]

OUTPUT_FILES = RUN_FILES


def run_folder(out_dir: Path | str, overwrite: bool):
    """The output folder of a run as a context manager yielding its Staging."""
    return output_folder(out_dir, overwrite=overwrite, results=OUTPUT_FILES)


def write_results(
    folder: Path,
    result: Result,
    *,
    formats: Sequence[str],
    vis_mesh: Callable[[int], VisMesh],
    fracture_ids: Sequence[int],
    step_time: Callable[[float], float] | None = None,
) -> None:
    """Write the output set of ``result`` into ``folder``.

    formats : the case's ``output.formats`` ("h5" always, "vtu" optional);
    vis_mesh : the split visualisation mesh of step ``i`` (0-based index into
        ``result.steps``), built only when a VTU file is written;
    fracture_ids : the case-file index of each fracture of the steps;
    step_time : the time of a step in the PVD and XDMF series, from its load
        factor (default: the load factor itself).
    """
    from xfemslip.io.xdmf import write_xdmf

    hdf5.write_result(
        folder / "result.h5",
        points=result.points,
        cells=result.cells,
        steps=result.steps,
        attrs=result.attrs,
        load_steps=result.load_steps,
        events=result.events,
        permeability=result.permeability,
        properties=result.fracture_properties,
        depletion=result.depletion,
    )
    if "csv" in formats and result.steps and result.steps[0].fractures:
        write_rows(folder / "profile.csv", PROFILE_COLUMNS, profile_rows(result))
    if "vtu" in formats and result.steps:
        # the ParaView files: those of the split mesh, and the description
        # of result.h5 that lets ParaView read it
        write_xdmf(folder, "result.h5", step_time=step_time)
        _write_vtu(folder, result, vis_mesh, fracture_ids, step_time)


def _write_vtu(folder, result, vis_mesh, fracture_ids, step_time) -> None:
    """The VTU (and PVD) files of the converged steps, stamped with run_id."""
    # here, not at the top: meshio costs 0.3 s of imports that a run writing
    # result.h5 alone does not pay
    from xfemslip.io import vtu

    series = result.load_steps > 1
    set_id = result.run_id
    entries, fracture_entries = [], []
    last = len(result.steps) - 1
    for i, f in enumerate(result.steps):
        interrupt.checkpoint()  # between files: a deferred signal stops here
        cell_data = {
            "stress": f.stress,
            "stress_zz": f.stress_zz,
            "principal_stress": f.principal_stress,
            **stress_for_paraview(f.stress, f.stress_zz),
        }
        if f.effective_stress is not None:
            cell_data["effective_stress"] = f.effective_stress
            cell_data["pore_pressure"] = f.pore_pressure
        fr = list(zip(fracture_ids, f.fractures, strict=True))
        names = []
        if series:
            (folder / "steps").mkdir(exist_ok=True)
            names.append(f"steps/%s_{f.step:04d}.vtu")
            time = f.load_factor if step_time is None else step_time(f.load_factor)
            entries.append((time, f"steps/result_{f.step:04d}.vtu"))
        if i == last:
            names.append("%s.vtu")
        vis = vis_mesh(i)
        for name in names:
            vtu.write_bulk(folder / (name % "result"), vis, cell_data, run_id=set_id)
            written = fr and vtu.write_fractures(
                folder / (name % "fractures"), fr, faces=vis.faces, run_id=set_id
            )
            if written and name.startswith("steps/"):
                fracture_entries.append((time, name % "fractures"))
    if series:
        vtu.write_pvd(folder / "result.pvd", entries, run_id=set_id)
        if fracture_entries:
            vtu.write_pvd(folder / "fractures.pvd", fracture_entries, run_id=set_id)
