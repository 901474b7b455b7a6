#pragma once
/// The remeshed streak surface: particles released from the seed curve in rows, joined into a
/// triangle mesh whose vertices keep their release labels (s, τ). After every release interval
/// the mesh adapts locally: an edge longer than split·ℓ gets a particle at its label midpoint
/// (released there and moved through the flow map, or, with interpolated insertion, placed at
/// the edge's midpoint one interval before and moved from there), an edge shorter than
/// collapse·ℓ is collapsed onto one of its ends (which keeps its exact label), and edges are
/// flipped to the Delaunay criterion. Stretching then adds vertices where the surface grows and
/// compression removes them where it shrinks: the vertex count follows the surface's area and
/// boundary. Faces of particles that stop (left the domain, no data) are removed.
#include "orthofront/seed/seed_curve.h"
#include "orthofront/spacetime/streak_flow_access.h"
#include "orthofront/spacetime/streak_surface.h"

namespace orthofront::spacetime {

/// Builds the frames of `options` (mesh = remeshed) and hands each to `sink` in order, from
/// the calling thread. Throws what check_streak_options throws, and InvalidArgument for a seed
/// with no particle inside the domain or a flow at rest on it.
StreakReport build_remeshed_streak(const StreakFlowAccess& access, const SeedCurve& seed,
                                   const StreakOptions& options, const StreakFrameSink& sink);

}  // namespace orthofront::spacetime
