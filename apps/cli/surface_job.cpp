#include "cli/surface_job.h"

#include <cstdio>

#include "cli/progress_bar.h"
#include "jobs/seed_spec.h"
#include "orthofront/io/open_field.h"

namespace orthofront::cli {

using namespace jobs;

SurfaceResult run_surface(SurfaceJob& job, bool show_progress, DeviceUse* used) {
  const auto field = io::open_field(job.field);
  const SeedCurve curve = parse_seed(job.seed);
  const Seed<3> seed = prepare_stream_seed(*field, curve, job);
  std::fputs(vertex_cap_warning(curve.length(), field->domain().extent(), job.options).c_str(),
             stderr);
  // SIGINT/SIGTERM also stop a step's long integrations, not only the next step.
  const StopRequest stop = [] { return interrupted(); };
  if (!show_progress) return run_stream_job(*field, seed, job, {}, stop, used);
  ProgressBar bar(job.field, job.options.max_vertices);
  return run_stream_job(*field, seed, job, [&](const Progress& p) { return bar.update(p); }, stop,
                        used);
}

std::string summarize(const SurfaceJob& job, const SurfaceReport& r) {
  const QualityReport& q = r.quality;
  char text[1024];
  std::snprintf(text, sizeof text,
                "%s surface of %s from %s: %zu vertices, %zu faces (%.1f%% quads), %d steps, "
                "stopped: %s%s. Quality: %.1f%% of quad angles within 90±10°, edge spread "
                "(median |1-l/l_avg|) %.3f, %zu folds, %zu non-manifold edges, %zu T-junctions, "
                "%zu degenerate faces; %zu rips. Time %.3f s (alpha %.3f, advance %.3f, adapt "
                "%.3f, stitch %.3f).",
                to_string(job.options.method), job.field.c_str(), job.seed.c_str(), r.vertices,
                r.faces, 100.0 * q.quad_share, r.steps, to_string(r.stop_reason),
                r.complete ? "" : " (incomplete)", 100.0 * q.quad_angles_within_10,
                q.edge_spread_median, q.folds, q.non_manifold_edges, q.t_junctions,
                q.degenerate_faces, r.rips, r.times.total, r.times.alpha, r.times.advance,
                r.times.adapt, r.times.stitch);
  std::string out = text;
  if (!r.message.empty()) out += " Note: " + r.message + ".";
  return out;
}

}  // namespace orthofront::cli
