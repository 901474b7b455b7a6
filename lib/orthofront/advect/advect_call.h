#pragma once
/// What every BatchAdvector::advect begins with (for the backends' sources only).
#include <chrono>
#include <string>
#include <vector>

#include "orthofront/advect/batch_advector.h"
#include "orthofront/error.h"
#include "orthofront/stage_timer.h"

namespace orthofront::advect {

/// Checks the options, counts the particles into `stats` and plans the slabs (plan_slabs).
inline SlabPlan begin_call(const std::vector<double>& times, ParticleBatch& particles,
                           double t_end, const MethodOptions& options,
                           AdvectionStatistics& stats) {
  check_method(options);
  stats.particles = particles.size();
  return plan_slabs(times, particles, t_end);
}

/// The slabs that move a resident set's particles from t_begin to t_end (all start together);
/// throws InvalidArgument when either time lies outside the series.
inline SlabPlan plan_resident(const std::vector<double>& times, double t_begin, double t_end) {
  ParticleBatch probe;
  probe.resize(1);
  probe.t[0] = t_begin;
  SlabPlan plan = plan_slabs(times, probe, t_end);
  if (probe.status[0] != ParticleStatus::moving)
    throw InvalidArgument("resident particles: times " + std::to_string(t_begin) + " -> " +
                          std::to_string(t_end) + " leave the series' [" +
                          std::to_string(times.front()) + ", " + std::to_string(times.back()) + "]");
  return plan;
}

}  // namespace orthofront::advect
