"""Render the Liu-Borja plate as ParaView shows it: result.pvd warped by its
displacement and coloured by von Mises, with fractures.pvd warped alike and
coloured by slip (not run in CI).

    xfemslip run cases/liu_borja_plate.toml -o out/plate
    xvfb-run -a pvpython docs/figures/paraview/screenshot.py out/plate \
        docs/figures/paraview/plate_von_mises.png 1

(Where xvfb-run finds no display, start one: `Xvfb :77 &` and run pvpython
with DISPLAY=:77.)  Nothing but "Warp By Vector" between the files and the
picture.
"""

import sys
from pathlib import Path

from paraview.simple import (
    ColorBy,
    CreateView,
    GetAnimationScene,
    GetColorTransferFunction,
    GetScalarBar,
    OpenDataFile,
    Render,
    SaveScreenshot,
    Show,
    WarpByVector,
)

folder, png = Path(sys.argv[1]), sys.argv[2]
scale = float(sys.argv[3]) if len(sys.argv) > 3 else 2.0

view = CreateView("RenderView")
view.ViewSize = [1200, 1000]
view.OrientationAxesVisibility = 0
view.Background = [1.0, 1.0, 1.0]
try:
    view.UseColorPaletteForBackground = 0
except AttributeError:
    pass

body = WarpByVector(Input=OpenDataFile(str(folder / "result.pvd")))
body.Vectors = ["POINTS", "displacement"]
body.ScaleFactor = scale
shown = Show(body, view)
ColorBy(shown, ("CELLS", "von_mises"))
shown.SetScalarBarVisibility(view, True)
lut = GetColorTransferFunction("von_mises")
lut.ApplyPreset("Viridis (matplotlib)", True)
cracks = WarpByVector(Input=OpenDataFile(str(folder / "fractures.pvd")))
cracks.Vectors = ["POINTS", "displacement"]
cracks.ScaleFactor = scale
lines = Show(cracks, view)
ColorBy(lines, ("POINTS", "slip"))
lines.LineWidth = 4.0
lines.SetScalarBarVisibility(view, True)
GetColorTransferFunction("slip").ApplyPreset("Cool to Warm", True)

for name, title in (("von_mises", "von Mises [Pa]"), ("slip", "slip [m]")):
    bar = GetScalarBar(GetColorTransferFunction(name), view)
    bar.Title, bar.ComponentTitle = title, ""
    bar.TitleColor = bar.LabelColor = [0.0, 0.0, 0.0]
    bar.TitleFontSize = bar.LabelFontSize = 20

scene = GetAnimationScene()
scene.UpdateAnimationUsingDataTimeSteps()
times = list(scene.TimeKeeper.TimestepValues)
scene.GoToLast()  # the last load step
for item in (shown, lines):
    item.RescaleTransferFunctionToDataRange(False, True)
view.ResetCamera()
view.CameraPosition = [0.5, 0.5, 4.0]
view.CameraFocalPoint = [0.5, 0.5, 0.0]
view.CameraViewUp = [0.0, 1.0, 0.0]
view.ResetCamera()
Render(view)
SaveScreenshot(png, view, ImageResolution=[1200, 1000])
print("time steps", list(times))
