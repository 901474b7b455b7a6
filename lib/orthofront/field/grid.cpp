#include "orthofront/field/grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace orthofront {

double next_interior_coordinate(const std::vector<double>& coords, double from, bool up) {
  constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
  if (coords.size() < 3) return kNone;
  const auto begin = coords.begin() + 1, end = coords.end() - 1;
  if (up) {
    const auto it = std::upper_bound(begin, end, from);
    return it == end ? kNone : *it;
  }
  const auto it = std::lower_bound(begin, end, from);
  return it == begin ? kNone : *(it - 1);
}

double GridGeometry::next_cell_face(const Vec3& x, const Vec3& w, double after) const {
  double first = std::numeric_limits<double>::infinity();
  for (int a = 0; a < dimension; ++a) {
    const auto ua = static_cast<std::size_t>(a);
    if (!(w[a] != 0)) continue;
    const bool up = w[a] > 0;
    // The face beyond where the search starts along this axis; rounding may put that one at
    // τ <= after (a point on a face), and then the next one is meant.
    double from = x[a] + after * w[a];
    double k = -1;  // uniform: the face's index, stepped on where the first is at τ <= after
    for (int attempt = 0; attempt < 2; ++attempt) {
      double face = 0;
      if (rectilinear()) {
        face = next_interior_coordinate(axes[ua], from, up);
      } else {
        if (attempt == 0) {
          const double u = (from - origin[a]) / spacing[a];
          // From outside the grid the nearest interior face comes first.
          const double last = static_cast<double>(size[ua] - 2);
          k = up ? std::max(std::floor(u) + 1, 1.0) : std::min(std::ceil(u) - 1, last);
        } else {
          k += up ? 1 : -1;
        }
        if (!(k >= 1 && k <= static_cast<double>(size[ua] - 2))) break;
        face = origin[a] + k * spacing[a];
      }
      const double tau = (face - x[a]) / w[a];  // NaN where there is no face: never taken
      if (tau > after) {
        first = std::min(first, tau);
        break;
      }
      from = face;
    }
  }
  return first;
}

}  // namespace orthofront
