"""Shared helpers of the Python tests: the command-line binary and files written like users do."""

import os
import subprocess

import numpy as np
import pytest


@pytest.fixture(scope="session")
def orthofront_binary():
    path = os.environ.get("ORTHOFRONT_BINARY")
    if not path or not os.path.isfile(path):
        pytest.fail("ORTHOFRONT_BINARY must name the orthofront executable (ctest sets it)")
    return path


def run_cli(binary, *args, check=True, env=None):
    """Runs the command line; returns the completed process (stdout and stderr as text)."""
    result = subprocess.run([binary, *map(str, args)], capture_output=True, text=True, env=env)
    if check and result.returncode != 0:
        raise AssertionError("orthofront %s failed (%d):\n%s%s" % (
            " ".join(map(str, args)), result.returncode, result.stdout, result.stderr))
    return result


def write_vti(path, values, origin, spacing):
    """VTK XML ImageData with ASCII point vectors (float32, printed to round-trip exactly)."""
    values = np.asarray(values, dtype=np.float32)
    if values.ndim == 3:  # (ny, nx, 2): a 2D grid
        ny, nx, _ = values.shape
        nz = 1
        vectors = values.reshape(-1, 2)
        origin, spacing = list(origin) + [0.0], list(spacing) + [1.0]
    else:
        nz, ny, nx, _ = values.shape
        vectors = values.reshape(-1, 3)
    components = vectors.shape[1]
    text = " ".join("%.9g" % v for v in vectors.ravel())
    with open(path, "w") as file:
        file.write(
            '<?xml version="1.0"?>\n<VTKFile type="ImageData" version="0.1">\n'
            '<ImageData WholeExtent="0 %d 0 %d 0 %d" Origin="%r %r %r" Spacing="%r %r %r">\n'
            '<Piece Extent="0 %d 0 %d 0 %d"><PointData%s>\n'
            '<DataArray type="Float32" Name="velocity" NumberOfComponents="%d" format="ascii">\n'
            '%s\n</DataArray></PointData></Piece></ImageData></VTKFile>\n' % (
                nx - 1, ny - 1, nz - 1, *origin, *spacing, nx - 1, ny - 1, nz - 1,
                # VTK's Vectors attribute takes 3 components only
                ' Vectors="velocity"' if components == 3 else "", components, text))


def read_png(path):
    """(height, width, channels) uint8 pixels, read by VTK's PNG reader."""
    import vtk
    from vtk.util import numpy_support
    reader = vtk.vtkPNGReader()
    reader.SetFileName(str(path))
    reader.Update()
    image = reader.GetOutput()
    width, height, _ = image.GetDimensions()
    scalars = image.GetPointData().GetScalars()
    pixels = numpy_support.vtk_to_numpy(scalars).reshape(height, width, -1)
    return pixels


def assert_picture(path, size):
    """The PNG has `size` (width, height), and it shows something: a good share of pixels
    differ from the white background and they carry several colours."""
    assert os.path.isfile(path), path
    pixels = read_png(path)[..., :3]
    assert (pixels.shape[1], pixels.shape[0]) == tuple(size)
    drawn = np.any(pixels < 240, axis=-1)
    assert drawn.mean() > 0.05, "%s is nearly blank (%.3f drawn)" % (path, drawn.mean())
    colours = np.unique(pixels[drawn].reshape(-1, 3) // 32, axis=0)
    assert len(colours) >= 8, "%s has only %d colour classes" % (path, len(colours))


def pvbatch_inputs(tmp_path_factory, name):
    """pvbatch (skipping visibly without it) and a folder holding the ParaView tests' inputs:
    helix.vti (a linear 3D field) and frame0.vti ... frame5.vti (a 2D shear series)."""
    import shutil
    from test_module import helix_grid, shear_series
    pvbatch = shutil.which("pvbatch")
    if pvbatch is None:
        pytest.skip("SKIPPED: no pvbatch (Debian: paraview, python3-paraview)")
    work = tmp_path_factory.mktemp(name)
    values, origin, spacing = helix_grid(9)
    write_vti(work / "helix.vti", values, origin, spacing)
    steps, _, origin2, spacing2 = shear_series()
    for i in range(len(steps)):
        write_vti(work / ("frame%d.vti" % i), steps[i], origin2, spacing2)
    return pvbatch, work
