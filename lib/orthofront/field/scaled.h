#pragma once
/// A field seen in other units: speeds times A, lengths times L (unit-invariance tests).
#include <array>
#include <charconv>
#include <cmath>
#include <string>

#include "orthofront/error.h"
#include "orthofront/field/field.h"

namespace orthofront {

/// v'(x) = A v(x / L), J'(x) = (A / L) J(x / L), domain [L lo, L hi].
/// A = L rescales the length unit (same flow, same geometry in new units); A = 1 gives a bigger
/// domain at equal speeds; L = 1 changes the time unit (v x A).
/// Non-owning: `base` must outlive this object. Immutable and thread-safe if `base` is.
template <int N>
class BasicScaledField final : public Field<N> {
 public:
  /// Throws InvalidArgument unless A is finite and non-zero and L is finite and positive.
  BasicScaledField(const Field<N>& base, double speed_factor, double length_factor)
      : base_(base),
        speed_(speed_factor),
        length_(length_factor),
        jacobian_factor_(speed_factor / length_factor) {
    if (!std::isfinite(speed_factor) || speed_factor == 0) {
      throw InvalidArgument("ScaledField: speed factor must be finite and non-zero, got " +
                            format(speed_factor));
    }
    if (!std::isfinite(length_factor) || !(length_factor > 0)) {
      throw InvalidArgument("ScaledField: length factor must be finite and positive, got " +
                            format(length_factor));
    }
    base_box_ = base.domain();
    box_.lo = base_box_.lo * length_factor;
    box_.hi = base_box_.hi * length_factor;
  }

  FieldStatus velocity(const Vec<N>& x, Vec<N>& v) const override {
    if (!box_.contains(x)) return FieldStatus::outside;
    const FieldStatus status = base_.velocity(to_base(x), v);
    // Outputs are unspecified (maybe unwritten) unless inside: leave them alone then.
    if (status == FieldStatus::inside) v *= speed_;
    return status;
  }
  FieldStatus velocity_jacobian(const Vec<N>& x, Vec<N>& v, Mat<N>& J) const override {
    if (!box_.contains(x)) return FieldStatus::outside;
    const FieldStatus status = base_.velocity_jacobian(to_base(x), v, J);
    if (status == FieldStatus::inside) {
      v *= speed_;
      J *= jacobian_factor_;
    }
    return status;
  }
  Box<N> domain() const override { return box_; }
  double next_kink(const Vec<N>& x, const Vec<N>& w, double after, double before) const override {
    return base_.next_kink(to_base(x), w / length_, after, before);
  }
  std::string describe() const override {
    return "scaled(speed=" + format(speed_) + ",length=" + format(length_) +
           "):" + base_.describe();
  }

  double speed_factor() const { return speed_; }
  double length_factor() const { return length_; }

 private:
  // x / L, clamped so that a point on the scaled boundary never falls outside the base domain
  // by a rounding error: domain() and the status then agree exactly.
  Vec<N> to_base(const Vec<N>& x) const {
    return (x / length_).cwiseMax(base_box_.lo).cwiseMin(base_box_.hi);
  }
  // Shortest text that reads back as the same double.
  static std::string format(double value) {
    std::array<char, 32> buffer{};
    const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
    return std::string(buffer.data(), result.ptr);
  }

  const Field<N>& base_;
  double speed_;
  double length_;
  double jacobian_factor_;
  Box<N> base_box_;
  Box<N> box_;
};

using ScaledField = BasicScaledField<3>;

}  // namespace orthofront
