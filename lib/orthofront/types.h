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
  bool contains(const Vec<N>& x) const {
    return (x.array() >= lo.array()).all() && (x.array() <= hi.array()).all();
  }
  Vec<N> extent() const { return hi - lo; }
};

}  // namespace orthofront
