# paraview_picture.py -- one frame of a VTU series written by lpfdm (OUTPUT VTU), drawn by
# ParaView: the points as Point Gaussian splats coloured by plastic shear strain `ep`, with
# a colour bar and the model time. Run with ParaView's Python; no window opens, but a
# ParaView that renders through X (Debian's) needs a display, which xvfb-run gives:
#
#   xvfb-run -a -s "-noreset -screen 0 1280x1024x24" pvpython tools/paraview_picture.py SERIES.pvd OUT.png [TIME] [EPMAX]
#   pvpython --force-offscreen-rendering tools/paraview_picture.py ...   (an EGL or OSMesa build)
#
# TIME: the frame at or before this model time in seconds (default: the last frame);
# EPMAX: the top of the colour scale (default: the frame's 98th percentile of ep, so that a
# few points sheared far more than the rest do not wash out the shear bands).
# tools/README.md gives the command that drew tools/cliff_paraview.png.
import sys

import numpy

from paraview import servermanager
from paraview.simple import (AnnotateTimeFilter, GetActiveViewOrCreate, GetColorTransferFunction,
                             GetScalarBar, PVDReader, SaveScreenshot, Show)
from vtk.numpy_interface import dataset_adapter

if len(sys.argv) not in (3, 4, 5):
    sys.exit("usage: pvpython tools/paraview_picture.py SERIES.pvd OUT.png [TIME] [EPMAX]")
series, png = sys.argv[1], sys.argv[2]

reader = PVDReader(FileName=series)
times = list(reader.TimestepValues) or [0.0]
time = times[-1]
if len(sys.argv) >= 4:
    earlier = [t for t in times if t <= float(sys.argv[3]) + 1e-9]
    time = earlier[-1] if earlier else times[0]
reader.UpdatePipeline(time)

view = GetActiveViewOrCreate("RenderView")
view.ViewSize = [1000, 480]
view.ViewTime = time
view.OrientationAxesVisibility = 0
view.Background = [1, 1, 1]
if hasattr(view, "UseColorPaletteForBackground"):
    view.UseColorPaletteForBackground = 0

points = Show(reader, view)
points.SetRepresentationType("Point Gaussian")
points.ShaderPreset = "Plain circle"
# The splat radius from the points' spacing: the frame's area over its number of points.
frame = dataset_adapter.WrapDataObject(servermanager.Fetch(reader))
ep_values = frame.PointData["ep"]
xmin, xmax, ymin, ymax = frame.GetBounds()[:4]
points.GaussianRadius = 0.4 * ((xmax - xmin) * (ymax - ymin) / max(len(ep_values), 1)) ** 0.5
points.ColorArrayName = ["POINTS", "ep"]
ep = GetColorTransferFunction("ep")
ep.ApplyPreset("Viridis (matplotlib)", True)
top = float(sys.argv[4]) if len(sys.argv) == 5 else float(numpy.percentile(ep_values, 98))
ep.RescaleTransferFunction(0.0, max(top, 1e-12))
ep.AutomaticRescaleRangeMode = "Never"

bar = GetScalarBar(ep, view)
bar.Title = "ep, plastic shear strain"
bar.ComponentTitle = ""
bar.Visibility = 1
bar.WindowLocation = "Any Location"
bar.Orientation = "Vertical"
bar.Position = [0.86, 0.2]
bar.ScalarBarLength = 0.6
bar.TitleColor = bar.LabelColor = [0, 0, 0]
bar.TitleFontSize = bar.LabelFontSize = 14
bar.RangeLabelFormat = "%-#.2g"

clock = AnnotateTimeFilter(reader)
# ParaView 5.10 and later format with Python's str.format, earlier ones with printf.
clock.Format = "t = {time:.2f} s" if "{" in clock.Format else "t = %.2f s"
label = Show(clock, view)
label.WindowLocation = "Upper Left Corner"
label.FontSize = 18
label.Color = [0, 0, 0]

# Parallel projection onto the x-y plane, the points filling the width left of the colour bar.
view.InteractionMode = "2D"
view.ResetCamera()
width, height = view.ViewSize
half = 1.15 * max((ymax - ymin) / 2, (xmax - xmin) / 2 / (0.8 * width / height))
cx = (xmin + xmax) / 2 + half * width / height * 0.15
cy = (ymin + ymax) / 2 + half * 0.05
view.CameraPosition = [cx, cy, 10 * half]
view.CameraFocalPoint = [cx, cy, 0]
view.CameraViewUp = [0, 1, 0]
view.CameraParallelProjection = 1
view.CameraParallelScale = half
SaveScreenshot(png, view, ImageResolution=view.ViewSize, CompressionLevel="9")
print("wrote %s: %s at t = %g s (%d frames), ep up to %g" % (png, series, time, len(times), top))
