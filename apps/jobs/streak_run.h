#pragma once
/// A streak surface run (the direct route) from parsed options, as the front ends that hold the
/// frames in memory (Python, ParaView) make it: ℓ from the grid unless given, the cache, every
/// frame, and the report.
#include <functional>
#include <nlohmann/json.hpp>
#include <vector>

#include "jobs/option_set.h"
#include "jobs/streak_job.h"
#include "orthofront/field/unsteady.h"
#include "orthofront/io/time_series.h"
#include "orthofront/seed/seed_curve.h"
#include "orthofront/spacetime/streak_surface.h"

namespace orthofront::jobs {

struct StreakRun {
  std::vector<spacetime::StreakFrame> frames;
  spacetime::StreakReport result;
  nlohmann::json report;  ///< as `streak --report` writes it
};

/// Builds the streak surface of `seed` through `series` or, where it is null, `analytic`, with
/// the options parsed into `set` and `args`. `keep_going` is asked as the particles move (false:
/// stop, the report says incomplete). Throws InvalidArgument for a route other than direct, no
/// frames, a device on an analytic field, or options the series refuses.
StreakRun run_streak_surface(const io::TimeSeries* series, const UnsteadyField* analytic,
                             const SeedCurve& seed, const OptionSet& set, StreakArgs& args,
                             const std::function<bool()>& keep_going);

}  // namespace orthofront::jobs
