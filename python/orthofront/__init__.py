"""Flow-orthogonal stream, path and streak surfaces.

Fields come from numpy arrays (``Field``, ``Series``), from xarray (``from_xarray``, or a
Dataset or DataArray where a field is expected), from files (``Field.open``, ``Series.open``, or
a file name where a field is expected) or by analytic name ("abc", "double-gyre:A=0.1"). Seeds are seed strings ("line:0,0,0:1,0,0") or arrays of points.
Options are the command line's, with '_' for '-': ``stream_surface(f, s, edge=0.05,
mu_mode="paper")`` is ``orthofront stream --edge 0.05 --mu-mode paper``, same defaults and checks.
The interpreter lock is released while a surface is built; Ctrl-C stops the build.
"""

import inspect
import json
import textwrap
import warnings

import numpy as np

from ._orthofront import Error, Field, Series, __version__
from . import _orthofront
from .xarray_input import (AxisOrderError, TimeError, UnitsError, from_xarray, is_xarray,
                           times_in_seconds)

__all__ = ["Error", "Field", "Series", "Surface", "StreakSurface", "stream_surface",
           "path_surface", "streak_surface", "from_xarray", "AxisOrderError", "UnitsError",
           "TimeError", "__version__"]


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
    if is_xarray(field):
        field = from_xarray(field)
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
    if is_xarray(field):
        field = from_xarray(field)
    times_in_seconds(field, options, ("t0", "t1"))
    surface = Surface(_orthofront._path_surface(field, seed, closed=closed, **options))
    _check_complete(surface.report, "the path surface")
    return surface


def streak_surface(field, seed, closed=False, **options):
    """The streak surface of dye released from ``seed``: one Surface per observation time.

    Options are those of ``orthofront streak`` (release=(t0, t1), frames=[...] or "a:b:n", edge,
    split, merge, insert, cache_budget, device, ...).
    """
    if is_xarray(field):
        field = from_xarray(field)
    times_in_seconds(field, options, ("release", "frames"))
    surface = StreakSurface(_orthofront._streak_surface(field, seed, closed=closed, **options))
    _check_complete(surface.report, "the streak surface")
    return surface


# The keyword arguments are the command line's options: their names, defaults and help come
# from the same option schema (apps/jobs, listed by ``_orthofront._keywords``), so signatures and
# docstrings cannot drift from what the functions take.
_DATA_DEFAULTS = {"edge": "the grid's cell size for gridded data, else %s",
                  "max_vertices": "from memory, half of it at ~300 B a vertex (now %s)"}


def _keyword_default(entry):
    """The keyword's default as a Python value: None where the command line has none (or where
    it comes from the data), False for a flag, else the number or text it shows."""
    if entry["flag"]:
        return False
    text = entry["default"]
    if text == "" or entry["name"] in _DATA_DEFAULTS:
        return None
    kind = entry["type"].split(":")[0]
    try:
        if kind == "FLOAT":
            return float(text)
        if kind in ("INT", "UINT"):
            return int(text)
    except ValueError:
        pass
    return text


def _keyword_doc(entry):
    kind = "bool" if entry["flag"] else entry["type"].split(":")[0].lower().replace("text", "str")
    if entry["name"] in _DATA_DEFAULTS:
        default = _DATA_DEFAULTS[entry["name"]] % (entry["default"] or "none")
    elif entry["flag"]:
        default = "False"
    else:
        default = entry["default"] or "none"
    help_text = entry["help"] or "(see orthofront %s --help)" % entry["option"]
    body = textwrap.fill("%s (%s; default: %s)" % (help_text, entry["option"], default), 76,
                         break_on_hyphens=False, break_long_words=False)
    return "%s : %s, optional\n%s" % (entry["name"], kind, textwrap.indent(body, "    "))


def _document(function, kind, summary_params):
    """Gives ``function`` (field, seed, closed=False, **options) a signature that lists every
    keyword with its default, and a numpydoc Parameters section."""
    keywords = _orthofront._keywords(kind)
    params = [inspect.Parameter("field", inspect.Parameter.POSITIONAL_OR_KEYWORD),
              inspect.Parameter("seed", inspect.Parameter.POSITIONAL_OR_KEYWORD),
              inspect.Parameter("closed", inspect.Parameter.POSITIONAL_OR_KEYWORD, default=False)]
    params += [inspect.Parameter(k["name"], inspect.Parameter.KEYWORD_ONLY,
                                 default=_keyword_default(k)) for k in keywords]
    function.__signature__ = inspect.Signature(params)
    doc = inspect.cleandoc(function.__doc__ or "")
    doc += "\n\nParameters\n----------\n" + summary_params.strip() + "\n"
    doc += _SEED_PARAMS.strip() + "\n"
    doc += "\n".join(_keyword_doc(k) for k in keywords)
    doc += ("\n\nA keyword left out, or None, takes the command line's default; an unknown one "
            "raises TypeError, a value the command line refuses ValueError.")
    function.__doc__ = doc


_SEED_PARAMS = """
closed : bool, optional
    Join the seed's last point to its first (default: False).
"""

_document(stream_surface, "stream", """
field : Field, xarray.Dataset, xarray.DataArray or str
    A Field, an xarray object (see ``from_xarray``), a data file name or an analytic field name.
seed : str or array_like
    A seed string ("line:0,0,0:1,0,0") or an (n, 2) or (n, 3) array of points.
""")
_document(path_surface, "path", """
field : Series, xarray.Dataset, xarray.DataArray or str
    A Series, an xarray object with a time dimension (see ``from_xarray``; t0 and t1 may then be
    datetime64), a file or glob of a series, or an unsteady analytic field name.
seed : str or array_like
    A seed string or an (n, 2) or (n, 3) array of points, at t0.
""")
_document(streak_surface, "streak", """
field : Series, xarray.Dataset, xarray.DataArray or str
    A Series, an xarray object with a time dimension (see ``from_xarray``; release and frames
    may then be datetime64), a file or glob of a series, or an unsteady analytic field name.
seed : str or array_like
    The curve the dye leaves: a seed string or an (n, 2) or (n, 3) array of points.
""")
