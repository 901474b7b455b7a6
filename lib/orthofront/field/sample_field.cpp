#include "orthofront/field/sample_field.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "orthofront/error.h"
#include "orthofront/huge_pages.h"

namespace orthofront {

GridGeometry sampling_geometry(const SampleOptions& options, const Box<3>& field_domain) {
  const Box<3> box = options.box.value_or(field_domain);
  const auto& n = options.resolution;
  for (int a = 0; a < 3; ++a) {
    const auto count = n[static_cast<std::size_t>(a)];
    if (count < 2 && !(a == 2 && count == 1))
      throw InvalidArgument("sampling resolution along " + std::string(1, char('x' + a)) +
                            " must be at least 2 (1 on z for a 2D grid), got " +
                            std::to_string(count));
    if (!std::isfinite(box.lo[a]) || !std::isfinite(box.hi[a]) ||
        (count > 1 && !(box.hi[a] > box.lo[a])))
      throw InvalidArgument("sampling box along " + std::string(1, char('x' + a)) +
                            " must be finite and non-empty, got [" + std::to_string(box.lo[a]) +
                            ", " + std::to_string(box.hi[a]) + "]");
  }
  GridGeometry g;
  g.dimension = n[2] == 1 ? 2 : 3;
  g.size = n;
  for (int a = 0; a < 3; ++a) {
    const auto count = n[static_cast<std::size_t>(a)];
    if (count == 1) {
      g.origin[a] = 0.5 * (box.lo[a] + box.hi[a]);
      g.spacing[a] = 1.0;
    } else {
      g.origin[a] = box.lo[a];
      g.spacing[a] = (box.hi[a] - box.lo[a]) / static_cast<double>(count - 1);
    }
  }
  return g;
}

void sample_field_into(const Field3& field, const GridGeometry& geometry, int components,
                       std::span<float> values) {
  if (components != 2 && components != 3)
    throw InvalidArgument("sample_field: components must be 2 or 3, got " +
                          std::to_string(components));
  const std::size_t expected = geometry.point_count() * static_cast<std::size_t>(components);
  if (values.size() != expected)
    throw InvalidArgument("sample_field: buffer of " + std::to_string(values.size()) +
                          " floats for " + std::to_string(expected) + " values");
  const Box<3> bounds = geometry.bounds();
  const std::int64_t nx = geometry.size[0], ny = geometry.size[1], nz = geometry.size[2];
  std::vector<double> xs(static_cast<std::size_t>(nx));
  for (std::int64_t i = 0; i < nx; ++i)
    xs[static_cast<std::size_t>(i)] = std::min(geometry.coordinate(0, i), bounds.hi.x());
  const float nan = std::numeric_limits<float>::quiet_NaN();
  tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, ny * nz), [&](const auto& rows) {
    Vec3 x, v;
    for (std::int64_t row = rows.begin(); row != rows.end(); ++row) {
      const std::int64_t j = row % ny, k = row / ny;
      x.y() = std::min(geometry.coordinate(1, j), bounds.hi.y());
      x.z() = std::min(geometry.coordinate(2, k), bounds.hi.z());
      float* out = values.data() + geometry.index(0, j, k) * static_cast<std::size_t>(components);
      for (std::int64_t i = 0; i < nx; ++i, out += components) {
        x.x() = xs[static_cast<std::size_t>(i)];
        const bool inside = field.velocity(x, v) == FieldStatus::inside;
        for (int c = 0; c < components; ++c) out[c] = inside ? static_cast<float>(v[c]) : nan;
      }
    }
  });
}

VectorGrid sample_field(const Field3& field, const SampleOptions& options) {
  if (options.components != 0 && options.components != 2 && options.components != 3)
    throw InvalidArgument("sample_field: components must be 0 (automatic), 2 or 3, got " +
                          std::to_string(options.components));
  VectorGrid grid;
  grid.geometry = sampling_geometry(options, field.domain());
  grid.components = 3;
  reserve_huge_pages(grid.values, grid.geometry.point_count() * 3);
  grid.values.resize(grid.geometry.point_count() * 3);
  sample_field_into(field, grid.geometry, 3, grid.values);
  bool planar = grid.geometry.dimension == 2;
  for (std::size_t p = 2; planar && p < grid.values.size(); p += 3)
    planar = grid.values[p] == 0.0f || std::isnan(grid.values[p]);
  const int components = options.components != 0 ? options.components : planar ? 2 : 3;
  if (components == 2) {
    // Drop v_z in place: point p's (v_x, v_y) moves from 3p to 2p, never overtaking a later read.
    const std::size_t points = grid.geometry.point_count();
    for (std::size_t p = 0; p < points; ++p) {
      grid.values[2 * p] = grid.values[3 * p];
      grid.values[2 * p + 1] = grid.values[3 * p + 1];
    }
    grid.values.resize(points * 2);
    grid.values.shrink_to_fit();
    grid.components = 2;
  }
  return grid;
}

}  // namespace orthofront
