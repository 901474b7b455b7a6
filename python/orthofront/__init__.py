"""Flow-orthogonal stream, path and streak surfaces.

Fields come from numpy arrays (``Field``, ``Series``), from files (``Field.open``,
``Series.open``, or a file name where a field is expected) or by analytic name ("abc",
"double-gyre:A=0.1"). Seeds are seed strings ("line:0,0,0:1,0,0") or arrays of points.
Options are the command line's, with '_' for '-': ``stream_surface(f, s, edge=0.05,
mu_mode="paper")`` is ``orthofront stream --edge 0.05 --mu-mode paper``, same defaults and checks.
The interpreter lock is released while a surface is built; Ctrl-C stops the build.
"""

import json
import warnings

import numpy as np

from ._orthofront import Error, Field, Series, __version__
from . import _orthofront

__all__ = ["Error", "Field", "Series", "Surface", "StreakSurface", "stream_surface",
           "path_surface", "streak_surface", "__version__"]


class Surface:
    """A surface mesh as numpy arrays.

    vertices: (n, 3) float64. faces: (m, 4) int32, -1 in the last column for a triangle
    (vtk_faces() gives VTK's padded cell array, to_vtk() a vtkPolyData). attributes: per-vertex
    arrays by name (time, alpha, s, error, front_id, step, and for streak surfaces release_time,
    age, speed, particle_id, on_path). report: the JSON report as a dict.
    """

    def __init__(self, data, report=None):
        self.vertices = data["vertices"]
        self.faces = data["faces"]
        self.attributes = dict(data["attributes"])
        self.report = json.loads(data["report"]) if report is None else report
        self.spacetime_vertices = data.get("spacetime_vertices")
        self.time = data.get("time")

    @property
    def quad_count(self):
        return int(np.count_nonzero(self.faces[:, 3] >= 0))

    def triangles(self):
        """The faces as triangles, (k, 3): each quad split along its first diagonal."""
        quads = self.faces[self.faces[:, 3] >= 0]
        tris = self.faces[self.faces[:, 3] < 0][:, :3]
        return np.concatenate([tris, quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])

    def vtk_faces(self):
        """The faces as VTK's padded cell array: for each face its corner count, then its corners
        (``[4, a, b, c, d, 3, e, f, g, ...]``), int64, as ``vtkCellArray`` and pyvista take it."""
        sizes = np.where(self.faces[:, 3] >= 0, 4, 3).astype(np.int64)
        cells = np.empty(len(self.faces) * 5, dtype=np.int64)
        cells[0::5] = sizes
        for corner in range(4):
            cells[corner + 1::5] = self.faces[:, corner]
        keep = np.ones(len(cells), dtype=bool)
        keep[4::5] = sizes == 4  # a triangle has no fourth corner
        return cells[keep]

    def to_vtk(self):
        """The surface as a ``vtkPolyData`` (needs the ``vtk`` module): positions as points,
        faces as polygons, every attribute as point data of its name."""
        try:
            from vtkmodules.util import numpy_support
            from vtkmodules.vtkCommonCore import vtkPoints
            from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
        except ImportError as error:
            raise ImportError("Surface.to_vtk needs the vtk module (Debian: python3-vtk9 or "
                              "python3-paraview)") from error
        points = vtkPoints()
        points.SetData(numpy_support.numpy_to_vtk(np.ascontiguousarray(self.vertices, np.float64),
                                                  deep=True))
        polys = vtkCellArray()
        polys.SetCells(len(self.faces), numpy_support.numpy_to_vtkIdTypeArray(
            np.ascontiguousarray(self.vtk_faces()), deep=True))
        mesh = vtkPolyData()
        mesh.SetPoints(points)
        mesh.SetPolys(polys)
        for name, values in self.attributes.items():
            values = np.ascontiguousarray(values)
            if values.shape[:1] != (len(self.vertices),):
                continue
            array = numpy_support.numpy_to_vtk(values, deep=True)
            array.SetName(name)
            mesh.GetPointData().AddArray(array)
        return mesh

    def save(self, path):
        """Writes the mesh with its attributes (.vtp, .ply or .obj, chosen by the extension)."""
        _orthofront._write_mesh(self.vertices, self.faces, self.attributes, str(path))

    def preview(self, png, color_by=None, size=(1024, 768)):
        """Renders a PNG of the surface (see orthofront.preview.render_surface)."""
        from . import preview
        return preview.render_surface(self, png, color_by=color_by, size=size)

    def __repr__(self):
        return "<orthofront.Surface %d vertices, %d faces (%d quads)>" % (
            len(self.vertices), len(self.faces), self.quad_count)


class StreakSurface:
    """The frames of a streak surface (one Surface per observation time) and the run's report."""

    def __init__(self, data):
        self.report = json.loads(data["report"])
        self.frames = [Surface(f) for f in data["frames"]]

    @property
    def times(self):
        return [f.time for f in self.frames]

    def __len__(self):
        return len(self.frames)

    def __getitem__(self, index):
        return self.frames[index]

    def __repr__(self):
        return "<orthofront.StreakSurface %d frames>" % len(self.frames)


def _check_complete(report, what):
    if not report.get("complete", True):
        warnings.warn("%s is incomplete: %s" % (what, report.get("message", "stopped early")),
                      RuntimeWarning, stacklevel=3)


def stream_surface(field, seed, closed=False, **options):
    """The stream surface of a steady ``field`` from ``seed``.

    field: a Field, a data file name or an analytic field name. seed: a seed string or an (n, 2)
    or (n, 3) array of points (``closed=True`` joins the last point to the first). options: the
    options of ``orthofront stream`` (seed_count, edge, steps, method, mu_mode, ...).
    """
    surface = Surface(_orthofront._stream_surface(field, seed, closed=closed, **options))
    _check_complete(surface.report, "the stream surface")
    if len(surface.faces) == 0:
        # As the command line warns: an empty surface is returned, never silently.
        warnings.warn("the stream surface has no faces (stopped: %s after %s steps); check steps, "
                      "edge and the field's speed along the seed"
                      % (surface.report.get("stop_reason", "?"), surface.report.get("steps", "?")),
                      RuntimeWarning, stacklevel=2)
    return surface


def path_surface(field, seed, closed=False, **options):
    """The path surface of an unsteady ``field`` from ``seed`` at t0 until its path lines reach t1.

    field: a Series, a file or glob of a series, or an unsteady analytic field name. Options are
    those of ``orthofront path`` (t0, t1, seed_count, edge, cache_budget, max_band, ...). Gridded
    series are streamed through the same brick cache as on the command line. For 2D flows the
    vertices are (x, y, c t), c = ``report["path"]["time_scale"]`` (``flat=True``: (x, y, 0));
    ``spacetime_vertices`` are (x, y, c t) either way, and ``attributes["time"]`` is t.
    """
    surface = Surface(_orthofront._path_surface(field, seed, closed=closed, **options))
    _check_complete(surface.report, "the path surface")
    return surface


def streak_surface(field, seed, closed=False, **options):
    """The streak surface of dye released from ``seed``: one Surface per observation time.

    Options are those of ``orthofront streak`` (release=(t0, t1), frames=[...] or "a:b:n", edge,
    split, merge, insert, cache_budget, device, ...).
    """
    surface = StreakSurface(_orthofront._streak_surface(field, seed, closed=closed, **options))
    _check_complete(surface.report, "the streak surface")
    return surface
