// The fold guard's check on hand-made strips: a strip that turns back over the previous one, a
// crease sharper than 90° between two faces of one strip, and strips that only bend.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <tuple>
#include <vector>

#include "orthofront/engine/fold_guard.h"

using namespace orthofront;

namespace {

constexpr double kDegree = 3.141592653589793 / 180;

/// The point at distance 1 from (1, y, 0) turned by `crease` degrees from +x towards +z.
Vec3 creased(double y, double crease) {
  return Vec3(1 + std::cos(crease * kDegree), y, std::sin(crease * kDegree));
}

/// Rows 0 and 1 of a strip made by the previous step: vertices 0 1 2 (y = 0) and 3 4 5 (y = 1),
/// quads (0 1 4 3) and (1 2 5 4); the first in the z = 0 plane (normal +z), the second turned up
/// by `crease` degrees about the column x = 1.
Mesh previous_strip(double crease = 0) {
  Mesh m;
  for (const double y : {0.0, 1.0}) {
    m.add_vertex(Vec3(0, y, 0), 0, 0, 0, 0, 0, 0);
    m.add_vertex(Vec3(1, y, 0), 0, 0, 0.5, 0, 0, 0);
    m.add_vertex(creased(y, crease), 0, 0, 1, 0, 0, 0);
  }
  m.add_quad(0, 1, 4, 3);
  m.add_quad(1, 2, 5, 4);
  return m;
}

/// The next row (vertices 6 7 8 at the given points) stitched to row 1 with two quads.
void add_next_row(Mesh& m, const Vec3& a, const Vec3& b, const Vec3& c) {
  for (const Vec3& p : {a, b, c}) m.add_vertex(p, 1, 1, 0, 0, 0, 2);
  m.add_quad(3, 4, 7, 6);
  m.add_quad(4, 5, 8, 7);
}

std::vector<std::int32_t> check(Mesh& m, const Vec3& a, const Vec3& b, const Vec3& c) {
  FoldGuard guard;
  guard.rebuild(m);  // rows 0-1 are the surface so far
  const std::size_t first_face = m.face_count(), first_vertex = m.vertex_count();
  add_next_row(m, a, b, c);
  return guard.folded_vertices(m, first_face, first_vertex);
}

}  // namespace

TEST_CASE("the fold guard passes strips that bend by less than 90 degrees", "[engine][fold]") {
  Mesh flat = previous_strip();
  CHECK(check(flat, Vec3(0, 2, 0), Vec3(1, 2, 0), Vec3(2, 2, 0)).empty());
  // Bent up by 80° across row 1, and creased by 80° at the middle column.
  Mesh bent = previous_strip();
  const double c = std::cos(80 * kDegree), s = std::sin(80 * kDegree);
  CHECK(check(bent, Vec3(0, 1 + c, s), Vec3(1, 1 + c, s), Vec3(2, 1 + c, s)).empty());
  Mesh sharp = previous_strip(80);
  CHECK(check(sharp, Vec3(0, 2, 0), Vec3(1, 2, 0), creased(2, 80)).empty());
}

TEST_CASE("the fold guard finds a strip turned back over the previous one", "[engine][fold]") {
  // Row 2 lies between rows 0 and 1, slightly above: the new quads face -z over the old ones.
  Mesh m = previous_strip();
  const std::vector<std::int32_t> folded =
      check(m, Vec3(0, 0.5, 0.01), Vec3(1, 0.5, 0.01), Vec3(2, 0.5, 0.01));
  // The folded edges are old (row 1): the new corners of the folded faces stand on the fold.
  CHECK(folded == std::vector<std::int32_t>{6, 7, 8});
}

TEST_CASE("the fold guard finds a crease sharper than 90 degrees inside a strip",
          "[engine][fold]") {
  // The front turns by 100° at the column x = 1 on both rows: the new end of the folded column
  // edge (4, 7), vertex 7, stands on the fold. (The previous strip's own crease is not this
  // step's to undo.)
  Mesh m = previous_strip(100);
  CHECK(check(m, Vec3(0, 2, 0), Vec3(1, 2, 0), creased(2, 100)) == std::vector<std::int32_t>{7});
}

TEST_CASE("the fold guard's boundary is the mesh's boundary, edge for edge", "[engine][fold]") {
  Mesh m = previous_strip(30);
  add_next_row(m, Vec3(0, 2, 0), Vec3(1, 2, 0), creased(2, 30));
  FoldGuard guard;
  guard.rebuild(m);
  const auto key = [](const BoundaryEdge& e) { return std::tuple(e.from, e.to, e.face); };
  const auto sorted = [&](std::vector<BoundaryEdge> edges) {
    std::sort(edges.begin(), edges.end(),
              [&](const BoundaryEdge& a, const BoundaryEdge& b) { return key(a) < key(b); });
    std::vector<std::tuple<std::int32_t, std::int32_t, std::int32_t>> out;
    for (const auto& e : edges) out.push_back(key(e));
    return out;
  };
  const auto from_guard = sorted(guard.boundary());
  CHECK(from_guard.size() == 8);  // a 2 x 2 sheet of quads
  CHECK(from_guard == sorted(boundary_edges(m)));
}

TEST_CASE("a strip is checked against the faces accepted before it", "[engine][fold]") {
  // Rows 0-1, then row 2 checked and accepted; row 3 turned back over row 2 must be found
  // against it, and the boundary must be the whole mesh's.
  Mesh m = previous_strip();
  FoldGuard guard;
  guard.rebuild(m);
  const std::size_t row2_faces = m.face_count();
  add_next_row(m, Vec3(0, 2, 0), Vec3(1, 2, 0), Vec3(2, 2, 0));
  REQUIRE(guard.folded_vertices(m, row2_faces, 6).empty());
  guard.accept(m, row2_faces);
  for (const double x : {0.0, 1.0, 2.0}) m.add_vertex(Vec3(x, 1.5, 0.01), 2, 2, 0, 0, 0, 3);
  const std::size_t row3_faces = m.face_count();
  m.add_quad(6, 7, 10, 9);
  m.add_quad(7, 8, 11, 10);
  CHECK(guard.folded_vertices(m, row3_faces, 9) == std::vector<std::int32_t>{9, 10, 11});
  m.faces.resize(row3_faces);  // undone: rows 0-2 are a 2 x 2 sheet of quads
  CHECK(guard.boundary().size() == 8);
  CHECK(boundary_edges(m).size() == 8);
}

TEST_CASE("the fold guard checks the second part of a step against its own faces",
          "[engine][fold]") {
  // Rows 0 and 1 over five columns (the last turned up by 100 degrees about x = 3), then row 2
  // in two parts checked one after the other, as the parts of one front step are: part A over
  // columns 0-1, part B over columns 2-4 with the same 100-degree crease at x = 3 between its two
  // faces. Part B's faces are compared with each other through the area vectors kept since part
  // A: the new end of the creased column edge (8, 13), vertex 13, stands on the fold.
  const auto point = [](int column, double y) {
    return column < 4 ? Vec3(column, y, 0)
                      : Vec3(3 + std::cos(100 * kDegree), y, std::sin(100 * kDegree));
  };
  Mesh m;
  for (const double y : {0.0, 1.0})
    for (int c = 0; c < 5; ++c) m.add_vertex(point(c, y), 0, 0, 0, 0, 0, 0);
  for (std::int32_t c = 0; c < 4; ++c) m.add_quad(c, c + 1, c + 6, c + 5);
  FoldGuard guard;
  guard.rebuild(m);
  const std::size_t first_vertex = m.vertex_count();
  const std::size_t part_a = m.face_count();
  m.add_vertex(point(0, 2), 1, 0, 0, 0, 0, 2);  // 10
  // Part A rises steeply in x: its area vector does not oppose part B's creased face, so a
  // check that took part A's for part B's first face would find nothing.
  m.add_vertex(Vec3(1, 2, 3), 1, 0, 0, 0, 0, 2);  // 11
  m.add_quad(5, 6, 11, 10);
  CHECK(guard.folded_vertices(m, part_a, first_vertex).empty());
  const std::size_t part_b = m.face_count();
  for (int c = 2; c < 5; ++c) m.add_vertex(point(c, 2), 1, 0, 0, 0, 0, 2);  // 12 13 14
  m.add_quad(7, 8, 13, 12);
  m.add_quad(8, 9, 14, 13);
  CHECK(guard.folded_vertices(m, part_b, first_vertex) == std::vector<std::int32_t>{13});
}

TEST_CASE("accepting checked strips gives the boundary of a guard built from the whole mesh",
          "[engine][fold]") {
  // Accepting a checked strip applies the boundary changes its check learnt; where an edge meets
  // more faces than a boundary edge and one strip face, or two strip faces, it looks every edge
  // up instead. Either way the boundary must be the one a guard gets from the whole mesh, edge
  // for edge and in the same order (gap closing walks it in that order).
  Mesh m = previous_strip(30);
  FoldGuard guard;
  guard.rebuild(m);
  const auto key = [](const BoundaryEdge& e) { return std::tuple(e.from, e.to, e.face); };
  const auto same_as_rebuilt = [&] {
    FoldGuard rebuilt;
    rebuilt.rebuild(m);
    const auto a = guard.boundary(), b = rebuilt.boundary();
    REQUIRE(a.size() == b.size());
    for (std::size_t i = 0; i < a.size(); ++i) CHECK(key(a[i]) == key(b[i]));
  };
  // Row 2: quads over row 1 (its edges come off the boundary, the column edges pair up).
  std::size_t first_face = m.face_count();
  add_next_row(m, Vec3(0, 2, 0), Vec3(1, 2, 0), creased(2, 30));
  REQUIRE(guard.folded_vertices(m, first_face, 6).empty());
  guard.accept(m, first_face);
  same_as_rebuilt();
  // Rows 3 and 4 at y = 3, 4: quads over the row below (its first vertex `below`).
  const auto add_row = [&](double y, std::int32_t below) {
    first_face = m.face_count();
    const auto v = static_cast<std::int32_t>(m.vertex_count());
    for (const double x : {0.0, 1.0, 2.0}) m.add_vertex(Vec3(x, y, 0), 2, 2, 0, 0, 0, 3);
    m.add_quad(below, below + 1, v + 1, v);
    m.add_quad(below + 1, below + 2, v + 2, v + 1);
  };
  // Row 3 with a triangle that closes the corner (6, 7, 9): edge (6, 7) is on the boundary and
  // shared by both the triangle and the quad over it, three faces in all.
  add_row(3, 6);
  m.add_triangle(7, 6, 9);
  guard.folded_vertices(m, first_face, 9);
  guard.accept(m, first_face);
  same_as_rebuilt();
  // Row 4 over row 3: plain again, after the lookup.
  add_row(4, 9);
  REQUIRE(guard.folded_vertices(m, first_face, 12).empty());
  guard.accept(m, first_face);
  same_as_rebuilt();
}
