#pragma once
/// The flow map φ(x, t0, t1): where the particle that is at x at time t0 is at time t1. The one
/// seam through which streak surfaces (and later the derived fields of the paper's route, and a
/// GPU backend) move particles; a backend overrides advect_all.
#include <span>
#include <string>

#include "orthofront/advect/particle_status.h"
#include "orthofront/field/unsteady.h"
#include "orthofront/integrate/runge_kutta.h"

namespace orthofront::spacetime {

/// Why a particle stopped (a particle asked to go past the field's time range stops with
/// time_bounds): one definition with the bulk advection backends.
using advect::ParticleStatus;
using advect::to_string;

struct Advected {
  Vec3 x = Vec3::Zero();
  ParticleStatus status = ParticleStatus::moving;
  double t = 0;          ///< time reached
  int evaluations = 0;   ///< field evaluations spent
};

class FlowMap {
 public:
  virtual ~FlowMap() = default;
  virtual int dimension() const = 0;
  /// φ(x, t0, t1), forward or backward in time. Thread-safe.
  virtual Advected advect(const Vec3& x, double t0, double t1) const = 0;
  /// Advects x[i] from t0[i] to t1 for every i, in place (status[i] set, evaluations summed);
  /// the default runs advect() in parallel with oneTBB. The result of each particle does not
  /// depend on the others or on the number of threads.
  virtual std::size_t advect_all(std::span<Vec3> x, std::span<const double> t0, double t1,
                                 std::span<ParticleStatus> status) const;
};

/// The flow map by Dormand-Prince 5(4) integration of dx/dt = v(x, t) at tolerance `tolerance`.
/// Non-owning: `flow` must outlive it.
class IntegratedFlowMap final : public FlowMap {
 public:
  IntegratedFlowMap(const UnsteadyField& flow, Tolerance tolerance);
  int dimension() const override { return flow_.dimension(); }
  Advected advect(const Vec3& x, double t0, double t1) const override;

 private:
  template <int N>
  Advected advect_in(const Vec3& x, double t0, double t1) const;
  const UnsteadyField& flow_;
  Tolerance tolerance_;
};

}  // namespace orthofront::spacetime
