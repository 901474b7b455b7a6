#pragma once
/// Advect (paper Figure 4, "advance"): the flow at a front's vertices, and every vertex moved
/// along its stream line by its own α-time τ_i = α_i h, per vertex through the field or through
/// a bulk backend (front_integrator.h).
#include <atomic>
#include <cstddef>
#include <vector>

#include "orthofront/engine/for_range.h"
#include "orthofront/engine/front.h"
#include "orthofront/engine/front_integrator.h"
#include "orthofront/engine/front_samples.h"
#include "orthofront/engine/options.h"
#include "orthofront/engine/report.h"
#include "orthofront/field/field.h"
#include "orthofront/integrate/runge_kutta.h"

namespace orthofront {

/// Why a front vertex cannot go on (ok: it can).
enum class VertexState : unsigned char { ok, outside, no_data, zero_speed, interrupted };

template <int N>
class FrontAdvect {
 public:
  /// `stop` is handed to the integrations; `stopping` set means the run stops inside this step
  /// (the vertices not yet moved end where they are). Counts go to `report`. All outlive this.
  FrontAdvect(const Field<N>& field, const StreamSurfaceOptions& options,
              const Tolerance& tolerance, const StopRequest& stop,
              const std::atomic<bool>& stopping, SurfaceReport& report);

  /// A bulk backend for whole fronts (null: per vertex); not owned.
  void set_front_integrator(FrontIntegrator<N>* integrator) { front_integrator_ = integrator; }

  /// v and |v| at every vertex of `f` (velocities(), speeds()); marks (keep[i] = 0) those without
  /// usable flow: outside, no data, or a speed below zero_speed_fraction of the median. Returns
  /// false when any was marked; `exits` counts those outside. `ahead`: the same samples taken
  /// already (samples_ahead.h), whose vectors this trades with its own.
  bool sample(const Front<N>& f, std::vector<char>& keep, std::size_t& exits,
              VertexSamples<N>* ahead = nullptr);
  /// What sample() found (the α step may rotate them with a closed front).
  std::vector<Vec<N>>& velocities() { return samples_.vel; }
  std::vector<double>& speeds() { return samples_.speed; }
  VertexState state(std::size_t i) const { return state_[i]; }

  /// `f` with every vertex moved along its stream line by α_i h; a vertex whose stream line ended
  /// (left the domain, met no data, or the run stopped) gets keep[i] = 0 and stays at its last
  /// valid point. New vertices keep their old one's index as `origin`. `room`: storage of an
  /// earlier front to reuse. `exits` counts those that left the domain.
  Front<N> advance(const Front<N>& f, const std::vector<double>& alpha, double h,
                   std::vector<char>& keep, std::size_t& exits,
                   std::vector<FrontVertex<N>>&& room);

 private:
  IntegrationResult<N> integrate(const Vec<N>& x, double tau) const;

  const Field<N>& field_;
  const StreamSurfaceOptions& opt_;
  const Tolerance& tol_;
  const StopRequest& stop_;
  const std::atomic<bool>& stopping_;
  SurfaceReport& report_;
  FrontIntegrator<N>* front_integrator_ = nullptr;
  // Scratch, reused between fronts and steps.
  VertexSamples<N> samples_;
  std::vector<VertexState> state_;
  std::vector<int> evaluations_;
  std::vector<Vec<N>> batch_x_;  ///< the bulk backend's arrays
  std::vector<double> batch_tau_;
  std::vector<IntegrationResult<N>> batch_out_;
  CheapLoop velocity_loop_;  ///< v at the front's vertices
};

extern template class FrontAdvect<3>;
extern template class FrontAdvect<4>;

}  // namespace orthofront
