#pragma once
// The first interior cell face a straight path crosses, by brute force: the reference for the
// grid's and the bulk step's face searches.
#include <algorithm>
#include <cstdint>
#include <limits>

#include "orthofront/field/grid.h"

namespace test {

/// The least τ > after over every interior sample plane of every axis (the grid's own
/// coordinates, so a point on a face gives τ = 0 there); +inf where there is none.
inline double first_face_brute_force(const orthofront::GridGeometry& g,
                                     const orthofront::Vec3& x, const orthofront::Vec3& w,
                                     double after) {
  double first = std::numeric_limits<double>::infinity();
  for (int a = 0; a < g.dimension; ++a) {
    if (w[a] == 0) continue;
    for (std::int64_t i = 1; i + 1 < g.size[static_cast<std::size_t>(a)]; ++i) {
      const double tau = (g.coordinate(a, i) - x[a]) / w[a];
      if (tau > after) first = std::min(first, tau);
    }
  }
  return first;
}

}  // namespace test
