// The link stage on hand-made fronts: a strip stitched between a front and the one it advanced
// from, and, with the fold guard, a strip that folds back over the surface undone and stitched
// again without the vertices on the fold.
#include <catch2/catch.hpp>
#include <cstdint>
#include <functional>
#include <vector>

#include "orthofront/engine/link.h"
#include "orthofront/quality/quality.h"

using namespace orthofront;

namespace {

/// A front of n vertices on y = `y`, each with a mesh vertex of its own (step `step`).
Front<3> row(Mesh& mesh, int n, double y, int step) {
  Front<3> f;
  for (int i = 0; i < n; ++i) {
    FrontVertex<3> fv;
    fv.x = fv.anchor = Vec3(i, y, 0);
    fv.s = i / (n - 1.0);
    fv.t = y;
    fv.mesh = emit_vertex(mesh, fv, false, 0.0, 0, step);
    f.v.push_back(fv);
  }
  return f;
}

/// `old` advanced: vertex i to `to(i)`, with its origin set and its old mesh vertex.
template <class To>
Front<3> advanced(const Front<3>& old, To to) {
  Front<3> f = old;
  for (std::size_t i = 0; i < f.v.size(); ++i) {
    f.v[i].x = to(static_cast<int>(i));
    f.v[i].origin = static_cast<std::int32_t>(i);
  }
  return f;
}

struct Counted {
  int calls = 0;
  FrontIds ids;
  std::vector<Front<3>> operator()(Front<3>&& f, const std::vector<char>& keep,
                                   const std::vector<char>& cut) {
    ++calls;
    return split_front(std::move(f), keep, cut, ids);
  }
};

}  // namespace

int quads(const Mesh& mesh) {
  int count = 0;
  for (const Face& f : mesh.faces) count += f.is_quad() ? 1 : 0;
  return count;
}

TEST_CASE("linking stitches quads between rows that advance together", "[engine][link]") {
  for (const bool guarded : {false, true}) {
    Mesh mesh;
    SurfaceReport report;
    StreamSurfaceOptions o;
    o.edge = 1;
    Counted counted;
    StripLinker<3> linker(o, o.row_skip, guarded, false, mesh, report, std::ref(counted));
    const Front<3> old = row(mesh, 5, 0, 0);
    std::vector<Front<3>> parts;
    parts.push_back(advanced(old, [](int i) { return Vec3(i, 1, 0); }));
    const std::vector<Front<3>> pieces =
        linker.link(std::move(parts), old, 1, mesh.vertex_count());
    REQUIRE(pieces.size() == 1);
    CHECK(pieces[0].v.size() == 5);
    for (std::size_t i = 0; i < 5; ++i) CHECK(pieces[0].v[i].mesh == static_cast<int>(5 + i));
    CHECK(mesh.face_count() == 4);
    CHECK(quads(mesh) == 4);
    CHECK(counted.calls == 0);
    CHECK(report.fold_rips == 0);
    if (guarded) CHECK(linker.boundary().size() == 10);  // the strip's rim: 4 + 4 + 2 edges
  }
}

TEST_CASE("a strip that folds back over the surface is stitched without the folded vertices",
          "[engine][link]") {
  // Rows y = -1 and y = 0 are the surface so far (six quads); the next row advances to y = 1
  // except its three middle vertices, which turn back over the previous strip.
  Mesh mesh;
  SurfaceReport report;
  StreamSurfaceOptions o;
  o.edge = 1;
  Counted counted;
  row(mesh, 7, -1, 0);
  const Front<3> old = row(mesh, 7, 0, 1);
  for (std::int32_t i = 0; i + 1 < 7; ++i) mesh.add_quad(i, i + 1, i + 8, i + 7);
  const auto turned_back = [](int i) {
    return i >= 2 && i <= 4 ? Vec3(i, -0.5, 0.01) : Vec3(i, 1, 0);
  };

  SECTION("without the guard the fold stays") {
    StripLinker<3> linker(o, o.row_skip, false, false, mesh, report, std::ref(counted));
    std::vector<Front<3>> parts;
    parts.push_back(advanced(old, turned_back));
    const auto pieces = linker.link(std::move(parts), old, 2, mesh.vertex_count());
    CHECK(pieces.size() == 1);
    CHECK(measure_quality(mesh).folds > 0);
  }
  SECTION("with the guard the folded vertices leave the front") {
    StripLinker<3> linker(o, o.row_skip, true, false, mesh, report, std::ref(counted));
    linker.rebuild(mesh);
    std::vector<Front<3>> parts;
    parts.push_back(advanced(old, turned_back));
    const auto pieces = linker.link(std::move(parts), old, 2, mesh.vertex_count());
    CHECK(report.fold_rips >= 1);
    CHECK(counted.calls >= 1);
    // What goes on is cut where the folded vertices were, and none of them is in it.
    std::size_t kept = 0;
    for (const auto& piece : pieces)
      for (const auto& fv : piece.v) {
        CHECK(fv.x.y() == 1.0);
        ++kept;
      }
    CHECK(kept >= 2);
    CHECK(kept < 7);
    const QualityReport q = measure_quality(mesh);
    CHECK(q.folds == 0);
    CHECK(q.non_manifold_edges == 0);
    CHECK(report.folds_left == 0);
    // The guard's boundary is the mesh's, edge for edge.
    CHECK(linker.boundary().size() == boundary_edges(mesh).size());
  }
}
