#pragma once
/// Fixed-size vector types shared by every part of the library.
#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products

namespace orthofront {

template <int N>
using Vec = Eigen::Matrix<double, N, 1>;
template <int N>
using Mat = Eigen::Matrix<double, N, N>;
using Vec3 = Vec<3>;
using Mat3 = Mat<3>;

/// Axis-aligned box [lo, hi] in R^N.
template <int N>
struct Box {
  Vec<N> lo = Vec<N>::Constant(-1.0);
  Vec<N> hi = Vec<N>::Constant(1.0);
  /// False for a NaN coordinate. One pass with `&` (no early exit): Eigen's all() of the two
  /// comparisons took a third of an analytic field's evaluation.
  bool contains(const Vec<N>& x) const {
    bool inside = true;
    for (int i = 0; i < N; ++i) inside &= (x[i] >= lo[i]) & (x[i] <= hi[i]);
    return inside;
  }
  Vec<N> extent() const { return hi - lo; }
};

}  // namespace orthofront
