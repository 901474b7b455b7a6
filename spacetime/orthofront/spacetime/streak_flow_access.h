#pragma once
/// What a streak builder needs from where the data lives: the field, and (streamed) a hook that
/// makes the data of [t_a, t_b] resident before particles are moved across it. Shared by the
/// streak mesh builders (rows over (s, τ), and the remeshed triangle mesh).
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "orthofront/field/unsteady.h"
#include "orthofront/spacetime/flow_map.h"
#include "orthofront/spacetime/streak_surface.h"

namespace orthofront::spacetime {

class BulkFlowMap;

struct StreakFlowAccess {
  const UnsteadyField& flow;
  /// Makes [t_a, t_b] resident; returns a read error (empty: none). May be empty (in memory).
  std::function<std::string(double, double)> prepare;
  std::function<std::string()> read_error;      ///< empty string: no error
  std::vector<double> step_times;               ///< streamed: the series' times (break points)
  const FlowMap* map = nullptr;                 ///< bulk advection; null: integrate `flow`
  const BulkFlowMap* bulk = nullptr;            ///< the same map, for particles kept on its backend
};

/// Throws InvalidArgument naming the value for an edge, split factor, release interval, frame
/// list, release step or seed count that no streak builder can take, and for times outside the
/// field's time range (`field_name` names it).
void check_streak_options(const StreakOptions& options, const UnsteadyField& flow,
                          const std::string& field_name);

/// Moves particles released at from[i] (x[i]: their seed points) to time t, with `map`. A
/// streamed series (access.prepare set) is swept forward one step interval at a time from the
/// earliest release, all particles together, so a batch reads each step once instead of once
/// per particle; the band is left at [t, t]. Adds the field evaluations to `evaluations`.
/// Returns a read error (empty: none).
std::string advect_from_release(const StreakFlowAccess& access, const FlowMap& map,
                                std::span<Vec3> x, std::span<const double> from, double t,
                                std::span<ParticleStatus> status, std::size_t& evaluations);

}  // namespace orthofront::spacetime
