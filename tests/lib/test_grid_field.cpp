// Grid fields: exact reproduction of linear fields, convergence order, no-data handling, 2D
// grids, and stream surfaces on sampled data against the analytic fields they came from.
#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "orthofront/engine/stream_surface.h"
#include "orthofront/error.h"
#include "orthofront/field/analytic.h"
#include "orthofront/field/grid_field.h"
#include "orthofront/field/sample_field.h"
#include "orthofront/integrate/runge_kutta.h"
#include "orthofront/seed/seed.h"
#include "lib/grid_faces.h"

using namespace orthofront;

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

std::vector<Vec3> random_points(const Box<3>& box, int count, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Vec3> points;
  for (int i = 0; i < count; ++i) {
    Vec3 x;
    for (int a = 0; a < 3; ++a) x[a] = box.lo[a] + unit(rng) * (box.hi[a] - box.lo[a]);
    points.push_back(x);
  }
  return points;
}

std::shared_ptr<const VectorGrid> sampled(const Field3& field, std::int64_t nx, std::int64_t ny,
                                          std::int64_t nz) {
  SampleOptions options;
  options.resolution = {nx, ny, nz};
  return std::make_shared<const VectorGrid>(sample_field(field, options));
}

GridFieldOptions analytic_samples() {
  GridFieldOptions options;
  options.zero_is_no_data = false;  // zero vectors of sampled formulas are critical points
  return options;
}

// Rectilinear axis from lo to hi with uneven cells whose coordinates are exact in float
// (multiples of 1/64), so samples of a linear field carry no rounding error.
std::vector<double> uneven_axis(double lo, double hi, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> width(4, 40);  // 1/16 .. 5/8
  std::vector<double> axis{lo};
  while (axis.back() < hi) axis.push_back(std::min(hi, axis.back() + width(rng) / 64.0));
  return axis;
}

double saddle_surface_error(const Mesh& mesh, double c) {
  double worst = 0;
  for (const Vec3& p : mesh.positions) worst = std::max(worst, std::abs(p.y() * p.z() - c));
  return worst;
}

// Endpoint of a stream line integrated with fixed-step RK4 (the same steps in every field).
Vec3 stream_line_end(const Field3& field, const Vec3& x0, double tau) {
  const IntegrationResult<3> r = integrate_rk4(field, x0, tau, 400);
  REQUIRE(r.status == FieldStatus::inside);
  return r.x;
}

double max_velocity_difference(const Field3& a, const Field3& b, const std::vector<Vec3>& points) {
  double worst = 0;
  for (const Vec3& x : points) {
    Vec3 va, vb;
    REQUIRE(a.velocity(x, va) == FieldStatus::inside);
    REQUIRE(b.velocity(x, vb) == FieldStatus::inside);
    worst = std::max(worst, (va - vb).norm());
  }
  return worst;
}

std::string constructor_error(VectorGrid grid) {
  try {
    GridField field(std::make_shared<const VectorGrid>(std::move(grid)));
  } catch (const InvalidArgument& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("grid fields reproduce the linear saddle3d exactly, values and Jacobians", "[grid]") {
  const auto saddle = make_analytic_field("saddle3d");
  Box<3> box;
  box.lo = Vec3::Constant(-4);
  box.hi = Vec3::Constant(4);

  auto check = [&](const GridField& field) {
    for (const Vec3& x : random_points(box, 5000, 7)) {
      Vec3 v, ve, v_only;
      Mat3 J, Je;
      REQUIRE(field.velocity_jacobian(x, v, J) == FieldStatus::inside);
      REQUIRE(field.velocity(x, v_only) == FieldStatus::inside);
      saddle->velocity_jacobian(x, ve, Je);
      CHECK((v - ve).norm() <= 1e-12);
      CHECK((J - Je).norm() <= 1e-12);
      CHECK(v_only == v);
    }
    // Sample points and the corners of the box themselves.
    for (const Vec3& x : {Vec3(-4, -4, -4), Vec3(4, 4, 4), Vec3(0, 0, 0), Vec3(4, -4, 0.25)}) {
      Vec3 v, ve;
      Mat3 J, Je;
      REQUIRE(field.velocity_jacobian(x, v, J) == FieldStatus::inside);
      saddle->velocity_jacobian(x, ve, Je);
      CHECK((v - ve).norm() <= 1e-12);
      CHECK((J - Je).norm() <= 1e-12);
    }
  };

  SECTION("uniform") {
    // Spacing 0.25: every sample coordinate, hence every sample of v, is exact in float.
    const GridField field(sampled(*saddle, 33, 33, 33), analytic_samples());
    CHECK(field.domain().lo.isApprox(box.lo));
    CHECK(field.domain().hi.isApprox(box.hi));
    check(field);
  }
  SECTION("rectilinear") {
    VectorGrid grid;
    grid.geometry.dimension = 3;
    for (int a = 0; a < 3; ++a) {
      grid.geometry.axes[static_cast<std::size_t>(a)] = uneven_axis(-4, 4, 11u + a);
      grid.geometry.size[static_cast<std::size_t>(a)] =
          static_cast<std::int64_t>(grid.geometry.axes[static_cast<std::size_t>(a)].size());
    }
    grid.values.resize(grid.geometry.point_count() * 3);
    sample_field_into(*saddle, grid.geometry, 3, grid.values);
    const GridField field(std::make_shared<const VectorGrid>(std::move(grid)), analytic_samples());
    CHECK(field.grid().geometry.rectilinear());
    check(field);
  }
}

TEST_CASE("grid fields report outside beyond the bounds", "[grid]") {
  const auto saddle = make_analytic_field("saddle3d");
  const GridField field(sampled(*saddle, 9, 9, 9), analytic_samples());
  Vec3 v;
  Mat3 J;
  CHECK(field.velocity(Vec3(4.001, 0, 0), v) == FieldStatus::outside);
  CHECK(field.velocity(Vec3(0, -4.5, 0), v) == FieldStatus::outside);
  CHECK(field.velocity_jacobian(Vec3(0, 0, 9), v, J) == FieldStatus::outside);
  CHECK(field.velocity(Vec3(std::nan(""), 0, 0), v) == FieldStatus::outside);
  CHECK(field.velocity(Vec3(3.999, -3.999, 0), v) == FieldStatus::inside);
  CHECK(field.describe().find("uniform 9x9x9") != std::string::npos);
}

TEST_CASE("2D grids: v_z = 0, independent of z, a slab domain around the plane", "[grid]") {
  const auto saddle = make_analytic_field("saddle");  // v = (x, -y, 0) on [-3,3]^2 x [-1,1]
  const auto grid = sampled(*saddle, 25, 25, 1);      // spacing 0.25
  REQUIRE(grid->geometry.dimension == 2);
  REQUIRE(grid->components == 2);  // automatic: v_z vanishes in the plane
  CHECK(grid->geometry.origin.z() == 0.0);

  const GridField field(grid, analytic_samples());
  CHECK(field.domain().lo.z() == -3.0);  // half the larger extent (6) around z = 0
  CHECK(field.domain().hi.z() == 3.0);
  GridFieldOptions thin = analytic_samples();
  thin.slab_half_thickness = 0.5;
  CHECK(GridField(grid, thin).domain().hi.z() == 0.5);

  for (const Vec3& x : random_points(field.domain(), 2000, 3)) {
    Vec3 v, ve;
    Mat3 J, Je;
    REQUIRE(field.velocity_jacobian(x, v, J) == FieldStatus::inside);
    saddle->velocity_jacobian(Vec3(x.x(), x.y(), 0), ve, Je);
    CHECK((v - ve).norm() <= 1e-12);
    CHECK((J - Je).norm() <= 1e-12);
    CHECK(v.z() == 0.0);
    CHECK(J.col(2).isZero(0));
  }
  Vec3 v;
  CHECK(field.velocity(Vec3(0, 0, 3.5), v) == FieldStatus::outside);

  // Three components on a 2D grid: v_z is interpolated, still independent of z.
  SampleOptions three;
  three.resolution = {25, 25, 1};
  three.components = 3;
  const GridField field3(std::make_shared<const VectorGrid>(sample_field(*saddle, three)),
                         analytic_samples());
  Vec3 a, b;
  REQUIRE(field3.velocity(Vec3(0.3, 0.7, -1), a) == FieldStatus::inside);
  REQUIRE(field3.velocity(Vec3(0.3, 0.7, 2), b) == FieldStatus::inside);
  CHECK(a == b);
}

TEST_CASE("stream surface on sampled saddle3d is as exact as on the analytic field",
          "[grid][engine]") {
  const auto saddle = make_analytic_field("saddle3d");
  const GridField grid(sampled(*saddle, 81, 81, 81), analytic_samples());  // spacing 0.1
  const Seed<3> seed = make_seed(SeedCurve::line(Vec3(-1, 2, 0.1), Vec3(1, 2, 0.1)), 21);
  StreamSurfaceOptions options;
  options.edge = 0.1;
  options.max_steps = 60;
  const SurfaceResult exact = build_stream_surface(*saddle, seed, options);
  const SurfaceResult sampled_result = build_stream_surface<3>(grid, seed, options);
  const double error_exact = saddle_surface_error(exact.mesh, 0.2);
  const double error_grid = saddle_surface_error(sampled_result.mesh, 0.2);
  INFO("max |y z - 0.2|: analytic " << error_exact << ", grid " << error_grid);
  REQUIRE(sampled_result.mesh.vertex_count() > 500);
  // Both are at rounding level: the engine's own error on the analytic field, plus the float
  // rounding of the samples (~3e-8 relative) for the grid.
  CHECK(error_grid <= std::max(2.0 * error_exact, 1e-7));
  const double vertex_ratio = static_cast<double>(sampled_result.mesh.vertex_count()) /
                              static_cast<double>(exact.mesh.vertex_count());
  CHECK(vertex_ratio == Approx(1.0).margin(0.02));
}

TEST_CASE("sampled fields converge to the analytic field at second order", "[grid]") {
  SECTION("sinus (2D grid): halving the spacing cuts the difference ~4x") {
    const auto sinus = make_analytic_field("sinus");  // [-10,10] x [-1,12] x [-1,1]
    const GridField coarse(sampled(*sinus, 161, 105, 1), analytic_samples());  // h = 0.125
    const GridField fine(sampled(*sinus, 321, 209, 1), analytic_samples());    // h = 0.0625
    Box<3> inner = sinus->domain();
    inner.lo += Vec3(0.5, 0.5, 0.5);
    inner.hi -= Vec3(0.5, 0.5, 0.5);
    const auto points = random_points(inner, 20000, 5);
    const double d_coarse = max_velocity_difference(*sinus, coarse, points);
    const double d_fine = max_velocity_difference(*sinus, fine, points);
    INFO("max |v - v_grid|: h " << d_coarse << ", h/2 " << d_fine);
    CHECK(d_coarse / d_fine == Approx(4.0).margin(0.6));

    // Short stream lines (unit time, from several starts): end points converge at order 2 too.
    double e_coarse = 0, e_fine = 0;
    for (const Vec3& x0 : {Vec3(-3, 0.2, 0), Vec3(0.5, 1, 0), Vec3(2, 4, 0), Vec3(-1, 7, 0)}) {
      const Vec3 exact = stream_line_end(*sinus, x0, 1.0);
      e_coarse = std::max(e_coarse, (stream_line_end(coarse, x0, 1.0) - exact).norm());
      e_fine = std::max(e_fine, (stream_line_end(fine, x0, 1.0) - exact).norm());
    }
    INFO("stream-line end point: h " << e_coarse << ", h/2 " << e_fine);
    CHECK(e_coarse / e_fine == Approx(4.0).margin(1.0));
  }
  SECTION("abc (3D grid): halving the spacing cuts the difference ~4x") {
    const auto abc = make_analytic_field("abc");
    SampleOptions coarse_options, fine_options;
    Box<3> box;
    box.lo = Vec3::Constant(0);
    box.hi = Vec3::Constant(3.2);
    coarse_options.box = fine_options.box = box;
    coarse_options.resolution = {33, 33, 33};  // h = 0.1
    fine_options.resolution = {65, 65, 65};    // h = 0.05
    const GridField coarse(std::make_shared<const VectorGrid>(sample_field(*abc, coarse_options)),
                           analytic_samples());
    const GridField fine(std::make_shared<const VectorGrid>(sample_field(*abc, fine_options)),
                         analytic_samples());
    Box<3> inner = box;
    inner.lo += Vec3::Constant(0.5);
    inner.hi -= Vec3::Constant(0.5);
    const auto points = random_points(inner, 20000, 9);
    const double d_coarse = max_velocity_difference(*abc, coarse, points);
    const double d_fine = max_velocity_difference(*abc, fine, points);
    INFO("max |v - v_grid|: h " << d_coarse << ", h/2 " << d_fine);
    CHECK(d_coarse / d_fine == Approx(4.0).margin(0.6));
    const Vec3 x0(1.6, 1.6, 1.6);
    const Vec3 exact = stream_line_end(*abc, x0, 0.5);
    const double e_coarse = (stream_line_end(coarse, x0, 0.5) - exact).norm();
    const double e_fine = (stream_line_end(fine, x0, 0.5) - exact).norm();
    INFO("stream-line end point: h " << e_coarse << ", h/2 " << e_fine);
    CHECK(e_coarse / e_fine == Approx(4.0).margin(1.0));
  }
  SECTION("lorenz is multilinear: trilinear samples reproduce it up to float rounding") {
    const auto lorenz = make_analytic_field("lorenz");
    const GridField grid(sampled(*lorenz, 65, 65, 65), analytic_samples());
    Box<3> inner = lorenz->domain();
    const auto points = random_points(inner, 20000, 13);
    double worst = 0;
    for (const Vec3& x : points) {
      Vec3 v, ve;
      Mat3 J, Je;
      REQUIRE(grid.velocity_jacobian(x, v, J) == FieldStatus::inside);
      lorenz->velocity_jacobian(x, ve, Je);
      worst = std::max(worst, (v - ve).norm() / std::max(1.0, ve.norm()));
      CHECK((J - Je).norm() <= 1e-5 * std::max(1.0, Je.norm()) * 100);
    }
    CHECK(worst <= 1e-5);  // float samples: ~6e-8 relative per value
  }
}

TEST_CASE("NaN and zero corners give no_data, and an engine run across them stays finite",
          "[grid][nodata]") {
  const auto saddle = make_analytic_field("saddle3d");
  auto grid = std::make_shared<VectorGrid>(*sampled(*saddle, 81, 81, 81));  // spacing 0.1
  const GridGeometry& g = grid->geometry;

  SECTION("a NaN corner poisons exactly the 8 cells around it") {
    const std::size_t p = g.index(40, 60, 50);  // the sample at (0, 2, 1)
    grid->values[3 * p + 1] = kNaN;
    const GridField field(grid, analytic_samples());
    Vec3 v;
    Mat3 J;
    CHECK(field.velocity(Vec3(0.05, 2.05, 1.05), v) == FieldStatus::no_data);
    CHECK(field.velocity_jacobian(Vec3(-0.05, 1.95, 0.95), v, J) == FieldStatus::no_data);
    CHECK(field.velocity(Vec3(0.15, 2.05, 1.05), v) == FieldStatus::inside);
    CHECK(field.velocity(Vec3(0.05, 2.15, 1.05), v) == FieldStatus::inside);
  }
  SECTION("zero vectors: no data by default, data when switched off") {
    const std::size_t p = g.index(40, 60, 50);
    for (int c = 0; c < 3; ++c) grid->values[3 * p + static_cast<std::size_t>(c)] = 0.0f;
    Vec3 v;
    CHECK(GridField(grid).velocity(Vec3(0.05, 2.05, 1.05), v) == FieldStatus::no_data);
    CHECK(GridField(grid, analytic_samples()).velocity(Vec3(0.05, 2.05, 1.05), v) ==
          FieldStatus::inside);
  }
  SECTION("a stream surface through a NaN block") {
    // The surface y z = 0.2 from y = 2 sweeps towards y -> 0, z -> large; a NaN block across
    // its middle (|x| < 0.3, 0.5 < y < 1) must cut it cleanly.
    for (std::int64_t k = 0; k < g.size[2]; ++k)
      for (std::int64_t j = 0; j < g.size[1]; ++j)
        for (std::int64_t i = 0; i < g.size[0]; ++i) {
          const double x = g.coordinate(0, i), y = g.coordinate(1, j);
          if (std::abs(x) < 0.3 && y > 0.5 && y < 1.0) grid->values[3 * g.index(i, j, k)] = kNaN;
        }
    const GridField field(grid, analytic_samples());
    const Seed<3> seed = make_seed(SeedCurve::line(Vec3(-1, 2, 0.1), Vec3(1, 2, 0.1)), 21);
    StreamSurfaceOptions options;
    options.edge = 0.1;
    options.max_steps = 80;
    const SurfaceResult result = build_stream_surface<3>(field, seed, options);
    CHECK(result.report.no_data_hits > 0);
    REQUIRE(result.mesh.vertex_count() > 100);
    for (const Vec3& p : result.mesh.positions) REQUIRE(p.allFinite());
    for (const Face& f : result.mesh.faces)
      for (int c = 0; c < f.size; ++c) {
        REQUIRE(f.v[static_cast<std::size_t>(c)] >= 0);
        REQUIRE(static_cast<std::size_t>(f.v[static_cast<std::size_t>(c)]) <
                result.mesh.vertex_count());
      }
    // No vertex lies in a no-data cell.
    Vec3 v;
    for (const Vec3& p : result.mesh.positions) CHECK(field.velocity(p, v) == FieldStatus::inside);
    CHECK(saddle_surface_error(result.mesh, 0.2) < 0.01);
  }
}

TEST_CASE("no-data cells on 2D and rectilinear grids", "[grid][nodata]") {
  const auto saddle = make_analytic_field("saddle");
  auto grid = std::make_shared<VectorGrid>(*sampled(*saddle, 25, 25, 1));  // spacing 0.25, 2D
  const std::size_t p = grid->geometry.index(12, 16, 0);                   // (0, 1)
  grid->values[2 * p] = kNaN;
  Vec3 v;
  const GridField field(grid, analytic_samples());
  for (const Vec3& x :
       {Vec3(0.1, 1.1, 0), Vec3(-0.1, 1.1, 2), Vec3(0.1, 0.9, -2), Vec3(-0.1, 0.9, 0)})
    CHECK(field.velocity(x, v) == FieldStatus::no_data);
  CHECK(field.velocity(Vec3(0.3, 1.1, 0), v) == FieldStatus::inside);
  CHECK(field.velocity(Vec3(0.1, 1.3, 0), v) == FieldStatus::inside);

  VectorGrid rect;
  rect.geometry.dimension = 3;
  rect.geometry.axes = {std::vector<double>{0, 1, 3, 6}, std::vector<double>{0, 2, 3},
                        std::vector<double>{-1, 0, 5}};
  rect.geometry.size = {4, 3, 3};
  rect.values.assign(rect.geometry.point_count() * 3, 1.0f);
  rect.values[3 * rect.geometry.index(3, 2, 2) + 2] = std::numeric_limits<float>::infinity();
  const GridField rect_field(std::make_shared<const VectorGrid>(std::move(rect)));
  CHECK(rect_field.velocity(Vec3(5, 2.5, 4), v) == FieldStatus::no_data);  // last cell
  CHECK(rect_field.velocity(Vec3(2, 2.5, 4), v) == FieldStatus::inside);
  CHECK(v.isApprox(Vec3(1, 1, 1)));
}

TEST_CASE("GridField rejects inconsistent grids, naming the problem", "[grid]") {
  VectorGrid good;
  good.geometry.size = {2, 2, 2};
  good.values.assign(24, 1.0f);
  CHECK(constructor_error(good).empty());

  VectorGrid g = good;
  g.values.pop_back();
  CHECK_THAT(constructor_error(g), Catch::Contains("23 values"));
  g = good;
  g.components = 4;
  CHECK_THAT(constructor_error(g), Catch::Contains("components must be 2 or 3, got 4"));
  g = good;
  g.geometry.size = {1, 2, 2};
  g.values.resize(12);
  CHECK_THAT(constructor_error(g), Catch::Contains("along x"));
  g = good;
  g.geometry.spacing.y() = 0;
  CHECK_THAT(constructor_error(g), Catch::Contains("spacing along y"));
  g = good;
  g.geometry.axes = {std::vector<double>{0, 1}, std::vector<double>{0, 1},
                     std::vector<double>{1, 1}};
  CHECK_THAT(constructor_error(g), Catch::Contains("axis z"));
  g = good;
  g.geometry.dimension = 2;
  CHECK_THAT(constructor_error(g), Catch::Contains("1 sample along z, got 2"));
}

TEST_CASE("sample_field writes NaN outside the field and validates its input", "[grid]") {
  const auto saddle = make_analytic_field("saddle3d");
  SampleOptions options;
  options.resolution = {5, 5, 5};
  Box<3> box;
  box.lo = Vec3(0, 0, 0);
  box.hi = Vec3(8, 8, 8);  // beyond the domain [-4,4]^3
  options.box = box;
  const VectorGrid grid = sample_field(*saddle, options);
  CHECK(grid.components == 3);
  CHECK(grid.values[3 * grid.geometry.index(1, 1, 1)] == 2.0f);
  CHECK(std::isnan(grid.values[3 * grid.geometry.index(4, 1, 1)]));
  options.resolution = {5, 1, 5};
  CHECK_THROWS_WITH(sample_field(*saddle, options), Catch::Contains("along y must be at least 2"));
}

namespace {

void check_next_face(const GridGeometry& g, const Vec3& x, const Vec3& w, double after) {
  const double want = test::first_face_brute_force(g, x, w, after);
  const double got = g.next_cell_face(x, w, after);
  if (std::isinf(want))
    REQUIRE(std::isinf(got));
  else
    REQUIRE(got == Approx(want).epsilon(1e-12).margin(1e-15));
}

// A field that hides its kinks from the integrator: DOPRI5 steps across cell faces as before.
class WithoutKinks final : public Field3 {
 public:
  explicit WithoutKinks(const Field3& base) : base_(base) {}
  FieldStatus velocity(const Vec3& x, Vec3& v) const override { return base_.velocity(x, v); }
  FieldStatus velocity_jacobian(const Vec3& x, Vec3& v, Mat3& J) const override {
    return base_.velocity_jacobian(x, v, J);
  }
  Box<3> domain() const override { return base_.domain(); }
  std::string describe() const override { return base_.describe(); }

 private:
  const Field3& base_;
};

}  // namespace

TEST_CASE("cell faces: the first interior face a straight path crosses", "[grid][kinks]") {
  GridGeometry uniform;
  uniform.size = {9, 9, 9};
  uniform.origin = Vec3(-4, -4, -4);
  // Hand-made: faces at integers strictly inside [-4, 4].
  CHECK(uniform.next_cell_face(Vec3(0.25, 0.5, -3.5), Vec3(1, -2, 0), 0) == 0.25);
  CHECK(uniform.next_cell_face(Vec3(0.25, 0.5, -3.5), Vec3(1, -2, 0), 0.25) == 0.75);
  CHECK(std::isinf(uniform.next_cell_face(Vec3(3.5, 0, 0), Vec3(1, 0, 0), 0)));  // the bound
  CHECK(std::isinf(uniform.next_cell_face(Vec3(0.5, 0.5, 0.5), Vec3::Zero(), 0)));
  GridField field(std::make_shared<const VectorGrid>(
                      VectorGrid{uniform, 3, std::vector<float>(uniform.point_count() * 3, 1.0f)}),
                  analytic_samples());
  CHECK(field.next_kink(Vec3(0.25, 0.5, -3.5), Vec3(1, -2, 0), 0, 0.3) == 0.25);
  CHECK(std::isinf(field.next_kink(Vec3(0.25, 0.5, -3.5), Vec3(1, -2, 0), 0, 0.2)));

  GridGeometry rectilinear = uniform;
  for (int a = 0; a < 3; ++a) rectilinear.axes[static_cast<std::size_t>(a)] = uneven_axis(-1, 1.5, 3 + a);
  for (int a = 0; a < 3; ++a)
    rectilinear.size[static_cast<std::size_t>(a)] =
        static_cast<std::int64_t>(rectilinear.axes[static_cast<std::size_t>(a)].size());
  GridGeometry flat = uniform;  // 2D: no faces across z
  flat.dimension = 2;
  flat.size[2] = 1;
  CHECK(std::isinf(flat.next_cell_face(Vec3(0.5, 0.5, 0.5), Vec3(0, 0, 1), 0)));

  // Spacings and origins that are not binary fractions: (x - origin) / spacing on a face rounds
  // to either side of the face's index.
  GridGeometry decimal;
  decimal.size = {61, 23, 37};
  decimal.origin = Vec3(0.03, -1.1, 0.7);
  decimal.spacing = Vec3(0.1, 0.3, 0.07);
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(-1, 1);
  for (const GridGeometry* g : {&uniform, &rectilinear, &flat, &decimal}) {
    const Box<3> box = g->bounds();
    for (int i = 0; i < 3000; ++i) {
      Vec3 x = 0.5 * (box.lo + box.hi) + 0.6 * (box.hi - box.lo).cwiseProduct(Vec3(u(rng), u(rng), u(rng)));
      if (i % 2 == 0) {  // on a face of one axis, or of all three
        for (int a = 0; a < 3; ++a) {
          if (i % 4 == 0 && a != i % 3) continue;
          const std::int64_t n = g->size[static_cast<std::size_t>(a)];
          if (n > 2) x[a] = g->coordinate(a, 1 + static_cast<std::int64_t>((u(rng) + 1) * 0.5 * static_cast<double>(n - 3)));
        }
      }
      const Vec3 w(u(rng), i % 5 == 0 ? 0.0 : u(rng), i % 7 == 0 ? 0.0 : u(rng));
      const double after = i % 3 == 0 ? 0.0 : 0.3 * (u(rng) + 1);
      check_next_face(*g, x, w, after);
    }
  }
}

TEST_CASE("cell-aware DOPRI5 steps: the same stream lines for fewer evaluations",
          "[grid][kinks][integrate]") {
  // A nonlinear field on a coarse grid: its trilinear interpolant has kinks at every face.
  const auto abc = make_analytic_field("abc");
  const GridField grid(sampled(*abc, 17, 17, 17), analytic_samples());
  const WithoutKinks hidden(grid);
  const Tolerance tol{1e-9, 1e-9};
  std::mt19937_64 rng(23);
  const Box<3> box = grid.domain();
  const Box<3> inner{box.lo + 0.25 * (box.hi - box.lo), box.hi - 0.25 * (box.hi - box.lo)};
  long with_kinks = 0, without = 0, compared = 0;
  double worst_with = 0, worst_without = 0;
  for (const Vec3& x0 : random_points(inner, 40, 29)) {
    for (const double tau : {1.5, -1.5}) {
      const IntegrationResult<3> a = integrate_dopri5(grid, x0, tau, tol);
      const IntegrationResult<3> b = integrate_dopri5(hidden, x0, tau, tol);
      REQUIRE(a.status == b.status);
      if (a.status != FieldStatus::inside) continue;
      ++compared;
      // Against the interpolant's stream line: cell-aware steps are at least as close to it as
      // steps across the faces. The reference steps across faces (it knows nothing of them) at a
      // far tighter tolerance.
      const IntegrationResult<3> exact = integrate_dopri5(hidden, x0, tau, Tolerance{1e-13, 1e-13});
      REQUIRE(exact.status == FieldStatus::inside);
      const double error_with = (a.x - exact.x).norm(), error_without = (b.x - exact.x).norm();
      UNSCOPED_INFO("errors " << error_with << " " << error_without);
      worst_with = std::max(worst_with, error_with);
      worst_without = std::max(worst_without, error_without);
      with_kinks += a.evaluations;
      without += b.evaluations;
    }
  }
  REQUIRE(compared > 40);
  INFO("worst errors " << worst_with << " " << worst_without);
  CHECK(worst_with <= worst_without);
  CHECK(worst_with < 1e-6);
  INFO("evaluations with cell-aware steps " << with_kinks << ", without " << without);
  CHECK(static_cast<double>(with_kinks) < 0.8 * static_cast<double>(without));
}
