#pragma once
/// The seed a surface starts from, as the engine sees it: a curve in R^N and the parameters of
/// the first front's vertices.
#include <functional>
#include <vector>

#include "orthofront/seed/seed_curve.h"
#include "orthofront/types.h"

namespace orthofront {

/// `point(s)` for s in [0, 1] (taken modulo 1 when closed); `parameters` increasing (for closed
/// seeds in [0, 1)).
template <int N>
struct Seed {
  std::function<Vec<N>(double)> point;
  std::vector<double> parameters;
  bool closed = false;
};

/// `count` vertices spread uniformly in arc length over a 3D seed curve (the curve is copied).
inline Seed<3> make_seed(const SeedCurve& curve, int count) {
  return Seed<3>{[curve](double s) { return curve.point(s); }, curve.sample(count),
                 curve.closed()};
}

}  // namespace orthofront
