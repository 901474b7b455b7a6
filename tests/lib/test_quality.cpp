#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <numbers>
#include <numeric>
#include <vector>

#include "orthofront/error.h"
#include "orthofront/quality/quality.h"

using namespace orthofront;

namespace {

std::int32_t add(Mesh& m, double x, double y, double z = 0) {
  return m.add_vertex(Vec3(x, y, z), 0, 0, 0, 0, 0, 0);
}

/// nx x ny quads on the vertices position(i, j), counter-clockwise seen from +z.
Mesh grid(int nx, int ny, const std::function<Vec3(int, int)>& position) {
  Mesh m;
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) m.add_vertex(position(i, j), 0, 0, 0, 0, 0, 0);
  }
  const auto id = [nx](int i, int j) { return j * (nx + 1) + i; };
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) m.add_quad(id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
  }
  return m;
}

Mesh unit_grid(int nx, int ny) {
  return grid(nx, ny, [](int i, int j) { return Vec3(i, j, 0); });
}

std::uint64_t total(const Histogram& h) {
  return std::accumulate(h.counts.begin(), h.counts.end(), std::uint64_t{0});
}

void check_valid(const QualityReport& r) {
  CHECK(r.folds == 0);
  CHECK(r.non_manifold_edges == 0);
  CHECK(r.inconsistent_edges == 0);
  CHECK(r.t_junctions == 0);
  CHECK(r.degenerate_faces == 0);
}

/// Big quad [0,2]^2 with two unit quads on its right side; the vertex (2, 1) lies on the big
/// quad's right edge. With `split`, the big quad becomes a quad and a triangle using (2, 1).
Mesh t_junction_mesh(bool split) {
  Mesh m;
  const auto v0 = add(m, 0, 0), v1 = add(m, 2, 0), v2 = add(m, 2, 2), v3 = add(m, 0, 2);
  const auto v4 = add(m, 2, 1), v5 = add(m, 3, 0), v6 = add(m, 3, 1), v7 = add(m, 3, 2);
  if (split) {
    m.add_quad(v0, v1, v4, v3);
    m.add_triangle(v3, v4, v2);
  } else {
    m.add_quad(v0, v1, v2, v3);
  }
  m.add_quad(v1, v5, v6, v4);
  m.add_quad(v4, v6, v7, v2);
  return m;
}

}  // namespace

TEST_CASE("quality: regular grid of unit squares is perfect", "[quality]") {
  QualityOptions options;
  options.angle_bins = 9;  // 20° bins: 90° falls mid-bin
  const auto r = measure_quality(unit_grid(10, 10), options);
  CHECK(r.vertices == 121);
  CHECK(r.faces == 100);
  CHECK(r.quads == 100);
  CHECK(r.triangles == 0);
  CHECK(r.measured_quads == 100);
  CHECK(r.quad_share == 1.0);
  CHECK(r.quad_angles_within_10 == 1.0);
  CHECK(r.quad_angle_mean_abs_dev == Approx(0).margin(1e-12));
  CHECK(r.quad_angle_abs_dev_p90 == Approx(0).margin(1e-12));
  CHECK(r.edge_spread_median == 0.0);
  CHECK(r.edge_spread_mean == 0.0);
  CHECK(r.edge_spread_p90 == 0.0);
  CHECK(r.boundary_edges == 40);
  check_valid(r);
  REQUIRE(r.quad_angles.counts.size() == 9);
  CHECK(r.quad_angles.counts[4] == 400);
  REQUIRE(r.edge_ratio.counts.size() == 40);
  CHECK(r.edge_ratio.counts[20] == 400);  // ratio 0 on [-1, 1]
  CHECK(total(r.quad_angles) == 400);
  CHECK(total(r.edge_ratio) == 400);
  CHECK(r.triangle_min_angle.counts.size() == 18);
  CHECK(total(r.triangle_min_angle) == 0);
}

TEST_CASE("quality: sheared grid has 60 and 120 degree angles", "[quality]") {
  const double c = std::cos(std::numbers::pi / 3), s = std::sin(std::numbers::pi / 3);
  QualityOptions options;
  options.angle_bins = 4;  // 45° bins: 60° in bin 1, 120° in bin 2
  const auto r = measure_quality(
      grid(10, 10, [&](int i, int j) { return Vec3(i + j * c, j * s, 0); }), options);
  CHECK(r.quad_angles_within_10 == 0.0);
  CHECK(r.quad_angle_mean_abs_dev == Approx(30).epsilon(1e-12));
  CHECK(r.quad_angle_abs_dev_p90 == Approx(30).epsilon(1e-12));
  CHECK(r.edge_spread_median == Approx(0).margin(1e-12));
  CHECK(r.quad_angles.counts == std::vector<std::uint64_t>{0, 200, 200, 0});
  CHECK(r.boundary_edges == 40);
  check_valid(r);
}

TEST_CASE("quality: 2 x 1 rectangles have edge spread 1/3", "[quality]") {
  const auto r = measure_quality(grid(4, 3, [](int i, int j) { return Vec3(2.0 * i, j, 0); }));
  CHECK(r.quad_angles_within_10 == 1.0);
  CHECK(r.edge_spread_median == Approx(1.0 / 3).epsilon(1e-12));
  CHECK(r.edge_spread_mean == Approx(1.0 / 3).epsilon(1e-12));
  CHECK(r.edge_spread_p90 == Approx(1.0 / 3).epsilon(1e-12));
  // 1 - 2/1.5 = -1/3 -> bin 13, 1 - 1/1.5 = 1/3 -> bin 26 of 40 over [-1, 1].
  CHECK(r.edge_ratio.counts[13] == 24);
  CHECK(r.edge_ratio.counts[26] == 24);
  CHECK(total(r.edge_ratio) == 48);
  check_valid(r);
}

TEST_CASE("quality: edge ratio keeps its sign in the histogram", "[quality]") {
  // Trapezoid with edges 4, sqrt 2, 2, sqrt 2 (mean 2.207): ratios -0.812, 0.359 (twice), 0.094.
  Mesh m;
  m.add_quad(add(m, 0, 0), add(m, 4, 0), add(m, 3, 1), add(m, 1, 1));
  const auto r = measure_quality(m);
  CHECK(r.edge_ratio.counts[3] == 1);
  CHECK(r.edge_ratio.counts[27] == 2);
  CHECK(r.edge_ratio.counts[21] == 1);
  CHECK(r.edge_spread_median == Approx(1 - std::sqrt(2.0) / (1.5 + std::sqrt(0.5))));
}

TEST_CASE("quality: edge spread median of an even count averages the middle values", "[quality]") {
  // A 2 x 1 rectangle (four values 1/3) and a unit square (four values 0), not touching.
  Mesh m;
  m.add_quad(add(m, 0, 0), add(m, 2, 0), add(m, 2, 1), add(m, 0, 1));
  m.add_quad(add(m, 5, 0), add(m, 6, 0), add(m, 6, 1), add(m, 5, 1));
  const auto r = measure_quality(m);
  CHECK(r.edge_spread_median == Approx(1.0 / 6).epsilon(1e-12));
  CHECK(r.edge_spread_mean == Approx(1.0 / 6).epsilon(1e-12));
  CHECK(r.edge_spread_p90 == Approx(1.0 / 3).epsilon(1e-12));
}

TEST_CASE("quality: mixed mesh reports triangle minimum angles", "[quality]") {
  Mesh m = unit_grid(2, 1);
  const double r3 = std::sqrt(3.0);
  // Minimum angles 30°, 45°, 60° and atan(0.1) = 5.71°, apart from each other and the quads.
  m.add_triangle(add(m, 10, 0), add(m, 10 + r3, 0), add(m, 10, 1));
  m.add_triangle(add(m, 20, 0), add(m, 21, 0), add(m, 20, 1));
  m.add_triangle(add(m, 30, 0), add(m, 31, 0), add(m, 30.5, r3 / 2));
  m.add_triangle(add(m, 40, 0), add(m, 41, 0), add(m, 41, 0.1));
  const auto r = measure_quality(m);
  CHECK(r.quads == 2);
  CHECK(r.triangles == 4);
  CHECK(r.measured_triangles == 4);
  CHECK(r.quad_share == Approx(2.0 / 6));
  CHECK(r.triangle_min_angle_median == Approx(37.5).epsilon(1e-12));
  CHECK(r.triangles_below_10deg == 0.25);
  CHECK(r.triangle_min_angle.counts[1] == 1);  // 5.71° in [5°, 10°)
  CHECK(r.triangle_min_angle.counts[0] == 0);
  CHECK(total(r.triangle_min_angle) == 4);
  CHECK(r.quad_angles_within_10 == 1.0);
  CHECK(r.boundary_edges == 6 + 12);
  check_valid(r);
}

TEST_CASE("quality: a flipped face gives inconsistent edges but no fold", "[quality]") {
  Mesh m = unit_grid(3, 3);
  Face& center = m.faces[4];
  std::swap(center.v[1], center.v[3]);
  const auto r = measure_quality(m);
  CHECK(r.inconsistent_edges == 4);
  CHECK(r.folds == 0);
  CHECK(r.boundary_edges == 12);
  CHECK(r.non_manifold_edges == 0);
  CHECK(r.quad_angles_within_10 == 1.0);
}

TEST_CASE("quality: a face folded back over its neighbour is a fold", "[quality]") {
  // Quad A in z = 0, quad B on A's edge x = 1; consistently oriented.
  const auto two_quads = [](double x_far, double z_far) {
    Mesh m;
    const auto v0 = add(m, 0, 0), v1 = add(m, 1, 0), v2 = add(m, 1, 1), v3 = add(m, 0, 1);
    const auto v4 = add(m, x_far, 0, z_far), v5 = add(m, x_far, 1, z_far);
    m.add_quad(v0, v1, v2, v3);
    m.add_quad(v1, v4, v5, v2);
    return m;
  };
  const auto flat = measure_quality(two_quads(2, 0));
  CHECK(flat.folds == 0);
  CHECK(flat.inconsistent_edges == 0);
  const auto folded = measure_quality(two_quads(0.5, 0.1));
  CHECK(folded.folds == 1);
  CHECK(folded.inconsistent_edges == 0);
  CHECK(folded.boundary_edges == 6);

  // A right-angle bend is a fold only for a stricter fold_cos.
  const Mesh bent = two_quads(1, 1);
  CHECK(measure_quality(bent).folds == 0);
  QualityOptions strict;
  strict.fold_cos = 0.5;
  CHECK(measure_quality(bent, strict).folds == 1);
}

TEST_CASE("quality: three faces on one edge make it non-manifold", "[quality]") {
  Mesh m;
  const auto v0 = add(m, 0, 0, 0), v1 = add(m, 0, 1, 0);
  for (int k = 0; k < 3; ++k) {
    const double theta = 2 * std::numbers::pi * k / 3;
    const double x = std::cos(theta), z = std::sin(theta);
    const auto a = add(m, x, 0, z), b = add(m, x, 1, z);
    m.add_quad(v0, a, b, v1);
  }
  const auto r = measure_quality(m);
  CHECK(r.non_manifold_edges == 1);
  CHECK(r.boundary_edges == 9);
  CHECK(r.folds == 0);
  CHECK(r.inconsistent_edges == 0);
  CHECK(r.t_junctions == 0);
}

TEST_CASE("quality: T-junction on a big quad's edge", "[quality]") {
  const auto r = measure_quality(t_junction_mesh(false));
  CHECK(r.t_junctions == 1);
  CHECK(r.boundary_edges == 10);
  CHECK(r.inconsistent_edges == 0);

  const auto fixed = measure_quality(t_junction_mesh(true));
  CHECK(fixed.t_junctions == 0);
  CHECK(fixed.boundary_edges == 7);
  check_valid(fixed);
}

TEST_CASE("quality: T-junction found after rotation, translation and scaling", "[quality]") {
  const Mat3 rotation = (Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized())).toRotationMatrix();
  const Vec3 shift(1e3, -50, 7);
  for (double scale : {1e-4, 1.0, 1e4}) {
    Mesh m = t_junction_mesh(false);
    for (auto& x : m.positions) x = rotation * (scale * x) + scale * shift;
    CHECK(measure_quality(m).t_junctions == 1);
    // Moved off the edge by a thousandth of its length: no longer a T-junction.
    m.positions[4] += rotation * Vec3(-2e-3 * scale, 0, 0);
    CHECK(measure_quality(m).t_junctions == 0);
  }
}

TEST_CASE("quality: T-junctions along a grid's boundary", "[quality]") {
  // A 20 x 20 grid next to a 10 x 10 grid of double-size squares sharing the line x = 20 only
  // at the big squares' corners: the 10 fine vertices between them are T-junctions.
  Mesh m = unit_grid(20, 20);
  const Mesh coarse = grid(10, 10, [](int i, int j) { return Vec3(20 + 2.0 * i, 2.0 * j, 0); });
  const auto offset = static_cast<std::int32_t>(m.positions.size());
  for (const auto& x : coarse.positions) m.add_vertex(x, 0, 0, 0, 0, 0, 0);
  for (Face f : coarse.faces) {
    for (auto& v : f.v) v += offset;
    m.faces.push_back(f);
  }
  const auto r = measure_quality(m);
  CHECK(r.t_junctions == 10);
  CHECK(r.folds == 0);
  CHECK(r.non_manifold_edges == 0);
}

TEST_CASE("quality: degenerate faces", "[quality]") {
  Mesh m;
  const auto a = add(m, 0, 0), b = add(m, 1, 0), c = add(m, 1, 1);
  m.add_quad(a, b, b, c);  // repeated index
  const auto r = measure_quality(m);
  CHECK(r.degenerate_faces == 1);
  CHECK(r.boundary_edges == 3);  // no self-loop edge
  CHECK(r.measured_quads == 0);  // no angles for a zero-length edge
  CHECK(total(r.quad_angles) == 0);
  CHECK(r.longest_edge == std::sqrt(2.0));  // c to a: a face left out of the shapes still counts

  Mesh line;
  line.add_triangle(add(line, 0, 0), add(line, 1, 0), add(line, 2, 0));  // zero area
  line.add_triangle(add(line, 5, 0), add(line, 6, 0), add(line, 5, 1));  // fine
  const auto rl = measure_quality(line);
  CHECK(rl.degenerate_faces == 1);
  CHECK(rl.longest_edge == 2.0);  // the zero-area triangle's
  CHECK(rl.triangle_min_angle_median == Approx(22.5));  // min angles 0° and 45°

  // A straight angle at a corner still leaves the quad its area (normal from the diagonals).
  Mesh straight;
  straight.add_quad(add(straight, 0, 0), add(straight, 1, 0), add(straight, 1, 1),
                    add(straight, -1, 0));
  CHECK(measure_quality(straight).degenerate_faces == 0);

  // The area threshold is relative to the edge lengths: a tiny, well-shaped mesh is fine.
  const Mesh tiny = grid(2, 2, [](int i, int j) { return Vec3(1e-8 * i, 1e-8 * j, 0); });
  CHECK(measure_quality(tiny).degenerate_faces == 0);

  // ... relative to the face's own edges: a tiny, well-shaped face among large ones is fine too
  // (a face near a critical point), a needle of the same area is not.
  Mesh mixed = grid(4, 4, [](int i, int j) { return Vec3(i, j, 0); });
  mixed.add_triangle(add(mixed, 10, 0), add(mixed, 10 + 1e-7, 0), add(mixed, 10, 1e-7));
  mixed.add_triangle(add(mixed, 20, 0), add(mixed, 21, 0), add(mixed, 20.5, 1e-14));
  CHECK(measure_quality(mixed).degenerate_faces == 1);

  Mesh thin;
  thin.add_triangle(add(thin, 0, 0), add(thin, 1, 0), add(thin, 0.5, 1e-7));
  CHECK(measure_quality(thin).degenerate_faces == 0);
  QualityOptions options;
  options.degenerate_area = 1e-6;
  CHECK(measure_quality(thin, options).degenerate_faces == 1);

  // Faces whose area vector is too large to square are whole faces, not degenerate ones (their
  // normals cannot be measured, so they take no part in folds either).
  const Mesh huge = grid(3, 3, [](int i, int j) { return Vec3(1e100 * i, 1e100 * j, 0); });
  const auto rh = measure_quality(huge);
  CHECK(rh.degenerate_faces == 0);
  CHECK(rh.folds == 0);
  CHECK(rh.quads == 9);
}

TEST_CASE("quality: histogram totals match the measured counts", "[quality]") {
  // Jittered grid with two quads cut into triangles and one quad with a straight angle.
  Mesh m = grid(8, 6, [](int i, int j) {
    return Vec3(i + 0.2 * std::sin(3.0 * i + j), j + 0.2 * std::cos(i - 2.0 * j), 0.1 * i * j);
  });
  for (int k : {5, 17}) {
    const Face q = m.faces[k];
    m.faces[k] = Face{{q.v[0], q.v[1], q.v[2], -1}, 3};
    m.add_triangle(q.v[0], q.v[2], q.v[3]);
  }
  m.add_quad(add(m, 100, 0), add(m, 101, 0), add(m, 102, 0), add(m, 101, 1));
  const auto r = measure_quality(m);
  CHECK(r.quads == 47);
  CHECK(r.triangles == 4);
  CHECK(r.measured_quads == r.quads);
  CHECK(r.measured_triangles == r.triangles);
  CHECK(total(r.quad_angles) == 4 * r.quads);
  CHECK(total(r.edge_ratio) == 4 * r.quads);
  CHECK(total(r.triangle_min_angle) == r.triangles);
  CHECK(r.quad_angles.counts.back() >= 1);  // 180° lands in the last bin
  CHECK(r.quad_angles_within_10 > 0.0);
  CHECK(r.quad_angles_within_10 < 1.0);
  CHECK(r.non_manifold_edges == 0);
  CHECK(r.inconsistent_edges == 0);
}

TEST_CASE("quality: invalid faces are rejected", "[quality]") {
  Mesh m = unit_grid(1, 1);
  m.add_triangle(0, 1, 7);
  CHECK_THROWS_AS(measure_quality(m), InvalidArgument);
  Mesh bad_size = unit_grid(1, 1);
  bad_size.faces[0].size = 5;
  CHECK_THROWS_AS(measure_quality(bad_size), InvalidArgument);
}

TEST_CASE("quality: empty mesh", "[quality]") {
  const auto r = measure_quality(Mesh{});
  CHECK(r.faces == 0);
  CHECK(r.quad_share == 0.0);
  CHECK(r.boundary_edges == 0);
  CHECK(total(r.quad_angles) == 0);
}

TEST_CASE("quality: 300k-vertex grid", "[quality][slow]") {
  const auto r = measure_quality(grid(549, 549, [](int i, int j) {
    return Vec3(i, j, 0.01 * std::sin(0.1 * i) * std::cos(0.1 * j));
  }));
  CHECK(r.vertices == 550 * 550);
  CHECK(r.quads == 549 * 549);
  CHECK(r.boundary_edges == 4 * 549);
  CHECK(r.quad_angles_within_10 == 1.0);
  check_valid(r);
}

TEST_CASE("quality: order statistics and means of over a million values (the parallel selection) "
          "are those of the sorted values",
          "[quality]") {
  // Angle deviations and edge ratios of a perturbed grid, recomputed here face by face.
  const auto jitter = [](int i, int j) {
    return Vec3(i + 0.3 * std::sin(0.7 * i + 1.3 * j), j + 0.3 * std::cos(1.1 * i - 0.4 * j),
                0.2 * std::sin(0.05 * i * j));
  };
  const auto angle = [](const Vec3& u, const Vec3& w) {
    return std::atan2(u.cross(w).norm(), u.dot(w)) * 180.0 / std::numbers::pi;
  };
  const auto quantile = [](std::vector<double> v, double q) {
    std::sort(v.begin(), v.end());
    const double pos = q * static_cast<double>(v.size() - 1);
    const auto k = static_cast<std::size_t>(pos);
    return k + 1 < v.size() ? v[k] + (pos - static_cast<double>(k)) * (v[k + 1] - v[k]) : v[k];
  };
  {
    const Mesh m = grid(600, 450, jitter);  // 270,000 quads: 1,080,000 corners
    std::vector<double> dev, spread;
    double dev_sum = 0, spread_sum = 0, longest = 0;
    for (const Face& f : m.faces) {
      std::array<Vec3, 4> e;
      double length[4], avg = 0;
      for (int i = 0; i < 4; ++i) {
        e[i] = m.positions[f.v[(i + 1) % 4]] - m.positions[f.v[i]];
        length[i] = e[i].norm();
        longest = std::max(longest, length[i]);
        avg += 0.25 * length[i];
      }
      for (int i = 0; i < 4; ++i) {
        dev.push_back(std::abs(angle(-e[(i + 3) % 4], e[i]) - 90));
        spread.push_back(std::abs(1 - length[i] / avg));
        dev_sum += dev.back();
        spread_sum += spread.back();
      }
    }
    REQUIRE(dev.size() > (std::size_t{1} << 20));
    const QualityReport r = measure_quality(m);
    CHECK(r.quad_angle_abs_dev_p90 == Approx(quantile(dev, 0.9)).epsilon(1e-12));
    CHECK(r.edge_spread_median == Approx(quantile(spread, 0.5)).epsilon(1e-12));
    CHECK(r.edge_spread_p90 == Approx(quantile(spread, 0.9)).epsilon(1e-12));
    CHECK(r.quad_angle_mean_abs_dev == Approx(dev_sum / static_cast<double>(dev.size())).epsilon(1e-12));
    CHECK(r.edge_spread_mean == Approx(spread_sum / static_cast<double>(spread.size())).epsilon(1e-12));
    CHECK(r.longest_edge == longest);
  }
  {
    // 1,100,000 triangles: two per cell.
    Mesh m;
    const int nx = 1000, ny = 550;
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) m.add_vertex(jitter(i, j), 0, 0, 0, 0, 0, 0);
    const auto id = [&](int i, int j) { return j * (nx + 1) + i; };
    std::vector<double> smallest;
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        m.faces.push_back(Face{{id(i, j), id(i + 1, j), id(i + 1, j + 1), -1}, 3});
        m.faces.push_back(Face{{id(i, j), id(i + 1, j + 1), id(i, j + 1), -1}, 3});
      }
    for (const Face& f : m.faces) {
      std::array<Vec3, 3> e;
      for (int i = 0; i < 3; ++i) e[i] = m.positions[f.v[(i + 1) % 3]] - m.positions[f.v[i]];
      double least = 180;
      for (int i = 0; i < 3; ++i) least = std::min(least, angle(-e[(i + 2) % 3], e[i]));  // at corner i
      smallest.push_back(least);
    }
    REQUIRE(smallest.size() > (std::size_t{1} << 20));
    const QualityReport r = measure_quality(m);
    CHECK(r.triangle_min_angle_median == Approx(quantile(smallest, 0.5)).epsilon(1e-12));
  }
}
