#include "jobs/path_run.h"

#include "jobs/edge_default.h"
#include "jobs/time_arg.h"
#include "orthofront/io/report_json.h"
#include "orthofront/spacetime/brick_cache.h"
#include "orthofront/spacetime/path_command_json.h"

namespace orthofront::jobs {

PathRun run_path_surface(const io::TimeSeries* series, const UnsteadyField* analytic,
                         const SeedCurve& seed, PathArgs& args, bool edge_given,
                         const std::function<bool()>& keep_going) {
  // Numbers, or for NetCDF series dates and durations, as the command line takes them.
  args.t0 = resolve_time(args.t0_text, "t0", series ? series->time(0) : 0.0, series);
  args.t1 = resolve_time(args.t1_text, "t1", args.t0, series);
  spacetime::PathSurfaceOptions o = path_options(args);
  const EdgeChoice edge =
      choose_edge(o.engine.edge, edge_given, series ? &series->geometry() : nullptr);
  o.engine.edge = edge.edge;
  if (keep_going) o.progress = [&](const spacetime::PathProgress&) { return keep_going(); };
  PathRun run;
  std::size_t cache_budget = 0;
  if (series == nullptr) {
    run.result = spacetime::build_path_surface(*analytic, seed, args.seed_count, o);
  } else {
    const spacetime::CacheOptions co = path_cache_options(args);
    cache_budget = co.budget_bytes;
    spacetime::BrickCache cache(*series, co);
    run.result = spacetime::build_path_surface(cache, seed, args.seed_count, o);
  }
  spacetime::PathSurfaceResult& result = run.result;
  if (!result.spacetime_positions.empty()) {
    run.lifted.positions.assign(result.spacetime_positions.begin(),
                                result.spacetime_positions.end());
    for (Vec3& p : run.lifted.positions) p.z() *= result.path.time_scale;
  }
  spacetime::place_for_output(result, args.flat);
  nlohmann::json& report = run.report;
  report = io::to_json(result.report);
  report["field"] = args.field;
  report["seed"] = args.seed;
  report["seed_count"] = args.seed_count;
  add_edge_keys(report, edge);
  report["complete"] = result.report.complete;
  report["path"] = spacetime::to_json(result.path);
  report["path"]["positions"] = spacetime::path_positions(result, args.flat);
  report["limits"] = args.limits.to_json();
  if (cache_budget > 0) report["limits"]["cache_budget_bytes"] = cache_budget;
  return run;
}

}  // namespace orthofront::jobs
