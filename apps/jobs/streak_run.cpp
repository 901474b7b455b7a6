#include "jobs/streak_run.h"

#include "jobs/edge_default.h"
#include "jobs/streak_report.h"
#include "orthofront/error.h"
#include "orthofront/spacetime/brick_cache.h"

namespace orthofront::jobs {

StreakRun run_streak_surface(const io::TimeSeries* series, const UnsteadyField* analytic,
                             const SeedCurve& seed, const OptionSet& set, StreakArgs& args,
                             const std::function<bool()>& keep_going) {
  if (args.route != "direct")
    throw InvalidArgument("route '" + args.route +
                          "': only the command line builds the other routes (orthofront streak "
                          "--route " + args.route + ")");
  if (args.frames.empty()) throw InvalidArgument("frames is required (the observation times)");
  spacetime::StreakOptions o = streak_options(set, args);
  const EdgeChoice edge =
      choose_edge(o.edge, set.given("edge"), series ? &series->geometry() : nullptr);
  o.edge = edge.edge;
  if (series == nullptr && o.device)
    throw InvalidArgument("device: bulk advection reads gridded series, not analytic fields");
  if (keep_going) o.progress = [&](const spacetime::StreakProgress&) { return keep_going(); };
  StreakRun run;
  const auto sink = [&](const spacetime::StreakFrame& frame) { run.frames.push_back(frame); };
  std::size_t cache_budget = 0;
  if (series == nullptr) {
    run.result = spacetime::build_streak_surface(*analytic, seed, o, sink);
  } else {
    spacetime::CacheOptions co;
    co.budget_bytes = streak_cache_budget(args);
    cache_budget = co.budget_bytes;
    spacetime::BrickCache cache(*series, co);
    run.result = spacetime::build_streak_surface(cache, seed, o, sink);
  }
  nlohmann::json& report = run.report;
  report = streak_report_json(run.result);
  report["field"] = args.field;
  report["seed"] = args.seed;
  add_edge_keys(report, edge);
  report["limits"] = args.limits.to_json();
  if (cache_budget > 0) report["limits"]["cache_budget_bytes"] = cache_budget;
  return run;
}

}  // namespace orthofront::jobs
