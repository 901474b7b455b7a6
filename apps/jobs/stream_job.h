#pragma once
/// One stream-surface job: its options, as every front end takes them, and the checks of its
/// seed.
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>

#include "jobs/engine_options.h"
#include "jobs/option_set.h"
#include "orthofront/advect/batch_advector.h"
#include "orthofront/engine/stream_surface.h"
#include "orthofront/field/field.h"
#include "orthofront/seed/seed.h"
#include "orthofront/seed/seed_curve.h"

namespace orthofront::jobs {

struct SurfaceJob {
  std::string field;          ///< field spec
  std::string seed;           ///< seed spec
  int seed_count = 20;
  StreamSurfaceOptions options;
  std::string device;         ///< device: empty (per vertex), cpu, cuda or auto
  std::size_t device_min_vertices = 0;  ///< 0: every front (cpu, cuda), the break-even (auto)
  std::string device_memory;  ///< empty: half the device's free memory
  /// false: ℓ (options.edge) is the grid's cell size where the field is a grid; the runner
  /// sets it and edge_source.
  bool edge_given = true;
  std::string edge_source = "--edge";
};

/// Adds the seed count, the engine's options, the memory and the device.
void add_stream_options(OptionSet& set, SurfaceJob& job, MemoryLimits& limits);

/// What the bulk front advance did (device).
struct DeviceUse {
  std::string backend;        ///< empty: no device; "none (...)": auto found nothing to do
  std::size_t min_vertices = 0, calls = 0;
  advect::AdvectionStatistics statistics;
};

/// Refuses a seed with fewer than 2 vertices inside `field`'s domain with data, or one where the
/// flow stands still at every vertex (InvalidArgument naming job.seed and job.field).
void check_stream_seed(const Field3& field, const Seed<3>& seed, const SurfaceJob& job);

/// The seed of `job` on `field`: sets ℓ from the field's grid unless job.edge_given (and
/// job.edge_source), checks the seed count against the vertex cap and the seed against the
/// domain (InvalidArgument naming them).
Seed<3> prepare_stream_seed(const Field3& field, const SeedCurve& curve, SurfaceJob& job);

/// Builds the surface from a prepared seed, the front advanced by bulk advection on job.device
/// where one is named (gridded fields only: InvalidArgument otherwise); `used` gets what it did.
SurfaceResult run_stream_job(const Field3& field, const Seed<3>& seed, const SurfaceJob& job,
                             const ProgressCallback& progress, const StopRequest& stop,
                             DeviceUse* used);

/// The report of a run as every front end writes it: the engine's report with the field, the
/// seed and its count, ℓ and where it came from, the memory limits and, where `device` ran the
/// fronts, what it did.
nlohmann::json stream_report(const SurfaceReport& report, const SurfaceJob& job,
                             const MemoryLimits& limits, const DeviceUse& device);

/// A warning (empty when none) for a run whose rows alone, about seed_length / ℓ vertices a
/// step, would pass options.max_vertices before options.max_steps: it names the seed's length,
/// the edge, the estimate and the cap, and suggests an edge from the domain's extent.
std::string vertex_cap_warning(double seed_length, const Vec3& domain_extent,
                               const StreamSurfaceOptions& options);

}  // namespace orthofront::jobs
