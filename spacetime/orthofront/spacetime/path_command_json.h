#pragma once
/// The space-time part of a path-surface report as JSON (c, time band per step, cache, times).
#include <nlohmann/json.hpp>

#include "orthofront/spacetime/path_surface.h"

namespace orthofront::spacetime {

/// What a front's bulk advance did (path --device, stream --device).
inline nlohmann::json device_json(const std::string& backend, std::size_t min_front_vertices,
                                  std::size_t calls, const advect::AdvectionStatistics& d) {
  return {{"backend", backend},
          {"min_front_vertices", min_front_vertices},
          {"calls", calls},
          {"particles", d.particles},
          {"slabs", d.slabs},
          {"steps_loaded", d.steps_loaded},
          {"steps_read_ahead", d.steps_read_ahead},
          {"particle_steps", d.particle_steps},
          {"evaluations", d.evaluations},
          {"seconds", d.total_seconds},
          {"compute_seconds", d.compute_seconds},
          {"upload_seconds", d.upload_seconds},
          {"host_seconds", d.host_seconds},
          {"bytes_uploaded", d.bytes_uploaded},
          {"download_seconds", d.download_seconds},
          {"pinned_seconds", d.pinned_seconds},
          {"bytes_downloaded", d.bytes_downloaded},
          {"overlap_seconds", d.overlap_seconds}};
}

inline nlohmann::json to_json(const CacheStatistics& s) {
  return {{"unit_bytes", s.unit_bytes},
          {"bricks_per_step", s.units_per_step},
          {"hits", s.hits},
          {"late_prefetches", s.late_prefetches},
          {"misses", s.misses},
          {"prefetches", s.prefetches},
          {"evictions", s.evictions},
          {"loads", s.loads},
          {"bytes_read", s.bytes_read},
          {"bytes_decoded", s.bytes_decoded},
          {"read_seconds", s.read_seconds},
          {"decode_seconds", s.decode_seconds},
          {"wait_seconds", s.wait_seconds},
          {"peak_bytes", s.peak_bytes},
          {"peak_resident_units", s.peak_resident_units},
          {"units_touched", s.units_touched},
          {"units_used", s.units_used},
          {"max_reads_of_a_unit", s.max_reads_of_a_unit},
          {"bytes_needed", s.bytes_needed},
          {"read_amplification", s.read_amplification()},
          {"units_read_per_step", s.units_read_per_step}};
}

/// What a written path surface's positions are: "x, y, c t" for a 2D flow (flat: "x, y, 0
/// (flat)", the surface pressed into the plane), "x, y, z" for a 3D one.
inline const char* path_positions(const PathSurfaceResult& result, bool flat) {
  if (result.spacetime_positions.empty()) return "x, y, z";
  return flat ? "x, y, 0 (flat)" : "x, y, c t";
}

/// A 2D flow's path surface as it is written: in (x, y, c t), c = the report's time scale, where
/// it is the surface the engine built (its angles, no folds; --time-scale 1 gives (x, y, t));
/// flat: (x, y, 0). The vertex attribute `time` is t either way. 3D flows: unchanged.
inline void place_for_output(PathSurfaceResult& result, bool flat) {
  if (flat || result.spacetime_positions.empty()) return;
  result.mesh.positions.assign(result.spacetime_positions.begin(),
                               result.spacetime_positions.end());
  for (auto& p : result.mesh.positions) p.z() *= result.path.time_scale;
}

inline nlohmann::json to_json(const PathReport& r) {
  nlohmann::json band = nlohmann::json::array();
  double widest = 0;
  for (const BandRecord& b : r.band) {
    widest = std::max(widest, b.t_max - b.t_min);
    band.push_back({{"step", b.step},
                    {"t_min", b.t_min},
                    {"t_max", b.t_max},
                    {"vertex_t_min", b.vertex_t_min},
                    {"vertex_t_max", b.vertex_t_max},
                    {"first_time_step", b.first_step},
                    {"last_time_step", b.last_step},
                    {"pinned_units", b.pinned_units}});
  }
  nlohmann::json j = {{"time_scale", r.time_scale},
                      {"time_scale_source", r.time_scale_source},
                      {"t0", r.t0},
                      {"t1", r.t1},
                      {"time_reached", r.time_reached},
                      {"dimension", r.dimension},
                      {"streamed", r.streamed},
                      {"complete", r.complete},
                      {"message", r.message},
                      {"widest_band", widest},
                      {"band", band},
                      {"seconds",
                       {{"total", r.total_seconds},
                        {"compute", r.compute_seconds},
                        {"wait", r.wait_seconds},
                        {"io", r.io_seconds},
                        {"decode", r.decode_seconds}}}};
  if (r.streamed) {
    j["cache"] = to_json(r.cache);
    j["slow_evaluations"] = r.slow_evaluations;
  }
  if (!r.device.empty())
    j["device"] = device_json(r.device, r.device_min_vertices, r.device_calls, r.device_statistics);
  return j;
}

}  // namespace orthofront::spacetime
