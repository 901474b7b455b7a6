#pragma once
/// The one multilinear-plus-Jacobian kernel: cell lookup along an axis of a uniform or
/// rectilinear grid, and bilinear (2D) or trilinear (3D) interpolation of a cell's corners with the
/// exact derivative of that interpolant. Every sampled field (in-memory grids, bricked time steps,
/// VDB leaves) goes through these functions, so a value does not depend on where the samples were
/// stored: same corners and same coordinates give the same bits.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "orthofront/types.h"

namespace orthofront::multilinear {

/// Where a coordinate falls along one axis: cell `i` (its first sample), local coordinate
/// `t` in [0, 1] and `w` = 1 / cell width.
struct AxisCell {
  std::int64_t i = 0;
  double t = 0;
  double w = 0;
};

/// Uniform axis: u = (x - origin) · inverse_spacing. The caller has checked x against the axis'
/// bounds; truncation sends tiny negatives to cell 0, and a point on the last sample belongs to the
/// last cell (t = 1).
inline AxisCell locate_uniform(double x, double origin, double inverse_spacing,
                               std::int64_t cells) {
  const double u = (x - origin) * inverse_spacing;
  std::int64_t i = std::min(static_cast<std::int64_t>(u), cells - 1);
  i = std::max<std::int64_t>(i, 0);
  return {i, u - static_cast<double>(i), inverse_spacing};
}

/// Rectilinear axis (strictly increasing coordinates, inverse_width[i] = 1 / (axis[i+1] - axis[i])).
inline AxisCell locate_rectilinear(double x, const std::vector<double>& axis,
                                   const double* inverse_width, std::int64_t cells) {
  std::int64_t i = std::upper_bound(axis.begin(), axis.end(), x) - axis.begin() - 1;
  i = std::clamp<std::int64_t>(i, 0, cells - 1);
  const double w = inverse_width[i];
  return {i, (x - axis[static_cast<std::size_t>(i)]) * w, w};
}

/// Interpolates `Components` values per corner; `corner(bx, by, bz)` returns a pointer (to float
/// or double samples) to the components of corner (i + bx, j + by, k + bz) of the cell. v gets the value; with a Jacobian,
/// J(c, a) = ∂v_c/∂x_a (column 2 is 0 on 2D cells; row 2 is 0 with two components).
template <int Axes, int Components, bool WithJacobian, class Corner>
inline void interpolate(const Corner& corner, const AxisCell (&cell)[3], Vec3& v, Mat3* J) {
  const auto* p000 = corner(0, 0, 0);
  const auto* p100 = corner(1, 0, 0);
  const auto* p010 = corner(0, 1, 0);
  const auto* p110 = corner(1, 1, 0);
  const double tx = cell[0].t, ty = cell[1].t;
  for (int c = 0; c < Components; ++c) {
    const double c000 = p000[c], c100 = p100[c], c010 = p010[c], c110 = p110[c];
    const double d00 = c100 - c000, d10 = c110 - c010;
    const double a00 = c000 + tx * d00, a10 = c010 + tx * d10;
    if constexpr (Axes == 2) {
      v[c] = a00 + ty * (a10 - a00);
      if constexpr (WithJacobian) {
        (*J)(c, 0) = (d00 + ty * (d10 - d00)) * cell[0].w;
        (*J)(c, 1) = (a10 - a00) * cell[1].w;
        (*J)(c, 2) = 0.0;
      }
    } else {
      const double tz = cell[2].t;
      const auto* p001 = corner(0, 0, 1);
      const auto* p101 = corner(1, 0, 1);
      const auto* p011 = corner(0, 1, 1);
      const auto* p111 = corner(1, 1, 1);
      const double c001 = p001[c], c101 = p101[c], c011 = p011[c], c111 = p111[c];
      const double d01 = c101 - c001, d11 = c111 - c011;
      const double a01 = c001 + tx * d01, a11 = c011 + tx * d11;
      const double b0 = a00 + ty * (a10 - a00), b1 = a01 + ty * (a11 - a01);
      v[c] = b0 + tz * (b1 - b0);
      if constexpr (WithJacobian) {
        const double e0 = d00 + ty * (d10 - d00), e1 = d01 + ty * (d11 - d01);
        const double f0 = a10 - a00, f1 = a11 - a01;
        (*J)(c, 0) = (e0 + tz * (e1 - e0)) * cell[0].w;
        (*J)(c, 1) = (f0 + tz * (f1 - f0)) * cell[1].w;
        (*J)(c, 2) = (b1 - b0) * cell[2].w;
      }
    }
  }
  if constexpr (Components == 2) {
    v[2] = 0.0;
    if constexpr (WithJacobian) J->row(2).setZero();
  }
}

/// True when every component of a sample point is zero.
template <int Components>
inline bool point_is_zero(const float* p) {
  bool zero = true;
  for (int c = 0; c < Components; ++c) zero = zero && p[c] == 0.0f;
  return zero;
}

/// True when a sample point carries no data: a non-finite component, or (zero_is_no_data) a zero
/// vector, which real data uses for land and solid cells.
template <int Components>
inline bool point_has_no_data(const float* p, bool zero_is_no_data) {
  bool finite = true;
  for (int c = 0; c < Components; ++c) finite = finite && std::isfinite(p[c]);
  return !finite || (zero_is_no_data && point_is_zero<Components>(p));
}

/// True when every component of an interpolated value is finite. Interpolating float corners, a
/// corner's NaN or infinity reaches its component of the value at every weight (0 · inf and
/// inf - inf are NaN; floats cannot overflow these sums of doubles), so this finds a cell with a
/// non-finite corner from the value alone, without looking at the 8 corners.
template <int Components>
inline bool value_is_finite(const Vec3& v) {
  bool finite = true;
  for (int c = 0; c < Components; ++c) finite = finite && v[c] - v[c] == 0.0;
  return finite;
}

/// True when any corner of the cell is a zero vector (no data where the data says so; a
/// non-finite corner shows in the value instead: value_is_finite).
template <int Axes, int Components, class Corner>
inline bool cell_has_zero_vector(const Corner& corner) {
  for (int bz = 0; bz < (Axes == 3 ? 2 : 1); ++bz)
    for (int by = 0; by < 2; ++by)
      for (int bx = 0; bx < 2; ++bx)
        if (point_is_zero<Components>(corner(bx, by, bz))) return true;
  return false;
}

}  // namespace orthofront::multilinear
