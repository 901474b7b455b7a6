#pragma once
/// The vector-field interface every engine runs on.
#include <limits>
#include <string>

#include "orthofront/types.h"

namespace orthofront {

/// Result of one field evaluation; per-vertex status, never an exception in loops.
enum class FieldStatus : unsigned char {
  inside = 0,   ///< value valid
  outside = 1,  ///< x lies outside the field's domain
  no_data = 2,  ///< inside the domain but no flow there (solid, fill value, NaN)
};

/// A steady vector field v: R^N -> R^N with its Jacobian J = dv/dx.
/// Implementations are immutable after construction and safe to call from many threads.
template <int N>
class Field {
 public:
  virtual ~Field() = default;
  /// v(x). `v` is left unspecified unless the status is `inside`.
  virtual FieldStatus velocity(const Vec<N>& x, Vec<N>& v) const = 0;
  /// v(x) and J(x) (J(r, c) = dv_r / dx_c). Analytic fields give exact Jacobians.
  virtual FieldStatus velocity_jacobian(const Vec<N>& x, Vec<N>& v, Mat<N>& J) const = 0;
  /// Bounding box of the domain, world units.
  virtual Box<N> domain() const = 0;
  /// Short human-readable description (name and parameters).
  virtual std::string describe() const = 0;
  /// The first τ in (after, before) at which the straight path x + τ w crosses a face where the
  /// field's derivative may jump (a face between two cells of an interpolated grid), or +inf
  /// where there is none: integrators end their steps just past such faces instead of stepping
  /// across them, since a step across a kink fails the error test unless it is tiny. Smooth
  /// fields keep the default.
  virtual double next_kink(const Vec<N>& x, const Vec<N>& w, double after, double before) const {
    (void)x, (void)w, (void)after, (void)before;
    return std::numeric_limits<double>::infinity();
  }
};

using Field3 = Field<3>;

}  // namespace orthofront
