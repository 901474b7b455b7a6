#include "cli/surface_job.h"

#include <cstdio>

#include "orthofront/io/open_field.h"
#include "cli/progress_bar.h"
#include "cli/seed_spec.h"
#include "orthofront/error.h"

namespace orthofront::cli {

void check_stream_seed(const Field3& field_ref, const Seed<3>& seed, const SurfaceJob& job) {
  const Field3* field = &field_ref;
  std::size_t inside = 0, no_data = 0, outside = 0, still = 0;
  Vec3 first_outside = Vec3::Zero(), first_no_data = Vec3::Zero(), first_still = Vec3::Zero();
  for (double s : seed.parameters) {
    Vec3 v;
    const Vec3 x = seed.point(s);
    const FieldStatus status = field->velocity(x, v);
    if (status == FieldStatus::inside) {
      ++inside;
      if (v.squaredNorm() == 0 && still++ == 0) first_still = x;
    } else if (status == FieldStatus::no_data) {
      if (no_data++ == 0) first_no_data = x;
    } else if (outside++ == 0) {
      first_outside = x;
    }
  }
  const auto point = [](const Vec3& x) {
    char text[128];
    std::snprintf(text, sizeof text, "(%g, %g, %g)", x.x(), x.y(), x.z());
    return std::string(text);
  };
  const std::string vertices_inside = std::to_string(inside) + " of " +
                                      std::to_string(seed.parameters.size()) + " seed vertices";
  if (inside < 2) {
    // Inside the domain but without data (NaN, fill values, zero vectors) is not "outside".
    if (no_data > 0 && no_data + inside == seed.parameters.size())
      throw InvalidArgument("seed '" + job.seed + "' lies where field '" + job.field +
                            "' has no data (NaN, fill values or zero vectors; e.g. at the point " +
                            point(first_no_data) + "; " + field->describe() + ")");
    throw InvalidArgument("seed '" + job.seed + "' lies outside the domain of field '" +
                          job.field + "' (" + vertices_inside + " inside, at least 2 needed; " +
                          "e.g. the point " + point(first_outside) + " is outside; " +
                          field->describe() + ")");
  }
  // A flow that stands still along the whole seed moves no front: nothing to build.
  if (still == inside)
    throw InvalidArgument("field '" + job.field + "' has zero velocity at every vertex of seed '" +
                          job.seed + "' inside its domain (" + vertices_inside +
                          " inside; e.g. at the point " + point(first_still) +
                          "): no flow to build a surface from");
}

SurfaceResult run_surface(const SurfaceJob& job, bool show_progress) {
  const auto field = io::open_field(job.field);
  const SeedCurve curve = parse_seed(job.seed);
  if (job.seed_count < 2)
    throw InvalidArgument("--seed-count must be at least 2, got " + std::to_string(job.seed_count));
  if (static_cast<std::size_t>(job.seed_count) > job.options.max_vertices)
    throw InvalidArgument("--seed-count " + std::to_string(job.seed_count) +
                          " exceeds the vertex budget of " + std::to_string(job.options.max_vertices) +
                          " (--max-vertices, or half of --memory at ~300 B a vertex)");
  const Seed<3> seed = make_seed(curve, job.seed_count);
  check_stream_seed(*field, seed, job);
  // SIGINT/SIGTERM also stop a step's long integrations, not only the next step.
  const StopRequest stop = [] { return interrupted(); };
  if (!show_progress) return build_stream_surface(*field, seed, job.options, {}, {}, stop);
  ProgressBar bar(job.field, job.options.max_vertices);
  return build_stream_surface(*field, seed, job.options,
                              [&](const Progress& p) { return bar.update(p); }, {}, stop);
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
