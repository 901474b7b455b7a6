#pragma once
/// Rip detection: separating stream lines show as sharp, slow peaks of α along the front.
#include <cstddef>
#include <span>
#include <vector>

namespace orthofront {

struct RipThresholds {
  double sharpness = 0.5;       ///< 1 - (α_{i-1} + α_{i+1}) / (2 α_i) above this ...
  double speed_fraction = 0.05; ///< ... and |v_i| below this share of the front's median speed
};

/// Marks the vertices at such peaks with keep[i] = 0 (the front's ends of an open front are
/// never peaks) and returns how many it marked. `alpha` and `speed` are per front vertex.
std::size_t find_rips(std::span<const double> alpha, std::span<const double> speed, bool closed,
                      const RipThresholds& thresholds, std::vector<char>& keep);

}  // namespace orthofront
