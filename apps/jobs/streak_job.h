#pragma once
/// The options of a streak surface, as every front end takes them (same names, defaults and
/// checks).
#include <cstddef>
#include <string>

#include "jobs/engine_options.h"
#include "jobs/option_set.h"
#include "orthofront/spacetime/streak_surface.h"

namespace orthofront::jobs {

struct StreakArgs {
  std::string field, seed, release, frames, out, report, budget, insertion = "exact";
  std::string route = "direct", point, device, device_memory, mesh = "remeshed";
  int seed_count = 0, releases_per_break = 1;
  double edge = 0.05, split = 1.5, merge = 0.5, collapse = 0.75, prune = 0.75,
         release_step = 0, coarsen_age = 0, flat_split = 0.01;
  std::size_t max_vertices = 0, vertex_budget = 0;
  std::string region;
  bool quiet = false;
  MemoryLimits limits;
};

/// Adds every option of a streak surface but the field, seed, outputs and quiet: release,
/// frames, route, particle spacing, insertion, memory, cache and device.
void add_streak_options(OptionSet& set, StreakArgs& args);

/// After parsing into `set`: the library's options for the direct route (resolves the memory;
/// throws InvalidArgument naming a bad release, frames or device).
spacetime::StreakOptions streak_options(const OptionSet& set, StreakArgs& args);

/// The cache budget, or a quarter of the memory.
std::size_t streak_cache_budget(const StreakArgs& args);

}  // namespace orthofront::jobs
