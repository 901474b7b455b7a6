#include "cli/bench_streak_real.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <tuple>
#include <vector>

#include "jobs/seed_spec.h"
#include "jobs/streak_report.h"
#include "orthofront/io/open_field.h"
#include "orthofront/spacetime/brick_cache.h"
#include "orthofront/spacetime/streak_surface.h"

namespace orthofront::cli {

using namespace jobs;

namespace {

struct RealRow {
  std::string name;
  spacetime::StreakReport report;
};

nlohmann::json frame_json(const spacetime::StreakFrameRecord& f, double edge) {
  const QualityReport& q = f.quality;
  return {{"time", f.time},
          {"vertices", f.vertices},
          {"vertex_estimate", f.vertex_estimate},
          {"pieces", f.pieces},
          {"folds", q.folds},
          {"t_junctions", q.t_junctions},
          {"degenerate_faces", q.degenerate_faces},
          {"max_edge_over_edge", f.max_edge / edge},
          {"triangle_min_angle_p05", q.triangle_min_angle_p05},
          {"quads", q.quad_share},
          {"quad_angles_within_10", q.quad_angles_within_10},
          {"area", f.area},
          {"area_pruned", f.area_pruned}};
}

nlohmann::json row_json(const RealRow& r, double edge) {
  const auto& rep = r.report;
  nlohmann::json frames = nlohmann::json::array();
  for (const auto& f : rep.frames) frames.push_back(frame_json(f, edge));
  return {{"name", r.name},
          {"complete", rep.complete},
          {"message", rep.message},
          {"time_reached", rep.time_reached},
          {"seconds", rep.total_seconds},
          {"advect_seconds", rep.advect_seconds},
          {"refine_seconds", rep.refine_seconds},
          {"coarsen_seconds", rep.coarsen_seconds},
          {"insert_seconds", rep.insert_seconds},
          {"frame_seconds", rep.frame_seconds + rep.frame_finish_seconds},
          {"exact_insertions", rep.exact_insertions},
          {"interpolated_insertions", rep.interpolated_insertions},
          {"faces_pruned", rep.faces_pruned},
          {"frames", frames}};
}

}  // namespace

nlohmann::json bench_streak_real(const BenchStreakRealArgs& a, bool quiet) {
  if (!std::filesystem::exists(a.field)) {
    if (!quiet)
      std::printf("\nReal data: skipped, %s not found (give --real FILE).\n", a.field.c_str());
    return {{"skipped", a.field + " not found"}};
  }
  const std::unique_ptr<io::TimeSeries> series = io::open_time_series(a.field, "orthofront-bench streak");
  const SeedCurve seed = parse_seed(a.seed);
  spacetime::StreakOptions o;
  std::tie(o.release_begin, o.release_end) = parse_streak_release(a.release);
  o.frames = parse_streak_frames(a.frames);
  o.edge = a.edge;
  o.seed_name = a.seed;
  o.field_name = a.field;
  o.progress = [&](const spacetime::StreakProgress& p) {
    return p.elapsed_seconds < a.limit_seconds;
  };
  const auto run = [&](const spacetime::StreakOptions& opts) {
    spacetime::CacheOptions co;
    co.budget_bytes = std::size_t{1} << 30;
    spacetime::BrickCache cache(*series, co);
    return spacetime::build_streak_surface(cache, seed, opts, {});
  };
  std::vector<RealRow> rows;
  o.mesh = spacetime::StreakMesh::remeshed;
  rows.push_back({"remeshed, exact (streak's default)", run(o)});
  o.flat_split = 0;
  rows.push_back({"remeshed, exact, --flat-split 0", run(o)});
  o.flat_split = spacetime::StreakOptions{}.flat_split;
  o.insertion = spacetime::ParticleInsertion::interpolate;
  rows.push_back({"remeshed, interpolated", run(o)});
  o.insertion = spacetime::ParticleInsertion::exact;
  o.prune = 0;
  rows.push_back({"remeshed, no pruning (--prune 0)", run(o)});
  o.mesh = spacetime::StreakMesh::rows;
  rows.push_back({"rows, exact (baseline)", run(o)});

  nlohmann::json out = {{"field", a.field},   {"seed", a.seed},
                        {"release", a.release}, {"frames", a.frames},
                        {"edge", a.edge},     {"limit_seconds", a.limit_seconds},
                        {"rows", nlohmann::json::array()}};
  for (const RealRow& r : rows) out["rows"].push_back(row_json(r, a.edge));
  if (quiet) return out;

  std::printf("\nReal data: %s, seed %s, release %s, frames %s, edge %g (runs stop after %g s)\n",
              a.field.c_str(), a.seed.c_str(), a.release.c_str(), a.frames.c_str(), a.edge,
              a.limit_seconds);
  std::printf("%-36s %7s %8s %7s %7s %7s %7s %7s %7s %9s %6s %6s %6s %6s %6s %7s\n", "run",
              "frames", "t", "time s", "advect", "refine", "insert", "coarse", "refine%", "vertices", "xbound",
              "pieces", "folds", "maxE/l", "p05", "pruned%");
  for (const RealRow& r : rows) {
    const auto& rep = r.report;
    if (rep.frames.empty()) {
      std::printf("%-36s %7s %8.4f %7.1f  no frame: %s\n", r.name.c_str(), "0",
                  rep.time_reached, rep.total_seconds, rep.message.c_str());
      continue;
    }
    const auto& f = rep.frames.back();
    std::size_t folds = 0;
    double worst_bound = 0;  // the row mesh does not measure its area
    for (const auto& g : rep.frames) {
      folds = std::max(folds, g.quality.folds);
      if (g.vertex_estimate > 0)
        worst_bound = std::max(worst_bound, static_cast<double>(g.vertices) / g.vertex_estimate);
    }
    char frames[32], bound[32], shape[32], pieces[32];
    std::snprintf(pieces, sizeof pieces, f.pieces > 0 ? "%zu" : "-", f.pieces);
    std::snprintf(frames, sizeof frames, "%zu/%zu", rep.frames.size(), o.frames.size());
    std::snprintf(bound, sizeof bound, worst_bound > 0 ? "%.2f" : "-", worst_bound);
    if (f.quality.quad_share > 0)
      std::snprintf(shape, sizeof shape, "%.1f%%q", 100 * f.quality.quad_angles_within_10);
    else
      std::snprintf(shape, sizeof shape, "%.1f", f.quality.triangle_min_angle_p05);
    std::printf(
        "%-36s %7s %8.4f %7.1f %7.1f %7.1f %7.1f %7.1f %7.1f %9zu %6s %6s %6zu %6.2f %6s %7.1f\n",
        r.name.c_str(), frames, rep.time_reached, rep.total_seconds, rep.advect_seconds,
        rep.refine_seconds, rep.insert_seconds, rep.coarsen_seconds, 100 * rep.refine_seconds / rep.total_seconds,
        f.vertices, bound, pieces, folds, f.max_edge / a.edge, shape,
        100 * f.area_pruned / std::max(f.area + f.area_pruned, 1e-300));
  }
  const auto& best = rows.front().report;
  std::printf("\nPer frame, %s:\n%8s %9s %9s %6s %6s %6s %6s %8s\n", rows.front().name.c_str(), "t",
              "vertices", "estimate", "pieces", "folds", "maxE/l", "p05", "pruned%");
  for (const auto& f : best.frames)
    std::printf("%8.4f %9zu %9.0f %6zu %6zu %6.2f %6.1f %8.1f\n", f.time, f.vertices,
                f.vertex_estimate, f.pieces, f.quality.folds, f.max_edge / a.edge,
                f.quality.triangle_min_angle_p05,
                100 * f.area_pruned / std::max(f.area + f.area_pruned, 1e-300));
  std::printf(
      "\nColumns: frames = frames written of those asked for; t = time reached; refine = "
      "adapting the mesh, insert its part moving inserted particles to now (remeshed), "
      "coarsen its part collapsing; "
      "xbound = the largest vertices / (1.155 area / l^2 + boundary / l) over the frames (- where not measured); folds "
      "= the most in any frame; p05 = 5th percentile of the triangles' smallest angles (deg, "
      "last frame; for quads N%%q: the share of quad angles within 90±10°); pruned%% = dye area pruned as thin filaments, of all dye.\n");
  return out;
}

}  // namespace orthofront::cli
