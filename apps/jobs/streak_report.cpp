#include "jobs/streak_report.h"

#include <cmath>
#include <exception>

#include "orthofront/error.h"
#include "orthofront/io/report_json.h"
#include "orthofront/spacetime/path_command_json.h"

namespace orthofront::jobs {
namespace {


std::vector<std::string> split_on(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::size_t begin = 0;
  for (;;) {
    const std::size_t end = text.find(separator, begin);
    parts.push_back(text.substr(begin, end - begin));
    if (end == std::string::npos) return parts;
    begin = end + 1;
  }
}

}  // namespace

double parse_time_number(const std::string& text, const std::string& option) {
  std::size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(value))
    throw InvalidArgument(option + ": '" + text + "' is not a finite number");
  return value;
}

std::pair<double, double> parse_streak_release(const std::string& text) {
  const auto parts = split_on(text, ':');
  if (parts.size() != 2)
    throw InvalidArgument("--release '" + text + "': expected T0:T1 (the release interval)");
  return {parse_time_number(parts[0], "--release"), parse_time_number(parts[1], "--release")};
}

// "t1,t2,..." or "START:END:COUNT" (COUNT times from START to END, both included).
std::vector<double> parse_streak_frames(const std::string& text) {
  std::vector<double> frames;
  if (text.find(':') != std::string::npos) {
    const auto parts = split_on(text, ':');
    if (parts.size() != 3)
      throw InvalidArgument("--frames '" + text +
                            "': expected START:END:COUNT or a list t1,t2,...");
    const double a = parse_time_number(parts[0], "--frames"), b = parse_time_number(parts[1], "--frames");
    const double n = parse_time_number(parts[2], "--frames");
    if (!(n >= 1 && n <= 100000 && n == std::floor(n)))
      throw InvalidArgument("--frames '" + text +
                            "': COUNT must be a whole number from 1 to 100000");
    if (n == 1) return {b};
    const int count = static_cast<int>(n);
    for (int i = 0; i + 1 < count; ++i) frames.push_back(a + (b - a) * i / (n - 1));
    frames.push_back(b);  // exactly END, whatever the rounding
    return frames;
  }
  for (const std::string& part : split_on(text, ','))
    frames.push_back(parse_time_number(part, "--frames"));
  return frames;
}

namespace {

// Infinity (no coarsening) as null: JSON has no infinity.
nlohmann::json finite_or_null(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json();
}

nlohmann::json frame_json(const spacetime::StreakFrameRecord& f) {
  const QualityReport& q = f.quality;
  return {{"index", f.index},       {"time", f.time},       {"vertices", f.vertices},
          {"faces", f.faces},       {"rows", f.rows},       {"stopped_particles", f.dead_particles},
          {"max_edge", f.max_edge}, {"seconds", f.seconds}, {"area", f.area},
          {"boundary_length", f.boundary_length}, {"vertex_estimate", f.vertex_estimate},
          {"pieces", f.pieces}, {"area_pruned", f.area_pruned},
          {"coarsen_age", finite_or_null(f.coarsen_age)}, {"max_edge_ratio", f.max_edge_ratio},
          {"quality", io::to_json(q)}};
}

}  // namespace

nlohmann::json streak_report_json(const spacetime::StreakReport& r) {
  nlohmann::json frames = nlohmann::json::array();
  for (const auto& f : r.frames) frames.push_back(frame_json(f));
  return {
      {"dimension", r.dimension},
      {"streamed", r.streamed},
      {"complete", r.complete},
      {"message", r.message},
      {"insertion", spacetime::to_string(r.insertion)},
      {"mesh", r.mesh},
      {"release",
       {{"begin", r.release_begin},
        {"end", r.release_end},
        {"step", r.release_step},
        {"rows", r.rows_released},
        {"rows_between_breaks", r.rows_released_between},
        {"seed_count", r.seed_count}}},
      {"time_reached", r.time_reached},
      {"particle_steps", r.particle_steps},
      {"particle_time", r.particle_time},
      {"evaluations", r.evaluations},
      {"intervals", r.intervals},
      {"refinement",
       {{"s_insertions", r.s_insertions},
        {"rows_inserted", r.rows_inserted},
        {"row_particles", r.row_particles},
        {"exact_insertions", r.exact_insertions},
        {"interpolated_insertions", r.interpolated_insertions},
        {"s_removals", r.s_removals},
        {"rows_removed", r.rows_removed},
        {"splits", r.splits},
        {"collapses", r.collapses},
        {"flips", r.flips},
        {"steered_insertions", r.steered_insertions},
        {"diverged_insertions", r.diverged_insertions},
        {"inexact_ends", r.inexact_ends},
        {"flat_insertions", r.flat_insertions},
        {"curve_insertions", r.curve_insertions},
        {"smoothed", r.smoothed},
        {"steps_shortened", r.steps_shortened},
        {"faces_turned", r.faces_turned},
        {"faces_removed_at_stops", r.faces_removed_at_stops},
        {"strip_faces_skipped", r.strip_faces_skipped},
        {"faces_pruned", r.faces_pruned},
        {"area_pruned", r.area_pruned},
        {"coarsened", r.coarsened},
        {"budget_coarsenings", r.budget_coarsenings},
        {"coarsen_age", finite_or_null(r.coarsen_age)}}},
      {"particles",
       {{"max", r.max_particles},
        {"left_domain", r.left_domain},
        {"left_region", r.left_region},
        {"no_data", r.no_data}}},
      {"frames", frames},
      {"cache", r.streamed ? spacetime::to_json(r.cache) : nlohmann::json()},
      {"slow_evaluations", r.slow_evaluations},
      {"device", r.device.empty() ? nlohmann::json()
                                  : nlohmann::json({{"backend", r.device},
                                                    {"slabs", r.bulk.slabs},
                                                    {"particle_steps", r.bulk.particle_steps},
                                                    {"compute_seconds", r.bulk.compute_seconds},
                                                    {"upload_seconds", r.bulk.upload_seconds},
                                                    {"bytes_uploaded", r.bulk.bytes_uploaded},
                                                    {"steps_loaded", r.bulk.steps_loaded},
                                                    {"steps_read_ahead", r.bulk.steps_read_ahead},
                                                    {"download_seconds", r.bulk.download_seconds},
                                                    {"pinned_seconds", r.bulk.pinned_seconds},
                                                    {"bytes_downloaded", r.bulk.bytes_downloaded},
                                                    {"overlap_seconds", r.bulk.overlap_seconds},
                                                    {"catch_up_calls", r.catch_up_calls},
                                                    {"catch_up_particles", r.catch_up_particles},
                                                    {"catch_up_seconds", r.catch_up_seconds},
                                                    {"catch_up_call_seconds", r.catch_up_call_seconds}})},
      {"seconds",
       {{"total", r.total_seconds},
        {"advect", r.advect_seconds},
        {"take", r.take_seconds},
        {"refine", r.refine_seconds},
        {"coarsen", r.coarsen_seconds},
        {"insert", r.insert_seconds},
        {"frames", r.frame_seconds},
        {"frames_finish", r.frame_finish_seconds},
        {"wait", r.wait_seconds},
        {"io", r.io_seconds},
        {"decode", r.decode_seconds}}}};
}

}  // namespace orthofront::jobs
