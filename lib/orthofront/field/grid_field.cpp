#include "orthofront/field/grid_field.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "orthofront/error.h"

namespace orthofront {
namespace {

std::string axis_name(int axis) {
  return std::string(1, static_cast<char>('x' + axis));
}

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

// Multilinear interpolation of the corners c (bit 0: +x, bit 1: +y, bit 2: +z) at local
// coordinates t, and its derivative with respect to t (columns of dt).
template <int Axes, bool WithDerivative>
inline void interpolate(const std::array<Vec3, 8>& c, const std::array<double, 3>& t, Vec3& v,
                        Mat3& dt) {
  const double tx = t[0], ty = t[1];
  if constexpr (Axes == 2) {
    const Vec3 dx0 = c[1] - c[0];
    const Vec3 dx1 = c[3] - c[2];
    const Vec3 a0 = c[0] + tx * dx0;
    const Vec3 a1 = c[2] + tx * dx1;
    v = a0 + ty * (a1 - a0);
    if constexpr (WithDerivative) {
      dt.col(0) = dx0 + ty * (dx1 - dx0);
      dt.col(1) = a1 - a0;
      dt.col(2).setZero();
    }
  } else {
    const double tz = t[2];
    const Vec3 d00 = c[1] - c[0], d10 = c[3] - c[2], d01 = c[5] - c[4], d11 = c[7] - c[6];
    const Vec3 a00 = c[0] + tx * d00, a10 = c[2] + tx * d10;
    const Vec3 a01 = c[4] + tx * d01, a11 = c[6] + tx * d11;
    const Vec3 b0 = a00 + ty * (a10 - a00), b1 = a01 + ty * (a11 - a01);
    v = b0 + tz * (b1 - b0);
    if constexpr (WithDerivative) {
      const Vec3 e0 = d00 + ty * (d10 - d00), e1 = d01 + ty * (d11 - d01);
      const Vec3 f0 = a10 - a00, f1 = a11 - a01;
      dt.col(0) = e0 + tz * (e1 - e0);
      dt.col(1) = f0 + tz * (f1 - f0);
      dt.col(2) = b1 - b0;
    }
  }
}

}  // namespace

GridField::GridField(std::shared_ptr<const VectorGrid> grid, const GridFieldOptions& options)
    : grid_(std::move(grid)), options_(options) {
  if (!grid_) throw InvalidArgument("GridField: no grid");
  const GridGeometry& g = grid_->geometry;
  if (g.dimension != 2 && g.dimension != 3)
    throw InvalidArgument("GridField: dimension must be 2 or 3, got " +
                          std::to_string(g.dimension));
  if (grid_->components != 2 && grid_->components != 3)
    throw InvalidArgument("GridField: components must be 2 or 3, got " +
                          std::to_string(grid_->components));
  axes_ = g.dimension;
  components_ = grid_->components;
  for (int a = 0; a < 3; ++a) {
    const auto n = g.size[static_cast<std::size_t>(a)];
    if (a < axes_ && n < 2)
      throw InvalidArgument("GridField: a " + std::to_string(axes_) + "D grid needs at least 2 " +
                            "samples along " + axis_name(a) + ", got " + std::to_string(n));
    if (a == 2 && axes_ == 2 && n != 1)
      throw InvalidArgument("GridField: a 2D grid has 1 sample along z, got " + std::to_string(n));
  }
  const std::size_t expected = g.point_count() * static_cast<std::size_t>(components_);
  if (grid_->values.size() != expected)
    throw InvalidArgument("GridField: the grid has " + std::to_string(grid_->values.size()) +
                          " values, its size and components need " + std::to_string(expected));
  if (!(options_.slab_half_thickness >= 0) || !std::isfinite(options_.slab_half_thickness))
    throw InvalidArgument("GridField: slab half thickness must be finite and >= 0, got " +
                          number(options_.slab_half_thickness));

  rectilinear_ = g.rectilinear();
  for (int a = 0; a < 3; ++a) {
    const auto ua = static_cast<std::size_t>(a);
    const std::int64_t n = g.size[ua];
    cells_[ua] = a < axes_ ? n - 1 : 0;
    stride_[ua] = static_cast<std::size_t>(components_) *
                  static_cast<std::size_t>(a == 0   ? 1
                                           : a == 1 ? g.size[0]
                                                    : g.size[0] * g.size[1]);
    if (rectilinear_) {
      const std::vector<double>& axis = g.axes[ua];
      if (static_cast<std::int64_t>(axis.size()) != n)
        throw InvalidArgument("GridField: rectilinear axis " + axis_name(a) + " has " +
                              std::to_string(axis.size()) + " coordinates for " +
                              std::to_string(n) + " samples");
      for (std::size_t i = 0; i < axis.size(); ++i) {
        if (!std::isfinite(axis[i]) || (i > 0 && !(axis[i] > axis[i - 1])))
          throw InvalidArgument("GridField: coordinates of axis " + axis_name(a) +
                                " must be finite and strictly increasing; entry " +
                                std::to_string(i) + " is " + number(axis[i]));
      }
      if (a < axes_) {
        inverse_width_[ua].resize(axis.size() - 1);
        for (std::size_t i = 0; i + 1 < axis.size(); ++i)
          inverse_width_[ua][i] = 1.0 / (axis[i + 1] - axis[i]);
      }
    } else {
      if (!std::isfinite(g.origin[a]))
        throw InvalidArgument("GridField: origin along " + axis_name(a) + " is " +
                              number(g.origin[a]));
      if (a < axes_ && (!std::isfinite(g.spacing[a]) || !(g.spacing[a] > 0)))
        throw InvalidArgument("GridField: spacing along " + axis_name(a) +
                              " must be finite and positive, got " + number(g.spacing[a]));
      origin_[ua] = g.origin[a];
      inverse_spacing_[ua] = a < axes_ ? 1.0 / g.spacing[a] : 0.0;
    }
  }
  values_ = grid_->values.data();

  domain_ = g.bounds();
  if (axes_ == 2) {
    const double z = domain_.lo.z();
    const double half = options_.slab_half_thickness > 0
                            ? options_.slab_half_thickness
                            : 0.5 * std::max(domain_.extent().x(), domain_.extent().y());
    domain_.lo.z() = z - half;
    domain_.hi.z() = z + half;
  }
}

bool GridField::locate(const Vec3& x, Cell& cell) const {
  if (!domain_.contains(x)) return false;  // also rejects NaN coordinates
  cell.base = 0;
  for (int a = 0; a < axes_; ++a) {
    const auto ua = static_cast<std::size_t>(a);
    std::int64_t i;
    double t;
    if (rectilinear_) {
      const std::vector<double>& axis = grid_->geometry.axes[ua];
      i = std::upper_bound(axis.begin(), axis.end(), x[a]) - axis.begin() - 1;
      i = std::clamp<std::int64_t>(i, 0, cells_[ua] - 1);
      t = (x[a] - axis[static_cast<std::size_t>(i)]) *
          inverse_width_[ua][static_cast<std::size_t>(i)];
    } else {
      const double u = (x[a] - origin_[ua]) * inverse_spacing_[ua];
      // u >= 0 up to rounding, and truncation sends tiny negatives to 0.
      i = std::min(static_cast<std::int64_t>(u), cells_[ua] - 1);
      i = std::max<std::int64_t>(i, 0);
      t = u - static_cast<double>(i);
    }
    cell.t[ua] = t;
    cell.inverse_width[ua] =
        rectilinear_ ? inverse_width_[ua][static_cast<std::size_t>(i)] : inverse_spacing_[ua];
    cell.base += static_cast<std::size_t>(i) * stride_[ua];
  }
  if (axes_ == 2) {
    cell.t[2] = 0.0;
    cell.inverse_width[2] = 0.0;
  }
  return true;
}

bool GridField::load_corners(const Cell& cell, std::array<Vec3, 8>& c) const {
  const int corners = axes_ == 2 ? 4 : 8;
  const bool zero_is_no_data = options_.zero_is_no_data;
  for (int n = 0; n < corners; ++n) {
    const float* p = values_ + cell.base + ((n & 1) ? stride_[0] : 0) + ((n & 2) ? stride_[1] : 0) +
                     ((n & 4) ? stride_[2] : 0);
    const float vx = p[0], vy = p[1], vz = components_ == 3 ? p[2] : 0.0f;
    if (std::isnan(vx) || std::isnan(vy) || std::isnan(vz)) return false;
    if (zero_is_no_data && vx == 0.0f && vy == 0.0f && vz == 0.0f) return false;
    c[static_cast<std::size_t>(n)] = Vec3(vx, vy, vz);
  }
  return true;
}

FieldStatus GridField::velocity(const Vec3& x, Vec3& v) const {
  Cell cell;
  if (!locate(x, cell)) return FieldStatus::outside;
  std::array<Vec3, 8> c;
  if (!load_corners(cell, c)) return FieldStatus::no_data;
  Mat3 unused;
  if (axes_ == 2)
    interpolate<2, false>(c, cell.t, v, unused);
  else
    interpolate<3, false>(c, cell.t, v, unused);
  return FieldStatus::inside;
}

FieldStatus GridField::velocity_jacobian(const Vec3& x, Vec3& v, Mat3& J) const {
  Cell cell;
  if (!locate(x, cell)) return FieldStatus::outside;
  std::array<Vec3, 8> c;
  if (!load_corners(cell, c)) return FieldStatus::no_data;
  Mat3 dt;
  if (axes_ == 2)
    interpolate<2, true>(c, cell.t, v, dt);
  else
    interpolate<3, true>(c, cell.t, v, dt);
  // dv/dx_a = dv/dt_a · dt_a/dx_a, with dt_a/dx_a = 1 / (width of the cell along a).
  J = dt * Eigen::Map<const Vec3>(cell.inverse_width.data()).asDiagonal();
  return FieldStatus::inside;
}

std::string GridField::describe() const {
  const GridGeometry& g = grid_->geometry;
  std::string text = "grid(" + std::string(rectilinear_ ? "rectilinear " : "uniform ") +
                     std::to_string(g.size[0]) + "x" + std::to_string(g.size[1]);
  if (axes_ == 3) text += "x" + std::to_string(g.size[2]);
  text += ", " + std::to_string(components_) + " components, bounds [" + number(domain_.lo.x()) +
          "," + number(domain_.hi.x()) + "]x[" + number(domain_.lo.y()) + "," +
          number(domain_.hi.y()) + "]x[" + number(domain_.lo.z()) + "," + number(domain_.hi.z()) +
          "]" + (options_.zero_is_no_data ? ", zero vectors = no data" : "") + ")";
  return text;
}

}  // namespace orthofront
