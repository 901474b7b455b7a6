#pragma once
/// Numpy arrays as grids and time series, and meshes as numpy arrays.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <string>

#include "orthofront/field/grid.h"
#include "orthofront/io/time_series.h"
#include "orthofront/mesh/mesh.h"

namespace orthofront::python {

/// Values in C order, x fastest: (ny, nx, 2) or (nz, ny, nx, 3) for one grid, with a leading
/// time axis for a series.
using FloatArray = pybind11::array_t<float, pybind11::array::c_style | pybind11::array::forcecast>;

/// One grid from `values`, placed by `origin` and `spacing` (sequences of 2 or 3 numbers; defaults
/// 0 and 1) or by `axes` (a sequence of increasing coordinate arrays, one per axis, for a
/// rectilinear grid). Throws ValueError naming the mismatch.
VectorGrid grid_from_array(const FloatArray& values, const pybind11::object& origin,
                           const pybind11::object& spacing, const pybind11::object& axes);

/// A series from `values` (nt, [nz,] ny, nx, C) at `times` (nt increasing numbers).
std::unique_ptr<io::TimeSeries> series_from_array(const FloatArray& values,
                                                  const pybind11::object& times,
                                                  const pybind11::object& origin,
                                                  const pybind11::object& spacing,
                                                  const pybind11::object& axes,
                                                  bool zero_is_no_data);

/// {"vertices": (n, 3) float64, "faces": (m, 4) int32 with -1 ending a triangle,
///  "attributes": {name: (n,) array}} with every recorded per-vertex attribute.
pybind11::dict mesh_to_dict(const Mesh& mesh);

/// The inverse of mesh_to_dict (attributes by the names the mesh files use).
Mesh mesh_from_arrays(const pybind11::array& vertices, const pybind11::array& faces,
                      const pybind11::dict& attributes);

}  // namespace orthofront::python
