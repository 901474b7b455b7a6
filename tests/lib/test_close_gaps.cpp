// Closing a gap: two strips of quads running side by side with a thin gap between them (as the
// halves of a surface torn at an obstacle), zipped together into one manifold sheet.
#include <catch2/catch.hpp>
#include <cmath>
#include <functional>

#include "orthofront/mesh/close_gaps.h"
#include "orthofront/quality/quality.h"

using namespace orthofront;

namespace {

/// A strip of n quads along x from y0 to y1 (vertices at x = 0 .. n), normal +z.
void add_strip(Mesh& m, int n, double y0, double y1, const std::function<double(double)>& z) {
  const auto base = static_cast<std::int32_t>(m.vertex_count());
  for (int i = 0; i <= n; ++i) {
    m.add_vertex(Vec3(i, y0, z(i)), 0, 0, 0, 0, 0, 0);
    m.add_vertex(Vec3(i, y1, z(i)), 0, 0, 0, 0, 0, 0);
  }
  for (int i = 0; i < n; ++i) {
    const std::int32_t a = base + 2 * i;
    m.add_quad(a, a + 2, a + 3, a + 1);
  }
}

}  // namespace

TEST_CASE("two strips side by side are zipped into one sheet", "[mesh][gaps]") {
  Mesh m;
  const auto flat = [](double) { return 0.0; };
  add_strip(m, 20, -3, -0.2, flat);
  add_strip(m, 20, 0.2, 3, flat);
  const QualityReport before = measure_quality(m);
  REQUIRE(before.boundary_edges == 4 * 20 + 4);

  const GapReport g = close_gaps(m, 0.5, 2.0);
  CHECK(g.stretches == 1);
  CHECK(g.refused == 0);
  const QualityReport after = measure_quality(m);
  // Every pair of vertices across the gap is joined, the strips' corners included.
  CHECK(g.faces == 20);
  CHECK(after.quads == before.quads + 20);
  CHECK(after.boundary_edges == before.boundary_edges - 40 + 2);
  CHECK(after.non_manifold_edges == 0);
  CHECK(after.inconsistent_edges == 0);
  CHECK(after.folds == 0);
  CHECK(after.t_junctions == 0);
  CHECK(after.degenerate_faces == 0);
}

TEST_CASE("a gap wider than the distance stays open, so does one whose faces would fold",
          "[mesh][gaps]") {
  const auto flat = [](double) { return 0.0; };
  SECTION("too wide") {
    Mesh m;
    add_strip(m, 20, -3, -0.5, flat);
    add_strip(m, 20, 0.5, 3, flat);
    const GapReport g = close_gaps(m, 0.5, 2.0);
    CHECK(g.faces == 0);
    CHECK(g.stretches == 0);
  }
  SECTION("the other strip lies turned over: a face across would fold") {
    Mesh m;
    add_strip(m, 20, -3, -0.2, flat);
    // The second strip runs back over the first (its far side above, at z = 0.3): normals
    // across the gap would turn by more than 90°.
    const auto base = static_cast<std::int32_t>(m.vertex_count());
    for (int i = 0; i <= 20; ++i) {
      m.add_vertex(Vec3(i, 0.2, 0), 0, 0, 0, 0, 0, 0);
      m.add_vertex(Vec3(i, -2, 0.3), 0, 0, 0, 0, 0, 0);
    }
    for (int i = 0; i < 20; ++i) {
      const std::int32_t a = base + 2 * i;
      m.add_quad(a, a + 2, a + 3, a + 1);
    }
    const GapReport g = close_gaps(m, 0.5, 2.0);
    CHECK(g.faces == 0);
    CHECK(measure_quality(m).folds == 0);
  }
  SECTION("shorter than min_length") {
    Mesh m;
    add_strip(m, 20, -3, -0.2, flat);
    add_strip(m, 20, 0.2, 3, flat);
    const GapReport g = close_gaps(m, 0.5, 25.0);
    CHECK(g.faces == 0);
  }
}

TEST_CASE("strips of different spacing are zipped with triangles, without T-junctions",
          "[mesh][gaps]") {
  Mesh m;
  add_strip(m, 20, -3, -0.2, [](double) { return 0.0; });
  // The upper strip has half the spacing and a gentle bend out of the plane.
  const auto base = static_cast<std::int32_t>(m.vertex_count());
  for (int i = 0; i <= 40; ++i) {
    const double x = 0.5 * i, z = 0.1 * std::sin(0.3 * x);
    m.add_vertex(Vec3(x, 0.25, z), 0, 0, 0, 0, 0, 0);
    m.add_vertex(Vec3(x, 3, z), 0, 0, 0, 0, 0, 0);
  }
  for (int i = 0; i < 40; ++i) {
    const std::int32_t a = base + 2 * i;
    m.add_quad(a, a + 2, a + 3, a + 1);
  }
  const GapReport g = close_gaps(m, 0.6, 2.0);
  CHECK(g.stretches == 1);
  CHECK(g.faces >= 40);
  const QualityReport q = measure_quality(m);
  CHECK(q.non_manifold_edges == 0);
  CHECK(q.inconsistent_edges == 0);
  CHECK(q.folds == 0);
  CHECK(q.t_junctions == 0);
  CHECK(q.degenerate_faces == 0);
  CHECK(q.boundary_edges == 20 + 40 + 2 * 2 + 2);
}

TEST_CASE("a gap on one closed boundary loop closes whatever the vertex numbering",
          "[mesh][gaps]") {
  // A U: two strips joined at their far end, so both sides of the gap lie on one boundary loop.
  Mesh u;
  const auto flat = [](double) { return 0.0; };
  add_strip(u, 20, -3, -0.2, flat);
  add_strip(u, 20, 0.2, 3, flat);
  u.add_quad(39, 41, 82, 80);  // the gap's last cell, x from 19 to 20, filled
  REQUIRE(measure_quality(u).boundary_edges == 84);  // two strips of 42, the bridge adds and covers 2
  REQUIRE(measure_quality(u).inconsistent_edges == 0);

  // The same mesh with a vertex in the middle of a gap side numbered first (the loop's start).
  Mesh renumbered = u;
  const std::int32_t middle = 2 * 10 + 1;  // strip A's upper side, x = 10
  std::swap(renumbered.positions[0], renumbered.positions[static_cast<std::size_t>(middle)]);
  for (Face& f : renumbered.faces)
    for (std::size_t k = 0; k < f.size; ++k)
      f.v[k] = f.v[k] == 0 ? middle : f.v[k] == middle ? 0 : f.v[k];

  const GapReport a = close_gaps(u, 0.5, 2.0);
  const GapReport b = close_gaps(renumbered, 0.5, 2.0);
  CHECK(a.faces > 10);
  CHECK(a.faces == b.faces);
  CHECK(a.stretches == b.stretches);
  const QualityReport qa = measure_quality(u), qb = measure_quality(renumbered);
  CHECK(qa.boundary_edges == qb.boundary_edges);
  CHECK(qb.non_manifold_edges == 0);
  CHECK(qb.inconsistent_edges == 0);
  CHECK(qb.folds == 0);
}
