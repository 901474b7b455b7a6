"""Run by pvbatch from test_paraview.py: loads the plugin, runs each filter on the files the test
wrote, and records the outputs' counts and a screenshot.

    pvbatch paraview_run_filters.py WORKDIR
"""

import json
import sys

from paraview import servermanager
from paraview.simple import (ColorBy, GetActiveViewOrCreate, Line, Render, ResetCamera,
                             SaveScreenshot, Show, UpdatePipeline, XMLImageDataReader)

import orthofront.paraview_plugin

work = sys.argv[1]
orthofront.paraview_plugin.load(globals())


def counts(proxy, time=None):
    UpdatePipeline(time=time, proxy=proxy)
    data = servermanager.Fetch(proxy)
    quads = sum(1 for i in range(data.GetNumberOfCells()) if data.GetCell(i).GetNumberOfPoints() == 4)
    arrays = sorted(data.GetPointData().GetArrayName(i)
                    for i in range(data.GetPointData().GetNumberOfArrays()))
    bounds = data.GetBounds()
    return {"points": data.GetNumberOfPoints(), "cells": data.GetNumberOfCells(), "quads": quads,
            "arrays": arrays, "bounds": list(bounds)}


result = {}
helix = XMLImageDataReader(FileName=[work + "/helix.vti"])
seed3 = Line(Point1=[0.5, 0.0, 0.2], Point2=[1.5, 0.0, 0.2], Resolution=7)
stream = FlowOrthogonalStreamSurface(Input=helix, Seeds=seed3)
stream.SeedCount = 8
stream.Edge = 0.15
stream.Steps = 20
result["stream"] = counts(stream)
# Edge left at 0: the input's cell size, as the command line does without --edge.
cell_sized = FlowOrthogonalStreamSurface(Input=helix, Seeds=seed3)
cell_sized.SeedCount = 8
cell_sized.Steps = 20
result["stream_cell_edge"] = counts(cell_sized)

frames = XMLImageDataReader(FileName=[work + "/frame%d.vti" % i for i in range(6)])
seed2 = Line(Point1=[0.2, 0.2, 0.0], Point2=[0.2, 0.6, 0.0], Resolution=8)
path = PathSurface(Input=frames, Seeds=seed2)
path.SeedCount = 9
path.Edge = 0.1
path.T0 = 0
path.T1 = 3
result["path"] = counts(path)

streak = StreakSurface(Input=frames, Seeds=seed2)
streak.Release = [0.0, 1.0]
streak.Frames = "2,3"
streak.Edge = 0.05
streak.Options = "seed_count=9"  # any other option of the command line, by name
streak.UpdatePipelineInformation()
result["streak_times"] = list(streak.TimestepValues)
result["streak"] = {str(t): counts(streak, t) for t in (2.0, 3.0)}

view = GetActiveViewOrCreate("RenderView")
view.ViewSize = [800, 600]
view.Background = [1, 1, 1]
try:
    view.UseColorPaletteForBackground = 0
except AttributeError:
    pass
display = Show(stream, view)
ColorBy(display, ("POINTS", "time"))
display.SetRepresentationType("Surface With Edges")
ResetCamera(view)
Render(view)
SaveScreenshot(work + "/stream.png", view, ImageResolution=[800, 600])

with open(work + "/result.json", "w") as file:
    json.dump(result, file)
