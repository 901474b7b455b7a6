#pragma once
/// The steady space-time field of an unsteady flow: for v(x, t) in R^d, the field (v, c) in
/// R^(d+1) over the coordinates (x, τ), τ = c t. Its stream surfaces are the path surfaces of v.
#include <algorithm>
#include <cmath>
#include <string>

#include "orthofront/error.h"
#include "orthofront/field/field.h"
#include "orthofront/field/unsteady.h"

namespace orthofront::spacetime {

/// Lifted field for N = d + 1 (N = 3 for 2D flows, N = 4 for 3D flows).
///
/// Coordinates X = (x_1..x_d, τ) with τ = c (t - t_ref), so t = τ / c + t_ref. V(X) = (v(x, t), c).
/// The origin t_ref (the surface's t0) keeps τ small: times of real data (seconds since 1950,
/// some 2e9) would leave τ few significant digits for the front's steps.
/// Jacobian by the chain rule: ∂V/∂X = [[∂v/∂x, ∂v/∂τ], [0, 0]] with ∂v/∂τ = (1/c) ∂v/∂t
/// (the last column is ∂v/∂t divided by c, not multiplied).
/// Domain: the flow's spatial box (first d axes) times [c t_begin, c t_end]; a stream line that
/// reaches τ = c t_end leaves the domain and its front ends there.
/// Non-owning (`flow` must outlive it); immutable and thread-safe when `flow` is.
template <int N>
class LiftedField final : public Field<N> {
  static_assert(N == 3 || N == 4, "lifted fields have N = 3 (2D flows) or N = 4 (3D flows)");

 public:
  static constexpr int d = N - 1;

  /// Throws InvalidArgument for a flow of the wrong dimension, c <= 0 or a time range that is
  /// empty or outside the flow's.
  LiftedField(const UnsteadyField& flow, double time_scale, TimeRange times,
              double time_origin = 0)
      : flow_(flow), c_(time_scale), t_ref_(time_origin), times_(times) {
    if (flow.dimension() != d)
      throw InvalidArgument("lifted field: a " + std::to_string(N) + "D space-time field needs a " +
                            std::to_string(d) + "D flow, '" + flow.describe() + "' is " +
                            std::to_string(flow.dimension()) + "D");
    if (!(std::isfinite(c_) && c_ > 0))
      throw InvalidArgument("lifted field: time scale must be finite and > 0, got " +
                            std::to_string(c_));
    const TimeRange own = flow.time_range();
    times_.begin = std::max(times_.begin, own.begin);
    times_.end = std::min(times_.end, own.end);
    if (!(std::isfinite(times_.begin) && std::isfinite(times_.end) && times_.end > times_.begin))
      throw InvalidArgument("lifted field: time range [" + std::to_string(times.begin) + ", " +
                            std::to_string(times.end) + "] is empty or unbounded within the "
                            "flow's time range");
    const Box<3> box = flow.domain();
    box_.lo.template head<d>() = box.lo.template head<d>();
    box_.hi.template head<d>() = box.hi.template head<d>();
    box_.lo[d] = c_ * (times_.begin - t_ref_);
    box_.hi[d] = c_ * (times_.end - t_ref_);
  }

  FieldStatus velocity(const Vec<N>& X, Vec<N>& V) const override {
    if (!box_.contains(X)) return FieldStatus::outside;
    Vec3 v;
    const FieldStatus st = flow_.velocity(spatial(X), time(X), v);
    if (st != FieldStatus::inside) return st;
    V.template head<d>() = v.template head<d>();
    V[d] = c_;
    return st;
  }
  FieldStatus velocity_jacobian(const Vec<N>& X, Vec<N>& V, Mat<N>& J) const override {
    if (!box_.contains(X)) return FieldStatus::outside;
    Vec3 v, dvdt;
    Mat3 j;
    const FieldStatus st = flow_.velocity_jacobian(spatial(X), time(X), v, j, dvdt);
    if (st != FieldStatus::inside) return st;
    V.template head<d>() = v.template head<d>();
    V[d] = c_;
    J.setZero();
    J.template topLeftCorner<d, d>() = j.template topLeftCorner<d, d>();
    J.template block<d, 1>(0, d) = dvdt.template head<d>() / c_;
    return st;
  }
  Box<N> domain() const override { return box_; }
  double next_kink(const Vec<N>& X, const Vec<N>& W, double after, double before) const override {
    return flow_.next_kink(spatial(X), time(X), spatial(W), time(W), after, before);
  }
  std::string describe() const override {
    return "spacetime(c=" + std::to_string(c_) + "):" + flow_.describe();
  }

  double time_scale() const { return c_; }
  /// t at τ = 0.
  double time_origin() const { return t_ref_; }
  TimeRange times() const { return times_; }
  /// Lifted point of (x, t).
  Vec<N> lift(const Vec3& x, double t) const {
    Vec<N> X;
    X.template head<d>() = x.template head<d>();
    X[d] = c_ * (t - t_ref_);
    return X;
  }
  /// Spatial point of X (z = 0 for 2D flows) and its physical time.
  static Vec3 spatial(const Vec<N>& X) {
    Vec3 x = Vec3::Zero();
    x.template head<d>() = X.template head<d>();
    return x;
  }
  double time(const Vec<N>& X) const { return X[d] / c_ + t_ref_; }
  /// Physical time of a lifted coordinate τ.
  double time_of(double tau) const { return tau / c_ + t_ref_; }

 private:
  const UnsteadyField& flow_;
  double c_;
  double t_ref_;
  TimeRange times_;
  Box<N> box_;
};

}  // namespace orthofront::spacetime
