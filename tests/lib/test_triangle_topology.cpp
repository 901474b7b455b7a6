#include <catch2/catch.hpp>

#include <map>
#include <random>
#include <utility>
#include <vector>

#include "orthofront/error.h"
#include "orthofront/mesh/mesh.h"
#include "orthofront/mesh/triangle_topology.h"
#include "orthofront/quality/quality.h"

using namespace orthofront;

namespace {

using Topology = TriangleTopology;

// An n x n grid of unit squares, each cut into two counter-clockwise triangles.
Topology grid(int n, std::vector<Vec3>& x) {
  Topology t;
  x.clear();
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      t.add_vertex();
      x.emplace_back(i, j, 0);
    }
  const auto at = [&](int i, int j) { return j * (n + 1) + i; };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      // The face that joins the faces so far along an edge first.
      const bool lower_first = j > 0 || i == 0;
      if (!lower_first) t.add_face(at(i, j), at(i + 1, j + 1), at(i, j + 1));
      t.add_face(at(i, j), at(i + 1, j), at(i + 1, j + 1));
      if (lower_first) t.add_face(at(i, j), at(i + 1, j + 1), at(i, j + 1));
    }
  return t;
}

// Every link is mutual, no directed edge is used twice, and every vertex's faces form the one
// fan that fan() walks (a manifold, oriented mesh).
void require_consistent(const Topology& t) {
  std::map<std::pair<int, int>, int> directed;
  std::vector<int> faces_of(t.vertex_slots(), 0);
  for (std::size_t f = 0; f < t.face_slots(); ++f) {
    const auto fi = static_cast<std::int32_t>(f);
    if (!t.face_alive(fi)) continue;
    const auto& c = t.face(fi);
    REQUIRE(c[0] != c[1]);
    REQUIRE(c[1] != c[2]);
    REQUIRE(c[0] != c[2]);
    for (int e = 0; e < 3; ++e) {
      ++faces_of[static_cast<std::size_t>(c[e])];
      REQUIRE(directed.emplace(std::make_pair(c[e], c[(e + 1) % 3]), fi).second);
      const std::int32_t g = t.neighbor(fi, e);
      if (g == Topology::none) continue;
      REQUIRE(t.face_alive(g));
      bool back = false;
      for (int k = 0; k < 3; ++k)
        if (t.face(g)[k] == c[(e + 1) % 3] && t.face(g)[(k + 1) % 3] == c[e])
          back = t.neighbor(g, k) == fi;
      REQUIRE(back);
    }
  }
  // A twin edge present means the faces are linked.
  for (const auto& [edge, f] : directed) {
    const auto twin = directed.find({edge.second, edge.first});
    if (twin == directed.end()) continue;
    bool linked = false;
    for (int e = 0; e < 3; ++e) linked = linked || t.neighbor(f, e) == twin->second;
    REQUIRE(linked);
  }
  std::vector<Topology::HalfEdge> ring;
  for (std::size_t v = 0; v < t.vertex_slots(); ++v) {
    const auto vi = static_cast<std::int32_t>(v);
    REQUIRE(t.face_count(vi) == faces_of[v]);
    t.fan(vi, ring);
    REQUIRE(static_cast<int>(ring.size()) == faces_of[v]);
    REQUIRE(t.has_faces(vi) == (faces_of[v] > 0));
  }
}

// The face and edge that run a -> b.
Topology::HalfEdge half_edge(const Topology& t, std::int32_t a, std::int32_t b) {
  for (std::size_t f = 0; f < t.face_slots(); ++f) {
    const auto fi = static_cast<std::int32_t>(f);
    if (!t.face_alive(fi)) continue;
    for (int e = 0; e < 3; ++e)
      if (t.face(fi)[e] == a && t.face(fi)[(e + 1) % 3] == b) return {fi, e};
  }
  FAIL("no edge " << a << " -> " << b);
  return {};
}

Mesh to_mesh(const Topology& t, const std::vector<Vec3>& x) {
  Mesh m;
  for (const Vec3& p : x) m.add_vertex(p, 0, 0, 0, 0, 0, 0);
  for (std::size_t f = 0; f < t.face_slots(); ++f) {
    const auto fi = static_cast<std::int32_t>(f);
    if (t.face_alive(fi)) m.add_triangle(t.face(fi)[0], t.face(fi)[1], t.face(fi)[2]);
  }
  return m;
}

}  // namespace

TEST_CASE("a triangle grid: fans, boundary, adjacency", "[mesh][topology]") {
  std::vector<Vec3> x;
  const Topology t = grid(3, x);
  require_consistent(t);
  CHECK(t.face_count() == 18);
  std::vector<Topology::HalfEdge> ring;
  CHECK_FALSE(t.fan(5, ring));  // (1, 1): interior
  CHECK(ring.size() == 6);
  CHECK(t.fan(0, ring));
  CHECK(ring.size() == 2);
  CHECK(t.fan(3, ring));  // (3, 0): one face
  CHECK(ring.size() == 1);
  CHECK(t.adjacent(0, 1));
  CHECK(t.adjacent(0, 5));
  CHECK(t.adjacent(0, 4));
  CHECK_FALSE(t.adjacent(0, 2));
  CHECK_FALSE(t.adjacent(1, 4));
}

TEST_CASE("faces that would not keep the mesh manifold are refused", "[mesh][topology]") {
  std::vector<Vec3> x;
  Topology t = grid(1, x);  // vertices 0 1 / 2 3, faces (0, 1, 3), (0, 3, 2)
  CHECK_FALSE(t.can_add_face(0, 1, 3));  // edge 0 -> 1 already used
  CHECK_FALSE(t.can_add_face(0, 0, 3));
  const std::int32_t a = t.add_vertex(), b = t.add_vertex();
  // Touching vertex 3 at a point only: two fans would meet there.
  CHECK_FALSE(t.can_add_face(3, a, b));
  // Along the boundary edge 1 -> 3 reversed: fine.
  CHECK(t.can_add_face(3, 1, a));
  CHECK_THROWS_AS(t.add_face(3, a, b), InvalidArgument);
  t.add_face(3, 1, a);
  require_consistent(t);
}

TEST_CASE("split, flip and collapse keep the mesh consistent", "[mesh][topology]") {
  std::vector<Vec3> x;
  Topology t = grid(2, x);
  // Split the interior diagonal of the first square, then a boundary edge.
  const Topology::HalfEdge diagonal = half_edge(t, 4, 0);  // inside the first square
  const std::int32_t m = t.split(diagonal.face, diagonal.edge);
  x.push_back(0.5 * (x[0] + x[4]));
  require_consistent(t);
  CHECK(t.face_count() == 10);
  CHECK(t.face_count(m) == 4);
  const Topology::HalfEdge bottom = half_edge(t, 0, 1);  // on the boundary
  const std::int32_t b = t.split(bottom.face, bottom.edge);
  x.push_back(0.5 * (x[0] + x[1]));
  require_consistent(t);
  CHECK(t.face_count() == 11);
  CHECK(t.face_count(b) == 2);
  CHECK(t.on_boundary(b));
  // Collapse the boundary split back: along the boundary only.
  CHECK_FALSE((t.can_collapse(m, b) && t.on_boundary(m)));
  REQUIRE(t.can_collapse(b, 0));
  t.collapse(b, 0);
  require_consistent(t);
  CHECK(t.face_count() == 10);
  CHECK_FALSE(t.has_faces(b));
  // Flip every interior edge once, then check that the mesh still covers the square.
  int flips = 0;
  for (std::size_t f = 0; f < t.face_slots(); ++f)
    for (int e = 0; e < 3; ++e)
      if (t.face_alive(static_cast<std::int32_t>(f)) && t.neighbor(static_cast<std::int32_t>(f), e) >
                                                            static_cast<std::int32_t>(f))
        flips += t.flip(static_cast<std::int32_t>(f), e) ? 1 : 0;
  CHECK(flips > 0);
  require_consistent(t);
  // A boundary edge does not flip.
  for (std::size_t f = 0; f < t.face_slots(); ++f)
    for (int e = 0; e < 3; ++e)
      if (t.face_alive(static_cast<std::int32_t>(f)) &&
          t.neighbor(static_cast<std::int32_t>(f), e) == Topology::none)
        CHECK_FALSE(t.flip(static_cast<std::int32_t>(f), e));
}

TEST_CASE("the link condition refuses a collapse that would pinch the mesh", "[mesh][topology]") {
  // A fan of three faces around vertex 0 (0 interior of nothing: all on the boundary) and a
  // valence-3 interior vertex inside a triangle.
  Topology t;
  for (int i = 0; i < 4; ++i) t.add_vertex();
  t.add_face(0, 1, 3);
  t.add_face(1, 2, 3);
  t.add_face(2, 0, 3);  // 3 is interior with three faces, 0 1 2 the boundary
  require_consistent(t);
  CHECK_FALSE(t.on_boundary(3));
  // 0 -> 1 along the boundary would leave (1, 2, 3) and (2, 1, 3): refused (common neighbours 2
  // and 3, but only 3 is opposite the edge).
  CHECK_FALSE(t.can_collapse(0, 1));
  // Interior 3 onto 0: the faces holding both go, (1, 2, 3) becomes (1, 2, 0): one face left.
  REQUIRE(t.can_collapse(3, 0));
  t.collapse(3, 0);
  require_consistent(t);
  CHECK(t.face_count() == 1);
  CHECK_FALSE(t.can_collapse(0, 1));  // the last face is an ear
}

TEST_CASE("removing a face in the middle of a boundary fan removes the smaller side",
          "[mesh][topology]") {
  std::vector<Vec3> x;
  Topology t = grid(3, x);
  // Vertex 1 = (1, 0) is on the boundary with three faces; remove the middle one.
  std::vector<Topology::HalfEdge> ring;
  REQUIRE(t.fan(1, ring));
  REQUIRE(ring.size() == 3);
  const std::size_t removed = t.remove_face(ring[1].face);
  CHECK(removed == 2);
  require_consistent(t);
  REQUIRE(t.fan(1, ring));
  CHECK(ring.size() == 1);
  const QualityReport q = measure_quality(to_mesh(t, x));
  CHECK(q.non_manifold_edges == 0);
  CHECK(q.inconsistent_edges == 0);
}

TEST_CASE("random splits, flips, collapses and removals keep the mesh manifold",
          "[mesh][topology]") {
  std::vector<Vec3> x;
  Topology t = grid(8, x);
  std::mt19937 random(12345);
  int splits = 0, flips = 0, collapses = 0, removals = 0;
  for (int step = 0; step < 3000 && t.face_count() > 4; ++step) {
    const auto f = static_cast<std::int32_t>(random() % t.face_slots());
    if (!t.face_alive(f)) continue;
    const int e = static_cast<int>(random() % 3);
    const std::int32_t a = t.face(f)[e], b = t.face(f)[(e + 1) % 3];
    switch (random() % 8) {
      case 0:
      case 1:
      case 2:
        t.split(f, e);
        x.push_back(0.5 * (x[static_cast<std::size_t>(a)] + x[static_cast<std::size_t>(b)]));
        ++splits;
        break;
      case 3:
      case 4:
        flips += t.flip(f, e) ? 1 : 0;
        break;
      case 5:
      case 6:
        if (t.can_collapse(a, b)) {
          t.collapse(a, b);
          ++collapses;
        }
        break;
      default:
        if (random() % 4 == 0) {
          t.remove_face(f);
          ++removals;
        }
    }
    if (step % 50 == 0) require_consistent(t);
  }
  require_consistent(t);
  CHECK(splits > 100);
  CHECK(flips > 100);
  CHECK(collapses > 50);
  CHECK(removals > 5);
  const QualityReport q = measure_quality(to_mesh(t, x));
  CHECK(q.non_manifold_edges == 0);
  CHECK(q.inconsistent_edges == 0);
  // Compacting keeps the faces and renumbers the vertices densely.
  const std::size_t faces = t.face_count();
  const std::vector<std::int32_t> index = t.compact({});
  require_consistent(t);
  CHECK(t.face_count() == faces);
  CHECK(t.face_slots() == faces);
  for (std::size_t v = 0; v < t.vertex_slots(); ++v) CHECK(t.has_faces(static_cast<std::int32_t>(v)));
  (void)index;
}
