// Fronts that stop advancing: vertices that kept their mesh vertex for stall_steps steps leave the
// front, and a front running into a no-slip wall of zero vectors (how real data marks solids)
// gives a valid surface without folds.
#include <catch2/catch.hpp>
#include <cmath>
#include <memory>

#include "orthofront/engine/stream_surface.h"
#include "orthofront/field/analytic.h"
#include "orthofront/field/grid_field.h"
#include "orthofront/field/sample_field.h"
#include "orthofront/seed/seed.h"
#include "lib/surface_checks.h"

using namespace orthofront;
using orthofront::test_support::require_valid;

namespace {

/// Stagnation flow onto a no-slip wall at y = 0: v = (2 x y, -y², 0) above it (divergence free,
/// zero on the wall), exactly zero inside it (y <= 0).
class WallStagnation final : public Field3 {
 public:
  FieldStatus velocity(const Vec3& x, Vec3& v) const override {
    const double y = std::max(x.y(), 0.0);
    v = Vec3(2 * x.x() * y, -y * y, 0);
    return FieldStatus::inside;
  }
  FieldStatus velocity_jacobian(const Vec3& x, Vec3& v, Mat3& j) const override {
    velocity(x, v);
    j.setZero();
    if (x.y() > 0) {
      j(0, 0) = 2 * x.y();
      j(0, 1) = 2 * x.x();
      j(1, 1) = -2 * x.y();
    }
    return FieldStatus::inside;
  }
  Box<3> domain() const override { return Box<3>{Vec3(-2, -0.5, -0.5), Vec3(2, 1.5, 0.5)}; }
  std::string describe() const override { return "wall stagnation"; }
};

}  // namespace

TEST_CASE("a front running into a no-slip wall of zero vectors folds nowhere",
          "[engine][fold][stall]") {
  SampleOptions sampling;
  sampling.resolution = {41, 41, 11};
  const auto grid = std::make_shared<const VectorGrid>(sample_field(WallStagnation(), sampling));
  const GridField field(grid);  // zero vectors mark the wall's cells as no data, as in real data
  // Tilted across z so the surface is not a plane.
  const Seed<3> seed =
      make_seed(SeedCurve::line(Vec3(-1, 1.2, -0.3), Vec3(1, 1.2, 0.3)), 21);
  StreamSurfaceOptions o;
  o.edge = 0.05;
  o.max_steps = 600;
  const SurfaceResult r = build_stream_surface<3>(field, seed, o);
  INFO("vertices " << r.report.vertices << ", steps " << r.report.steps << ", stall cuts "
                   << r.report.stall_cuts << ", no-data hits " << r.report.no_data_hits
                   << ", fold rips " << r.report.fold_rips);
  CHECK(r.report.vertices > 2000);
  // The front reaches the wall's cells: they cut it.
  CHECK(r.report.no_data_hits > 0);
  require_valid(r);
  CHECK(r.report.folds_left == 0);
}

TEST_CASE("vertices that stop advancing leave the front, the surface stays valid",
          "[engine][stall]") {
  // The planar saddle (the bench's row): the front halves stall at the stagnation point, where
  // the surface rips.
  const auto saddle = make_analytic_field("saddle");
  const Seed<3> seed = make_seed(SeedCurve::line(Vec3(-1, 1, 0), Vec3(1, 1, 0)), 20);
  StreamSurfaceOptions o;
  o.edge = 0.02;
  o.max_steps = 240;
  o.stall_steps = 0;
  const SurfaceResult kept = build_stream_surface<3>(*saddle, seed, o);
  CHECK(kept.report.stall_cuts == 0);
  require_valid(kept);

  for (const int window : {50, 10}) {
    o.stall_steps = window;
    const SurfaceResult cut = build_stream_surface<3>(*saddle, seed, o);
    INFO("window " << window << ": " << cut.report.stall_cuts << " cuts, "
                   << cut.report.skipped_vertex_steps << " of " << cut.report.vertex_steps
                   << " vertex-steps skipped (" << kept.report.skipped_vertex_steps << " of "
                   << kept.report.vertex_steps << " without)");
    CHECK(cut.report.stall_cuts >= 1);
    require_valid(cut);
    // Fewer vertex-steps spent on vertices that wait.
    CHECK(cut.report.skipped_vertex_steps < kept.report.skipped_vertex_steps);
    // No mesh vertex was kept by a front vertex for longer than the window: every face joins
    // rows at most window + 1 steps apart.
    int widest = 0;
    for (const Face& f : cut.mesh.faces) {
      int lo = 1 << 30, hi = -1;
      for (int c = 0; c < f.size; ++c) {
        const int s = cut.mesh.step[static_cast<std::size_t>(f.v[static_cast<std::size_t>(c)])];
        lo = std::min(lo, s);
        hi = std::max(hi, s);
      }
      widest = std::max(widest, hi - lo);
    }
    CHECK(widest <= window + 1);
  }
}

namespace {

/// WallStagnation with NaN velocities (inside the domain) beyond x = 1.2: a defective field.
class NanBeyond final : public Field3 {
 public:
  FieldStatus velocity(const Vec3& x, Vec3& v) const override {
    wall_.velocity(x, v);
    if (x.x() > 1.2) v = Vec3::Constant(std::nan(""));
    return FieldStatus::inside;
  }
  FieldStatus velocity_jacobian(const Vec3& x, Vec3& v, Mat3& j) const override {
    wall_.velocity_jacobian(x, v, j);
    if (x.x() > 1.2) v = Vec3::Constant(std::nan(""));
    return FieldStatus::inside;
  }
  Box<3> domain() const override { return wall_.domain(); }
  std::string describe() const override { return "wall stagnation, NaN beyond x = 1.2"; }

 private:
  WallStagnation wall_;
};

}  // namespace

TEST_CASE("vertices without flow (zero or NaN velocity) leave the front", "[engine][stall]") {
  StreamSurfaceOptions o;
  o.edge = 0.05;
  o.max_steps = 40;
  // Seed vertices on and inside the wall (y <= 0) have exactly zero velocity: the first step
  // cuts them (and only them) from the front.
  const Seed<3> across = make_seed(SeedCurve::line(Vec3(-1, 1, 0), Vec3(-1, -0.45, 0)), 30);
  std::size_t in_wall = 0;
  for (const double s : across.parameters) in_wall += across.point(s).y() <= 0 ? 1 : 0;
  REQUIRE(in_wall > 3);
  const SurfaceResult wall = build_stream_surface<3>(WallStagnation(), across, o);
  CHECK(wall.report.zero_velocity_cuts >= in_wall);
  require_valid(wall);
  // NaN velocities count as no flow too (the median test's answer), not as fast flow.
  const Seed<3> along = make_seed(SeedCurve::line(Vec3(0.5, 1, 0), Vec3(1.45, 1, 0)), 20);
  std::size_t in_nan = 0;
  for (const double s : along.parameters) in_nan += along.point(s).x() > 1.2 ? 1 : 0;
  REQUIRE(in_nan > 2);
  const SurfaceResult nan = build_stream_surface<3>(NanBeyond(), along, o);
  CHECK(nan.report.zero_velocity_cuts >= in_nan);
  require_valid(nan);
}
