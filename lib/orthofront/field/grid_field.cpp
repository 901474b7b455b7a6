#include "orthofront/field/grid_field.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <utility>

#include "orthofront/error.h"
#include "orthofront/field/multilinear.h"

namespace orthofront {
namespace {

std::string axis_name(int axis) {
  return std::string(1, static_cast<char>('x' + axis));
}

std::string number(double value) {
  // Shortest text that reads back as the same double.
  char text[32];
  const auto result = std::to_chars(text, text + sizeof text, value);
  return std::string(text, result.ptr);
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
  kind_ = 4 * (axes_ == 3) + 2 * (components_ == 3) + (rectilinear_ ? 1 : 0);
  cell_stride_ = {1, static_cast<std::size_t>(cells_[0]),
                  static_cast<std::size_t>(cells_[0] * std::max<std::int64_t>(cells_[1], 1))};
  build_no_data_mask();

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

void GridField::build_no_data_mask() {
  const GridGeometry& g = grid_->geometry;
  const std::size_t points = g.point_count();
  const auto c = static_cast<std::size_t>(components_);
  const bool zero_is_no_data = options_.zero_is_no_data;
  // Pass 1: points without data.
  std::vector<std::uint8_t> bad(points, 0);
  const bool any = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, points, 1 << 14), false,
      [&](const tbb::blocked_range<std::size_t>& r, bool found) {
        for (std::size_t p = r.begin(); p != r.end(); ++p) {
          const float* v = values_ + p * c;
          const bool no_data = c == 3 ? multilinear::point_has_no_data<3>(v, zero_is_no_data)
                                      : multilinear::point_has_no_data<2>(v, zero_is_no_data);
          if (no_data) {
            bad[p] = 1;
            found = true;
          }
        }
        return found;
      },
      [](bool a, bool b) { return a || b; });
  if (!any) return;
  // Pass 2: a cell has no data when one of its corners has none; one task per run of 64 cells.
  const std::size_t cx = static_cast<std::size_t>(cells_[0]),
                    cy = static_cast<std::size_t>(cells_[1]);
  const std::size_t cz = axes_ == 3 ? static_cast<std::size_t>(cells_[2]) : 1;
  const std::size_t cells = cx * cy * cz;
  const std::size_t px = stride_[1] / c, pxy = axes_ == 3 ? stride_[2] / c : 0;
  no_data_cells_.assign((cells + 63) / 64, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, no_data_cells_.size(), 256),
                    [&](const tbb::blocked_range<std::size_t>& words) {
                      for (std::size_t w = words.begin(); w != words.end(); ++w) {
                        std::uint64_t bits = 0;
                        for (std::size_t b = 0; b < 64 && 64 * w + b < cells; ++b) {
                          const std::size_t cell = 64 * w + b;
                          const std::size_t i = cell % cx, j = (cell / cx) % cy,
                                            k = cell / (cx * cy);
                          const std::size_t p = i + px * j + pxy * k;
                          bool no_data = bad[p] || bad[p + 1] || bad[p + px] || bad[p + px + 1];
                          if (axes_ == 3)
                            no_data = no_data || bad[p + pxy] || bad[p + pxy + 1] ||
                                      bad[p + pxy + px] || bad[p + pxy + px + 1];
                          if (no_data) bits |= std::uint64_t{1} << b;
                        }
                        no_data_cells_[w] = bits;
                      }
                    });
}

template <int Axes, int Components, bool Rectilinear, bool WithJacobian>
FieldStatus GridField::evaluate(const Vec3& x, Vec3& v, Mat3* J) const {
  if (!domain_.contains(x)) return FieldStatus::outside;  // also rejects NaN coordinates
  std::size_t base = 0, cell = 0;
  multilinear::AxisCell at[3];
  for (int a = 0; a < Axes; ++a) {
    const auto ua = static_cast<std::size_t>(a);
    if constexpr (Rectilinear)
      at[a] = multilinear::locate_rectilinear(x[a], grid_->geometry.axes[ua],
                                              inverse_width_[ua].data(), cells_[ua]);
    else
      at[a] = multilinear::locate_uniform(x[a], origin_[ua], inverse_spacing_[ua], cells_[ua]);
    base += static_cast<std::size_t>(at[a].i) * stride_[ua];
    cell += static_cast<std::size_t>(at[a].i) * cell_stride_[ua];
  }
  if (!no_data_cells_.empty() && ((no_data_cells_[cell >> 6] >> (cell & 63)) & 1u) != 0)
    return FieldStatus::no_data;
  const float* p = values_ + base;
  const std::size_t sy = stride_[1], sz = stride_[2];
  const auto corner = [p, sy, sz](int bx, int by, int bz) {
    return p + static_cast<std::size_t>(bx) * Components + static_cast<std::size_t>(by) * sy +
           static_cast<std::size_t>(bz) * sz;
  };
  multilinear::interpolate<Axes, Components, WithJacobian>(corner, at, v, J);
  return FieldStatus::inside;
}

template <bool WithJacobian>
FieldStatus GridField::dispatch(const Vec3& x, Vec3& v, Mat3* J) const {
  switch (kind_) {
    case 0:
      return evaluate<2, 2, false, WithJacobian>(x, v, J);
    case 1:
      return evaluate<2, 2, true, WithJacobian>(x, v, J);
    case 2:
      return evaluate<2, 3, false, WithJacobian>(x, v, J);
    case 3:
      return evaluate<2, 3, true, WithJacobian>(x, v, J);
    case 4:
      return evaluate<3, 2, false, WithJacobian>(x, v, J);
    case 5:
      return evaluate<3, 2, true, WithJacobian>(x, v, J);
    case 6:
      return evaluate<3, 3, false, WithJacobian>(x, v, J);
    default:
      return evaluate<3, 3, true, WithJacobian>(x, v, J);
  }
}

double GridField::next_kink(const Vec3& x, const Vec3& w, double after, double before) const {
  const double tau = grid_->geometry.next_cell_face(x, w, after);
  return tau < before ? tau : std::numeric_limits<double>::infinity();
}

FieldStatus GridField::velocity(const Vec3& x, Vec3& v) const {
  return dispatch<false>(x, v, nullptr);
}

FieldStatus GridField::velocity_jacobian(const Vec3& x, Vec3& v, Mat3& J) const {
  return dispatch<true>(x, v, &J);
}

std::string GridField::describe() const {
  // Built by appending: GCC 12 warns (-Wrestrict, a false positive) on long "a" + b chains.
  const GridGeometry& g = grid_->geometry;
  std::string text = "grid(";
  text += rectilinear_ ? "rectilinear " : "uniform ";
  text += std::to_string(g.size[0]);
  text += 'x';
  text += std::to_string(g.size[1]);
  if (axes_ == 3) {
    text += 'x';
    text += std::to_string(g.size[2]);
  }
  text += ", ";
  text += std::to_string(components_);
  text += " components, bounds";
  for (int a = 0; a < 3; ++a) {
    text += a == 0 ? " [" : "x[";
    text += number(domain_.lo[a]);
    text += ',';
    text += number(domain_.hi[a]);
    text += ']';
  }
  if (options_.zero_is_no_data) text += ", zero vectors = no data";
  text += ')';
  return text;
}

}  // namespace orthofront
