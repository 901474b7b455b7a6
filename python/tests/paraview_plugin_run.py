"""Run by pvbatch with the compiled plugin on PV_PLUGIN_PATH: describes the Orthofront Stream
Surface filter's properties and runs it on WORK/helix.vti, and the path and streak filters on
the series WORK/frame0.vti ... frame5.vti. Writes WORK/plugin.json and the surfaces as .vtp
files."""

import json
import sys

from paraview import servermanager as sm
from paraview.simple import (OrthofrontPathSurface, OrthofrontStreakSurface,
                             OrthofrontStreamSurface, SaveData, XMLImageDataReader)

work = sys.argv[1]
reader = XMLImageDataReader(FileName=[work + "/helix.vti"])
reader.UpdatePipeline()
surface = OrthofrontStreamSurface(Input=reader)
result = {"vectors": list(surface.Vectors), "properties": {}}


def describe(proxy):
    """Each property's documentation, domains and raw elements."""
    properties = {}
    for name in proxy.ListProperties():
        properties[name] = describe_property(proxy.GetProperty(name))
    return properties


def describe_property(prop):
    smp = prop.SMProperty
    doc = smp.GetDocumentation()
    domains = []
    it = smp.NewDomainIterator()
    it.Begin()
    while not it.IsAtEnd():
        domain = it.GetDomain()
        entry = {"class": domain.GetClassName()}
        if domain.IsA("vtkSMDoubleRangeDomain") or domain.IsA("vtkSMIntRangeDomain"):
            entry["min"] = domain.GetMinimum(0) if domain.GetMinimumExists(0) else None
            entry["max"] = domain.GetMaximum(0) if domain.GetMaximumExists(0) else None
        if domain.IsA("vtkSMEnumerationDomain"):
            entry["entries"] = [domain.GetEntryText(i) for i in range(domain.GetNumberOfEntries())]
        domains.append(entry)
        it.Next()
    value = None  # the raw elements, as the server manager holds them
    if smp.IsA("vtkSMVectorProperty"):
        value = [smp.GetElement(i) for i in range(smp.GetNumberOfElements())]
        value = value[0] if len(value) == 1 else value
    return {
        "xml_name": smp.GetXMLName(),
        "documentation": doc.GetDescription() if doc is not None else "",
        "domains": domains,
        "value": value,
    }


result["properties"] = describe(surface)


def run(out, **properties):
    for key, value in properties.items():
        setattr(surface, key, value)
    surface.UpdatePipeline()
    data = sm.Fetch(surface)
    report = data.GetFieldData().GetAbstractArray("orthofront_report")
    SaveData(out, proxy=surface, DataMode="Ascii")
    field_data = data.GetFieldData()
    notes = {field_data.GetAbstractArray(i).GetName(): field_data.GetAbstractArray(i).GetValue(0)
             for i in range(field_data.GetNumberOfArrays())}
    return {"points": data.GetNumberOfPoints(), "cells": data.GetNumberOfCells(),
            "report": json.loads(report.GetValue(0)) if report is not None else None,
            "notes": notes}


seed = dict(SeedPoint1=[0.5, 0.0, 0.2], SeedPoint2=[1.5, 0.0, 0.2], SeedCount=8, Steps=20)
result["given_edge"] = run(work + "/plugin-edge.vtp", Edge=0.15, **seed)
result["cell_edge"] = run(work + "/plugin-cell.vtp", Edge=0.0, **seed)
result["bad_edge"] = run(work + "/plugin-bad.vtp", Edge=-1.0, **seed)
# A rectilinear grid (z spacing growing): the helix field v = (-y, x, 1) at its points.
import numpy as np
from paraview.simple import PVTrivialProducer
from vtkmodules.util import numpy_support
from vtkmodules.vtkCommonDataModel import vtkRectilinearGrid
axes = [np.linspace(-2.0, 2.0, 9), np.linspace(-2.0, 2.0, 9), 4.0 * np.linspace(0.0, 1.0, 9) ** 1.5]
rectilinear = vtkRectilinearGrid()
rectilinear.SetDimensions(9, 9, 9)
for setter, axis in zip((rectilinear.SetXCoordinates, rectilinear.SetYCoordinates,
                         rectilinear.SetZCoordinates), axes):
    setter(numpy_support.numpy_to_vtk(axis.copy(), deep=1))
zz, yy, xx = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
velocity = np.stack([-yy, xx, np.ones_like(xx)], axis=-1).reshape(-1, 3).astype(np.float32)
array = numpy_support.numpy_to_vtk(velocity, deep=1)
array.SetName("velocity")
rectilinear.GetPointData().AddArray(array)
producer = PVTrivialProducer()
producer.GetClientSideObject().SetOutput(rectilinear)
producer.UpdatePipeline()
on_rectilinear = OrthofrontStreamSurface(Input=producer, Vectors=["POINTS", "velocity"], Edge=0.15,
                                         **seed)
on_rectilinear.UpdatePipeline()
SaveData(work + "/plugin-rectilinear.vtp", proxy=on_rectilinear, DataMode="Ascii")

# A series of files: ParaView numbers them 0, 1, 2, ...
frames = XMLImageDataReader(FileName=[work + "/frame%d.vti" % i for i in range(6)])
frames.UpdatePipeline(0)
# The properties as a new filter has them.
result["path_properties"] = describe(OrthofrontPathSurface(Input=frames))
result["streak_properties"] = describe(OrthofrontStreakSurface(Input=frames))
seed2 = dict(SeedPoint1=[0.2, 0.2, 0.0], SeedPoint2=[0.2, 0.6, 0.0], SeedCount=9)
path = OrthofrontPathSurface(Input=frames, Vectors=["POINTS", "velocity"], Edge=0.1, T0="0",
                             T1="3", **seed2)
path.UpdatePipeline()
SaveData(work + "/plugin-path.vtp", proxy=path, DataMode="Ascii")
result["path"] = json.loads(
    sm.Fetch(path).GetFieldData().GetAbstractArray("orthofront_report").GetValue(0))
streak = OrthofrontStreakSurface(Input=frames, Vectors=["POINTS", "velocity"], Edge=0.05,
                                 Release="0:1", Frames="2,3", **seed2)
streak.UpdatePipelineInformation()
result["streak_times"] = list(streak.TimestepValues)
for t in result["streak_times"]:
    streak.UpdatePipeline(t)
    SaveData(work + "/plugin-streak-%g.vtp" % t, proxy=streak, DataMode="Ascii")
# Left at their defaults (empty), release and frames are the input's whole range and its steps.
streak_default = OrthofrontStreakSurface(Input=frames, Vectors=["POINTS", "velocity"], Edge=0.1,
                                         **seed2)
streak_default.UpdatePipelineInformation()
result["streak_default_times"] = list(streak_default.TimestepValues)
with open(work + "/plugin.json", "w") as file:
    json.dump(result, file)
