"""Pictures of surfaces and of their quality.

render_surface: a shaded PNG of a surface with its wireframe, coloured by a per-vertex attribute,
seen from an automatic viewpoint, drawn by VTK's renderer (the `vtk` module of Debian's
python3-paraview). plot_histograms: the paper's two quality histograms (quad angles, and
1 - l_i / l_avg of quad edges) from a report, drawn by matplotlib (SVG or PNG by the extension).

VTK's X11 render window needs a display; without one, a private Xvfb is started for the picture
and stopped after it.

Command line (what `orthofront stream|path|streak --preview` and `demo` run; both options
repeat, pairing by rank):
    python3 -m orthofront.preview --mesh M.vtp --png M.png [--color time]
    python3 -m orthofront.preview --report R.json --histograms R.histograms.svg
"""

import argparse
import contextlib
import json
import os
import random
import shutil
import socket
import subprocess
import sys
import time

import numpy as np

DEFAULT_COLORS = ("time", "age", "alpha", "s")


def _wait_for_x_socket(number, seconds=10.0):
    """Waits until the server's socket takes connections: a client that connects as soon as the
    server has named its display now and then finds nothing there ("bad X server connection")."""
    path = "/tmp/.X11-unix/X" + number
    deadline = time.monotonic() + seconds
    while True:
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as probe:
            try:
                probe.connect(path)
                return
            except OSError:
                if time.monotonic() > deadline:
                    raise RuntimeError("Xvfb named display :%s but %s takes no connections"
                                       % (number, path))
        time.sleep(0.05)


@contextlib.contextmanager
def display():
    """A display for VTK's render window: the current one, or a private Xvfb for the duration."""
    if os.environ.get("DISPLAY"):
        yield os.environ["DISPLAY"]
        return
    xvfb = shutil.which("Xvfb")
    if xvfb is None:
        raise RuntimeError("no display to render on and no Xvfb (Debian: apt-get install xvfb)")
    # -noreset: by default the server resets when its last client leaves (the socket probe below
    # is one), and a client that connects during the reset is refused; VTK then aborts the process.
    # A display number of our own, far from the low ones Xvfb -displayfd would pick: a server on
    # a number another process has just given up can lose its socket to that process's cleanup.
    chooser = random.Random(os.getpid() ^ time.monotonic_ns())
    number, server = "", None
    for _ in range(20):
        read_end, write_end = os.pipe()
        server = subprocess.Popen([xvfb, ":%d" % chooser.randrange(100, 30000), "-displayfd",
                                   str(write_end), "-screen", "0", "1280x1024x24", "-nolisten",
                                   "tcp", "-noreset"], pass_fds=(write_end,), stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL)
        os.close(write_end)
        with os.fdopen(read_end) as pipe:
            number = pipe.readline().strip()
        if number:
            break
        server.wait()  # that number was taken: try another
    if not number:
        raise RuntimeError("Xvfb did not start")
    _wait_for_x_socket(number)
    os.environ["DISPLAY"] = ":" + number
    try:
        yield os.environ["DISPLAY"]
    finally:
        del os.environ["DISPLAY"]
        server.terminate()
        server.wait()


def _polydata(vertices, faces, attributes):
    import vtk
    from vtk.util import numpy_support
    poly = vtk.vtkPolyData()
    points = vtk.vtkPoints()
    points.SetData(numpy_support.numpy_to_vtk(np.ascontiguousarray(vertices, dtype=np.float64),
                                              deep=True))
    poly.SetPoints(points)
    faces = np.asarray(faces)
    sizes = np.where(faces[:, 3] >= 0, 4, 3).astype(np.int64)
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    connectivity = faces[faces >= 0].astype(np.int64)  # row-major: each face's vertices in order
    cells = vtk.vtkCellArray()
    cells.SetData(numpy_support.numpy_to_vtkIdTypeArray(offsets, deep=True),
                  numpy_support.numpy_to_vtkIdTypeArray(connectivity, deep=True))
    poly.SetPolys(cells)
    for name, values in attributes.items():
        array = numpy_support.numpy_to_vtk(np.ascontiguousarray(values), deep=True)
        array.SetName(name)
        poly.GetPointData().AddArray(array)
    return poly


def read_mesh(path):
    """A .vtp, .ply or .obj file as (vertices, faces (m, 4) with -1 for triangles, attributes)."""
    import vtk
    from vtk.util import numpy_support
    path = str(path)
    readers = {".vtp": vtk.vtkXMLPolyDataReader, ".ply": vtk.vtkPLYReader,
               ".obj": vtk.vtkOBJReader}
    extension = os.path.splitext(path)[1].lower()
    if extension not in readers:
        raise ValueError("%s: unknown mesh extension (expected .vtp, .ply or .obj)" % path)
    if not os.path.isfile(path):
        raise FileNotFoundError("%s: no such mesh file" % path)
    reader = readers[extension]()
    reader.SetFileName(path)
    reader.Update()
    poly = reader.GetOutput()
    vertices = (numpy_support.vtk_to_numpy(poly.GetPoints().GetData()).astype(np.float64)
                if poly.GetPoints() else np.zeros((0, 3)))
    polys = poly.GetPolys()
    offsets = numpy_support.vtk_to_numpy(polys.GetOffsetsArray()).astype(np.int64)
    connectivity = numpy_support.vtk_to_numpy(polys.GetConnectivityArray()).astype(np.int64)
    faces = np.full((len(offsets) - 1, 4), -1, dtype=np.int32)
    for corner in range(4):
        has = offsets[:-1] + corner < offsets[1:]
        faces[has, corner] = connectivity[offsets[:-1][has] + corner]
    attributes = {}
    data = poly.GetPointData()
    for i in range(data.GetNumberOfArrays()):
        array = data.GetArray(i)
        if array is not None and array.GetNumberOfComponents() == 1:
            attributes[array.GetName()] = numpy_support.vtk_to_numpy(array)
    return vertices, faces, attributes


def quad_angle_deviation(vertices, faces):
    """Per vertex: the largest |angle - 90 degrees| over the quad corners at it (0 where it has
    none), the quality the paper measures, as a colour."""
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces)
    quads = faces[faces[:, 3] >= 0]
    worst = np.zeros(len(vertices))
    for corner in range(4):
        here = vertices[quads[:, corner]]
        to_next = vertices[quads[:, (corner + 1) % 4]] - here
        to_prev = vertices[quads[:, (corner + 3) % 4]] - here
        norms = np.linalg.norm(to_next, axis=1) * np.linalg.norm(to_prev, axis=1)
        cosine = np.einsum("ij,ij->i", to_next, to_prev) / np.where(norms > 0, norms, 1.0)
        deviation = np.abs(np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0))) - 90.0)
        np.maximum.at(worst, quads[:, corner], deviation)
    return worst


def _camera_direction(vertices):
    """Looks at the surface along its least-spread axis, tilted so that a curved surface shows
    depth; a flat (2D) surface is seen from straight above."""
    centred = vertices - vertices.mean(axis=0)
    _, spread, axes = np.linalg.svd(centred, full_matrices=False)
    normal = axes[-1]
    if spread[-1] <= 1e-9 * max(spread[0], 1e-300):
        return normal if normal[2] >= 0 else -normal, axes[1]
    direction = normal + 0.35 * axes[0] + 0.25 * axes[1]
    return direction / np.linalg.norm(direction), axes[1]


def render_surface(surface, png, color_by=None, size=(1024, 768), title=None):
    """Writes a PNG of `surface` (an orthofront.Surface, a (vertices, faces, attributes) tuple or
    a mesh file) coloured by the per-vertex attribute `color_by` (default: the first of time,
    age, alpha, s that the mesh has). Returns the PNG's path."""
    import vtk
    if isinstance(surface, (str, os.PathLike)):
        vertices, faces, attributes = read_mesh(surface)
        title = title or os.path.basename(str(surface))
    elif isinstance(surface, tuple):
        vertices, faces, attributes = surface
    else:
        vertices, faces, attributes = surface.vertices, surface.faces, surface.attributes
    if len(vertices) == 0 or len(faces) == 0:
        raise ValueError("the surface has no faces: nothing to draw")
    if color_by == "quality":
        attributes = dict(attributes)
        attributes["quality"] = quad_angle_deviation(vertices, faces)
    if color_by is None:
        color_by = next((a for a in DEFAULT_COLORS if a in attributes), None)
    elif color_by not in attributes:
        raise ValueError("no attribute '%s' to colour by (the mesh has: %s)"
                         % (color_by, ", ".join(sorted(attributes)) or "none"))
    poly = _polydata(vertices, faces, attributes)

    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputData(poly)
    renderer = vtk.vtkRenderer()
    renderer.SetBackground(1.0, 1.0, 1.0)
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    surface_property = actor.GetProperty()
    surface_property.EdgeVisibilityOn()
    surface_property.SetEdgeColor(0.15, 0.15, 0.15)
    surface_property.SetLineWidth(1.2)
    surface_property.SetAmbient(0.25)
    surface_property.SetDiffuse(0.75)
    if color_by is not None:
        values = np.asarray(attributes[color_by], dtype=np.float64)
        finite = values[np.isfinite(values)]
        lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
        mapper.SetScalarModeToUsePointFieldData()
        mapper.SelectColorArray(color_by)
        mapper.SetScalarRange(lo, hi if hi > lo else lo + 1.0)
        table = vtk.vtkLookupTable()
        table.SetHueRange(0.667, 0.0)  # blue to red
        table.Build()
        mapper.SetLookupTable(table)
        mapper.ScalarVisibilityOn()
        bar = vtk.vtkScalarBarActor()
        bar.SetLookupTable(table)
        bar.SetTitle("|quad angle - 90|" if color_by == "quality" else color_by)
        bar.SetNumberOfLabels(5)
        bar.SetWidth(0.08)
        bar.SetHeight(0.6)
        bar.SetPosition(0.9, 0.2)
        for text in (bar.GetTitleTextProperty(), bar.GetLabelTextProperty()):
            text.SetColor(0.1, 0.1, 0.1)
            text.ShadowOff()
        renderer.AddActor2D(bar)
    else:
        mapper.ScalarVisibilityOff()
        surface_property.SetColor(0.55, 0.7, 0.9)
    renderer.AddActor(actor)
    if title:
        caption = vtk.vtkTextActor()
        caption.SetInput(title)
        caption.GetTextProperty().SetColor(0.1, 0.1, 0.1)
        caption.GetTextProperty().SetFontSize(36)  # the picture is drawn at twice its size
        caption.SetPosition(12, 12)
        renderer.AddActor2D(caption)

    direction, up = _camera_direction(np.asarray(vertices, dtype=np.float64))
    camera = renderer.GetActiveCamera()
    centre = np.asarray(vertices).mean(axis=0)
    camera.SetFocalPoint(*centre)
    camera.SetPosition(*(centre + direction))
    camera.SetViewUp(*up)
    renderer.ResetCamera()
    camera.Zoom(1.1)

    png = str(png)
    temporary = png + ".part"
    try:
        _draw(renderer, size, temporary)
        if not os.path.isfile(temporary) or os.path.getsize(temporary) == 0:
            raise RuntimeError("%s: VTK wrote no picture" % png)
        os.replace(temporary, png)
    finally:
        if os.path.exists(temporary):
            os.remove(temporary)
    return png


def _draw(renderer, size, path):
    """Renders `renderer` off screen at `size` into the PNG file `path`."""
    import vtk
    with display():
        window = vtk.vtkRenderWindow()
        window.SetOffScreenRendering(1)
        window.SetMultiSamples(0)
        window.AddRenderer(renderer)
        # Drawn at twice the size and filtered down: dense wireframes shade smoothly instead of
        # forming moire patterns.
        window.SetSize(2 * int(size[0]), 2 * int(size[1]))
        window.Render()
        grab = vtk.vtkWindowToImageFilter()
        grab.SetInput(window)
        grab.ReadFrontBufferOff()
        shrink = vtk.vtkImageResize()
        shrink.SetInputConnection(grab.GetOutputPort())
        shrink.SetResizeMethodToOutputDimensions()
        shrink.SetOutputDimensions(int(size[0]), int(size[1]), 1)
        shrink.InterpolateOn()
        writer = vtk.vtkPNGWriter()
        writer.SetFileName(path)
        writer.SetInputConnection(shrink.GetOutputPort())
        writer.Write()
        window.Finalize()


def _quality_of(report):
    """The quality block of a stream, path or streak report (a streak run: its last frame)."""
    if "quality" in report:
        return report["quality"]
    frames = report.get("frames") or []
    for frame in reversed(frames):
        if "quality" in frame:
            return frame["quality"]
    raise ValueError("the report has no quality block (nothing was measured)")


def plot_histograms(report, out, title=None):
    """Writes the paper's two histograms of `report` (a dict or a JSON file): quad interior
    angles in degrees, and 1 - l_i / l_avg of each quad's edges. SVG or PNG by the extension."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    if isinstance(report, (str, os.PathLike)):
        with open(report) as file:
            title = title or os.path.basename(str(report))
            report = json.load(file)
    quality = _quality_of(report)
    histograms = quality["histograms"]
    figure, axes = plt.subplots(1, 2, figsize=(10, 3.8))
    panels = [
        (histograms["quad_angles_deg"], "quad interior angle (degrees)",
         "%.1f%% within 90 ± 10°" % (100 * quality.get("quad_angles_within_10deg", 0))),
        (histograms["edge_ratio"], "1 - l_i / l_avg (quad edges)",
         "median |1 - l_i/l_avg| = %.3f" % quality.get("edge_spread_median", 0)),
    ]
    for axis, (h, label, note) in zip(axes, panels):
        counts = np.asarray(h["counts"], dtype=np.float64)
        edges = np.linspace(h["lo"], h["hi"], len(counts) + 1)
        total = counts.sum()
        shares = counts / total if total > 0 else counts
        axis.bar(edges[:-1], shares, width=np.diff(edges), align="edge", color="#4a7fb5",
                 edgecolor="#26476b", linewidth=0.5)
        axis.set_xlabel(label)
        axis.set_ylabel("share")
        axis.set_xlim(h["lo"], h["hi"])
        axis.set_title(note, fontsize=10)
    figure.suptitle(title or "surface quality", fontsize=11)
    figure.tight_layout()
    out = str(out)
    extension = os.path.splitext(out)[1].lower()
    if extension not in (".svg", ".png"):
        raise ValueError("%s: histograms are written as .svg or .png" % out)
    temporary = out + ".part"
    try:
        figure.savefig(temporary, format=extension[1:], dpi=100)
        os.replace(temporary, out)
    finally:
        plt.close(figure)
        # A full disk or a failed draw leaves no half-written file behind.
        if os.path.exists(temporary):
            os.remove(temporary)
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python3 -m orthofront.preview",
                                     description="Pictures of orthofront surfaces and reports")
    parser.add_argument("--mesh", action="append", default=[],
                        help="mesh file (.vtp, .ply, .obj) to render (repeatable)")
    parser.add_argument("--png", action="append", default=[],
                        help="where to write the picture of the --mesh of the same rank")
    parser.add_argument("--color", action="append", default=[],
                        help="attribute to colour the --mesh of the same rank by (auto: time, "
                             "age, alpha or s; quality: each vertex's worst quad angle)")
    parser.add_argument("--size", default="1024x768", help="picture size WxH")
    parser.add_argument("--report", action="append", default=[],
                        help="JSON report whose quality histograms to plot (repeatable)")
    parser.add_argument("--histograms", action="append", default=[],
                        help="where to write them (.svg or .png)")
    args = parser.parse_args(argv)
    if len(args.mesh) != len(args.png) or len(args.report) != len(args.histograms):
        parser.error("each --mesh needs a --png, and each --report a --histograms")
    if args.color and len(args.color) != len(args.mesh):
        parser.error("give a --color for every --mesh, or none")
    colors = [None if c == "auto" else c for c in args.color] or [None] * len(args.mesh)
    try:
        width, height = (int(v) for v in args.size.lower().split("x"))
        with display() if args.mesh else contextlib.nullcontext():
            for mesh, png, color in zip(args.mesh, args.png, colors):
                render_surface(mesh, png, color_by=color, size=(width, height))
        for report, out in zip(args.report, args.histograms):
            plot_histograms(report, out)
    except (OSError, ValueError, RuntimeError, KeyError) as error:
        print("orthofront.preview: %s" % error, file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
