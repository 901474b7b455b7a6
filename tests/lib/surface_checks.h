#pragma once
/// Checks every engine test makes of a finished surface: a valid mesh.
#include <catch2/catch.hpp>

#include "orthofront/engine/stream_surface.h"

namespace orthofront::test_support {

/// No non-manifold or inconsistent edges, no degenerate faces, T-junctions or folds, finite
/// positions.
inline void require_valid(const SurfaceResult& r) {
  const QualityReport& q = r.report.quality;
  CHECK(q.non_manifold_edges == 0);
  CHECK(q.degenerate_faces == 0);
  CHECK(q.t_junctions == 0);
  CHECK(q.folds == 0);
  CHECK(q.inconsistent_edges == 0);
  for (const Vec3& p : r.mesh.positions) REQUIRE(p.allFinite());
}

}  // namespace orthofront::test_support
