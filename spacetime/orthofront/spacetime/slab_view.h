#pragma once
/// A plain, trivially shareable view of the resident time steps of a time series: the grid,
/// the step times and one pointer per resident step. Field evaluations read only this view, so
/// they are lock-free and cheap; the cache publishes a new view between front steps.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "orthofront/field/field.h"
#include "orthofront/field/grid.h"

namespace orthofront::spacetime {

/// Result of sampling a view: `missing` means a needed step is not in the view.
enum class SlabStatus : unsigned char { inside, outside, no_data, missing };

struct SlabView {
  const GridGeometry* grid = nullptr;
  int components = 3;                ///< floats per point (2 or 3)
  const std::vector<double>* times = nullptr;  ///< time of every step of the series
  std::size_t first = 0;             ///< step index of steps[0]
  std::vector<const float*> steps;   ///< resident steps first..first+size-1 (nullptr: absent)

  const float* step(std::size_t k) const {
    return k >= first && k - first < steps.size() ? steps[k - first] : nullptr;
  }
};

/// Time interval of t: k with times[k] <= t <= times[k+1] and the weight w of step k+1.
/// False when t lies outside [times.front(), times.back()].
inline bool locate_time(const std::vector<double>& times, double t, std::size_t& k, double& w) {
  if (times.size() < 2 || !(t >= times.front() && t <= times.back())) return false;
  const auto it = std::upper_bound(times.begin(), times.end(), t);
  k = static_cast<std::size_t>(std::max<std::ptrdiff_t>(it - times.begin() - 1, 0));
  k = std::min(k, times.size() - 2);
  w = (t - times[k]) / (times[k + 1] - times[k]);
  return true;
}

namespace detail {

struct CellLocation {
  std::array<std::int64_t, 3> i{};
  std::array<double, 3> u{};      // local coordinate in [0, 1]
  std::array<double, 3> width{};  // cell width
};

inline bool locate_axis(const GridGeometry& g, int axis, double x, std::int64_t& i, double& u,
                        double& width) {
  const auto a = static_cast<std::size_t>(axis);
  const std::int64_t n = g.size[a];
  if (g.rectilinear()) {
    const std::vector<double>& c = g.axes[a];
    if (!(x >= c.front() && x <= c.back())) return false;
    const auto it = std::upper_bound(c.begin(), c.end(), x);
    i = std::min<std::int64_t>(std::max<std::int64_t>(it - c.begin() - 1, 0), n - 2);
    width = c[static_cast<std::size_t>(i + 1)] - c[static_cast<std::size_t>(i)];
    u = (x - c[static_cast<std::size_t>(i)]) / width;
    return true;
  }
  const double s = (x - g.origin[axis]) / g.spacing[axis];
  if (!(s >= 0 && s <= static_cast<double>(n - 1))) return false;
  i = std::min<std::int64_t>(static_cast<std::int64_t>(s), n - 2);
  u = s - static_cast<double>(i);
  width = g.spacing[axis];
  return true;
}

// Multilinear value and gradient of one step at a located cell. False on a NaN corner.
inline bool interpolate(const GridGeometry& g, int components, const float* data,
                        const CellLocation& c, int axes, Vec3& v, Mat3* J) {
  v.setZero();
  if (J) J->setZero();
  const int corners = axes == 3 ? 8 : 4;
  for (int corner = 0; corner < corners; ++corner) {
    const int bx = corner & 1, by = (corner >> 1) & 1, bz = (corner >> 2) & 1;
    const std::size_t index = g.index(c.i[0] + bx, c.i[1] + by, axes == 3 ? c.i[2] + bz : 0) *
                              static_cast<std::size_t>(components);
    Vec3 value = Vec3::Zero();
    for (int k = 0; k < components; ++k) {
      const float f = data[index + static_cast<std::size_t>(k)];
      if (std::isnan(f)) return false;
      value[k] = f;
    }
    const double wx = bx ? c.u[0] : 1 - c.u[0], wy = by ? c.u[1] : 1 - c.u[1];
    const double wz = axes == 3 ? (bz ? c.u[2] : 1 - c.u[2]) : 1.0;
    v += wx * wy * wz * value;
    if (J) {
      const double dx = (bx ? 1.0 : -1.0) / c.width[0] * wy * wz;
      const double dy = (by ? 1.0 : -1.0) / c.width[1] * wx * wz;
      J->col(0) += dx * value;
      J->col(1) += dy * value;
      if (axes == 3) J->col(2) += (bz ? 1.0 : -1.0) / c.width[2] * wx * wy * value;
    }
  }
  return true;
}

}  // namespace detail

/// v(x, t): multilinear in space (bilinear on 2D grids, where z is ignored), linear in time
/// between the two steps around t. J = ∂v/∂x of that interpolant, dvdt = (v_{k+1} - v_k) / Δt.
/// Thread-safe (reads only); no allocation.
inline SlabStatus sample_slab(const SlabView& view, const Vec3& x, double t, Vec3& v, Mat3* J,
                              Vec3* dvdt) {
  const GridGeometry& g = *view.grid;
  std::size_t k = 0;
  double w = 0;
  if (!locate_time(*view.times, t, k, w)) return SlabStatus::outside;
  detail::CellLocation cell;
  const int axes = g.dimension;
  for (int a = 0; a < axes; ++a)
    if (!detail::locate_axis(g, a, x[a], cell.i[static_cast<std::size_t>(a)],
                             cell.u[static_cast<std::size_t>(a)],
                             cell.width[static_cast<std::size_t>(a)]))
      return SlabStatus::outside;
  const float* s0 = view.step(k);
  const float* s1 = view.step(k + 1);
  if (s0 == nullptr || s1 == nullptr) return SlabStatus::missing;
  Vec3 v0, v1;
  Mat3 J0, J1;
  if (!detail::interpolate(g, view.components, s0, cell, axes, v0, J ? &J0 : nullptr) ||
      !detail::interpolate(g, view.components, s1, cell, axes, v1, J ? &J1 : nullptr))
    return SlabStatus::no_data;
  v = (1 - w) * v0 + w * v1;
  if (J) *J = (1 - w) * J0 + w * J1;
  if (dvdt) *dvdt = (v1 - v0) / ((*view.times)[k + 1] - (*view.times)[k]);
  return SlabStatus::inside;
}

}  // namespace orthofront::spacetime
