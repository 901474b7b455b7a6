#pragma once
/// What every BatchAdvector::advect begins with (for the backends' sources only).
#include <chrono>
#include <vector>

#include "orthofront/advect/batch_advector.h"

namespace orthofront::advect {

inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// Checks the options, counts the particles into `stats` and plans the slabs (plan_slabs).
inline SlabPlan begin_call(const std::vector<double>& times, ParticleBatch& particles,
                           double t_end, const MethodOptions& options,
                           AdvectionStatistics& stats) {
  check_method(options);
  stats.particles = particles.size();
  return plan_slabs(times, particles, t_end);
}

}  // namespace orthofront::advect
