#include "numpy_grid.h"

#include <pybind11/stl.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "orthofront/io/grid_series.h"
#include "orthofront/io/mesh_attributes.h"

namespace py = pybind11;

namespace orthofront::python {

namespace {

/// The grid geometry of the last `grid_axes + 1` axes of `values`.
GridGeometry geometry_of(const FloatArray& values, py::ssize_t first_axis, int& components,
                         const py::object& origin, const py::object& spacing,
                         const py::object& axes) {
  const py::ssize_t grid_axes = values.ndim() - first_axis - 1;
  if (grid_axes != 2 && grid_axes != 3)
    throw py::value_error("the array has shape " +
                          py::repr(py::tuple(py::cast(std::vector<py::ssize_t>(
                                       values.shape(), values.shape() + values.ndim()))))
                              .cast<std::string>() +
                          "; a grid is (ny, nx, 2) or (nz, ny, nx, 3), C order with x fastest" +
                          (first_axis > 0 ? ", after the time axis" : ""));
  const int dimension = static_cast<int>(grid_axes);
  components = static_cast<int>(values.shape(values.ndim() - 1));
  if (components != dimension)
    throw py::value_error("a " + std::to_string(dimension) + "D grid needs " +
                          std::to_string(dimension) + " components in its last axis, got " +
                          std::to_string(components));
  GridGeometry g;
  g.dimension = dimension;
  for (int a = 0; a < dimension; ++a)  // numpy axes are (z,) y, x
    g.size[static_cast<std::size_t>(a)] = values.shape(values.ndim() - 2 - a);
  const auto numbers = [&](const py::object& given, const char* what, double fill) {
    Vec3 v = Vec3::Constant(fill);
    if (dimension == 2) v.z() = fill == 0 ? 0.0 : 1.0;
    if (given.is_none()) return v;
    const auto list = given.cast<std::vector<double>>();
    if (static_cast<int>(list.size()) != dimension)
      throw py::value_error(std::string(what) + " needs " + std::to_string(dimension) +
                            " numbers for a " + std::to_string(dimension) + "D grid, got " +
                            std::to_string(list.size()));
    for (int a = 0; a < dimension; ++a) v[a] = list[static_cast<std::size_t>(a)];
    return v;
  };
  g.origin = numbers(origin, "origin", 0.0);
  g.spacing = numbers(spacing, "spacing", 1.0);
  if (!axes.is_none()) {
    if (!origin.is_none() || !spacing.is_none())
      throw py::value_error("give either axes or origin and spacing, not both");
    const auto lists = axes.cast<std::vector<std::vector<double>>>();
    if (static_cast<int>(lists.size()) != dimension)
      throw py::value_error("axes needs " + std::to_string(dimension) + " coordinate arrays, got " +
                            std::to_string(lists.size()));
    for (int a = 0; a < dimension; ++a) {
      const auto ua = static_cast<std::size_t>(a);
      if (static_cast<std::int64_t>(lists[ua].size()) != g.size[ua])
        throw py::value_error("axes[" + std::to_string(a) + "] has " +
                              std::to_string(lists[ua].size()) + " coordinates, the array " +
                              std::to_string(g.size[ua]) + " samples on that axis");
      g.axes[ua] = lists[ua];
    }
    if (dimension == 2) g.axes[2] = {0.0};
  }
  return g;
}

std::vector<double> times_of(const py::object& times, std::size_t steps) {
  if (times.is_none()) throw py::type_error("a series needs times (one per step)");
  // datetime64 / timedelta64 would be cast to their integer ticks (nanoseconds, days, ...)
  // and taken as seconds: refused, with the conversion to write.
  if (const py::object dtype = py::getattr(times, "dtype", py::none()); !dtype.is_none()) {
    const std::string kind = py::str(dtype.attr("kind"));
    if (kind == "M" || kind == "m")
      throw py::value_error(
          "times are numpy datetime64/timedelta64: give seconds as numbers, e.g. "
          "(times - times[0]) / np.timedelta64(1, 's'), and t0, t1 in the same seconds");
  }
  auto list = times.cast<std::vector<double>>();
  if (list.size() != steps)
    throw py::value_error("times holds " + std::to_string(list.size()) + " values for " +
                          std::to_string(steps) + " steps");
  return list;
}

}  // namespace

VectorGrid grid_from_array(const FloatArray& values, const py::object& origin,
                           const py::object& spacing, const py::object& axes) {
  VectorGrid grid;
  grid.geometry = geometry_of(values, 0, grid.components, origin, spacing, axes);
  grid.values.assign(values.data(), values.data() + values.size());
  return grid;
}

std::unique_ptr<io::TimeSeries> series_from_array(const FloatArray& values, const py::object& times,
                                                  const py::object& origin,
                                                  const py::object& spacing,
                                                  const py::object& axes,
                                                  bool zero_is_no_data) {
  int components = 0;
  if (values.ndim() < 1) throw py::value_error("a series needs a time axis");
  GridGeometry geometry = geometry_of(values, 1, components, origin, spacing, axes);
  const auto steps = static_cast<std::size_t>(values.shape(0));
  const std::size_t floats = geometry.point_count() * static_cast<std::size_t>(components);
  std::vector<std::vector<float>> data(steps);
  for (std::size_t i = 0; i < steps; ++i)
    data[i].assign(values.data() + i * floats, values.data() + (i + 1) * floats);
  return std::make_unique<io::MemorySeries>(std::move(geometry), components, std::move(data),
                                            times_of(times, steps), "numpy array series",
                                            zero_is_no_data);
}

py::dict mesh_to_dict(const Mesh& mesh) {
  const auto n = static_cast<py::ssize_t>(mesh.vertex_count());
  py::array_t<double> vertices({n, py::ssize_t{3}});
  auto v = vertices.mutable_unchecked<2>();
  for (py::ssize_t i = 0; i < n; ++i)
    for (py::ssize_t a = 0; a < 3; ++a)
      v(i, a) = mesh.positions[static_cast<std::size_t>(i)][static_cast<int>(a)];
  const auto m = static_cast<py::ssize_t>(mesh.face_count());
  py::array_t<std::int32_t> faces({m, py::ssize_t{4}});
  auto f = faces.mutable_unchecked<2>();
  for (py::ssize_t i = 0; i < m; ++i)
    for (py::ssize_t c = 0; c < 4; ++c)
      f(i, c) = mesh.faces[static_cast<std::size_t>(i)].v[static_cast<std::size_t>(c)];
  py::dict attributes;
  for (const auto& a : io::detail::kRealAttributes)
    if (io::detail::is_recorded(mesh, mesh.*a.values))
      attributes[a.name] = py::array_t<double>(n, (mesh.*a.values).data());
  for (const auto& a : io::detail::kIntAttributes)
    if (io::detail::is_recorded(mesh, mesh.*a.values))
      attributes[a.name] = py::array_t<std::int32_t>(n, (mesh.*a.values).data());
  py::dict out;
  out["vertices"] = vertices;
  out["faces"] = faces;
  out["attributes"] = attributes;
  return out;
}

Mesh mesh_from_arrays(const py::array& vertices_in, const py::array& faces_in,
                      const py::dict& attributes) {
  const auto vertices =
      py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(vertices_in);
  const auto faces =
      py::array_t<std::int32_t, py::array::c_style | py::array::forcecast>::ensure(faces_in);
  if (!vertices || vertices.ndim() != 2 || vertices.shape(1) != 3)
    throw py::value_error("vertices must be an (n, 3) array");
  if (!faces || faces.ndim() != 2 || (faces.shape(1) != 3 && faces.shape(1) != 4))
    throw py::value_error("faces must be an (m, 3) or (m, 4) array (-1 ends a triangle)");
  Mesh mesh;
  const auto n = vertices.shape(0);
  const auto v = vertices.unchecked<2>();
  for (py::ssize_t i = 0; i < n; ++i) mesh.positions.emplace_back(v(i, 0), v(i, 1), v(i, 2));
  const auto f = faces.unchecked<2>();
  for (py::ssize_t i = 0; i < faces.shape(0); ++i) {
    Face face;
    for (py::ssize_t c = 0; c < faces.shape(1); ++c) {
      const std::int32_t index = f(i, c);
      if (index < 0) break;
      if (index >= n)
        throw py::value_error("face " + std::to_string(i) + " names vertex " +
                              std::to_string(index) + " of " + std::to_string(n));
      face.v[static_cast<std::size_t>(face.size++)] = index;
    }
    if (face.size < 3)
      throw py::value_error("face " + std::to_string(i) + " has fewer than 3 vertices");
    mesh.faces.push_back(face);
  }
  const auto take = [&](const char* name, auto& values) {
    using T = typename std::decay_t<decltype(values)>::value_type;
    if (!attributes.contains(name)) return;
    const auto a =
        py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(attributes[name]);
    if (!a || a.size() != n)
      throw py::value_error(std::string("attribute '") + name + "' needs " + std::to_string(n) +
                            " values");
    values.assign(a.data(), a.data() + a.size());
  };
  for (const auto& a : io::detail::kRealAttributes) take(a.name, mesh.*a.values);
  for (const auto& a : io::detail::kIntAttributes) take(a.name, mesh.*a.values);
  return mesh;
}

}  // namespace orthofront::python
