#pragma once
/// Time-dependent analytic vector fields v(x, t) with exact spatial Jacobians and exact ∂v/∂t:
/// the classic unsteady test flows (double gyre, unsteady ABC) and a flow whose path lines are
/// known in closed form (exact tests of path surfaces).
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "orthofront/field/analytic.h"
#include "orthofront/field/field.h"

namespace orthofront {

/// Closed time interval [begin, end] (infinite ends allowed for analytic fields).
struct TimeRange {
  double begin = -std::numeric_limits<double>::infinity();
  double end = std::numeric_limits<double>::infinity();
  bool contains(double t) const { return t >= begin && t <= end; }
};

/// An unsteady field v(x, t) in R^d, d = 2 or 3. Vectors live in R^3; for d = 2 the z
/// coordinate is ignored (v_z = 0, J's third row and column are 0, the domain check uses x, y).
/// Implementations are immutable and safe to call from many threads.
class UnsteadyField {
 public:
  virtual ~UnsteadyField() = default;
  /// Spatial dimension d (2 or 3).
  virtual int dimension() const = 0;
  /// v(x, t); `v` is unspecified unless the status is `inside`.
  virtual FieldStatus velocity(const Vec3& x, double t, Vec3& v) const = 0;
  /// v(x, t), J = ∂v/∂x (J(r, c) = ∂v_r/∂x_c) and dvdt = ∂v/∂t, all exact.
  virtual FieldStatus velocity_jacobian(const Vec3& x, double t, Vec3& v, Mat3& J,
                                        Vec3& dvdt) const = 0;
  /// Spatial domain, world units (for d = 2 only x and y count).
  virtual Box<3> domain() const = 0;
  /// Times at which the field is defined.
  virtual TimeRange time_range() const = 0;
  virtual std::string describe() const = 0;
  /// The first τ in (after, before) at which the straight space-time path (x + τ w, t + τ w_t)
  /// crosses a face where the field's derivative may jump (a grid cell's face, a time step of
  /// a series that is linear in time between steps), or +inf (the default: smooth fields).
  /// See Field::next_kink.
  virtual double next_kink(const Vec3& x, double t, const Vec3& w, double w_t, double after,
                           double before) const {
    (void)x, (void)t, (void)w, (void)w_t, (void)after, (void)before;
    return std::numeric_limits<double>::infinity();
  }
  /// Exact flow map: the position at time t of the particle that is at x0 at time t0. Returns
  /// false when the field has no closed form (the default).
  virtual bool exact_flow_map(const Vec3& x0, double t0, double t, Vec3& x) const {
    (void)x0, (void)t0, (void)t, (void)x;
    return false;
  }
};

/// All unsteady analytic fields, in a stable order (for `orthofront fields`).
const std::vector<AnalyticFieldInfo>& unsteady_fields();

/// Builds a field from "name" or "name:key=value,..." (e.g. "double-gyre:A=0.1,eps=0.25").
/// Throws InvalidArgument naming the unknown field, the unknown key or the malformed value.
std::unique_ptr<UnsteadyField> make_unsteady_field(std::string_view spec);

/// True when `spec` names an unsteady analytic field (its part before ':' is a known name).
bool is_unsteady_field_name(std::string_view spec);

}  // namespace orthofront
