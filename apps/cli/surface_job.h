#pragma once
/// A stream-surface job run from the command line (a file field, a progress bar), and its
/// summary text.
#include <cstddef>
#include <string>

#include "jobs/stream_job.h"
#include "orthofront/engine/stream_surface.h"
#include "orthofront/field/field.h"
#include "orthofront/seed/seed.h"

namespace orthofront::cli {

/// Opens the field, builds the seed and runs the engine (with a progress bar when asked).
/// Throws InvalidArgument for a bad field, seed, or a seed outside the domain.
/// With job.device: gridded fields only (InvalidArgument otherwise); `used` gets what it did.
/// Without job.edge_given, sets job.options.edge (and job.edge_source) from the field's grid.
SurfaceResult run_surface(jobs::SurfaceJob& job, bool show_progress,
                          jobs::DeviceUse* used = nullptr);

/// One paragraph: counts, quality, time, stop reason.
std::string summarize(const jobs::SurfaceJob& job, const SurfaceReport& report);

}  // namespace orthofront::cli
