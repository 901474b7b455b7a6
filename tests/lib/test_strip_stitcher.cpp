// Stitch and emit on hand-made fronts: quads between rows that advance together, triangles where
// a row has more segments or a vertex kept its mesh vertex, consistently oriented.
#include <catch2/catch.hpp>
#include <map>
#include <stdexcept>
#include <utility>
#include <vector>

#include "orthofront/engine/stitch.h"

using namespace orthofront;

namespace {

/// A previous front of n vertices on y = 0 (mesh vertices 0 .. n-1), as a step left it.
Front<3> previous_row(Mesh& mesh, int n) {
  Front<3> old;
  for (int i = 0; i < n; ++i) {
    FrontVertex<3> fv;
    fv.x = fv.anchor = Vec3(i, 0, 0);
    fv.s = i / (n - 1.0);
    fv.mesh = emit_vertex(mesh, fv, false, 0.0, 0, 0);
    old.v.push_back(fv);
  }
  return old;
}

/// The front after advancing every vertex of `old` to y = dy (origins set, mesh vertices not yet).
Front<3> advanced(const Front<3>& old, double dy) {
  Front<3> f = old;
  for (std::size_t i = 0; i < f.v.size(); ++i) {
    f.v[i].x.y() += dy;
    f.v[i].origin = static_cast<std::int32_t>(i);
  }
  return f;
}

/// Every edge used by at most two faces, in opposite directions when by two.
bool consistently_oriented(const Mesh& mesh) {
  std::map<std::pair<int, int>, int> directed;
  for (const Face& f : mesh.faces)
    for (int k = 0; k < f.size; ++k) {
      const int a = f.v[static_cast<std::size_t>(k)];
      const int b = f.v[static_cast<std::size_t>((k + 1) % f.size)];
      if (++directed[{a, b}] > 1) return false;
    }
  return true;
}

int count_quads(const Mesh& mesh) {
  int quads = 0;
  for (const Face& f : mesh.faces) quads += f.is_quad() ? 1 : 0;
  return quads;
}

}  // namespace

TEST_CASE("rows that advance together are joined by quads", "[engine][stitch]") {
  Mesh mesh;
  SurfaceReport report;
  StreamSurfaceOptions o;
  o.edge = 1;
  StripStitcher<3> stitcher(o, o.row_skip, false, mesh, report);
  const Front<3> old = previous_row(mesh, 5);
  Front<3> f = advanced(old, 1.0);
  stitcher.emit_moved(f, old, 1);
  stitcher.stitch(old, f);
  CHECK(mesh.vertex_count() == 10);
  CHECK(mesh.face_count() == 4);
  CHECK(count_quads(mesh) == 4);
  CHECK(report.skipped_vertex_steps == 0);
  CHECK(consistently_oriented(mesh));
  for (std::size_t i = 0; i < f.v.size(); ++i) CHECK(f.v[i].mesh == static_cast<int>(5 + i));
}

TEST_CASE("a row with an inserted vertex gets one triangle beside a quad", "[engine][stitch]") {
  Mesh mesh;
  SurfaceReport report;
  StreamSurfaceOptions o;
  o.edge = 1;
  StripStitcher<3> stitcher(o, o.row_skip, false, mesh, report);
  const Front<3> old = previous_row(mesh, 3);
  Front<3> f = advanced(old, 1.0);
  // Insert a vertex between 1 and 2 (already a mesh vertex, as split_long makes it).
  FrontVertex<3> inserted;
  inserted.x = inserted.anchor = Vec3(1.5, 1.0, 0);
  inserted.mesh = emit_vertex(mesh, inserted, false, 0.0, 0, 1);
  f.v.insert(f.v.begin() + 2, inserted);
  stitcher.emit_moved(f, old, 1);
  stitcher.stitch(old, f);
  CHECK(mesh.face_count() == 3);
  CHECK(count_quads(mesh) == 2);
  CHECK(consistently_oriented(mesh));
}

TEST_CASE("row skipping: a vertex that moved less than skip_fraction l keeps its mesh vertex",
          "[engine][stitch]") {
  Mesh mesh;
  SurfaceReport report;
  StreamSurfaceOptions o;
  o.edge = 1;
  o.row_skip = RowSkip::vertex;
  StripStitcher<3> stitcher(o, o.row_skip, false, mesh, report);
  const Front<3> old = previous_row(mesh, 3);
  Front<3> f = advanced(old, 1.0);
  f.v[2].x.y() = 0.2;  // moved 0.2 < 0.5 ℓ
  stitcher.emit_moved(f, old, 1);
  CHECK(f.v[2].mesh == old.v[2].mesh);
  CHECK(f.v[2].anchor == old.v[2].anchor);
  CHECK(report.skipped_vertex_steps == 1);
  stitcher.stitch(old, f);
  // The quad on the waiting vertex collapses to a triangle.
  CHECK(mesh.vertex_count() == 5);
  CHECK(mesh.face_count() == 2);
  CHECK(count_quads(mesh) == 1);
  CHECK(consistently_oriented(mesh));
}

TEST_CASE("zipper places a row's extra segments as triangles at the shorter diagonal",
          "[engine][stitch]") {
  Mesh mesh;
  SurfaceReport report;
  StreamSurfaceOptions o;
  StripStitcher<3> stitcher(o, o.row_skip, false, mesh, report);
  // Old chain 0-1 (one segment), new chain 2-3-4 (two), the new one fanned out to the right.
  for (const Vec3& p : {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0), Vec3(2, 1, 0)})
    mesh.add_vertex(p, 0, 0, 0, 0, 0, 0);
  stitcher.zipper({0, 1}, {2, 3, 4});
  REQUIRE(mesh.face_count() == 2);
  CHECK(count_quads(mesh) == 1);
  CHECK(consistently_oriented(mesh));
  // The triangle is the one at the right end (the quad 0-1-3-2 is square).
  const Face& quad = mesh.faces[0].is_quad() ? mesh.faces[0] : mesh.faces[1];
  CHECK(quad.v == std::array<std::int32_t, 4>{0, 1, 3, 2});
}

TEST_CASE("row skipping by runs: a waiting run of up to 16 vertices beside moving ones moves once "
          "each has gone a twentieth of the skip distance, a longer or slower run waits",
          "[engine][stitch]") {
  constexpr std::size_t n = 40;
  // Vertices 0 .. n-1 advance by l except those in [first, first + count), which move `by`.
  const auto skipped = [](std::size_t first, std::size_t count, double by, int& quads,
                          int& triangles) {
    Mesh mesh;
    SurfaceReport report;
    StreamSurfaceOptions o;
    o.edge = 1;
    o.row_skip = RowSkip::run;  // skip distance 0.5 l: short runs move from 0.025 l
    StripStitcher<3> stitcher(o, o.row_skip, false, mesh, report);
    const Front<3> old = previous_row(mesh, static_cast<int>(n));
    Front<3> f = advanced(old, 1.0);
    for (std::size_t i = first; i < first + count; ++i) f.v[i].x.y() = by;
    stitcher.emit_moved(f, old, 1);
    stitcher.stitch(old, f);
    CHECK(consistently_oriented(mesh));
    quads = count_quads(mesh);
    triangles = static_cast<int>(mesh.face_count()) - quads;
    CHECK(report.triangles_at_waiting_vertices == static_cast<std::size_t>(triangles));
    return report.skipped_vertex_steps;
  };
  int quads = 0, triangles = 0;
  CHECK(skipped(3, 1, 0.03, quads, triangles) == 0);  // one vertex: moves, every face a quad
  CHECK(quads == 39);
  CHECK(skipped(10, 16, 0.03, quads, triangles) == 0);  // sixteen: move
  CHECK(quads == 39);
  CHECK(skipped(n - 5, 5, 0.03, quads, triangles) == 0);  // at an open end: move
  CHECK(quads == 39);
  // Seventeen wait: the faces between two waiting vertices vanish, a triangle at each end.
  CHECK(skipped(10, 17, 0.03, quads, triangles) == 17);
  CHECK(quads == 39 - 16 - 2);
  CHECK(triangles == 2);
  CHECK(skipped(10, 2, 0.02, quads, triangles) == 2);  // not far enough: they wait
  CHECK(triangles == 2);
  CHECK(skipped(0, n, 0.03, quads, triangles) == n);  // a front that waits as a whole

  // On a closed front a run goes on across its last and first vertex: vertices n-2 .. 1 are one
  // run of four between moving ones.
  for (const double by : {0.02, 0.03}) {
    Mesh mesh;
    SurfaceReport report;
    StreamSurfaceOptions o;
    o.edge = 1;
    StripStitcher<3> stitcher(o, o.row_skip, false, mesh, report);
    Front<3> old = previous_row(mesh, static_cast<int>(n));
    old.closed = true;
    Front<3> f = advanced(old, 1.0);
    for (const std::size_t i : {n - 2, n - 1, std::size_t{0}, std::size_t{1}}) f.v[i].x.y() = by;
    stitcher.emit_moved(f, old, 1);
    INFO("moved " << by);
    CHECK(report.skipped_vertex_steps == (by < 0.025 ? 4u : 0u));
  }
}

