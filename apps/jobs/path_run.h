#pragma once
/// A path surface run from parsed options, as the front ends that hold the surface in memory
/// (Python, ParaView) make it: the times resolved against the series, ℓ from the grid unless
/// given, the cache, the positions placed for output, and the report.
#include <functional>
#include <nlohmann/json.hpp>

#include "jobs/path_job.h"
#include "orthofront/field/unsteady.h"
#include "orthofront/io/time_series.h"
#include "orthofront/mesh/mesh.h"
#include "orthofront/seed/seed_curve.h"
#include "orthofront/spacetime/path_surface.h"

namespace orthofront::jobs {

struct PathRun {
  spacetime::PathSurfaceResult result;  ///< the mesh placed for output (args.flat: flat)
  Mesh lifted;                          ///< 2D flows: positions (x, y, c·t); empty in 3D
  nlohmann::json report;                ///< as `path --report` writes it
};

/// Builds the path surface of `seed` through `series` or, where it is null, `analytic`.
/// `args` holds the parsed options (after apply_memory_limits), `edge_given` whether ℓ was
/// given; `keep_going` is asked between steps (false: stop, the report says incomplete).
/// Throws InvalidArgument for times or options the series refuses.
PathRun run_path_surface(const io::TimeSeries* series, const UnsteadyField* analytic,
                         const SeedCurve& seed, PathArgs& args, bool edge_given,
                         const std::function<bool()>& keep_going);

}  // namespace orthofront::jobs
