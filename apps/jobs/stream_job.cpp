#include "jobs/stream_job.h"

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "jobs/edge_default.h"
#include "jobs/path_job.h"
#include "orthofront/io/report_json.h"
#include "orthofront/spacetime/path_command_json.h"
#include "orthofront/advect/steady_front_integrator.h"
#include "orthofront/error.h"
#include "orthofront/field/grid_field.h"
#include "orthofront/seed/seed_check.h"
#include "orthofront/spacetime/brick_cache.h"

namespace orthofront::jobs {

void add_stream_options(OptionSet& set, SurfaceJob& job, MemoryLimits& limits) {
  set.integer("seed-count", job.seed_count, "Vertices on the seed curve");
  add_engine_options(set, job.options);
  add_memory_option(set, limits);
  set.text("device", job.device,
           "Gridded fields: advance the front by bulk advection on cpu or cuda; auto: cuda for "
           "fronts of at least " +
               std::to_string(advect::kCudaSteadyFrontBreakEven) +
               " vertices where a device is present. Default: per vertex")
      .one_of({"cpu", "cuda", "auto"})
      .group(OptionGroup::performance)
      .derived_default();
  set.count("device-min-vertices", job.device_min_vertices,
            "With --device: smaller fronts advance per vertex (0: every front for cpu and cuda, "
            "the break-even size for auto)")
      .group(OptionGroup::performance);
  set.text("device-memory", job.device_memory,
           "With --device cuda/auto: what the device may hold of the grid (default: half its "
           "free memory)")
      .group(OptionGroup::performance)
      .derived_default();
}

namespace {

// Fronts smaller than this advance per vertex under a device (auto: the break-even size).
std::size_t device_min_vertices(const SurfaceJob& job) {
  if (job.device_min_vertices > 0 || job.device != "auto") return job.device_min_vertices;
  return advect::kCudaSteadyFrontBreakEven;
}

// The front advance through the bulk backend, for a gridded field.
std::unique_ptr<advect::SteadyFrontIntegrator> bulk_advance(const SurfaceJob& job,
                                                            const Field3& field) {
  if (job.device.empty()) return nullptr;
  const auto* grid = dynamic_cast<const GridField*>(&field);
  if (!grid)
    throw InvalidArgument("--device: bulk advection moves particles through a grid; '" +
                          job.field + "' is not a gridded field");
  const advect::Device device = advect::parse_device(job.device);
  const std::size_t bytes =
      job.device_memory.empty() ? 0 : spacetime::parse_bytes(job.device_memory);
  advect::SteadyBackendFactory factory;
  if (device == advect::Device::auto_select) {
    // CUDA starts (and is looked for) only when a front reaches the break-even size.
    factory = [bytes]() -> std::shared_ptr<advect::BatchAdvector> {
      if (!advect::cuda_available()) return nullptr;
      return advect::make_advector(advect::Device::cuda, bytes);
    };
  } else {
    std::shared_ptr<advect::BatchAdvector> backend = advect::make_advector(device, bytes);
    factory = [backend] { return backend; };
  }
  return std::make_unique<advect::SteadyFrontIntegrator>(
      *grid, factory, advect::front_method(job.options), device_min_vertices(job));
}

}  // namespace

Seed<3> prepare_stream_seed(const Field3& field, const SeedCurve& curve, SurfaceJob& job) {
  const auto* grid = dynamic_cast<const GridField*>(&field);
  const EdgeChoice edge =
      choose_edge(job.options.edge, job.edge_given, grid ? &grid->grid().geometry : nullptr);
  job.options.edge = edge.edge;
  job.edge_source = edge.source;
  check_seed_count(job.seed_count, job.options.max_vertices);
  const Seed<3> seed = make_seed(curve, job.seed_count);
  check_stream_seed(field, seed, job);
  return seed;
}

SurfaceResult run_stream_job(const Field3& field, const Seed<3>& seed, const SurfaceJob& job,
                             const ProgressCallback& progress, const StopRequest& stop,
                             DeviceUse* used) {
  const std::unique_ptr<advect::SteadyFrontIntegrator> bulk = bulk_advance(job, field);
  SurfaceResult result = build_stream_surface(field, seed, job.options, progress, {}, stop,
                                              bulk.get());
  if (bulk && used) {
    used->min_vertices = device_min_vertices(job);
    used->backend = bulk->backend_name();
    if (used->backend.empty())
      used->backend = "none (auto: no front reached " + std::to_string(used->min_vertices) +
                      " vertices, or no CUDA device)";
    used->calls = bulk->calls();
    used->statistics = bulk->statistics();
  }
  return result;
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

nlohmann::json stream_report(const SurfaceReport& report, const SurfaceJob& job,
                             const MemoryLimits& limits, const DeviceUse& device) {
  nlohmann::json out = io::to_json(report);
  out["field"] = job.field;
  out["seed"] = job.seed;
  out["seed_count"] = job.seed_count;
  add_edge_keys(out, {job.options.edge, job.edge_source});
  out["limits"] = limits.to_json();
  if (!device.backend.empty())
    out["device"] = spacetime::device_json(device.backend, device.min_vertices, device.calls,
                                           device.statistics);
  return out;
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
