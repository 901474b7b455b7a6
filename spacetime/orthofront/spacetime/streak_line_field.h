#pragma once
/// The paper's route to streak surfaces (Section 8, after Weinkauf & Theisel 2010): at an
/// observation time t, the streak surface of a seed curve is a stream surface of a derived
/// field over (x, a), where a is the age of a particle (t minus its release time).
///
/// Let Ψ(x, a) = φ(x, t, t - a) be where the particle that is at x at time t was a time units
/// earlier. Along one streak line the release point is fixed, Ψ(x(a), a) = x0, so
/// ∇Ψ dx/da + ∂Ψ/∂a = 0 with ∂Ψ/∂a = -v(Ψ, t - a), which gives the streak-line field
///
///   s(x, a) = [∇Ψ(x, a)]^(-1) v(Ψ(x, a), t - a).
///
/// Its tangent curves, read as path lines of s with "time" a, are the streak lines at t, older
/// particles further along. So the streak surface at t is the path surface of s from the seed
/// curve at age 0 (or from the youngest row's positions when the release ended before t), built
/// by the flow-orthogonal engine in (x, c a). The flow map and its gradient come from one
/// backward integration of the variational equations dΨ/dτ = v, d(∇Ψ)/dτ = ∇v ∇Ψ per evaluation,
/// on demand: exact to the integrator's tolerance, and the expensive part of the route.
#include <atomic>
#include <string>
#include <vector>

#include "orthofront/field/unsteady.h"
#include "orthofront/integrate/runge_kutta.h"
#include "orthofront/mesh/mesh.h"
#include "orthofront/seed/seed_curve.h"
#include "orthofront/spacetime/path_surface.h"

namespace orthofront::spacetime {

/// Ψ(x, a) and ∇Ψ(x, a) (zero third row and column for 2D flows).
struct FlowMapGradient {
  Vec3 x = Vec3::Zero();
  Mat3 gradient = Mat3::Identity();
  FieldStatus status = FieldStatus::inside;
  int evaluations = 0;
};

/// φ(x, t0, t1) and its spatial gradient by Dormand-Prince 5(4) on the variational equations.
FlowMapGradient flow_map_gradient(const UnsteadyField& flow, const Vec3& x, double t0, double t1,
                                  const Tolerance& tolerance);

/// The streak-line field s(x, a) of `flow` at observation time t, as an unsteady field whose
/// time is the age a ∈ [0, t - oldest release]. Its Jacobian (which the engine's α step uses) is
/// taken by central differences of s. Non-owning; thread-safe.
class StreakLineField final : public UnsteadyField {
 public:
  /// Throws InvalidArgument when [t - max_age, t] is not inside the flow's time range.
  StreakLineField(const UnsteadyField& flow, double observation_time, double max_age,
                  Tolerance tolerance);
  int dimension() const override { return flow_.dimension(); }
  FieldStatus velocity(const Vec3& x, double age, Vec3& s) const override;
  FieldStatus velocity_jacobian(const Vec3& x, double age, Vec3& s, Mat3& J,
                                Vec3& dsda) const override;
  Box<3> domain() const override { return flow_.domain(); }
  TimeRange time_range() const override { return {0.0, max_age_}; }
  std::string describe() const override;

  std::size_t derived_evaluations() const { return derived_.load(); }        ///< values of s
  std::size_t flow_evaluations() const { return flow_evaluations_.load(); }  ///< of v and ∇v

 private:
  const UnsteadyField& flow_;
  double t_, max_age_;
  Tolerance tolerance_;
  double dx_, da_;  ///< difference steps of the Jacobian
  mutable std::atomic<std::size_t> derived_{0}, flow_evaluations_{0};
};

struct StreakLineSurfaceOptions {
  PathSurfaceOptions path;  ///< engine options (ℓ in (x, c a)), time_scale c (0: derived)
  double release_begin = 0, release_end = 1;
  double observation_time = 1;  ///< t; > release_begin
  int seed_count = 0;           ///< vertices on the seed row; 0: row length / ℓ + 1
  Tolerance tolerance{1e-10, 1e-10};
};

struct StreakLineSurface {
  /// Positions (x, y, 0) for 2D flows; attributes release_time, age, s, particle_id (-1), speed
  /// (|v| at t). `time` holds the age too.
  Mesh mesh;
  std::vector<Vec3> lifted;  ///< (x, y, a) per vertex: the surface the engine built
  SurfaceReport report;      ///< quality in (x, y, c a)
  PathReport path;
  double first_age = 0;  ///< age of the seed row (t - release_end, or 0)
  std::size_t derived_evaluations = 0, flow_evaluations = 0;
  double seconds = 0;
};

/// The streak surface at `observation_time` by the paper's route (2D flows). Throws
/// InvalidArgument naming the value for a flow that is not 2D, bad times, or a seed row outside
/// the domain.
StreakLineSurface build_streak_line_surface(const UnsteadyField& flow, const SeedCurve& seed,
                                            const StreakLineSurfaceOptions& options);

}  // namespace orthofront::spacetime
