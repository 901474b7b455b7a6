#pragma once
/// Checks engine tests make of finished surfaces: a valid mesh, and two runs that must agree
/// bit for bit.
#include <tbb/task_arena.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstring>
#include <vector>

#include "orthofront/engine/stream_surface.h"
#include "orthofront/field/analytic.h"
#include "orthofront/seed/seed.h"
#include "orthofront/seed/seed_curve.h"

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

/// A surface to build: an analytic field by name, a seed curve, ℓ and the steps.
struct SurfaceCase {
  const char* field;
  SeedCurve seed;
  double edge;
  int steps;
};

/// Work ahead (seed-shot legs, front samples) on and off: the surface of `c` with 20 seeds built
/// with `o` as given and again with `o.*ahead` false, both in an arena of two threads (so an idle
/// thread exists).
struct BuiltWithAndWithout {
  SurfaceResult ahead, in_place;
};
inline BuiltWithAndWithout built_with_and_without(const SurfaceCase& c, StreamSurfaceOptions o,
                                                  bool StreamSurfaceOptions::*ahead) {
  const auto field = make_analytic_field(c.field);
  o.edge = c.edge;
  o.max_steps = c.steps;
  BuiltWithAndWithout out;
  tbb::task_arena arena(2);
  arena.execute([&] {
    out.ahead = build_stream_surface<3>(*field, make_seed(c.seed, 20), o);
    o.*ahead = false;
    out.in_place = build_stream_surface<3>(*field, make_seed(c.seed, 20), o);
  });
  return out;
}

template <typename T, typename A>
bool same_bits(const std::vector<T, A>& a, const std::vector<T, A>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

/// Index of the first vertex whose position differs in any bit (the count when none does).
inline std::size_t first_moved_vertex(const Mesh& a, const Mesh& b) {
  const std::size_t n = std::min(a.vertex_count(), b.vertex_count());
  for (std::size_t i = 0; i < n; ++i)
    if (std::memcmp(a.positions[i].data(), b.positions[i].data(), sizeof(Vec3)) != 0) return i;
  return n;
}

/// The same mesh, bit for bit, with every attribute, from runs that stopped alike.
inline void check_identical(const SurfaceResult& first, const SurfaceResult& second) {
  const Mesh& a = first.mesh;
  const Mesh& b = second.mesh;
  REQUIRE(a.vertex_count() == b.vertex_count());
  CHECK(first_moved_vertex(a, b) == a.vertex_count());
  CHECK(a.faces == b.faces);
  CHECK(same_bits(a.time, b.time));
  CHECK(same_bits(a.alpha, b.alpha));
  CHECK(same_bits(a.s, b.s));
  CHECK(same_bits(a.error, b.error));
  CHECK(a.front_id == b.front_id);
  CHECK(a.step == b.step);
  CHECK(first.report.steps == second.report.steps);
  CHECK(first.report.stop_reason == second.report.stop_reason);
}

}  // namespace orthofront::test_support
