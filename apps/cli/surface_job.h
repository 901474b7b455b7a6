#pragma once
/// One stream-surface job as the command line describes it, and its summary text.
#include <cstddef>
#include <string>

#include "orthofront/advect/batch_advector.h"
#include "orthofront/engine/stream_surface.h"
#include "orthofront/field/field.h"
#include "orthofront/seed/seed.h"

namespace orthofront::cli {

struct SurfaceJob {
  std::string field;          ///< --field spec
  std::string seed;           ///< --seed spec
  int seed_count = 20;
  StreamSurfaceOptions options;
  std::string device;         ///< --device: empty (per vertex), cpu, cuda or auto
  std::size_t device_min_vertices = 0;  ///< 0: every front (cpu, cuda), the break-even (auto)
  std::string device_memory;  ///< empty: half the device's free memory
  /// false: ℓ (options.edge) is the grid's cell size where the field is a grid; run_surface
  /// sets it and edge_source.
  bool edge_given = true;
  std::string edge_source = "--edge";
};

/// What the bulk front advance did (--device).
struct DeviceUse {
  std::string backend;        ///< empty: no --device; "none (...)": auto found nothing to do
  std::size_t min_vertices = 0, calls = 0;
  advect::AdvectionStatistics statistics;
};

/// Refuses a seed with fewer than 2 vertices inside `field`'s domain with data, or one where the
/// flow stands still at every vertex (InvalidArgument naming job.seed and job.field).
void check_stream_seed(const Field3& field, const Seed<3>& seed, const SurfaceJob& job);

/// A warning (empty when none) for a run whose rows alone, about seed_length / ℓ vertices a
/// step, would pass options.max_vertices before options.max_steps: it names the seed's length,
/// the edge, the estimate and the cap, and suggests an edge from the domain's extent.
std::string vertex_cap_warning(double seed_length, const Vec3& domain_extent,
                               const StreamSurfaceOptions& options);

/// Opens the field, builds the seed and runs the engine (with a progress bar when asked).
/// Throws InvalidArgument for a bad field, seed, or a seed outside the domain.
/// With job.device: gridded fields only (InvalidArgument otherwise); `used` gets what it did.
/// Without job.edge_given, sets job.options.edge (and job.edge_source) from the field's grid.
SurfaceResult run_surface(SurfaceJob& job, bool show_progress, DeviceUse* used = nullptr);

/// One paragraph: counts, quality, time, stop reason.
std::string summarize(const SurfaceJob& job, const SurfaceReport& report);

}  // namespace orthofront::cli
