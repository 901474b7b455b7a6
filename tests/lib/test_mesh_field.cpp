// Unstructured meshes: exact interpolation of linear fields on every cell shape, mesh checks,
// the locator against an independent containment test, planar (2D) meshes, time series, and a
// stream surface on a tetrahedral mesh against the analytic field it samples.
#include <Eigen/Dense>
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "lib/mesh_builders.h"
#include "orthofront/engine/stream_surface.h"
#include "orthofront/error.h"
#include "orthofront/field/analytic.h"
#include "orthofront/field/cell_locator.h"
#include "orthofront/field/mesh_field.h"
#include "orthofront/seed/seed.h"

using namespace orthofront;
using test_support::box_mesh;
using test_support::BoxCells;

namespace {

// A linear field v = a + B x.
struct Linear {
  Vec3 a{0.3, -1.2, 0.7};
  Mat3 B = (Mat3() << 0.5, -2, 1, 1.5, 0.25, -0.75, -1, 0.6, 2).finished();
  Vec3 at(const Vec3& x) const { return a + B * x; }
};

std::vector<float> sample(const UnstructuredMesh& m, const Linear& f) {
  std::vector<float> v;
  for (std::size_t i = 0; i < m.point_count(); ++i) {
    const Vec3 x(m.points[3 * i], m.points[3 * i + 1], m.points[3 * i + 2]);
    const Vec3 y = f.at(x);
    for (int a = 0; a < 3; ++a) v.push_back(static_cast<float>(y[a]));
  }
  return v;
}

// The reference cell of a shape in VTK's order (wedge: first triangle facing away from the
// second), before an affine map.
std::vector<Vec3> reference_cell(CellShape s) {
  switch (s) {
    case CellShape::tetrahedron: return {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    case CellShape::pyramid: return {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 1}};
    case CellShape::wedge:
      return {{0, 0, 0}, {0, 1, 0}, {1, 0, 0}, {0, 0, 1}, {0, 1, 1}, {1, 0, 1}};
    case CellShape::hexahedron:
      return {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  }
  return {};
}

// Whether x lies in the tetrahedron (a, b, c, d), by barycentric coordinates from Eigen's LU:
// independent of the library's Newton inversion.
bool in_tetrahedron(const Vec3& x, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  Mat3 T;
  T << b - a, c - a, d - a;
  const Vec3 l = T.partialPivLu().solve(x - a);
  return l.minCoeff() >= -1e-9 && l.sum() <= 1 + 1e-9;
}

Vec3 point(const UnstructuredMesh& m, std::int32_t i) {
  const auto k = 3 * static_cast<std::size_t>(i);
  return {m.points[k], m.points[k + 1], m.points[k + 2]};
}

std::string mesh_error(const UnstructuredMesh& m) {
  try {
    check_mesh(m, "test.vtu");
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("every cell shape reproduces a linear field exactly, values and Jacobian", "[mesh]") {
  const Linear f;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1), wobble(-0.08, 0.08);
  for (CellShape shape : {CellShape::tetrahedron, CellShape::pyramid, CellShape::wedge,
                          CellShape::hexahedron}) {
    CAPTURE(shape_name(shape));
    // A sheared, scaled copy of the reference cell, its points then moved a little (the map is
    // no longer affine for pyramids, wedges and hexahedra; linear fields stay exact since the
    // shape functions sum to one and reproduce x itself).
    Mat3 M;
    M << 2, 0.3, -0.2, 0.1, 1.5, 0.4, 0.2, -0.1, 0.8;
    UnstructuredMesh m;
    for (const Vec3& r : reference_cell(shape)) {
      Vec3 x = M * r + Vec3(1, -2, 3);
      for (int a = 0; a < 3; ++a) x[a] += wobble(rng);
      for (int a = 0; a < 3; ++a) m.points.push_back(x[a]);
    }
    std::vector<std::int32_t> ids(static_cast<std::size_t>(cell::point_count(shape)));
    for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = static_cast<std::int32_t>(i);
    m.add_cell(shape, ids.data());
    const auto g = std::make_shared<const MeshGeometry>(m, "cell");
    REQUIRE_FALSE(g->planar());
    const MeshField field(g, sample(m, f), "linear");
    double p[8][3];
    m.gather(0, p);
    int inside = 0;
    for (int k = 0; k < 600; ++k) {
      double xi[3] = {u(rng), u(rng), u(rng)};
      if (shape == CellShape::tetrahedron && xi[0] + xi[1] + xi[2] > 1) continue;
      if (shape == CellShape::wedge && xi[0] + xi[1] > 1) continue;
      if (shape == CellShape::pyramid) xi[2] *= 0.9;
      double x[3], A[3][3];
      cell::map_point(shape, p, xi, x, A);
      const Vec3 X(x[0], x[1], x[2]);
      // The inverse map finds ξ back.
      double back[3];
      REQUIRE(cell::invert(shape, p, x, back));
      for (int a = 0; a < 3; ++a) CHECK(back[a] == Approx(xi[a]).margin(1e-10));
      Vec3 v;
      Mat3 J;
      REQUIRE(field.velocity_jacobian(X, v, J) == FieldStatus::inside);
      // Float samples: 1e-6 relative.
      CHECK((v - f.at(X)).norm() <= 1e-5 * f.at(X).norm() + 1e-5);
      CHECK((J - f.B).norm() <= 1e-4 * f.B.norm());
      ++inside;
    }
    CHECK(inside > 80);
    // Far away: outside.
    Vec3 v;
    CHECK(field.velocity(Vec3(40, 40, 40), v) == FieldStatus::outside);
  }
}

TEST_CASE("mesh checks name the file, the cell and the fault", "[mesh]") {
  UnstructuredMesh good = box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1), {2, 2, 2}, BoxCells::hexahedra);
  CHECK(mesh_error(good).empty());

  UnstructuredMesh inverted = good;
  std::swap(inverted.connectivity[8 * 3 + 1], inverted.connectivity[8 * 3 + 3]);  // cell 3
  CHECK(mesh_error(inverted) == "test.vtu: cell 3 (hexahedron) is inverted (its points are in "
                                "the mirrored order or it folds)");

  UnstructuredMesh repeated = good;
  repeated.connectivity[8 * 5 + 2] = repeated.connectivity[8 * 5 + 1];
  CHECK(mesh_error(repeated).find("cell 5 (hexahedron) point") != std::string::npos);

  UnstructuredMesh flat = good;
  for (int q = 4; q < 8; ++q) {  // cell 0's top face onto its bottom
    const auto top = 3 * static_cast<std::size_t>(flat.connectivity[static_cast<std::size_t>(q)]);
    flat.points[top + 2] = 0;
  }
  CHECK(mesh_error(flat).find("(hexahedron) is degenerate") != std::string::npos);

  UnstructuredMesh out_of_range = good;
  out_of_range.connectivity[17] = 999;
  CHECK(mesh_error(out_of_range) == "test.vtu: cell 2 (hexahedron) point index 999 is out of range");

  UnstructuredMesh nan = good;
  nan.points[4] = std::nan("");
  CHECK(mesh_error(nan) == "test.vtu: point 1 has a non-finite coordinate");

  CHECK(mesh_error(UnstructuredMesh{}) == "test.vtu: the mesh has no cells");

  // The mixed builder's wedges and pyramids are VTK-oriented.
  CHECK(mesh_error(box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1), {5, 5, 5}, BoxCells::mixed)).empty());
}

TEST_CASE("face neighbours: conforming tetrahedra match, the box's boundary does not", "[mesh]") {
  const UnstructuredMesh m =
      box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1), {4, 3, 2}, BoxCells::tetrahedra, 0.2, 3);
  const CellNeighbours n(m);
  // Boundary faces of a Kuhn-split box: two triangles per boundary square.
  CHECK(n.boundary_faces() == 2 * 2 * (4 * 3 + 3 * 2 + 4 * 2));
  // Symmetry: c's neighbour across f lists c back.
  for (std::size_t c = 0; c < m.cell_count(); ++c)
    for (int f = 0; f < 4; ++f) {
      const std::int32_t d = n.neighbour(c, f);
      if (d < 0) continue;
      int back = 0;
      for (int g = 0; g < 4; ++g) back += n.neighbour(static_cast<std::size_t>(d), g) == static_cast<std::int32_t>(c);
      CHECK(back == 1);
    }
}

TEST_CASE("the locator finds a containing cell for every point, by bins and by walks",
          "[mesh][locator]") {
  const UnstructuredMesh m =
      box_mesh(Vec3(-1, 0, 2), Vec3(2, 1, 3.5), {12, 5, 7}, BoxCells::tetrahedra, 0.25, 11);
  check_mesh(m, "tets");
  const CellLocator locator(m);
  const CellLocatorView& v = locator.view();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> ux(-1.2, 2.2), uy(-0.2, 1.2), uz(1.8, 3.7);
  std::uniform_int_distribution<std::int32_t> any_cell(0, static_cast<std::int32_t>(m.cell_count()) - 1);
  int inside = 0, outside = 0;
  for (int k = 0; k < 3000; ++k) {
    const Vec3 x(ux(rng), uy(rng), uz(rng));
    const double p[3] = {x.x(), x.y(), x.z()};
    // Brute force, with an independent containment test.
    bool contained = false;
    for (std::size_t c = 0; c < m.cell_count() && !contained; ++c) {
      const std::int32_t* ids = m.cell_points(c);
      contained = in_tetrahedron(x, point(m, ids[0]), point(m, ids[1]), point(m, ids[2]), point(m, ids[3]));
    }
    double xi[3];
    const std::int32_t found = locate::find_cell(v, p, xi);
    const std::int32_t walked = locate::cell_of(v, p, any_cell(rng), xi);
    CAPTURE(x.transpose());
    CHECK((found >= 0) == contained);
    CHECK((walked >= 0) == contained);
    for (std::int32_t c : {found, walked}) {
      if (c < 0) continue;
      const std::int32_t* ids = m.cell_points(static_cast<std::size_t>(c));
      CHECK(in_tetrahedron(x, point(m, ids[0]), point(m, ids[1]), point(m, ids[2]), point(m, ids[3])));
    }
    ++(contained ? inside : outside);
  }
  CHECK(inside > 1000);
  CHECK(outside > 500);
  // The same mesh gives the same bins.
  const CellLocator again(m);
  CHECK(again.leaf_count() == locator.leaf_count());
  CHECK(std::equal(v.leaf_cells, v.leaf_cells + v.leaf_cells_first[locator.leaf_count()],
                   again.view().leaf_cells));
}

TEST_CASE("the locator on hexahedra and on a mixed mesh: cells contain their points",
          "[mesh][locator]") {
  for (BoxCells kind : {BoxCells::hexahedra, BoxCells::mixed}) {
    const UnstructuredMesh m = box_mesh(Vec3(0, 0, 0), Vec3(1, 2, 1), {6, 9, 5}, kind,
                                        kind == BoxCells::hexahedra ? 0.2 : 0.0, 2);
    const auto g = std::make_shared<const MeshGeometry>(m, "mesh");
    const Linear f;
    const MeshField field(g, sample(m, f), "linear");
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> u(0, 1);
    for (int k = 0; k < 2000; ++k) {
      const Vec3 x(u(rng), 2 * u(rng), u(rng));
      Vec3 v;
      Mat3 J;
      REQUIRE(field.velocity_jacobian(x, v, J) == FieldStatus::inside);
      CHECK((v - f.at(x)).norm() <= 1e-5 * f.at(x).norm() + 1e-5);
      CHECK((J - f.B).norm() <= 1e-4 * f.B.norm());
      // The cell found maps its ξ back to x.
      double xi[3];
      const std::int32_t c = g->locate(x, xi);
      REQUIRE(c >= 0);
      double p[8][3], y[3], A[3][3];
      m.gather(static_cast<std::size_t>(c), p);
      cell::map_point(m.shapes[static_cast<std::size_t>(c)], p, xi, y, A);
      CHECK(Vec3(y[0], y[1], y[2]).isApprox(x, 1e-10));
    }
    Vec3 v;
    CHECK(field.velocity(Vec3(1.01, 1, 0.5), v) == FieldStatus::outside);
    CHECK(field.velocity(Vec3(0.5, -1e-3, 0.5), v) == FieldStatus::outside);
  }
}

TEST_CASE("a mesh one cell thick in z is a 2D case: v_z = 0, independent of z", "[mesh]") {
  const UnstructuredMesh m =
      box_mesh(Vec3(0, 0, -0.01), Vec3(2, 1, 0.01), {8, 4, 1}, BoxCells::hexahedra, 0.2, 4);
  const auto g = std::make_shared<const MeshGeometry>(m, "flat");
  REQUIRE(g->planar());
  CHECK(g->plane_z() == Approx(0).margin(1e-15));
  CHECK(g->domain().lo.z() == Approx(-1));  // ± half the larger of the x and y extents
  CHECK(g->domain().hi.z() == Approx(1));
  std::vector<float> values;
  for (std::size_t i = 0; i < m.point_count(); ++i) {
    values.push_back(static_cast<float>(1 + m.points[3 * i + 1]));
    values.push_back(static_cast<float>(-0.5 * m.points[3 * i]));
    values.push_back(0);
  }
  const MeshField field(g, values, "shear");
  Vec3 a, b;
  Mat3 J;
  REQUIRE(field.velocity_jacobian(Vec3(0.7, 0.3, 0.6), a, J) == FieldStatus::inside);
  REQUIRE(field.velocity(Vec3(0.7, 0.3, -0.9), b) == FieldStatus::inside);
  CHECK(a == b);
  CHECK(a.x() == Approx(1.3));
  CHECK(a.y() == Approx(-0.35));
  CHECK(a.z() == 0);
  CHECK(J.col(2).isZero());
  CHECK(J.row(2).isZero());
  CHECK(J(0, 1) == Approx(1));
  CHECK(field.velocity(Vec3(0.7, 0.3, 1.5), b) == FieldStatus::outside);

  // A "2D" case whose vectors have a z component is refused.
  values[2] = 0.5f;
  CHECK_THROWS_WITH(MeshField(g, values, "w"),
                    Catch::Contains("flat: the mesh is one cell thick in z (a 2D case)"));
}

TEST_CASE("mesh series: linear in time between steps, exact ∂v/∂t, NaN is no data", "[mesh]") {
  const UnstructuredMesh m =
      box_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1), {3, 3, 3}, BoxCells::tetrahedra, 0.1, 8);
  const auto g = std::make_shared<const MeshGeometry>(m, "series");
  const Linear f;
  std::vector<float> s0 = sample(m, f), s1 = s0;
  for (float& x : s1) x *= 3;  // v(t = 2) = 3 v(t = 0)
  MeshSeriesField series(g, {0.0, 2.0}, {s0, s1}, "two steps");
  CHECK(series.dimension() == 3);
  const Vec3 x(0.4, 0.6, 0.3);
  Vec3 v, dvdt;
  Mat3 J;
  REQUIRE(series.velocity_jacobian(x, 0.5, v, J, dvdt) == FieldStatus::inside);
  CHECK((v - 1.5 * f.at(x)).norm() <= 1e-5);
  CHECK((J - 1.5 * f.B).norm() <= 1e-4);
  CHECK((dvdt - f.at(x)).norm() <= 1e-5);
  CHECK(series.velocity(x, 2.0001, v) == FieldStatus::outside);
  CHECK(series.velocity(x, 2.0, v) == FieldStatus::inside);
  CHECK_THROWS_WITH(MeshSeriesField(g, {0.0, 0.0}, {s0, s1}, "bad"),
                    Catch::Contains("series: step times must increase strictly (step 1"));
  // A NaN at a point makes the cells around it no data.
  std::vector<float> holes = s0;
  const std::int32_t corner = m.cell_points(0)[0];
  holes[3 * static_cast<std::size_t>(corner)] = std::nanf("");
  const MeshField with_hole(g, holes, "hole");
  const Vec3 at = point(m, corner) * 0.9 + Vec3(0.05, 0.05, 0.05) * 0.1;
  CHECK(with_hole.velocity(point(m, corner) + Vec3(1e-3, 1e-3, 1e-3), v) == FieldStatus::no_data);
  (void)at;
}

TEST_CASE("stream surface on a tetrahedral mesh of saddle3d is as exact as the analytic one",
          "[mesh][engine]") {
  const auto saddle = make_analytic_field("saddle3d");
  const UnstructuredMesh m =
      box_mesh(Vec3(-4, -4, -4), Vec3(4, 4, 4), {16, 16, 16}, BoxCells::tetrahedra, 0.2, 6);
  std::vector<float> values;
  for (std::size_t i = 0; i < m.point_count(); ++i) {
    Vec3 v;
    REQUIRE(saddle->velocity(point(m, static_cast<std::int32_t>(i)), v) == FieldStatus::inside);
    for (int a = 0; a < 3; ++a) values.push_back(static_cast<float>(v[a]));
  }
  const MeshField field(std::make_shared<const MeshGeometry>(m, "tets"), values, "saddle on tets");
  const Seed<3> seed = make_seed(SeedCurve::line(Vec3(-1, 2, 0.1), Vec3(1, 2, 0.1)), 21);
  StreamSurfaceOptions options;
  options.edge = 0.1;
  options.max_steps = 60;
  const SurfaceResult exact = build_stream_surface(*saddle, seed, options);
  const SurfaceResult on_mesh = build_stream_surface<3>(field, seed, options);
  double worst = 0;
  for (const Vec3& p : on_mesh.mesh.positions) worst = std::max(worst, std::abs(p.y() * p.z() - 0.2));
  double worst_exact = 0;
  for (const Vec3& p : exact.mesh.positions) worst_exact = std::max(worst_exact, std::abs(p.y() * p.z() - 0.2));
  INFO("max |y z - 0.2|: analytic " << worst_exact << ", tetrahedra " << worst);
  REQUIRE(on_mesh.mesh.vertex_count() > 500);
  CHECK(worst <= std::max(2.0 * worst_exact, 1e-6));
  const double ratio = static_cast<double>(on_mesh.mesh.vertex_count()) /
                       static_cast<double>(exact.mesh.vertex_count());
  CHECK(ratio == Approx(1.0).margin(0.02));
}
