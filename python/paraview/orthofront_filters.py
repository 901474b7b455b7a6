"""ParaView filters of orthofront: "Flow-Orthogonal Stream Surface", "Path Surface" and "Streak
Surface" (Filters > orthofront), built on the `orthofront` Python module.

Load it with Tools > Manage Plugins > Load New (or LoadPlugin(path, ns=globals()) in pvpython),
with the module on PYTHONPATH (the build's python/ folder; this file's parent folder is added
when ParaView gives the plugin its path).

Inputs: vtkImageData with a point vector array (for path and streak surfaces, a time series
reader's output: every time step is read), and a seed: the points of a line or polyline source,
in order. Properties mirror the command-line options; "Options" takes any other option as
`name=value` pairs (the command line's names with '_' for '-'). Output: vtkPolyData with every
per-vertex attribute; a streak surface has one time step per observation time.
"""

import os
import sys

try:  # the module sits beside this plugin's folder in the build
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
except NameError:
    pass

import numpy as np
from paraview.util.vtkAlgorithm import smdomain, smhint, smproperty, smproxy
from vtkmodules.util import numpy_support
from vtkmodules.util.vtkAlgorithm import VTKPythonAlgorithmBase
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkImageData, vtkPolyData
from vtkmodules.vtkCommonExecutionModel import vtkStreamingDemandDrivenPipeline

import orthofront

MENU = '<ShowInMenu category="orthofront" />'


def _vector_array(image, name):
    """The named point array, or the first one with 2 or 3 components."""
    data = image.GetPointData()
    if name:
        array = data.GetArray(name)
        if array is None:
            raise ValueError("the input has no point array '%s'" % name)
        return array
    for i in range(data.GetNumberOfArrays()):
        array = data.GetArray(i)
        if array is not None and array.GetNumberOfComponents() in (2, 3):
            return array
    raise ValueError("the input has no point vector array (2 or 3 components)")


def image_to_grid(image, name=""):
    """(values, origin, spacing) of a vtkImageData in orthofront's layout: (ny, nx, 2) when the
    image is one slice thick, (nz, ny, nx, 3) otherwise."""
    nx, ny, nz = image.GetDimensions()
    array = numpy_support.vtk_to_numpy(_vector_array(image, name)).astype(np.float32)
    components = array.shape[1] if array.ndim == 2 else 1
    origin, spacing = image.GetOrigin(), image.GetSpacing()
    if nz == 1:
        values = array.reshape(ny, nx, components)[..., :2]
        return np.ascontiguousarray(values), origin[:2], spacing[:2]
    if components != 3:
        raise ValueError("a 3D image needs 3 vector components, got %d" % components)
    return array.reshape(nz, ny, nx, 3), origin, spacing


def seed_points(polydata):
    """The seed's points in order: the first line or polyline cell, else all points."""
    points = numpy_support.vtk_to_numpy(polydata.GetPoints().GetData()).astype(np.float64)
    lines = polydata.GetLines()
    if lines is not None and lines.GetNumberOfCells() > 0:
        ids = numpy_support.vtk_to_numpy(lines.GetConnectivityArray())
        offsets = numpy_support.vtk_to_numpy(lines.GetOffsetsArray())
        if lines.GetNumberOfCells() == 1:
            return points[ids[offsets[0]:offsets[1]]]
    return points


def surface_to_polydata(surface, output, positions=None):
    vertices = surface.vertices if positions is None else positions
    points = vtkPoints()
    points.SetData(numpy_support.numpy_to_vtk(np.ascontiguousarray(vertices), deep=True))
    output.SetPoints(points)
    faces = surface.faces
    sizes = np.where(faces[:, 3] >= 0, 4, 3)
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    cells = vtkCellArray()
    cells.SetData(numpy_support.numpy_to_vtkIdTypeArray(offsets, deep=True),
                  numpy_support.numpy_to_vtkIdTypeArray(faces[faces >= 0].astype(np.int64),
                                                        deep=True))
    output.SetPolys(cells)
    for name, values in surface.attributes.items():
        array = numpy_support.numpy_to_vtk(np.ascontiguousarray(values), deep=True)
        array.SetName(name)
        output.GetPointData().AddArray(array)
    if "time" in surface.attributes:
        output.GetPointData().SetActiveScalars("time")


def parse_options(text):
    """"mu_mode=paper tolerance=1e-8" -> {"mu_mode": "paper", "tolerance": "1e-8"}."""
    options = {}
    for item in (text or "").replace(",", " ").split():
        name, equals, value = item.partition("=")
        if not equals:
            options[name] = True
        else:
            options[name] = value
    return options


# Edge: 0 (the default) takes the input grid's cell size, as the command line does without
# --edge; the value is in the input's length unit.
_EDGE_DOMAIN = ('<DoubleRangeDomain name="range" min="0"/><Documentation>Target edge length of '
                'the mesh, in the input\'s length unit; 0: the input grid\'s cell size.'
                '</Documentation>')


class _SurfaceFilter(VTKPythonAlgorithmBase):
    """Two inputs (field, seed), one polydata output; properties kept in self._options."""

    def __init__(self):
        VTKPythonAlgorithmBase.__init__(self, nInputPorts=2, nOutputPorts=1,
                                        outputType="vtkPolyData")
        self._options = {}
        self._extra = ""
        self._vectors = ""

    def _set(self, name, value):
        if self._options.get(name) != value:
            self._options[name] = value
            self.Modified()

    def FillInputPortInformation(self, port, info):
        info.Set(self.INPUT_REQUIRED_DATA_TYPE(), "vtkImageData" if port == 0 else "vtkPolyData")
        return 1

    def options(self):
        merged = dict(self._options)
        merged.update(parse_options(self._extra))
        edge = float(merged.get("edge", 0) or 0)
        if edge < 0:
            raise ValueError("Edge must be positive, or 0 for the input's cell size; got %g" % edge)
        if edge == 0:
            merged.pop("edge", None)  # the module takes the grid's cell size
        return merged


def _input_times(executive, in_info):
    key = vtkStreamingDemandDrivenPipeline.TIME_STEPS()
    return list(in_info.Get(key)) if in_info.Has(key) else []


def _read_series(algorithm, times, vectors):
    """Every time step of the upstream reader as an orthofront.Series."""
    upstream = algorithm.GetInputAlgorithm(0, 0)
    port = algorithm.GetInputConnection(0, 0).GetIndex()
    steps, geometry = [], None
    for t in times:
        upstream.UpdateTimeStep(t)
        image = upstream.GetOutputDataObject(port)
        values, origin, spacing = image_to_grid(image, vectors)
        if geometry is None:
            geometry = (values.shape, tuple(origin), tuple(spacing))
        elif geometry != (values.shape, tuple(origin), tuple(spacing)):
            raise ValueError("time step %g has another grid than the first" % t)
        steps.append(values)
    return orthofront.Series(np.stack(steps), times, origin=geometry[1], spacing=geometry[2])


@smproxy.filter(name="OrthofrontStreamSurface", label="Flow-Orthogonal Stream Surface")
@smhint.xml(MENU)
@smproperty.input(name="Seeds", port_index=1)
@smdomain.datatype(dataTypes=["vtkPolyData"], composite_data_supported=False)
@smproperty.input(name="Input", port_index=0)
@smdomain.datatype(dataTypes=["vtkImageData"], composite_data_supported=False)
class StreamSurface(_SurfaceFilter):
    """The stream surface of a steady vector field from a seed curve (orthofront stream)."""

    def __init__(self):
        _SurfaceFilter.__init__(self)
        self._options = {"seed_count": 20, "edge": 0.0, "steps": 100, "method": "orthogonal"}

    @smproperty.stringvector(name="Vectors", default_values="")
    def SetVectors(self, value):
        self._vectors = value
        self.Modified()

    @smproperty.intvector(name="SeedCount", default_values=20)
    def SetSeedCount(self, value):
        self._set("seed_count", int(value))

    @smproperty.doublevector(name="Edge", default_values=0)
    @smdomain.xml(_EDGE_DOMAIN)
    def SetEdge(self, value):
        self._set("edge", float(value))

    @smproperty.intvector(name="Steps", default_values=100)
    def SetSteps(self, value):
        self._set("steps", int(value))

    @smproperty.stringvector(name="Method", default_values="orthogonal")
    @smdomain.xml('<StringListDomain name="list"><String value="orthogonal"/>'
                  '<String value="timeline"/></StringListDomain>')
    def SetMethod(self, value):
        self._set("method", value)

    @smproperty.stringvector(name="Options", default_values="")
    def SetOptions(self, value):
        self._extra = value
        self.Modified()

    def RequestData(self, request, in_info, out_info):
        image = vtkImageData.GetData(in_info[0])
        seeds = vtkPolyData.GetData(in_info[1])
        values, origin, spacing = image_to_grid(image, self._vectors)
        field = orthofront.Field(values, origin=origin, spacing=spacing)
        surface = orthofront.stream_surface(field, seed_points(seeds), **self.options())
        surface_to_polydata(surface, vtkPolyData.GetData(out_info))
        return 1


@smproxy.filter(name="OrthofrontPathSurface", label="Path Surface")
@smhint.xml(MENU)
@smproperty.input(name="Seeds", port_index=1)
@smdomain.datatype(dataTypes=["vtkPolyData"], composite_data_supported=False)
@smproperty.input(name="Input", port_index=0)
@smdomain.datatype(dataTypes=["vtkImageData"], composite_data_supported=False)
class PathSurface(_SurfaceFilter):
    """The path surface of a time series of vector fields from a seed curve at T0 until its path
    lines reach T1 (orthofront path). Every time step of the input is read."""

    def __init__(self):
        _SurfaceFilter.__init__(self)
        self._options = {"seed_count": 20, "edge": 0.0, "t0": 0.0, "t1": 1.0}
        self._spacetime = False

    @smproperty.stringvector(name="Vectors", default_values="")
    def SetVectors(self, value):
        self._vectors = value
        self.Modified()

    @smproperty.intvector(name="SeedCount", default_values=20)
    def SetSeedCount(self, value):
        self._set("seed_count", int(value))

    @smproperty.doublevector(name="Edge", default_values=0)
    @smdomain.xml(_EDGE_DOMAIN)
    def SetEdge(self, value):
        self._set("edge", float(value))

    @smproperty.doublevector(name="T0", default_values=0.0)
    def SetT0(self, value):
        self._set("t0", float(value))

    @smproperty.doublevector(name="T1", default_values=1.0)
    def SetT1(self, value):
        self._set("t1", float(value))

    @smproperty.doublevector(name="TimeScale", default_values=0.0)
    def SetTimeScale(self, value):
        self._set("time_scale", float(value))

    @smproperty.doublevector(name="MaxBand", default_values=0.0)
    def SetMaxBand(self, value):
        self._set("max_band", float(value))

    @smproperty.intvector(name="SpacetimeOut", default_values=0)
    @smdomain.xml('<BooleanDomain name="bool"/>')
    def SetSpacetimeOut(self, value):
        self._spacetime = bool(value)
        self.Modified()

    @smproperty.stringvector(name="Options", default_values="")
    def SetOptions(self, value):
        self._extra = value
        self.Modified()

    def RequestInformation(self, request, in_info, out_info):
        # The surface spans all times: the output is not a time series.
        info = out_info.GetInformationObject(0)
        info.Remove(vtkStreamingDemandDrivenPipeline.TIME_STEPS())
        info.Remove(vtkStreamingDemandDrivenPipeline.TIME_RANGE())
        return 1

    def RequestData(self, request, in_info, out_info):
        times = _input_times(self.GetExecutive(), in_info[0].GetInformationObject(0))
        if len(times) < 2:
            raise ValueError("Path Surface needs a time series input (2 or more time steps)")
        series = _read_series(self, times, self._vectors)
        seeds = seed_points(vtkPolyData.GetData(in_info[1]))
        surface = orthofront.path_surface(series, seeds, **self.options())
        positions = surface.spacetime_vertices if self._spacetime else None
        surface_to_polydata(surface, vtkPolyData.GetData(out_info), positions)
        return 1


@smproxy.filter(name="OrthofrontStreakSurface", label="Streak Surface")
@smhint.xml(MENU)
@smproperty.input(name="Seeds", port_index=1)
@smdomain.datatype(dataTypes=["vtkPolyData"], composite_data_supported=False)
@smproperty.input(name="Input", port_index=0)
@smdomain.datatype(dataTypes=["vtkImageData"], composite_data_supported=False)
class StreakSurface(_SurfaceFilter):
    """Dye released from a seed curve over [ReleaseBegin, ReleaseEnd], seen at the observation
    times Frames (orthofront streak): one output time step per observation time."""

    def __init__(self):
        _SurfaceFilter.__init__(self)
        self._options = {"release": (0.0, 1.0), "frames": "1", "edge": 0.0, "split": 1.5,
                         "merge": 0.5, "insert": "exact"}
        self._result = None
        self._result_key = None

    @smproperty.stringvector(name="Vectors", default_values="")
    def SetVectors(self, value):
        self._vectors = value
        self.Modified()

    @smproperty.doublevector(name="Release", number_of_elements=2, default_values=[0.0, 1.0])
    def SetRelease(self, begin, end):
        self._set("release", (float(begin), float(end)))

    @smproperty.stringvector(name="Frames", default_values="1")
    def SetFrames(self, value):
        self._set("frames", value)

    @smproperty.doublevector(name="Edge", default_values=0)
    @smdomain.xml(_EDGE_DOMAIN)
    def SetEdge(self, value):
        self._set("edge", float(value))

    @smproperty.doublevector(name="Split", default_values=1.5)
    def SetSplit(self, value):
        self._set("split", float(value))

    @smproperty.doublevector(name="Merge", default_values=0.5)
    def SetMerge(self, value):
        self._set("merge", float(value))

    @smproperty.stringvector(name="Insert", default_values="exact")
    @smdomain.xml('<StringListDomain name="list"><String value="exact"/>'
                  '<String value="interpolate"/></StringListDomain>')
    def SetInsert(self, value):
        self._set("insert", value)

    @smproperty.stringvector(name="Options", default_values="")
    def SetOptions(self, value):
        self._extra = value
        self.Modified()

    def _frame_times(self):
        text = str(self._options["frames"])
        if text.count(":") == 2:
            start, end, count = text.split(":")
            return list(np.linspace(float(start), float(end), int(count)))
        return [float(t) for t in text.replace(" ", "").split(",") if t]

    @smproperty.doublevector(name="TimestepValues", information_only="1",
                             si_class="vtkSITimeStepsProperty")
    def GetTimestepValues(self):
        # The observation times, for ParaView's animation.
        return self._frame_times()

    def RequestInformation(self, request, in_info, out_info):
        times = self._frame_times()
        info = out_info.GetInformationObject(0)
        info.Set(vtkStreamingDemandDrivenPipeline.TIME_STEPS(), times, len(times))
        info.Set(vtkStreamingDemandDrivenPipeline.TIME_RANGE(), [times[0], times[-1]], 2)
        return 1

    def RequestData(self, request, in_info, out_info):
        key = (self.GetMTime(), self.GetInputAlgorithm(0, 0).GetMTime(),
               self.GetInputAlgorithm(1, 0).GetMTime())
        if self._result is None or self._result_key != key:
            # The whole surface is built once; each output time step is one of its frames.
            input_times = _input_times(self.GetExecutive(), in_info[0].GetInformationObject(0))
            if len(input_times) < 2:
                raise ValueError("Streak Surface needs a time series input (2 or more steps)")
            series = _read_series(self, input_times, self._vectors)
            seeds = seed_points(vtkPolyData.GetData(in_info[1]))
            self._result = orthofront.streak_surface(series, seeds, **self.options())
            self._result_key = key
        info = out_info.GetInformationObject(0)
        wanted = (info.Get(vtkStreamingDemandDrivenPipeline.UPDATE_TIME_STEP())
                  if info.Has(vtkStreamingDemandDrivenPipeline.UPDATE_TIME_STEP())
                  else self._result.times[-1])
        frames = self._result.frames
        frame = min(frames, key=lambda f: abs(f.time - wanted))
        output = vtkPolyData.GetData(out_info)
        surface_to_polydata(frame, output)
        output.GetInformation().Set(output.DATA_TIME_STEP(), frame.time)
        return 1
