#pragma once
/// A comparison of lengths |d| with a limit, bit for bit as `d.norm() < limit` (or <=) decides
/// it, without a square root where |d|² is clearly on one side: the passes of a streak surface
/// over every edge of every row are bound by the root's latency otherwise.
#include <cmath>

#include "orthofront/types.h"

namespace orthofront::spacetime {

class LengthLimit {
 public:
  explicit LengthLimit(double limit)
      : limit_(limit), below_(limit * limit * (1 - 1e-12)), above_(limit * limit * (1 + 1e-12)) {}
  bool shorter(const Vec3& d) const {
    const double q = d.squaredNorm();
    return q < below_ || (q <= above_ && std::sqrt(q) < limit_);
  }
  bool not_longer(const Vec3& d) const {
    const double q = d.squaredNorm();
    return q < below_ || (q <= above_ && std::sqrt(q) <= limit_);
  }
  /// A square above this has a root above the limit, whatever the roundings.
  double above_squared() const { return above_; }

 private:
  double limit_, below_, above_;
};

}  // namespace orthofront::spacetime
