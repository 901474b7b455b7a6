#pragma once
/// The advancing front: vertices on their stream lines, each standing for a mesh vertex; how a
/// front is cut into parts, interpolated between its vertices, and measured.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "orthofront/mesh/mesh.h"
#include "orthofront/types.h"

namespace orthofront {

template <int N>
struct FrontVertex {
  Vec<N> x;       ///< current position on its stream line
  Vec<N> anchor;  ///< position of the mesh vertex that stands for it
  double s = 0;   ///< seed parameter (may exceed 1 on closed fronts: taken modulo 1)
  double t = 0;   ///< integration time in v since the seed
  std::int32_t mesh = -1;
  std::int32_t origin = -1;  ///< index in the previous front (-1: inserted this step)
  /// Seed shots beside this vertex (insertions integrated from the seed) that missed the front
  /// in a row, none hitting it since: where they keep missing, insertions beside it start from
  /// the previous row (FrontAdapter::split_long).
  std::uint8_t seed_misses = 0;
};

/// One front line; a surface has several after rips, domain exits and no-data cuts.
template <int N>
struct Front {
  std::vector<FrontVertex<N>> v;
  bool closed = false;
  std::int32_t id = 0;
};

/// Where new fronts get their ids, and how many were made.
struct FrontIds {
  std::int32_t next = 0;
  std::size_t created = 0;
};

/// Splits a front at vertices with keep[i] == 0 (removed) and after segments with cut[i] != 0
/// (segment i joins i and i+1). Parts with fewer than two vertices are dropped. The first part
/// keeps the front's id; further parts are new fronts. A closed front becomes open parts, each a
/// contiguous run starting right after a break.
template <int N>
std::vector<Front<N>> split_front(Front<N>&& f, const std::vector<char>& keep,
                                  const std::vector<char>& cut, FrontIds& ids) {
  const std::size_t n = f.v.size();
  bool any = false;
  for (std::size_t i = 0; i < n; ++i) any = any || !keep[i] || cut[i];
  std::vector<Front<N>> parts;
  if (!any) {
    parts.push_back(std::move(f));
    return parts;
  }
  std::size_t start = 0;
  if (f.closed) {
    for (std::size_t i = 0; i < n; ++i) {
      if (!keep[i]) {
        start = i;
        break;
      }
      if (cut[i]) {
        start = (i + 1) % n;
        break;
      }
    }
  }
  Front<N> current;
  auto flush = [&]() {
    if (current.v.size() >= 2) {
      if (parts.empty()) {
        current.id = f.id;
      } else {
        current.id = ids.next++;
        ++ids.created;
      }
      parts.push_back(std::move(current));
    }
    current = Front<N>{};
  };
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = (start + k) % n;
    if (!keep[i]) {
      flush();
      continue;
    }
    current.v.push_back(f.v[i]);
    if (cut[i] && (f.closed || i + 1 < n)) flush();
  }
  flush();
  return parts;
}

/// Point at fraction λ of segment i → i+1 of front f (positions only), Catmull-Rom on the
/// front with reflected end points.
template <int N>
Vec<N> cubic_point(const Front<N>& f, std::size_t i, double lambda) {
  const std::size_t n = f.v.size();
  const std::size_t j = (i + 1) % n;
  const Vec<N>& p1 = f.v[i].x;
  const Vec<N>& p2 = f.v[j].x;
  Vec<N> p0, p3;
  if (f.closed || i > 0)
    p0 = f.v[(i + n - 1) % n].x;
  else
    p0 = 2 * p1 - p2;
  if (f.closed || j + 1 < n)
    p3 = f.v[(j + 1) % n].x;
  else
    p3 = 2 * p2 - p1;
  const double t = lambda, t2 = t * t, t3 = t2 * t;
  return 0.5 * ((2 * p1) + (-p0 + p2) * t + (2 * p0 - 5 * p1 + 4 * p2 - p3) * t2 +
                (-p0 + 3 * p1 - 3 * p2 + p3) * t3);
}

/// Whether the front's polyline (with the closing segment of a closed front) is shorter than
/// `length`. Stops at the first segments that reach it: most fronts are many times longer, and a
/// sum of non-negative terms never falls, so the answer is that of the whole sum.
template <int N>
bool front_shorter_than(const Front<N>& f, double length) {
  double sum = 0;
  for (std::size_t i = 0; i + 1 < f.v.size(); ++i) {
    sum += (f.v[i + 1].x - f.v[i].x).norm();
    if (sum >= length) return false;
  }
  if (f.closed && f.v.size() > 1) sum += (f.v.front().x - f.v.back().x).norm();
  return sum < length;
}

/// Whether a front vertex moved away from its mesh vertex (one whose α was clamped to 0 did not:
/// a copy of its mesh vertex would make zero-area faces). Inserted ones are new.
template <int N>
bool has_moved(const FrontVertex<N>& fv, double edge) {
  return fv.origin < 0 || (fv.x - fv.anchor).norm() > 1e-12 * edge;
}

/// Adds the mesh vertex that stands for a front vertex (its first three coordinates). Closed
/// seeds wrap s into [0, 1); on open seeds s = 1 is the end of the curve.
template <int N>
std::int32_t emit_vertex(Mesh& mesh, const FrontVertex<N>& fv, bool closed_seed, double alpha,
                         std::int32_t front, int step) {
  const Vec3 p = fv.x.template head<3>();
  const double s = closed_seed ? fv.s - std::floor(fv.s) : fv.s;
  return mesh.add_vertex(p, fv.t, alpha, s, 0.0, front, step);
}

/// The index after i (before i) on a cyclic list of n: (i + 1) % n without a division, which
/// per vertex of a front cost more than the work around it.
inline std::size_t next_index(std::size_t i, std::size_t n) { return i + 1 == n ? 0 : i + 1; }
inline std::size_t previous_index(std::size_t i, std::size_t n) { return i == 0 ? n - 1 : i - 1; }

/// Median of a list of values (0 for none).
inline double median_of(std::vector<double> values) {
  if (values.empty()) return 0;
  const auto mid = values.begin() + static_cast<long>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

}  // namespace orthofront
