#pragma once
/// Sampled vector data on structured grids: the geometry of the sample points and the samples.
/// Readers in io/ produce these; grid fields in lib/ interpolate them.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "orthofront/types.h"

namespace orthofront {

/// Positions of the sample points of a 2D or 3D structured grid: uniform (origin + spacing) or
/// rectilinear (one increasing coordinate array per axis). A 2D grid has size[2] == 1.
struct GridGeometry {
  int dimension = 3;                            ///< 2 or 3
  std::array<std::int64_t, 3> size{1, 1, 1};    ///< sample points per axis
  Vec3 origin = Vec3::Zero();                   ///< uniform: position of point (0, 0, 0)
  Vec3 spacing = Vec3::Ones();                  ///< uniform: distance between points per axis
  std::array<std::vector<double>, 3> axes;      ///< rectilinear: coordinates (empty if uniform)

  bool rectilinear() const { return !axes[0].empty(); }
  std::size_t point_count() const {
    return static_cast<std::size_t>(size[0] * size[1] * size[2]);
  }
  /// Coordinate of sample i along `axis`, world units.
  double coordinate(int axis, std::int64_t i) const {
    const auto a = static_cast<std::size_t>(axis);
    return rectilinear() ? axes[a][static_cast<std::size_t>(i)]
                         : origin[axis] + static_cast<double>(i) * spacing[axis];
  }
  /// Box spanned by the first and last sample on every axis.
  Box<3> bounds() const {
    Box<3> b;
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = coordinate(a, 0);
      b.hi[a] = coordinate(a, size[static_cast<std::size_t>(a)] - 1);
    }
    return b;
  }
  /// The first τ > after at which the straight path x + τ w crosses a face between two cells
  /// (an interior sample plane of one of the grid's `dimension` axes); +inf where it crosses none.
  double next_cell_face(const Vec3& x, const Vec3& w, double after) const;
  /// Linear index of point (i, j, k): x fastest.
  std::size_t index(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return static_cast<std::size_t>(i + size[0] * (j + size[1] * k));
  }
};

/// The first of the interior coordinates coords[1 .. size - 2] (increasing) strictly above
/// `from` (`up`) or strictly below it; NaN where there is none. Interior sample planes (and
/// interior time steps of a series) are where an interpolant's derivative jumps.
double next_interior_coordinate(const std::vector<double>& coords, double from, bool up);

/// Vector samples on a grid: `components` floats per point (2 or 3), interleaved, x fastest.
/// NaN marks a missing value (fill values are turned into NaN by the readers).
struct VectorGrid {
  GridGeometry geometry;
  int components = 3;
  std::vector<float> values;  ///< geometry.point_count() * components entries

  std::size_t bytes() const { return values.size() * sizeof(float); }
};

}  // namespace orthofront
