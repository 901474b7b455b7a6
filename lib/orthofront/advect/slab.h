#pragma once
/// A slab: two consecutive time steps of a gridded series, the unit bulk advection works on.
/// Views are trivially copyable (plain pointers and numbers) so one definition serves the CPU
/// and a CUDA kernel; the owner keeps the memory they point to. sample_slab() gives the values of
/// StreamedField (field/multilinear.h's arithmetic, linear in time), bit for bit on the CPU.
#include <cstdint>
#include <type_traits>

#include "orthofront/advect/host_device.h"

namespace orthofront::advect {

/// One axis of a uniform or rectilinear grid.
struct AxisView {
  const double* coordinates = nullptr;    ///< rectilinear: `cells + 1` increasing values
  const double* inverse_width = nullptr;  ///< rectilinear: 1 / (c[i+1] - c[i]), `cells` values
  double origin = 0;                      ///< uniform
  double inverse_spacing = 1;             ///< uniform
  double spacing = 1;                     ///< uniform (faces at origin + k spacing)
  std::int64_t cells = 1;                 ///< sample points - 1
  double lo = 0, hi = 1;                  ///< first and last sample
};

/// The geometry of the grid and how its samples are stored (x fastest, components interleaved).
struct GridView {
  int axes = 3;        ///< 2 or 3
  int components = 3;  ///< 2 or 3
  bool rectilinear = false;
  bool zero_is_no_data = false;  ///< a zero vector marks land or solid (as in StreamedField)
  AxisView axis[3];
  std::int64_t stride[3] = {3, 0, 0};  ///< floats between neighbouring points per axis
};

/// Two steps of samples at times t0 < t1.
struct SlabView {
  GridView grid;
  const float* step0 = nullptr;
  const float* step1 = nullptr;
  double t0 = 0, t1 = 1;
};

static_assert(std::is_trivially_copyable_v<SlabView>, "kernels receive SlabView by value");

/// Result of one sample.
enum class SampleStatus : unsigned char { inside = 0, outside = 1, no_data = 2 };

namespace detail {

/// Cell of x along one axis (x already checked against [lo, hi]); the arithmetic of
/// multilinear::locate_uniform / locate_rectilinear.
template <bool Rectilinear>
ORTHOFRONT_HD inline void locate(const AxisView& a, double x, std::int64_t& i, double& t,
                                 double& w) {
  if constexpr (Rectilinear) {
    // upper_bound over the cells + 1 coordinates, minus one, clamped to [0, cells - 1].
    std::int64_t first = 0, count = a.cells + 1;
    while (count > 0) {
      const std::int64_t step = count / 2;
      if (!(x < a.coordinates[first + step])) {
        first += step + 1;
        count -= step + 1;
      } else {
        count = step;
      }
    }
    i = first - 1;
    i = i < 0 ? 0 : (i > a.cells - 1 ? a.cells - 1 : i);
    w = a.inverse_width[i];
    t = (x - a.coordinates[i]) * w;
  } else {
    const double u = (x - a.origin) * a.inverse_spacing;
    i = static_cast<std::int64_t>(u);
    i = i > a.cells - 1 ? a.cells - 1 : i;
    i = i < 0 ? 0 : i;
    t = u - static_cast<double>(i);
    w = a.inverse_spacing;
  }
}

/// True when every component of a sample is zero (no data where the series says so).
template <int Components>
ORTHOFRONT_HD inline bool point_is_zero(const float* p) {
  bool zero = true;
  for (int c = 0; c < Components; ++c) zero = zero && p[c] == 0.0f;
  return zero;
}

/// Multilinear value of one step at a located cell (multilinear::interpolate's operations in its
/// order); false when a corner has no data. As in multilinear::value_is_finite, a corner's NaN or
/// infinity shows in the value, which is checked instead of the 8 corners (checking them was a
/// large share of a CPU particle step: docs/benchmarks/README.md); all-zero corners are looked
/// for only where they mean no data.
template <int Axes, int Components>
ORTHOFRONT_HD inline bool interpolate_step(const float* base, const std::int64_t* stride,
                                           double tx, double ty, double tz, bool zero_is_no_data,
                                           double* v) {
  const float* p000 = base;
  const float* p100 = base + stride[0];
  const float* p010 = base + stride[1];
  const float* p110 = base + stride[0] + stride[1];
  const float* p001 = Axes == 3 ? base + stride[2] : base;
  const float* p101 = Axes == 3 ? p001 + stride[0] : base;
  const float* p011 = Axes == 3 ? p001 + stride[1] : base;
  const float* p111 = Axes == 3 ? p001 + stride[0] + stride[1] : base;
  if (zero_is_no_data &&
      (point_is_zero<Components>(p000) || point_is_zero<Components>(p100) ||
       point_is_zero<Components>(p010) || point_is_zero<Components>(p110) ||
       (Axes == 3 && (point_is_zero<Components>(p001) || point_is_zero<Components>(p101) ||
                      point_is_zero<Components>(p011) || point_is_zero<Components>(p111)))))
    return false;
  for (int c = 0; c < Components; ++c) {
    const double c000 = p000[c], c100 = p100[c], c010 = p010[c], c110 = p110[c];
    const double d00 = c100 - c000, d10 = c110 - c010;
    const double a00 = c000 + tx * d00, a10 = c010 + tx * d10;
    if constexpr (Axes == 2) {
      v[c] = a00 + ty * (a10 - a00);
    } else {
      const double c001 = p001[c], c101 = p101[c], c011 = p011[c], c111 = p111[c];
      const double d01 = c101 - c001, d11 = c111 - c011;
      const double a01 = c001 + tx * d01, a11 = c011 + tx * d11;
      const double b0 = a00 + ty * (a10 - a00), b1 = a01 + ty * (a11 - a01);
      v[c] = b0 + tz * (b1 - b0);
    }
  }
  // Not std::isfinite (not a device function everywhere): NaN and infinity give v - v = NaN.
  bool finite = true;
  for (int c = 0; c < Components; ++c) finite = finite && v[c] - v[c] == 0.0;
  if constexpr (Components == 2) v[2] = 0.0;
  return finite;
}

/// floor / ceil of u from + - and casts (device code without <cmath>); |u| < 2^62.
ORTHOFRONT_HD inline double floor_of(double u) {
  const double f = static_cast<double>(static_cast<std::int64_t>(u));
  return f > u ? f - 1 : f;
}
ORTHOFRONT_HD inline double ceil_of(double u) {
  const double c = static_cast<double>(static_cast<std::int64_t>(u));
  return c < u ? c + 1 : c;
}
/// |a|, max and min for host and device code alike (no <cmath>, no std::).
ORTHOFRONT_HD inline double abs_of(double a) { return a < 0 ? -a : a; }
ORTHOFRONT_HD inline double max_of(double a, double b) { return a < b ? b : a; }
ORTHOFRONT_HD inline double min_of(double a, double b) { return a < b ? a : b; }

/// The first τ > after at which the straight path x + τ w crosses an interior face between two
/// cells (GridGeometry::next_cell_face on the view), or -1 where it crosses none. A point on a
/// face (rounding may put that face at τ <= after) looks on to the next one.
template <int Axes, bool Rectilinear>
ORTHOFRONT_HD inline double next_face(const GridView& g, const double* x, const double* w,
                                      double after) {
  double first = -1;
  for (int d = 0; d < Axes; ++d) {
    if (!(w[d] != 0)) continue;
    const AxisView& a = g.axis[d];
    const bool up = w[d] > 0;
    double from = x[d] + after * w[d];
    double k = -1;  // uniform: the face's index, stepped on where the first is at τ <= after
    for (int attempt = 0; attempt < 2; ++attempt) {
      double face = 0;
      if constexpr (Rectilinear) {
        // Interior coordinates c[1 .. cells - 1]: the first above `from` (upper bound), or the
        // last below it (lower bound, minus one).
        std::int64_t lo = 1, count = a.cells - 1;
        while (count > 0) {
          const std::int64_t step = count / 2;
          const double c = a.coordinates[lo + step];
          if (up ? !(from < c) : c < from) {
            lo += step + 1;
            count -= step + 1;
          } else {
            count = step;
          }
        }
        if (up ? lo > a.cells - 1 : lo - 1 < 1) break;
        face = a.coordinates[up ? lo : lo - 1];
      } else {
        if (attempt == 0) {
          const double u = (from - a.origin) * a.inverse_spacing;
          if (!(u > -4e18 && u < 4e18)) break;
          // From outside the grid the nearest interior face comes first.
          const double last = static_cast<double>(a.cells - 1);
          k = up ? max_of(floor_of(u) + 1, 1.0) : min_of(ceil_of(u) - 1, last);
        } else {
          k += up ? 1 : -1;
        }
        if (!(k >= 1 && k <= static_cast<double>(a.cells - 1))) break;
        face = a.origin + k * a.spacing;
      }
      const double tau = (face - x[d]) / w[d];
      if (tau > after) {
        if (first < 0 || tau < first) first = tau;
        break;
      }
      from = face;
    }
  }
  return first;
}

}  // namespace detail

/// v(x, t) for t in [s.t0, s.t1]: multilinear in space, linear in time. `outside` when x leaves
/// the grid's box (or is NaN), `no_data` when a corner of the cell has none at either step.
template <int Axes, int Components, bool Rectilinear>
ORTHOFRONT_HD inline SampleStatus sample_slab(const SlabView& s, const double* x, double t,
                                              double* v) {
  const GridView& g = s.grid;
  std::int64_t offset = 0;
  double u[3] = {0, 0, 0};
  for (int a = 0; a < Axes; ++a) {
    if (!(x[a] >= g.axis[a].lo && x[a] <= g.axis[a].hi)) return SampleStatus::outside;
    std::int64_t i = 0;
    double w = 0;
    detail::locate<Rectilinear>(g.axis[a], x[a], i, u[a], w);
    offset += i * g.stride[a];
  }
  double v0[3], v1[3];
  if (!detail::interpolate_step<Axes, Components>(s.step0 + offset, g.stride, u[0], u[1], u[2],
                                                  g.zero_is_no_data, v0) ||
      !detail::interpolate_step<Axes, Components>(s.step1 + offset, g.stride, u[0], u[1], u[2],
                                                  g.zero_is_no_data, v1))
    return SampleStatus::no_data;
  const double w = (t - s.t0) / (s.t1 - s.t0);
  for (int c = 0; c < 3; ++c) v[c] = (1 - w) * v0[c] + w * v1[c];
  return SampleStatus::inside;
}

}  // namespace orthofront::advect
