// orthofront-pop-convert: POP ocean model output (NetCDF, read by orthofront's reader) on its
// curvilinear lon/lat grid and layered depth, or a 2D product of surface currents (--w none
// --depth none) -> a uniform grid in the project's HDF5 layout, one step per input file. Land (velocity exactly zero, or fill values) becomes NaN (no data). The resampling
// loss is measured by interpolating the uniform grid back at every original ocean point.
//
//   orthofront-pop-convert t.x1_SAMOC_flux.1690*.nc --out pop.h5 [--coords degrees|metres]
//       [--resolution NX,NY,NZ] [--dt SECONDS | --times T0,T1,...] [--compress gzip[:L]]
//       [--report loss.json]
//
// Coordinates (--coords):
//   degrees (default): x = longitude (deg east), y = latitude (deg north), z = -depth (m, up);
//     velocity (dlon/dt, dlat/dt, dz/dt) in deg/s, deg/s, m/s: trajectories are those on the
//     sphere (radius 6371.22 km, POP's), exactly.
//   metres: the equirectangular projection about the domain's centre, x = R cos(lat_c) dlon,
//     y = R dlat, z = -depth, all in m; velocity (u cos(lat_c) / cos(lat), v, w) in m/s, so
//     trajectories are again exactly those on the sphere, mapped to the plane.
// Times: the files in natural order at t = 0, dt, 2 dt, ... (--dt, default 1 with unit "step"),
// or --times. The files carry no time variable.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "orthofront/io/grid_series.h"
#include "orthofront/error.h"
#include "orthofront/field/grid.h"
#include "orthofront/field/grid_field.h"
#include "orthofront/io/error.h"
#include "orthofront/io/hdf5_layout.h"
#include "orthofront/io/netcdf_series.h"

namespace fs = std::filesystem;
using orthofront::Error;
using orthofront::GridGeometry;
using orthofront::InvalidArgument;
using orthofront::Vec3;
using orthofront::VectorGrid;
using orthofront::io::FormatError;
using orthofront::io::IoError;

namespace {

constexpr double kEarthRadius = 6.37122e6;  // m, POP's radius
constexpr double kDegree = M_PI / 180.0;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// ------------------------------------------------------------------------------------------------
// Reading the model's variables (netCDF-C through orthofront's NetCDF reader: classic, 64-bit
// offset and NetCDF-4 files; packing, fill and missing values and the valid range applied)

struct Variable {
  std::vector<std::size_t> dims;
  std::vector<float> values;  // no data already NaN
  std::string units;
};

/// The variable with leading length-1 dimensions (a time axis of one step) dropped down to
/// `rank`; FormatError naming the file, the variable and its shape when it does not have `rank`
/// dimensions then.
Variable read_variable(const fs::path& path, const std::string& name, std::size_t rank) {
  orthofront::io::NetcdfVariable v = orthofront::io::read_netcdf_variable(path, name);
  while (v.shape.size() > rank && v.shape.front() == 1) {
    v.shape.erase(v.shape.begin());
    v.dimensions.erase(v.dimensions.begin());
  }
  if (v.shape.size() != rank) {
    std::string shape;
    for (std::size_t k = 0; k < v.shape.size(); ++k)
      shape += (k ? ", " : "") + v.dimensions[k] + " = " + std::to_string(v.shape[k]);
    throw FormatError(path.string() + ": variable '" + name + "' has dimensions (" + shape +
                      "); expected " + std::to_string(rank));
  }
  Variable out;
  out.dims = v.shape;
  out.units = v.units;
  out.values.resize(v.values.size());
  for (std::size_t p = 0; p < v.values.size(); ++p) {
    const double x = v.values[p];
    out.values[p] = std::abs(x) > 1e30 ? kNaN : static_cast<float>(x);  // POP's unflagged fill
  }
  return out;
}

bool given(const std::string& name) { return !name.empty() && name != "none"; }

struct PopFile {
  std::vector<float> u, v, w;  // [k][j][i], in the file's velocity unit, NaN = fill
};

/// Positions of one variable's samples: a curvilinear lon/lat grid and depth levels.
struct Layout {
  std::vector<double> lon, lat;  // [j][i], degrees (lon unwrapped to a continuous range)
  std::vector<double> z;         // levels, m, up (negative depths), k = 0 at the top
};

/// POP's B grid: UVEL and VVEL at U points (ULON, ULAT) and layer centres; WVEL at T points (the
/// centres of the U cells: U(i, j) is the north-east corner of T(i, j)) on the top face of each
/// layer (w_dep[k]). A 2D product (no depth) has one level and no w.
struct PopGrid {
  std::size_t ni = 0, nj = 0, nk = 0;
  bool surface_only = false;  // 2D: u and v only, one level
  double metres_per_unit = 0.01;  // velocity unit of the files
  std::string velocity_units;
  Layout uv;  // U points, layer centres
  Layout w;   // T points, layer tops
};

struct Names {
  std::string u = "UVEL", v = "VVEL", w = "WVEL", lon = "ULON", lat = "ULAT", depth = "w_dep";
  std::string units;  // overrides the files' velocity units
};

/// lon and lat as (j, i) arrays: 2D variables as they are, 1D axes (lon(i), lat(j)) spread out.
void read_lon_lat(const fs::path& path, const Names& names, PopGrid& g) {
  const auto rank = orthofront::io::read_netcdf_variable(path, names.lon).shape.size();
  if (rank == 1) {
    const Variable lon = read_variable(path, names.lon, 1);
    const Variable lat = read_variable(path, names.lat, 1);
    if (lon.dims[0] != g.ni || lat.dims[0] != g.nj)
      throw FormatError(path.string() + ": " + names.lon + "(" + std::to_string(lon.dims[0]) +
                        ") and " + names.lat + "(" + std::to_string(lat.dims[0]) +
                        ") do not match " + names.u + "'s (j, i) = (" + std::to_string(g.nj) +
                        ", " + std::to_string(g.ni) + ")");
    for (std::size_t j = 0; j < g.nj; ++j)
      for (std::size_t i = 0; i < g.ni; ++i) {
        g.uv.lon.push_back(lon.values[i]);
        g.uv.lat.push_back(lat.values[j]);
      }
    return;
  }
  const Variable lon = read_variable(path, names.lon, 2);
  const Variable lat = read_variable(path, names.lat, 2);
  if (lon.dims != std::vector<std::size_t>{g.nj, g.ni} || lat.dims != lon.dims)
    throw FormatError(path.string() + ": " + names.lon + "/" + names.lat + " are not (j, i) = (" +
                      std::to_string(g.nj) + ", " + std::to_string(g.ni) + ") like " + names.u);
  g.uv.lon.assign(lon.values.begin(), lon.values.end());
  g.uv.lat.assign(lat.values.begin(), lat.values.end());
}

PopGrid read_grid(const fs::path& path, const Names& names) {
  PopGrid g;
  g.surface_only = !given(names.depth);
  if (g.surface_only == given(names.w))
    throw InvalidArgument("give both --w and --depth for 3D output, or neither (--w none "
                          "--depth none) for a 2D product");
  const Variable u = read_variable(path, names.u, g.surface_only ? 2 : 3);
  g.nk = g.surface_only ? 1 : u.dims[0];
  g.nj = u.dims[u.dims.size() - 2];
  g.ni = u.dims[u.dims.size() - 1];
  if (g.ni < 2 || g.nj < 2 || (!g.surface_only && g.nk < 2))
    throw FormatError(path.string() + ": fewer than 2 points on an axis of " + names.u);
  g.velocity_units = names.units.empty() ? u.units : names.units;
  if (g.velocity_units.empty()) {
    g.velocity_units = "cm/s (assumed: " + names.u + " states no units; POP's)";
  } else if (const auto factor = orthofront::io::metres_per_second(g.velocity_units)) {
    g.metres_per_unit = *factor;
  } else {
    throw FormatError(path.string() + ": " + names.u + " has units '" + g.velocity_units +
                      "', not a speed (give --units m/s or cm/s if they are)");
  }
  read_lon_lat(path, names, g);
  for (std::size_t p = 0; p < g.uv.lon.size(); ++p) {
    if (!std::isfinite(g.uv.lon[p]) || !std::isfinite(g.uv.lat[p]))
      throw FormatError(path.string() + ": " + names.lon + "/" + names.lat + " hold fill values");
    while (g.uv.lon[p] - g.uv.lon[0] > 180.0) g.uv.lon[p] -= 360.0;
    while (g.uv.lon[p] - g.uv.lon[0] < -180.0) g.uv.lon[p] += 360.0;
  }
  if (g.surface_only) {
    g.uv.z = {0.0};
    g.w = g.uv;
    return g;
  }
  const Variable depth = read_variable(path, names.depth, 1);
  const std::size_t nd = depth.values.size();
  if (nd != g.nk && nd != g.nk + 1) {
    throw FormatError(path.string() + ": " + names.depth + " has " + std::to_string(nd) +
                      " values; expected " + std::to_string(g.nk) + " layer centres or " +
                      std::to_string(g.nk + 1) + " interfaces");
  }
  for (std::size_t k = 0; k < g.nk; ++k) {
    const double d = nd == g.nk ? depth.values[k] : 0.5 * (depth.values[k] + depth.values[k + 1]);
    g.uv.z.push_back(-d);
    // W on the top face of layer k; with centres only, half way to the centre above.
    const double top = nd == g.nk + 1 ? depth.values[k]
                                      : (k == 0 ? 0.0 : 0.5 * (depth.values[k - 1] + depth.values[k]));
    g.w.z.push_back(-top);
    if (k > 0 && (!(g.uv.z[k] < g.uv.z[k - 1]) || !(g.w.z[k] < g.w.z[k - 1])))
      throw FormatError(path.string() + ": " + names.depth + " does not increase with k");
  }
  // T points: the centre of the four U points around them (U(i, j) is the north-east corner of
  // T(i, j)); on the first row and column the missing U points are extrapolated linearly.
  const std::function<double(std::ptrdiff_t, std::ptrdiff_t, const std::vector<double>&)> u_at =
      [&](std::ptrdiff_t i, std::ptrdiff_t j, const std::vector<double>& a) -> double {
    if (j < 0) return 2 * u_at(i, 0, a) - u_at(i, 1, a);
    if (i < 0) return 2 * u_at(0, j, a) - u_at(1, j, a);
    return a[static_cast<std::size_t>(j) * g.ni + static_cast<std::size_t>(i)];
  };
  g.w.lon.resize(g.uv.lon.size());
  g.w.lat.resize(g.uv.lat.size());
  for (std::size_t j = 0; j < g.nj; ++j)
    for (std::size_t i = 0; i < g.ni; ++i) {
      const auto ii = static_cast<std::ptrdiff_t>(i), jj = static_cast<std::ptrdiff_t>(j);
      for (auto [from, to] : {std::pair{&g.uv.lon, &g.w.lon}, std::pair{&g.uv.lat, &g.w.lat}}) {
        (*to)[j * g.ni + i] = 0.25 * (u_at(ii, jj, *from) + u_at(ii - 1, jj, *from) +
                                      u_at(ii, jj - 1, *from) + u_at(ii - 1, jj - 1, *from));
      }
    }
  return g;
}

PopFile read_step(const fs::path& path, const PopGrid& grid, const Names& names) {
  PopFile step;
  const std::size_t rank = grid.surface_only ? 2 : 3;
  const std::vector<std::size_t> shape =
      grid.surface_only ? std::vector<std::size_t>{grid.nj, grid.ni}
                        : std::vector<std::size_t>{grid.nk, grid.nj, grid.ni};
  for (auto [name, target] : {std::pair{&names.u, &step.u}, std::pair{&names.v, &step.v},
                              std::pair{&names.w, &step.w}}) {
    if (!given(*name)) continue;
    Variable v = read_variable(path, *name, rank);
    if (v.dims != shape)
      throw FormatError(path.string() + ": " + *name + " is not (" +
                        (grid.surface_only ? "" : "k, ") + "j, i) = (" +
                        (grid.surface_only ? "" : std::to_string(grid.nk) + ", ") +
                        std::to_string(grid.nj) + ", " + std::to_string(grid.ni) +
                        ") like the first file's");
    *target = std::move(v.values);
  }
  if (grid.surface_only) step.w.assign(step.u.size(), 0.0f);
  // The grid must be the first file's.
  PopGrid same;
  same.ni = grid.ni;
  same.nj = grid.nj;
  read_lon_lat(path, names, same);
  for (std::size_t p = 0; p < same.uv.lon.size(); ++p) {
    double x = same.uv.lon[p];
    while (x - grid.uv.lon[0] > 180.0) x -= 360.0;
    while (x - grid.uv.lon[0] < -180.0) x += 360.0;
    if (std::abs(x - grid.uv.lon[p]) > 1e-9 || std::abs(same.uv.lat[p] - grid.uv.lat[p]) > 1e-9)
      throw FormatError(path.string() + ": " + names.lon + "/" + names.lat +
                        " differ from the first file's");
  }
  return step;
}

// ------------------------------------------------------------------------------------------------
// Coordinates and velocities of the output

struct Mapping {
  bool metres = false;
  double metres_per_unit = 0.01;  // the files' velocity unit (POP: cm/s)
  double lon_c = 0, lat_c = 0;  // projection centre (metres)

  // (lon, lat, z) -> output position
  Vec3 position(double lon, double lat, double z) const {
    if (!metres) return Vec3(lon, lat, z);
    return Vec3(kEarthRadius * std::cos(lat_c * kDegree) * (lon - lon_c) * kDegree,
                kEarthRadius * (lat - lat_c) * kDegree, z);
  }
  // Output velocity per file unit of (u east, v north, w up) at latitude lat: the diagonal scale.
  Vec3 scale(double lat) const {
    const double cos_lat = std::cos(lat * kDegree);
    const double f = metres_per_unit;
    if (!metres) return Vec3(f / (kEarthRadius * cos_lat) / kDegree, f / kEarthRadius / kDegree, f);
    return Vec3(f * std::cos(lat_c * kDegree) / cos_lat, f, f);
  }
  std::string length_unit() const { return metres ? "m (equirectangular x east, y north; z up)" : "deg (x longitude east, y latitude north), m (z up)"; }
  std::string velocity_unit() const { return metres ? "m/s" : "deg/s (x, y), m/s (z)"; }
};

// ------------------------------------------------------------------------------------------------
// Resampling

/// Where a target (lon, lat) falls in a curvilinear grid: cell (i, j) and bilinear (s, t).
struct CellHit {
  std::size_t i = 0, j = 0;
  double s = 0, t = 0;
};

class Locator {
 public:
  Locator(const Layout& layout, std::size_t ni, std::size_t nj) : l_(layout), ni_(ni), nj_(nj) {}

  /// Inverse bilinear map within cell (i, j) by Newton; false when it does not converge.
  bool local(std::size_t i, std::size_t j, double lon, double lat, double& s, double& t) const {
    const auto at = [&](std::size_t ii, std::size_t jj) {
      const std::size_t p = jj * ni_ + ii;
      return std::array<double, 2>{l_.lon[p], l_.lat[p]};
    };
    const auto p00 = at(i, j), p10 = at(i + 1, j), p01 = at(i, j + 1), p11 = at(i + 1, j + 1);
    s = 0.5;
    t = 0.5;
    for (int it = 0; it < 30; ++it) {
      double f[2], ds[2], dt[2];
      for (std::size_t c = 0; c < 2; ++c) {
        f[c] = (1 - s) * (1 - t) * p00[c] + s * (1 - t) * p10[c] + (1 - s) * t * p01[c] +
               s * t * p11[c] - (c == 0 ? lon : lat);
        ds[c] = (1 - t) * (p10[c] - p00[c]) + t * (p11[c] - p01[c]);
        dt[c] = (1 - s) * (p01[c] - p00[c]) + s * (p11[c] - p10[c]);
      }
      const double det = ds[0] * dt[1] - ds[1] * dt[0];
      if (det == 0 || !std::isfinite(det)) return false;
      const double step_s = (f[0] * dt[1] - f[1] * dt[0]) / det;
      const double step_t = (ds[0] * f[1] - ds[1] * f[0]) / det;
      s -= step_s;
      t -= step_t;
      if (std::abs(step_s) < 1e-13 && std::abs(step_t) < 1e-13) return true;
    }
    return std::abs(s) < 1e6 && std::abs(t) < 1e6;
  }

  /// Walks from the last hit towards the point, then searches every cell. With `clamp`, a point
  /// beyond the grid takes the nearest border cell's value (s, t clamped: constant extrapolation).
  bool find(double lon, double lat, bool clamp, CellHit& hit) {
    constexpr double eps = 1e-9;
    const auto accept = [&](std::size_t i, std::size_t j, double s, double t) {
      hit = {i, j, std::clamp(s, 0.0, 1.0), std::clamp(t, 0.0, 1.0)};
      last_i_ = i;
      last_j_ = j;
      return true;
    };
    std::size_t i = last_i_, j = last_j_;
    for (std::size_t walk = 0; walk < ni_ + nj_ + 4; ++walk) {
      double s = 0, t = 0;
      if (!local(i, j, lon, lat, s, t)) break;
      if (s >= -eps && s <= 1 + eps && t >= -eps && t <= 1 + eps) return accept(i, j, s, t);
      const auto move = [](std::size_t c, double f, std::size_t n) {
        const double target = static_cast<double>(c) + std::floor(f);
        return static_cast<std::size_t>(std::clamp(target, 0.0, static_cast<double>(n - 2)));
      };
      const std::size_t ni = move(i, s, ni_), nj = move(j, t, nj_);
      if (ni == i && nj == j) {  // at the border and still outside
        if (clamp) return accept(i, j, s, t);
        break;
      }
      i = ni;
      j = nj;
    }
    for (std::size_t jj = 0; jj + 1 < nj_; ++jj) {
      for (std::size_t ii = 0; ii + 1 < ni_; ++ii) {
        double s = 0, t = 0;
        if (local(ii, jj, lon, lat, s, t) && s >= -eps && s <= 1 + eps && t >= -eps && t <= 1 + eps)
          return accept(ii, jj, s, t);
      }
    }
    return false;
  }

 private:
  const Layout& l_;
  std::size_t ni_, nj_;
  std::size_t last_i_ = 0, last_j_ = 0;
};

/// Interpolation weights of one target point: up to 8 source samples.
struct Stencil {
  std::array<std::uint32_t, 8> index{};
  std::array<double, 8> weight{};
  int count = 0;  // 0: outside the source grid
};

struct Target {
  GridGeometry geometry;
  double lon_lo = 0, lon_hi = 0, lat_lo = 0, lat_hi = 0, z_bottom = 0, z_top = 0;
  std::vector<Stencil> uv;  // per target point, from the U points and layer centres
  std::vector<Stencil> w;   // per target point, from the T points and layer tops

  double lon(std::int64_t i) const { return lon_lo + (lon_hi - lon_lo) * static_cast<double>(i) / static_cast<double>(geometry.size[0] - 1); }
  double lat(std::int64_t j) const { return lat_lo + (lat_hi - lat_lo) * static_cast<double>(j) / static_cast<double>(geometry.size[1] - 1); }
  double z(std::int64_t k) const {
    if (geometry.size[2] == 1) return z_top;  // a 2D product: one level
    return z_bottom + (z_top - z_bottom) * static_cast<double>(k) / static_cast<double>(geometry.size[2] - 1);
  }
};

/// Trilinear stencils (bilinear in the curvilinear cell, linear between levels) of every target
/// point. With `extrapolate`, points beyond the source grid take the border values (levels too).
std::vector<Stencil> build_stencils(const Layout& layout, const PopGrid& g, const Target& target,
                                    bool extrapolate) {
  const GridGeometry& geo = target.geometry;
  Locator locator(layout, g.ni, g.nj);
  std::vector<CellHit> columns(static_cast<std::size_t>(geo.size[0] * geo.size[1]));
  std::vector<bool> found(columns.size());
  for (std::int64_t j = 0; j < geo.size[1]; ++j)
    for (std::int64_t i = 0; i < geo.size[0]; ++i) {
      const auto c = static_cast<std::size_t>(j * geo.size[0] + i);
      found[c] = locator.find(target.lon(i), target.lat(j), extrapolate, columns[c]);
    }
  std::vector<Stencil> stencils(geo.point_count());
  for (std::int64_t k = 0; k < geo.size[2]; ++k) {
    // The source levels around z (z decreases with the source k); beyond them: the last level.
    const double z = target.z(k);
    std::size_t layer = 0;
    while (layer + 2 < g.nk && layout.z[layer + 1] > z) ++layer;
    const double r = g.nk == 1 ? 0.0
                               : std::clamp((layout.z[layer] - z) / (layout.z[layer] - layout.z[layer + 1]), 0.0, 1.0);
    for (std::int64_t j = 0; j < geo.size[1]; ++j)
      for (std::int64_t i = 0; i < geo.size[0]; ++i) {
        const auto c = static_cast<std::size_t>(j * geo.size[0] + i);
        Stencil& st = stencils[geo.index(i, j, k)];
        if (!found[c]) continue;
        const CellHit& h = columns[c];
        for (int corner = 0; corner < 8; ++corner) {
          const std::size_t di = corner & 1, dj = corner >> 1 & 1, dk = corner >> 2 & 1;
          const double w = (di ? h.s : 1 - h.s) * (dj ? h.t : 1 - h.t) * (dk ? r : 1 - r);
          if (w == 0) continue;
          st.index[static_cast<std::size_t>(st.count)] =
              static_cast<std::uint32_t>(((layer + dk) * g.nj + h.j + dj) * g.ni + h.i + di);
          st.weight[static_cast<std::size_t>(st.count)] = w;
          ++st.count;
        }
      }
  }
  return stencils;
}

Target build_target(const PopGrid& g, const Mapping& map, std::array<std::int64_t, 3> resolution) {
  Target target;
  target.lon_lo = *std::min_element(g.uv.lon.begin(), g.uv.lon.end());
  target.lon_hi = *std::max_element(g.uv.lon.begin(), g.uv.lon.end());
  target.lat_lo = *std::min_element(g.uv.lat.begin(), g.uv.lat.end());
  target.lat_hi = *std::max_element(g.uv.lat.begin(), g.uv.lat.end());
  target.z_top = g.uv.z.front();
  target.z_bottom = g.uv.z.back();
  if (g.surface_only) {
    resolution[2] = 1;
  } else if (resolution[2] == 0) {
    double finest = INFINITY;
    for (std::size_t k = 1; k < g.nk; ++k) finest = std::min(finest, g.uv.z[k - 1] - g.uv.z[k]);
    resolution[2] = static_cast<std::int64_t>(std::ceil((target.z_top - target.z_bottom) / finest)) + 1;
  }
  GridGeometry& geo = target.geometry;
  geo.dimension = g.surface_only ? 2 : 3;
  geo.size = resolution;
  // Uniform in (lon, lat, z); the mapping is affine per axis, so also uniform in the output.
  const Vec3 lo = map.position(target.lon_lo, target.lat_lo, target.z_bottom);
  const Vec3 hi = map.position(target.lon_hi, target.lat_hi, target.z_top);
  geo.origin = lo;
  for (int a = 0; a < geo.dimension; ++a)
    geo.spacing[a] = (hi[a] - lo[a]) / static_cast<double>(resolution[static_cast<std::size_t>(a)] - 1);
  target.uv = build_stencils(g.uv, g, target, false);
  target.w = build_stencils(g.w, g, target, true);
  return target;
}

/// Source samples in output units: (u, v) at the U points, NaN on land (u = v = 0 exactly) and
/// at fill values; w at the T points (NaN at fill values only: w = 0 at walls is data).
struct Source {
  std::vector<double> u, v, w;
  std::size_t land = 0;
};

Source source_samples(const PopGrid& g, const PopFile& f, const Mapping& map) {
  Source src;
  src.u.assign(f.u.size(), 0.0);
  src.v.assign(f.u.size(), 0.0);
  src.w.assign(f.w.size(), 0.0);
  for (std::size_t k = 0; k < g.nk; ++k)
    for (std::size_t j = 0; j < g.nj; ++j)
      for (std::size_t i = 0; i < g.ni; ++i) {
        const std::size_t p = (k * g.nj + j) * g.ni + i;
        const double u = f.u[p], v = f.v[p];
        src.w[p] = std::isfinite(f.w[p]) ? map.metres_per_unit * f.w[p] : NAN;
        if (!std::isfinite(u) || !std::isfinite(v) || (u == 0 && v == 0)) {
          src.u[p] = NAN;
          src.v[p] = NAN;
          ++src.land;
          continue;
        }
        const Vec3 scale = map.scale(g.uv.lat[j * g.ni + i]);
        src.u[p] = scale[0] * u;
        src.v[p] = scale[1] * v;
      }
  return src;
}

void resample(const Target& target, const Source& src, int components, std::vector<float>& values) {
  const auto nc = static_cast<std::size_t>(components);
  for (std::size_t p = 0; p < target.uv.size(); ++p) {
    const Stencil& a = target.uv[p];
    const Stencil& b = target.w[p];
    double u = 0, v = 0, w = 0;
    bool ok = a.count > 0 && b.count > 0;
    for (int c = 0; c < a.count && ok; ++c) {
      const std::size_t at = a.index[static_cast<std::size_t>(c)];
      ok = std::isfinite(src.u[at]);
      u += a.weight[static_cast<std::size_t>(c)] * src.u[at];
      v += a.weight[static_cast<std::size_t>(c)] * src.v[at];
    }
    for (int c = 0; c < b.count && ok; ++c) {
      const double s = src.w[b.index[static_cast<std::size_t>(c)]];
      ok = std::isfinite(s);
      w += b.weight[static_cast<std::size_t>(c)] * s;
    }
    values[nc * p] = ok ? static_cast<float>(u) : kNaN;
    values[nc * p + 1] = ok ? static_cast<float>(v) : kNaN;
    if (nc == 3) values[nc * p + 2] = ok ? static_cast<float>(w) : kNaN;
  }
}

struct Error2 {
  std::size_t samples = 0;   // original samples (ocean)
  std::size_t compared = 0;  // of them, inside the resampled data
  double max = 0, sum = 0, max_value = 0;  // cm/s
  double mean() const { return compared ? sum / static_cast<double>(compared) : 0.0; }
  void add(const Error2& o) {
    samples += o.samples;
    compared += o.compared;
    max = std::max(max, o.max);
    sum += o.sum;
    max_value = std::max(max_value, o.max_value);
  }
};

struct Loss {
  Error2 horizontal;  // |(du, dv)| at the U points, layer centres
  Error2 vertical;    // |dw| at the T points, layer tops
};

/// Interpolates the resampled grid back at every original ocean sample; differences in cm/s.
Loss measure_loss(const PopGrid& g, const PopFile& f, const Mapping& map, const GridGeometry& geometry,
                  const std::vector<float>& values) {
  auto grid = std::make_shared<VectorGrid>();
  grid->geometry = geometry;
  grid->components = geometry.dimension;
  grid->values = values;
  orthofront::GridFieldOptions options;
  options.zero_is_no_data = false;
  const orthofront::GridField field(grid, options);
  const double to_cm = 100.0 * map.metres_per_unit;  // differences are stated in cm/s
  Loss loss;
  for (std::size_t k = 0; k < g.nk; ++k)
    for (std::size_t j = 0; j < g.nj; ++j)
      for (std::size_t i = 0; i < g.ni; ++i) {
        const std::size_t p = (k * g.nj + j) * g.ni + i;
        const std::size_t c = j * g.ni + i;
        const double u = f.u[p], v = f.v[p], w = f.w[p];
        const bool ocean = std::isfinite(u) && std::isfinite(v) && !(u == 0 && v == 0);
        Vec3 back;
        if (ocean) {
          Error2& e = loss.horizontal;
          ++e.samples;
          e.max_value = std::max(e.max_value, to_cm * std::hypot(u, v));
          if (field.velocity(map.position(g.uv.lon[c], g.uv.lat[c], g.uv.z[k]), back) == orthofront::FieldStatus::inside) {
            const Vec3 unit = back.cwiseQuotient(map.scale(g.uv.lat[c]));  // the file's unit
            const double d = to_cm * std::hypot(unit[0] - u, unit[1] - v);
            ++e.compared;
            e.max = std::max(e.max, d);
            e.sum += d;
          }
        }
        if (std::isfinite(w) && w != 0.0) {
          Error2& e = loss.vertical;
          ++e.samples;
          e.max_value = std::max(e.max_value, to_cm * std::abs(w));
          if (field.velocity(map.position(g.w.lon[c], g.w.lat[c], g.w.z[k]), back) == orthofront::FieldStatus::inside) {
            const double d = std::abs(100.0 * back[2] - to_cm * w);
            ++e.compared;
            e.max = std::max(e.max, d);
            e.sum += d;
          }
        }
      }
  return loss;
}

struct Args {
  std::vector<std::string> inputs;
  std::string out;
  std::string coords = "degrees";
  std::string resolution;
  double dt = 1.0;
  std::string time_unit;
  std::string times;
  int gzip = 0;
  std::string report;
  Names names;
  bool quiet = false;
};

std::array<std::int64_t, 3> parse_resolution(const std::string& text, const PopGrid& g) {
  // Twice the source's cells: U points (u, v) and T points (w, half a cell away) of a regular
  // grid both fall on samples.
  if (text.empty())
    return {2 * static_cast<std::int64_t>(g.ni - 1) + 1, 2 * static_cast<std::int64_t>(g.nj - 1) + 1, 0};
  std::array<std::int64_t, 3> n{};
  std::size_t start = 0;
  const bool two = std::count(text.begin(), text.end(), ',') == 1;  // NX,NY: NZ chosen (or 2D)
  for (std::size_t a = 0; a < (two ? 2u : 3u); ++a) {
    const std::size_t comma = text.find(',', start);
    if ((a + 1 < (two ? 2u : 3u)) == (comma == std::string::npos))
      throw InvalidArgument("--resolution '" + text + "' must be NX,NY or NX,NY,NZ");
    const std::string part = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const auto r = std::from_chars(part.data(), part.data() + part.size(), n[a]);
    if (r.ec != std::errc() || r.ptr != part.data() + part.size() || n[a] < 2)
      throw InvalidArgument("--resolution '" + text + "': '" + part + "' is not an integer >= 2");
    start = comma + 1;
  }
  return n;
}

int run(const Args& args) {
  std::vector<std::string> files = args.inputs;
  std::stable_sort(files.begin(), files.end(), orthofront::io::natural_less);
  const std::string ext = fs::path(args.out).extension().string();
  if (ext != ".h5" && ext != ".hdf5") throw InvalidArgument("--out '" + args.out + "' must end in .h5");
  if (args.coords != "degrees" && args.coords != "metres" && args.coords != "meters")
    throw InvalidArgument("--coords '" + args.coords + "' must be degrees or metres");

  const PopGrid grid = read_grid(files.front(), args.names);
  const int components = grid.surface_only ? 2 : 3;
  Mapping map;
  map.metres = args.coords != "degrees";
  map.metres_per_unit = grid.metres_per_unit;
  if (map.metres) {
    const auto [lon_lo, lon_hi] = std::minmax_element(grid.uv.lon.begin(), grid.uv.lon.end());
    const auto [lat_lo, lat_hi] = std::minmax_element(grid.uv.lat.begin(), grid.uv.lat.end());
    map.lon_c = 0.5 * (*lon_lo + *lon_hi);
    map.lat_c = 0.5 * (*lat_lo + *lat_hi);
  }
  const Target target = build_target(grid, map, parse_resolution(args.resolution, grid));
  const GridGeometry& geo = target.geometry;

  std::vector<double> times;
  if (!args.times.empty()) {
    std::size_t start = 0;
    for (;;) {
      const std::size_t comma = args.times.find(',', start);
      times.push_back(std::stod(args.times.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
    if (times.size() != files.size())
      throw InvalidArgument("--times gives " + std::to_string(times.size()) + " times for " + std::to_string(files.size()) + " files");
  } else {
    if (!(args.dt > 0)) throw InvalidArgument("--dt must be positive");
    for (std::size_t s = 0; s < files.size(); ++s) times.push_back(static_cast<double>(s) * args.dt);
  }

  orthofront::io::Hdf5WriteOptions options;
  options.gzip_level = args.gzip;
  options.units.length = map.length_unit();
  options.units.velocity = map.velocity_unit();
  options.units.time = !args.time_unit.empty() ? args.time_unit : (args.times.empty() && args.dt == 1.0 ? "step" : "s");
  options.zero_is_no_data = true;
  orthofront::io::Hdf5SeriesWriter writer(args.out, geo, components, times, options);

  nlohmann::json report;
  report["inputs"] = files;
  report["output"] = args.out;
  report["coords"] = map.metres ? "metres" : "degrees";
  report["source_grid"] = {grid.ni, grid.nj, grid.nk};
  report["velocity_units"] = grid.velocity_units;
  report["target_grid"] = {geo.size[0], geo.size[1], geo.size[2]};
  report["origin"] = {geo.origin[0], geo.origin[1], geo.origin[2]};
  report["spacing"] = {geo.spacing[0], geo.spacing[1], geo.spacing[2]};
  report["times"] = times;
  const auto error_json = [](const Error2& e) {
    return nlohmann::json{{"samples", e.samples}, {"compared", e.compared},
                          {"not_compared_near_land", e.samples - e.compared},
                          {"max_cm_s", e.max}, {"mean_cm_s", e.mean()}, {"max_value_cm_s", e.max_value},
                          {"relative_max", e.max_value > 0 ? e.max / e.max_value : 0.0}};
  };
  if (!args.quiet) {
    std::cout << (grid.surface_only ? "2D product " : "POP ") << grid.ni << " x " << grid.nj << " x " << grid.nk
              << (grid.surface_only ? " (u, v in " + grid.velocity_units + ") -> uniform "
                                    : " (B grid: u, v at U points and layer centres, w at T points and layer tops; " +
                                          grid.velocity_units + ") -> uniform ")
              << geo.size[0] << " x " << geo.size[1] << " x " << geo.size[2] << " in "
              << report["coords"].get<std::string>() << "; land (u = v = 0 or fill) -> NaN\n"
              << "resampling loss: the uniform grid interpolated back at the original samples (cm/s)\n"
              << "  step  file                          |d(u,v)| max     mean    (max |(u,v)|)   |dw| max       mean\n";
  }
  Loss total;
  std::vector<float> values(geo.point_count() * static_cast<std::size_t>(components));
  for (std::size_t s = 0; s < files.size(); ++s) {
    const PopFile step = read_step(files[s], grid, args.names);
    const Source source = source_samples(grid, step, map);
    resample(target, source, components, values);
    writer.write_step(values);
    const Loss loss = measure_loss(grid, step, map, geo, values);
    std::size_t nan = 0;
    for (std::size_t p = 0; p < geo.point_count(); ++p) nan += std::isnan(values[static_cast<std::size_t>(components) * p]) ? 1 : 0;
    report["steps"].push_back({{"file", files[s]}, {"time", times[s]}, {"source_land_points", source.land},
                               {"target_nan_points", nan}, {"horizontal", error_json(loss.horizontal)},
                               {"vertical", error_json(loss.vertical)}});
    total.horizontal.add(loss.horizontal);
    total.vertical.add(loss.vertical);
    if (!args.quiet) {
      char line[256];
      std::snprintf(line, sizeof line, "  %4zu  %-28s %9.4f  %9.5f   (%7.3f)      %9.2e  %9.2e\n", s,
                    fs::path(files[s]).filename().string().c_str(), loss.horizontal.max, loss.horizontal.mean(),
                    loss.horizontal.max_value, loss.vertical.max, loss.vertical.mean());
      std::cout << line;
    }
  }
  writer.commit();
  report["loss"] = {{"horizontal", error_json(total.horizontal)}, {"vertical", error_json(total.vertical)}};
  if (!args.report.empty()) {
    std::ofstream out(args.report);
    out << report.dump(2) << "\n";
    if (!out) throw IoError("cannot write " + args.report);
  }
  if (!args.quiet) {
    const Error2& h = total.horizontal;
    const Error2& v = total.vertical;
    char line[1024];
    std::snprintf(line, sizeof line,
                  "all steps: (u, v) max error %.4f cm/s = %.2f%% of the max speed %.3f cm/s, mean %.5f cm/s over %zu "
                  "of %zu ocean samples (%zu next to land have no resampled value);\n"
                  "           w max error %.3g cm/s = %.2f%% of max |w| %.3g cm/s, mean %.3g cm/s over %zu of %zu samples\n",
                  h.max, 100.0 * (h.max_value > 0 ? h.max / h.max_value : 0.0), h.max_value, h.mean(), h.compared,
                  h.samples, h.samples - h.compared, v.max, 100.0 * (v.max_value > 0 ? v.max / v.max_value : 0.0),
                  v.max_value, v.mean(), v.compared, v.samples);
    std::cout << line << "Wrote " << args.out << " (" << files.size() << " steps at t = " << times.front() << " .. "
              << times.back() << " " << options.units.time << ")\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"POP ocean output, or a 2D lon/lat product of surface currents (NetCDF: classic, "
               "64-bit offset or NetCDF-4) -> uniform grid in the orthofront HDF5 layout"};
  Args args;
  app.add_option("inputs", args.inputs, "NetCDF files, one per time step (natural order)")->required();
  app.add_option("--out", args.out, "Output .h5 (with .xmf sidecar)")->required();
  app.add_option("--coords", args.coords, "degrees (lon, lat, z m; deg/s) or metres (equirectangular, m/s)")
      ->capture_default_str();
  app.add_option("--resolution", args.resolution,
                 "Target samples NX,NY,NZ (default: 2 (ni - 1) + 1, 2 (nj - 1) + 1, so that the U points "
                 "(u, v) and the T points (w) of a regular grid fall on samples; NZ so that dz <= the "
                 "thinnest layer). Prefer NX = m (ni - 1) + 1: other counts smooth grid-scale structure");
  app.add_option("--dt", args.dt, "Time between files")->capture_default_str();
  app.add_option("--time-unit", args.time_unit, "Unit of the times (default: step, or s with --dt/--times)");
  app.add_option("--times", args.times, "Times of the files t0,t1,...");
  app.add_option("--gzip", args.gzip, "gzip level 0-9")->check(CLI::Range(0, 9))->capture_default_str();
  app.add_option("--report", args.report, "Write the loss report as JSON here");
  app.add_option("--u", args.names.u, "Variable of the eastward velocity")->capture_default_str();
  app.add_option("--v", args.names.v, "Variable of the northward velocity")->capture_default_str();
  app.add_option("--w", args.names.w, "Variable of the upward velocity (none: a 2D product, with --depth none)")
      ->capture_default_str();
  app.add_option("--lon", args.names.lon, "Longitude variable: (j, i), or an axis lon(i)")->capture_default_str();
  app.add_option("--lat", args.names.lat, "Latitude variable: (j, i), or an axis lat(j)")->capture_default_str();
  app.add_option("--depth", args.names.depth,
                 "Depth variable: layer interfaces (nk + 1) or centres (nk); none: a 2D product (u, v only)")
      ->capture_default_str();
  app.add_option("--units", args.names.units,
                 "Velocity units of the files when their `units` attribute is absent or wrong (m/s, cm/s); "
                 "default: the attribute, or POP's cm/s when there is none");
  app.add_flag("--quiet", args.quiet, "No report on stdout");
  try {
    app.parse(argc, argv);
    return run(args);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const Error& e) {
    std::cerr << "orthofront-pop-convert: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "orthofront-pop-convert: unexpected error: " << e.what() << "\n";
    return 3;
  }
}
