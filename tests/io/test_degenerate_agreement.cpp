// The report's degenerate-face count agrees with an independent count on the written file: each
// file format is read back and its faces are judged from scratch (Heron's formula on a fan of
// triangles, repeated corners), against measure_quality's count on the mesh before writing.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <vector>

#include "orthofront/io/mesh_io.h"
#include "orthofront/mesh/mesh.h"
#include "orthofront/quality/quality.h"
#include "temp_dir.h"

using namespace orthofront;

namespace {

/// A face is degenerate if a corner repeats or its area is at most 1e-12 of its longest edge
/// squared (QualityOptions::degenerate_area's definition), computed here without the library:
/// the area of a quad is taken as half the norm of the sum of its two fan triangles' cross
/// products (the same vector as the diagonals' cross product for any quad).
std::size_t count_degenerate(const Mesh& mesh) {
  std::size_t count = 0;
  for (const Face& f : mesh.faces) {
    std::vector<Vec3> p;
    bool repeated = false;
    for (int i = 0; i < f.size; ++i) {
      for (int j = 0; j < i; ++j) repeated = repeated || f.v[i] == f.v[j];
      p.push_back(mesh.positions[static_cast<std::size_t>(f.v[i])]);
    }
    if (repeated) {
      ++count;
      continue;
    }
    Vec3 twice_area = Vec3::Zero();
    for (std::size_t k = 1; k + 1 < p.size(); ++k) twice_area += (p[k] - p[0]).cross(p[k + 1] - p[0]);
    double longest = 0;
    for (std::size_t k = 0; k < p.size(); ++k)
      longest = std::max(longest, (p[(k + 1) % p.size()] - p[k]).norm());
    if (!(0.5 * twice_area.norm() > 1e-12 * longest * longest)) ++count;
  }
  return count;
}

Mesh mixed_mesh() {
  Mesh m;
  const auto v = [&m](double x, double y, double z = 0) {
    return m.add_vertex(Vec3(x, y, z), 0, 0, 0, 0, 0, 0);
  };
  // A unit grid of quads, non-planar in places.
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) v(i, j, 0.1 * ((i * j) % 3));
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) m.add_quad(4 * j + i, 4 * j + i + 1, 4 * j + i + 5, 4 * j + i + 4);
  // Degenerate: a repeated corner, collinear corners, a needle, a quad folded flat onto a line.
  m.add_quad(0, 1, 1, 5);
  m.add_triangle(v(10, 0), v(11, 0), v(12, 0));
  m.add_triangle(v(20, 0), v(21, 0), v(20.5, 1e-14));
  m.add_quad(v(30, 0), v(31, 0), v(32, 0), v(31, 0));
  // Not degenerate: tiny but well shaped, and a thin but honest sliver.
  m.add_triangle(v(40, 0), v(40 + 1e-7, 0), v(40, 1e-7));
  m.add_triangle(v(50, 0), v(51, 0), v(50.5, 1e-4));
  return m;
}

}  // namespace

TEST_CASE("the degenerate-face count of the report agrees with an independent count of the file",
          "[io][quality]") {
  const Mesh mesh = mixed_mesh();
  const std::size_t reported = measure_quality(mesh).degenerate_faces;
  CHECK(reported == 4);
  CHECK(count_degenerate(mesh) == reported);
  const test_support::TempDir dir("degenerate-agreement");
  for (const char* name : {"m.vtp", "m.ply", "m.obj"}) {
    INFO(name);
    const auto path = dir.path() / name;
    io::write_mesh(mesh, path);
    const Mesh back = io::read_mesh(path);
    REQUIRE(back.face_count() == mesh.face_count());
    CHECK(count_degenerate(back) == reported);
    CHECK(measure_quality(back).degenerate_faces == reported);
  }
}
