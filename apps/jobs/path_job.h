#pragma once
/// The options of a path surface, as every front end takes them (same names, defaults and
/// checks).
#include <cstddef>
#include <string>

#include "jobs/engine_options.h"
#include "jobs/option_set.h"
#include "orthofront/spacetime/brick_cache.h"
#include "orthofront/spacetime/path_surface.h"

namespace orthofront::jobs {

struct PathArgs {
  std::string field, seed, out, report, budget;  // budget: empty = a quarter of the memory
  int seed_count = 20;
  double t0 = 0, t1 = 1, time_scale = 0, max_band = 0, band_ramp = 1.0;
  // t0 and t1 as given (numbers, durations or dates: time_arg.h), resolved into t0 and t1 once
  // the field is open.
  std::string t0_text = "0", t1_text = "1";
  bool spacetime_out = false, flat = false, quiet = false, no_prefetch = false, warm = false;
  std::string cache_unit = "brick";
  std::string device;                 // empty: per vertex through the streamed field
  std::size_t device_min_vertices = 0;
  std::string device_memory;          // empty: half the device's free memory
  StreamSurfaceOptions options = path_engine_defaults();
  MemoryLimits limits;

  static StreamSurfaceOptions path_engine_defaults() {
    StreamSurfaceOptions o;
    o.max_steps = 1'000'000;  // path surfaces end at t1
    return o;
  }
};

/// Adds every option of a path surface but the field, seed, outputs and quiet: the seed count,
/// times, cache, band, engine and memory options.
void add_path_options(OptionSet& set, PathArgs& args);

/// Throws InvalidArgument for fewer than 2 seed vertices or more than the vertex cap.
void check_seed_count(int seed_count, std::size_t max_vertices);

/// The library's options (after apply_memory_limits); errors name args.seed and args.field.
spacetime::PathSurfaceOptions path_options(const PathArgs& args);

/// The cache of a streamed series: the cache budget (default: a quarter of the memory),
/// prefetch and unit.
spacetime::CacheOptions path_cache_options(const PathArgs& args);

}  // namespace orthofront::jobs
