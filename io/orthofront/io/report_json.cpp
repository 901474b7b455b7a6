#include "orthofront/io/report_json.h"

#include <cmath>

#include "orthofront/io/atomic_file.h"

namespace orthofront::io {

namespace {
nlohmann::json to_json(const Histogram& h) {
  return {{"lo", h.lo}, {"hi", h.hi}, {"counts", h.counts}};
}
}  // namespace

nlohmann::json to_json(const StreamSurfaceOptions& o) {
  return {
      {"method", to_string(o.method)},
      {"edge", o.edge},
      {"max_steps", o.max_steps},
      {"max_vertices", o.max_vertices},
      {"mu_mode", to_string(o.mu_mode)},
      {"damping", o.damping},
      {"mu", o.mu},
      {"negative_alpha", to_string(o.negative_alpha)},
      {"insertion", to_string(o.insertion)},
      {"split_factor", o.split_factor},
      {"merge_factor", o.merge_factor},
      {"row_skip", to_string(o.row_skip)},
      {"skip_fraction", o.skip_fraction},
      {"join_fraction", o.join_fraction},
      {"rip", o.rip},
      {"fold_guard", o.fold_guard},
      {"stall_steps", o.stall_steps},
      {"close_gaps", o.close_gaps},
      {"gap_distance", o.gap_distance},
      {"rip_sharpness", o.rip_sharpness},
      {"rip_speed_fraction", o.rip_speed_fraction},
      {"shots_ahead", o.shots_ahead},
      {"samples_ahead", o.samples_ahead},
      {"shot_evaluations", o.shot_evaluations},
      {"integrator", to_string(o.integrator)},
      {"tolerance", o.tolerance},
      {"timeline_step", o.timeline_step},
  };
}

nlohmann::json to_json(const QualityReport& q) {
  return {
      {"vertices", q.vertices},
      {"faces", q.faces},
      {"quads", q.quads},
      {"triangles", q.triangles},
      {"quad_share", q.quad_share},
      {"quad_angles_within_10deg", q.quad_angles_within_10},
      {"quad_angle_mean_abs_dev_deg", q.quad_angle_mean_abs_dev},
      {"edge_spread_median", q.edge_spread_median},
      {"edge_spread_mean", q.edge_spread_mean},
      {"triangle_min_angle_median_deg", q.triangle_min_angle_median},
      {"triangle_min_angle_p05_deg", q.triangle_min_angle_p05},
      {"triangles_below_10deg", q.triangles_below_10deg},
      {"folds", q.folds},
      {"non_manifold_edges", q.non_manifold_edges},
      {"inconsistent_edges", q.inconsistent_edges},
      {"t_junctions", q.t_junctions},
      {"degenerate_faces", q.degenerate_faces},
      {"boundary_edges", q.boundary_edges},
      {"longest_edge", q.longest_edge},
      {"histograms",
       {{"quad_angles_deg", to_json(q.quad_angles)},
        {"edge_ratio", to_json(q.edge_ratio)},
        {"triangle_min_angle_deg", to_json(q.triangle_min_angle)}}},
  };
}

nlohmann::json to_json(const SurfaceReport& r) {
  nlohmann::json steps = nlohmann::json::array();
  for (const StepRecord& s : r.per_step)
    steps.push_back({{"step", s.step},
                     {"fronts", s.fronts},
                     {"front_vertices", s.front_vertices},
                     {"h_min", s.h_min},
                     {"h_max", s.h_max},
                     {"orthogonality_mean", s.orthogonality_mean},
                     {"orthogonality_max", s.orthogonality_max}});
  return {
      {"parameters", to_json(r.options)},
      {"complete", r.complete},
      {"stop_reason", to_string(r.stop_reason)},
      {"steps", r.steps},
      {"counts",
       {{"vertices", r.vertices},
        {"faces", r.faces},
        {"quads", r.quads},
        {"triangles", r.triangles},
        {"triangles_by_cause",
         {{"row_changes", r.triangles_at_row_changes},
          {"waiting_vertices", r.triangles_at_waiting_vertices},
          {"closing_gaps", r.triangles_closing_gaps}}},
        {"vertex_steps", r.vertex_steps},
        {"rips", r.rips},
        {"negative_alpha", r.negative_alpha},
        {"clamped_alpha", r.clamped_alpha},
        {"clamped_alpha_by_cause",
         {{"slow_flow", r.clamped_slow_flow},
          {"front_end", r.clamped_front_end},
          {"infeasible_damping_step", r.clamped_infeasible_step},
          {"ahead_of_neighbours", r.clamped_ahead}}},
        {"lag_raised_alpha", r.lag_raised_alpha},
        {"splits", r.splits},
        {"merges", r.merges},
        {"streamline_insertions", r.streamline_insertions},
        {"previous_row_insertions", r.previous_row_insertions},
        {"seed_shots_skipped", r.seed_shots_skipped},
        {"seed_shots_over_budget", r.seed_shots_over_budget},
        // Flow time from the seed beyond which insertions start from the previous row (none:
        // null).
        {"seed_shot_time_limit", std::isfinite(r.seed_shot_time_limit)
                                     ? nlohmann::json(r.seed_shot_time_limit)
                                     : nlohmann::json(nullptr)},
        {"seed_legs_ahead", {{"started", r.legs_started_ahead}, {"used", r.legs_used_ahead}}},
        {"front_samples_ahead",
         {{"started", r.samples_started_ahead}, {"used", r.samples_used_ahead}}},
        {"insertion_fallbacks", r.insertion_fallbacks},
        {"insertion_fallbacks_by_cause",
         {{"left_domain_or_no_data", r.fallback_left_domain},
          {"far_from_front", r.fallback_far_from_front}}},
        {"fold_rips", r.fold_rips},
        {"folds_left_by_guard", r.folds_left},
        {"stall_cuts", r.stall_cuts},
        {"gaps_closed", {{"stretches", r.gap_stretches}, {"faces", r.gap_faces},
                         {"refused", r.gaps_refused}}},
        {"skipped_vertex_steps", r.skipped_vertex_steps},
        {"domain_exits", r.domain_exits},
        {"no_data_hits", r.no_data_hits},
        {"zero_velocity_cuts", r.zero_velocity_cuts},
        {"fronts_created", r.fronts_created},
        {"fronts_dropped_short", r.fronts_dropped_short},
        {"fronts_stalled", r.fronts_stalled},
        {"infeasible_damping_steps", r.infeasible_damping_steps},
        {"field_evaluations", r.field_evaluations}}},
      {"timeline_step", r.timeline_step},
      {"closed_seed", r.closed_seed},
      {"closed_front_opened", r.closed_front_opened},
      {"closed_log_product", r.closed_log_product},
      {"message", r.message},
      {"times_s",
       {{"alpha", r.times.alpha},
        {"rip", r.times.rip},
        {"advance", r.times.advance},
        {"adapt", r.times.adapt},
        {"stitch", r.times.stitch},
        {"gaps", r.times.gaps},
        {"quality", r.times.quality},
        {"total", r.times.total}}},
      {"quality", to_json(r.quality)},
      {"per_step", steps},
  };
}

void write_json(const nlohmann::json& value, const std::filesystem::path& path) {
  const std::string text = value.dump(2) + "\n";
  write_atomically(path, [&](std::ofstream& out) { out << text; });
}

void write_json(const nlohmann::json& value, const std::filesystem::path& path,
                AtomicFileSet& files) {
  const std::string text = value.dump(2) + "\n";
  files.add(path, [&](std::ofstream& out) { out << text; });
}

}  // namespace orthofront::io
