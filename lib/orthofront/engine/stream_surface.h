#pragma once
/// The advancing-front stream-surface engine: α solve → rip → advance → adapt → stitch.
#include <functional>
#include <span>
#include <vector>

#include "orthofront/engine/front_integrator.h"
#include "orthofront/engine/options.h"
#include "orthofront/engine/report.h"
#include "orthofront/field/field.h"
#include "orthofront/integrate/runge_kutta.h"
#include "orthofront/mesh/mesh.h"
#include "orthofront/seed/seed.h"

namespace orthofront {

struct Progress {
  int step = 0, max_steps = 0;
  std::size_t vertices = 0, fronts = 0, front_vertices = 0;
  double elapsed_seconds = 0;
};
/// Called once per front step; return false to stop (the mesh built so far is returned).
using ProgressCallback = std::function<bool(const Progress&)>;

/// The front before a step: every front vertex's position, N coordinates each. A data cache uses
/// it to hold what the step will sample; return false to stop (the mesh built so far is kept).
struct FrontSnapshot {
  int step = 0;  ///< the step about to run (1 for the first)
  int dimension = 3;
  std::span<const double> positions;
};
using FrontHook = std::function<bool(const FrontSnapshot&)>;

struct SurfaceResult {
  Mesh mesh;
  SurfaceReport report;
};

/// Builds the stream surface of `field` from `seed`.
/// The mesh holds 3D positions (the first three coordinates when N = 4).
/// Throws InvalidArgument for unusable options or a seed with fewer than two vertices inside
/// the domain. `stop` (thread-safe) is asked inside long stream-line integrations too, so a
/// DOPRI5 crawling towards its evaluation cap does not hold up a cancel; the surface then ends
/// where its fronts got to (stop reason cancelled, report incomplete). `front_integrator` (not
/// owned; may be null): advances fronts in bulk (SurfaceBuilder::set_front_integrator).
template <int N>
SurfaceResult build_stream_surface(const Field<N>& field, const Seed<N>& seed,
                                   const StreamSurfaceOptions& options,
                                   const ProgressCallback& progress = {},
                                   const FrontHook& before_step = {},
                                   const StopRequest& stop = {},
                                   FrontIntegrator<N>* front_integrator = nullptr);

extern template SurfaceResult build_stream_surface<3>(const Field<3>&, const Seed<3>&,
                                                      const StreamSurfaceOptions&,
                                                      const ProgressCallback&, const FrontHook&,
                                                      const StopRequest&, FrontIntegrator<3>*);
extern template SurfaceResult build_stream_surface<4>(const Field<4>&, const Seed<4>&,
                                                      const StreamSurfaceOptions&,
                                                      const ProgressCallback&, const FrontHook&,
                                                      const StopRequest&, FrontIntegrator<4>*);

}  // namespace orthofront
