#include "jobs/stream_job.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "orthofront/seed/seed_check.h"

namespace orthofront::jobs {

void add_stream_options(OptionSet& set, SurfaceJob& job, MemoryLimits& limits) {
  set.integer("seed-count", job.seed_count, "Vertices on the seed curve");
  add_engine_options(set, job.options);
  add_memory_option(set, limits);
}

void check_stream_seed(const Field3& field, const Seed<3>& seed, const SurfaceJob& job) {
  SeedSurvey survey;
  for (double s : seed.parameters) {
    Vec3 v = Vec3::Zero();
    const Vec3 x = seed.point(s);
    survey.add(x, field.velocity(x, v), v);
  }
  SeedContext context;
  context.seed = "seed '" + job.seed + "'";
  context.field = "field '" + job.field + "'";
  context.domain = describe_box(field.domain(), 3);
  context.about = field.describe();
  require_seed_inside(survey, context, true);
}

std::string vertex_cap_warning(double seed_length, const Vec3& domain_extent,
                               const StreamSurfaceOptions& options) {
  // Each step adds about a row of seed_length / ℓ vertices (more where the flow spreads): a run
  // whose rows alone would pass the cap ends there, after a fraction of its steps.
  const double per_row = seed_length / options.edge + 1;
  const double rows = per_row * options.max_steps;
  if (!(rows > static_cast<double>(options.max_vertices))) return {};
  // Analytic fields may have no bounds worth the name: then the seed's length sets the scale.
  const double diagonal = domain_extent.norm();
  const bool bounded = std::isfinite(diagonal) && diagonal < 1e3 * seed_length;
  char text[640];
  std::snprintf(text, sizeof text,
                "orthofront: warning: the seed is %.4g long: at --edge %g each front has about "
                "%.0f vertices, and %d steps would make about %.3g, past the vertex cap of %zu; "
                "the run will stop at the cap (an edge of about %.3g, %s, suits most data; see "
                "docs/user-guide.md, Choosing the edge length)\n",
                seed_length, options.edge, per_row, options.max_steps, rows,
                options.max_vertices, bounded ? diagonal / 300 : seed_length / 100,
                bounded ? "the domain's diagonal over 300" : "the seed's length over 100");
  return text;
}

}  // namespace orthofront::jobs
