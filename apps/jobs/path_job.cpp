#include "jobs/path_job.h"

#include <string>

#include "jobs/process_memory.h"
#include "orthofront/advect/batch_advector.h"
#include "orthofront/spacetime/bulk_front_integrator.h"
#include "orthofront/error.h"

namespace orthofront::jobs {

void add_path_options(OptionSet& set, PathArgs& args) {
  using G = OptionGroup;
  set.integer("seed-count", args.seed_count, "Vertices on the seed curve");
  set.text("t0", args.t0_text,
           "Seed time: a number in the field's time unit; for NetCDF series also a date "
           "(2002-01-01, '2002-01-01 06:00') or a duration after the first step ('10 days')")
      .group(G::input);
  set.text("t1", args.t1_text,
           "End time: the surface stops where its path lines reach it (as --t0; a duration "
           "counts from t0: '30 days')")
      .group(G::input);
  set.real("time-scale", args.time_scale,
           "c of the lifted time coordinate tau = c (t - t0) (length per time unit); 0: median "
           "seed speed at t0")
      .at_least(0);
  set.text("cache-budget", args.budget,
           "Memory for resident and in-flight data (e.g. 256MiB, 2GiB); never exceeded "
           "(default: a quarter of --memory, now " +
               format_memory(cache_budget_for(available_memory_bytes())) + ")")
      .group(G::budget)
      .derived_default();
  set.text("cache-unit", args.cache_unit,
           "What the cache holds: brick (the file's bricks, a space-time band around the front) "
           "or step (whole time steps: the baseline of orthofront-bench path)")
      .one_of({"brick", "step"})
      .group(G::performance);
  set.flag("no-prefetch", args.no_prefetch, "Load on demand only (no read-ahead)")
      .group(G::performance);
  set.flag("warm", args.warm,
           "Build the surface twice through one cache that keeps everything it read, and report "
           "the second build: compute with the data in memory (needs a budget that holds every "
           "brick the surface touches)")
      .group(G::performance);
  set.real("max-band", args.max_band,
           "Bound the front's time band (time units; 0: none): vertices further behind keep "
           "pace, so long runs fit a small cache")
      .at_least(0)
      .group(G::budget);
  set.real("band-ramp", args.band_ramp,
           "With --max-band: share of the bound over which lagging vertices' alpha ramps up "
           "smoothly (0: a hard switch at the bound)")
      .range(0.0, 1.0)
      .group(G::budget);
  set.text("device", args.device,
           "Gridded series: advance the front by bulk advection (whole time steps, slab by slab) "
           "on cpu or cuda; auto: cuda for fronts of at least " +
               std::to_string(spacetime::kCudaFrontBreakEven) +
               " vertices where a device is present. Default: per vertex through the streamed "
               "field")
      .one_of({"cpu", "cuda", "auto"})
      .group(G::performance)
      .derived_default();
  set.count("device-min-vertices", args.device_min_vertices,
            "With --device: smaller fronts advance per vertex (0: every front for cpu and cuda, "
            "the break-even size for auto)")
      .group(G::performance);
  set.text("device-memory", args.device_memory,
           "With --device cuda/auto: time steps kept on the device (e.g. 8GiB; default: half its "
           "free memory)")
      .group(G::performance)
      .derived_default();
  set.flag("flat", args.flat,
           "2D flows: write positions (x, y, 0), the surface pressed into the plane (it overlaps "
           "itself where path lines cross); default (x, y, c t), c the time scale (--time-scale "
           "1: (x, y, t))")
      .group(G::output);
  set.flag("spacetime-out", args.spacetime_out,
           "2D flows: write positions in space-time (the default; kept for old scripts)")
      .group(G::output);
  add_engine_options(set, args.options);
  add_memory_option(set, args.limits);
}

void check_seed_count(int seed_count, std::size_t max_vertices) {
  if (seed_count < 2)
    throw InvalidArgument("--seed-count must be at least 2, got " + std::to_string(seed_count));
  if (static_cast<std::size_t>(seed_count) > max_vertices)
    throw InvalidArgument("--seed-count " + std::to_string(seed_count) +
                          " exceeds the vertex budget of " + std::to_string(max_vertices) +
                          " (--max-vertices, or half of --memory at ~300 B a vertex)");
}

spacetime::PathSurfaceOptions path_options(const PathArgs& args) {
  if (args.flat && args.spacetime_out)
    throw InvalidArgument("--flat and --spacetime-out exclude each other (2D positions are "
                          "written either pressed flat or in space-time)");
  spacetime::PathSurfaceOptions o;
  o.engine = args.options;
  o.t0 = args.t0;
  o.t1 = args.t1;
  o.time_scale = args.time_scale;
  o.max_band = args.max_band;
  o.engine.lag_ramp = args.band_ramp;
  o.seed_name = args.seed;  // errors name the seed and field as given
  o.field_name = args.field;
  if (!args.device.empty()) o.device = advect::parse_device(args.device);
  o.device_min_vertices = args.device_min_vertices;
  if (!args.device_memory.empty()) o.device_bytes = spacetime::parse_bytes(args.device_memory);
  return o;
}

spacetime::CacheOptions path_cache_options(const PathArgs& args) {
  spacetime::CacheOptions co;
  // An explicit cache budget wins over the share of the memory.
  co.budget_bytes = args.budget.empty() ? cache_budget_for(args.limits.memory_bytes)
                                        : spacetime::parse_bytes(args.budget);
  co.prefetch = !args.no_prefetch;
  co.whole_steps = args.cache_unit == "step";
  return co;
}

}  // namespace orthofront::jobs
