#include "cli/surface_job.h"

#include <cmath>
#include <cstdio>
#include <memory>

#include "orthofront/io/open_field.h"
#include "jobs/edge_default.h"
#include "cli/progress_bar.h"
#include "jobs/seed_spec.h"
#include "orthofront/advect/steady_front_integrator.h"
#include "orthofront/error.h"
#include "orthofront/field/grid_field.h"
#include "orthofront/seed/seed_check.h"
#include "orthofront/spacetime/brick_cache.h"

namespace orthofront::cli {

using namespace jobs;


namespace {

// Fronts smaller than this advance per vertex under --device (auto: the break-even size).
std::size_t device_min_vertices(const SurfaceJob& job) {
  if (job.device_min_vertices > 0 || job.device != "auto") return job.device_min_vertices;
  return advect::kCudaSteadyFrontBreakEven;
}

// The front advance through the bulk backend (--device), for a gridded field.
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

SurfaceResult run_surface(SurfaceJob& job, bool show_progress, DeviceUse* used) {
  const auto field = io::open_field(job.field);
  const auto* grid = dynamic_cast<const GridField*>(field.get());
  const EdgeChoice edge =
      choose_edge(job.options.edge, job.edge_given, grid ? &grid->grid().geometry : nullptr);
  job.options.edge = edge.edge;
  job.edge_source = edge.source;
  const SeedCurve curve = parse_seed(job.seed);
  if (job.seed_count < 2)
    throw InvalidArgument("--seed-count must be at least 2, got " + std::to_string(job.seed_count));
  if (static_cast<std::size_t>(job.seed_count) > job.options.max_vertices)
    throw InvalidArgument("--seed-count " + std::to_string(job.seed_count) +
                          " exceeds the vertex budget of " + std::to_string(job.options.max_vertices) +
                          " (--max-vertices, or half of --memory at ~300 B a vertex)");
  const Seed<3> seed = make_seed(curve, job.seed_count);
  check_stream_seed(*field, seed, job);
  std::fputs(vertex_cap_warning(curve.length(), field->domain().extent(), job.options).c_str(),
             stderr);
  // SIGINT/SIGTERM also stop a step's long integrations, not only the next step.
  const StopRequest stop = [] { return interrupted(); };
  const std::unique_ptr<advect::SteadyFrontIntegrator> bulk = bulk_advance(job, *field);
  SurfaceResult result;
  if (!show_progress) {
    result = build_stream_surface(*field, seed, job.options, {}, {}, stop, bulk.get());
  } else {
    ProgressBar bar(job.field, job.options.max_vertices);
    result = build_stream_surface(*field, seed, job.options,
                                  [&](const Progress& p) { return bar.update(p); }, {}, stop,
                                  bulk.get());
  }
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
