#pragma once
// orthofront-bench streak's real-data rows: streak surfaces of a real unsteady series (by default the
// shared backward-facing step), remeshed against the row mesh, side by side.
#include <nlohmann/json.hpp>
#include <string>

namespace orthofront::cli {

struct BenchStreakRealArgs {
  std::string field = "../shared/datasets/pitzdaily-les/step.pvd";
  std::string seed = "line:-0.002,0.0003,0:-0.002,0.0063,0";
  std::string release = "0.03:0.07", frames = "0.035:0.07:8";
  double edge = 0.001;
  double limit_seconds = 30;  // a run that has not finished by then stops (and says where)
};

/// Runs the rows (remeshed exact, remeshed interpolated, remeshed without pruning, rows) and
/// returns their figures; prints a table unless `quiet`. A missing field gives
/// {"skipped": why} and a line saying so.
nlohmann::json bench_streak_real(const BenchStreakRealArgs& args, bool quiet);

}  // namespace orthofront::cli
