#pragma once
/// Distances from points to a mesh, for comparing two surfaces (routes, tests): the exact
/// point-triangle distance to every triangle (quads split along one diagonal), by brute force.
#include <algorithm>
#include <array>
#include <limits>
#include <span>
#include <vector>

#include "orthofront/mesh/mesh.h"

namespace orthofront {

using Triangle = std::array<Vec3, 3>;

inline double point_triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  // Closest point on triangle (Ericson, Real-Time Collision Detection, 5.1.5).
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return ap.norm();
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bp.norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return cp.norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return (p - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b))).norm();
  const double denom = 1 / (va + vb + vc);
  return (p - (a + ab * (vb * denom) + ac * (vc * denom))).norm();
}

/// The triangles of `faces` over `positions`.
inline std::vector<Triangle> triangles_of(std::span<const Vec3> positions,
                                          std::span<const Face> faces) {
  std::vector<Triangle> triangles;
  for (const Face& f : faces) {
    const auto p = [&](int k) { return positions[static_cast<std::size_t>(f.v[k])]; };
    triangles.push_back({p(0), p(1), p(2)});
    if (f.size == 4) triangles.push_back({p(0), p(2), p(3)});
  }
  return triangles;
}

/// Distance from p to the nearest triangle.
inline double distance_to(const Vec3& p, const std::vector<Triangle>& triangles) {
  double best = std::numeric_limits<double>::infinity();
  for (const Triangle& t : triangles)
    best = std::min(best, point_triangle_distance(p, t[0], t[1], t[2]));
  return best;
}

}  // namespace orthofront
