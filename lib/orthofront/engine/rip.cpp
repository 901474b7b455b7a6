#include "orthofront/engine/rip.h"

#include <vector>

#include "orthofront/engine/front.h"

namespace orthofront {

std::size_t find_rips(std::span<const double> alpha, std::span<const double> speed, bool closed,
                      const RipThresholds& thresholds, std::vector<char>& keep) {
  const std::size_t n = alpha.size();
  if (n < 3) return 0;
  // The median speed only where a sharp peak asks for it: most fronts have none.
  double median = -1;
  std::size_t count = 0;
  const std::size_t first = closed ? 0 : 1;
  const std::size_t last = closed ? n : n - 1;
  for (std::size_t i = first; i < last; ++i) {
    const double a = alpha[i];
    const double am = alpha[previous_index(i, n)];
    const double ap = alpha[next_index(i, n)];
    if (!(a > 0 && a > am && a > ap)) continue;
    const double sharpness = 1.0 - (am + ap) / (2.0 * a);
    if (!(sharpness > thresholds.sharpness)) continue;
    if (median < 0) median = median_of(std::vector<double>(speed.begin(), speed.end()));
    if (speed[i] < thresholds.speed_fraction * median) {
      keep[i] = 0;
      ++count;
    }
  }
  return count;
}

}  // namespace orthofront
