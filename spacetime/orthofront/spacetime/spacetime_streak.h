#pragma once
/// The flow-orthogonal route to streak surfaces (paper, Section 8), for 2D flows: the streak
/// lines of a seed point x0 at every observation time t form one surface in (x, y, t), the
/// space-time streak surface (the paper's STREAKCYLINDER). Every point of it is (φ_τ^t(x0), t)
/// for a release time τ <= t, so it is swept by the path lines that leave x0: it is the stream
/// surface of the lifted field (v, c) over (x, y, c t) from the release segment {x0} × [T0, T1],
/// built here by the flow-orthogonal engine. Its slice at t = t_f is the streak line at t_f.
/// (The streak surface of a seed curve at one time, as a stream surface of Weinkauf & Theisel's
/// streak-line field: streak_line_field.h.)
#include <algorithm>
#include <vector>

#include "orthofront/engine/stream_surface.h"
#include "orthofront/field/unsteady.h"

namespace orthofront::spacetime {

struct SpacetimeStreakOptions {
  StreamSurfaceOptions engine;     ///< edge ℓ (in (x, y, c t)), max_steps, ...
  double release_begin = 0, release_end = 1;  ///< release interval at x0
  double t_end = 2;                ///< last observation time: the surface stops there
  double time_scale = 0;           ///< c; 0: the speed |v(x0, t)| averaged over the release
  int seed_count = 20;             ///< vertices on the release segment
};

struct SpacetimeStreakResult {
  Mesh mesh;                       ///< positions (x, y, t); `time` = t, `s` = release parameter
  SurfaceReport report;
  double time_scale = 0;
};

/// Release time of a mesh vertex with seed parameter s (the release segment ends at
/// min(release_end, t_end)).
inline double release_time(const SpacetimeStreakOptions& o, double s) {
  return o.release_begin + s * (std::min(o.release_end, o.t_end) - o.release_begin);
}

/// Throws InvalidArgument for a flow that is not 2D, bad times, or a seed point outside the
/// domain or where the flow is zero.
SpacetimeStreakResult build_spacetime_streak_surface(const UnsteadyField& flow, const Vec3& x0,
                                                     const SpacetimeStreakOptions& options);

/// Points where the mesh's edges cross the plane t = t_f (x, y, t_f): the streak line at t_f as
/// the space-time surface gives it.
std::vector<Vec3> slice_at_time(const Mesh& mesh, double t_f);

}  // namespace orthofront::spacetime
