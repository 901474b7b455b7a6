#pragma once
// An independent path-line integration for tests: classic RK4 with a fixed small step on
// v(x, t) directly, sharing nothing with the flow map's or the engine's adaptive integrators.
#include <catch2/catch.hpp>

#include <cmath>

#include "orthofront/field/unsteady.h"

namespace streak_test {

inline orthofront::Vec3 reference_path(const orthofront::UnsteadyField& flow, orthofront::Vec3 x,
                                       double t0, double t1) {
  using orthofront::Vec3;
  const int n = std::max(1, static_cast<int>(std::ceil(std::abs(t1 - t0) / 2e-3)));
  const double h = (t1 - t0) / n;
  double t = t0;
  const auto v = [&](const Vec3& p, double s) {
    Vec3 out;
    REQUIRE(flow.velocity(p, s, out) == orthofront::FieldStatus::inside);
    if (flow.dimension() == 2) out.z() = 0;
    return out;
  };
  for (int i = 0; i < n; ++i) {
    const Vec3 k1 = v(x, t), k2 = v(x + 0.5 * h * k1, t + 0.5 * h);
    const Vec3 k3 = v(x + 0.5 * h * k2, t + 0.5 * h), k4 = v(x + h * k3, t + h);
    x += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    t += h;
  }
  return x;
}

}  // namespace streak_test
