"""Open every ParaView file of some output folders in ParaView, warp each by
its displacement and print what ParaView sees (not run in CI):

    xvfb-run -a pvpython docs/figures/paraview/open_every_output.py out/*/

One line per file: the number of time steps and the first and last time, the
components of `displacement`, whether Warp By Vector moved the data, and
whether the cells carry `von_mises` and the 6-component `stress_tensor`.
The XDMF files are read with ParaView's "XDMF Reader" (docs/paraview.md).
"""

import sys
from pathlib import Path

from paraview.simple import Delete, OpenDataFile, WarpByVector, XDMFReader

NAMES = (
    "result.vtu",
    "fractures.vtu",
    "result.pvd",
    "fractures.pvd",
    "result.xdmf",
    "result_steps.xdmf",
)

for folder in map(Path, sys.argv[1:]):
    for name in NAMES:
        path = folder / name
        if not path.exists():
            continue
        if path.suffix == ".xdmf":
            reader = XDMFReader(FileNames=[str(path)])
            reader.UpdatePipelineInformation()
            reader.PointArrayStatus = reader.GetProperty("PointArrayInfo")[::2]
            reader.CellArrayStatus = reader.GetProperty("CellArrayInfo")[::2]
        else:
            reader = OpenDataFile(str(path))
        times = list(getattr(reader, "TimestepValues", None) or [])
        last = times[-1] if times else 0.0
        reader.UpdatePipeline(last)
        warp = WarpByVector(Input=reader)
        warp.Vectors = ["POINTS", "displacement"]
        warp.UpdatePipeline(last)
        points = {a.GetName(): a.GetNumberOfComponents() for a in reader.PointData}
        cells = {a.GetName(): a.GetNumberOfComponents() for a in reader.CellData}
        moved = warp.GetDataInformation().GetBounds() != (
            reader.GetDataInformation().GetBounds()
        )
        print(
            f"{folder.name} {name}: {len(times)} steps"
            + (f" ({times[0]:g} .. {times[-1]:g})" if times else "")
            + f", displacement {points.get('displacement')} components"
            + f", warped {moved}, von_mises {'von_mises' in cells}"
            + f", stress_tensor {cells.get('stress_tensor')}"
        )
        Delete(warp)
        Delete(reader)
