"""Makes docs/figures/paraview_xdmf.png: ParaView opening a case's XDMF file (knotflow-xdmf).

    xvfb-run -a python3 docs/figures/paraview_xdmf.py results/demo/A1.40_orb.xdmf2 \
        docs/figures/paraview_xdmf.png [frame]

Needs ParaView's Python (pvpython, or Debian's python3-paraview) and, without a display, an X
server such as Xvfb (Debian xvfb: xvfb-run, or `Xvfb :95 &` and DISPLAY=:95).  The XDMF polyline is turned into surface polygons (Extract Surface)
so that the Tube filter can thicken it; colour: the point data 'half'.
"""
import sys

from paraview.simple import (ColorBy, CreateRenderView, ExtractSurface, GetColorTransferFunction,
                             GetParaViewVersion, OpenDataFile, Render, SaveScreenshot, Show, Text,
                             Tube)

src, out = sys.argv[1], sys.argv[2]
frame = int(sys.argv[3]) if len(sys.argv) > 3 else 3
reader = OpenDataFile(src)                      # ParaView picks its Xdmf Reader for .xdmf2
reader.UpdatePipelineInformation()
t = reader.TimestepValues[frame]
view = CreateRenderView()
view.ViewSize = [800, 600]
view.ViewTime = t
tube = Tube(Input=ExtractSurface(Input=reader))
tube.Radius = 0.5
tube.UpdatePipeline(t)
shown = Show(tube, view)
ColorBy(shown, ("POINTS", "half"))
GetColorTransferFunction("half").ApplyPreset("Rainbow Uniform", True)
view.CameraPosition = [60, 60, 50]
view.CameraFocalPoint = [0, 0, 0]
view.CameraViewUp = [0, 0, 1]
view.ResetCamera()
Render(view)
version = GetParaViewVersion()
Show(Text(Text=f"ParaView {version.major}.{version.minor}: {src.split('/')[-1]}, t = {t:g}, "
               "colour: half"), view)
SaveScreenshot(out, view, ImageResolution=[800, 600])
print(out)
