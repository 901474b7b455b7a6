// The α step on hand-made fronts in a uniform flow: an orthogonal front advances uniformly, a
// tilted one turns towards orthogonal, negative α is clamped and counted by cause.
#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "lib/uniform_field.h"
#include "orthofront/engine/alpha_step.h"

using namespace orthofront;

namespace {

/// n vertices from (0, 0, 0) along `direction`, spaced 0.1.
Front<3> straight_front(const Vec3& direction, int n) {
  Front<3> f;
  for (int i = 0; i < n; ++i) {
    FrontVertex<3> fv;
    fv.x = fv.anchor = 0.1 * i * direction.normalized();
    f.v.push_back(fv);
  }
  return f;
}

struct Setup {
  test::UniformField field;
  StreamSurfaceOptions options;
  Mesh mesh;
  SurfaceReport report;
  StepRecord record;
  AlphaStep<3> step{field, options, mesh, report, record};
  std::vector<Vec3> vel;
  std::vector<double> speed, alpha;
  std::vector<char> cut;

  AlphaStep<3>::Outcome solve(Front<3>& f) {
    const std::size_t n = f.v.size();
    vel.assign(n, Vec3(1, 0, 0));
    speed.assign(n, 1.0);
    alpha.assign(n, 1.0);
    cut.assign(n, 0);
    step.begin_step();
    return step.solve(f, vel, speed, alpha, cut);
  }
};

}  // namespace

TEST_CASE("an orthogonal front in a uniform flow advances uniformly", "[engine][alpha]") {
  Setup s;
  Front<3> f = straight_front(Vec3(0, 1, 0), 11);
  REQUIRE(s.solve(f) == AlphaStep<3>::Outcome::solved);
  for (const double a : s.alpha) CHECK(a == Approx(s.alpha[0]).epsilon(1e-12));
  CHECK(s.alpha[0] > 0);
  CHECK(s.step.orthogonality_mean() == Approx(0).margin(1e-15));
}

TEST_CASE("a tilted front turns towards orthogonal: the vertex ahead waits for the one behind",
          "[engine][alpha]") {
  Setup s;
  // Tilted by 30° from orthogonal: x grows along the front.
  const double tilt = 3.141592653589793 / 6;
  Front<3> f = straight_front(Vec3(std::sin(tilt), std::cos(tilt), 0), 11);
  REQUIRE(s.solve(f) == AlphaStep<3>::Outcome::solved);
  for (std::size_t i = 1; i < s.alpha.size(); ++i) CHECK(s.alpha[i] < s.alpha[i - 1]);
  CHECK(s.step.orthogonality_mean() == Approx(0.5).epsilon(1e-6));  // |cos 60°|
  CHECK(s.record.orthogonality_max == Approx(0.5).epsilon(1e-6));
}

TEST_CASE("negative alpha is clamped to 0 and counted by cause", "[engine][alpha]") {
  Setup s;
  Front<3> f = straight_front(Vec3(0, 1, 0), 5);
  std::vector<double> alpha{-1, 1, -0.5, 1, -2};
  std::vector<double> speed{1, 1, 1, 1, 1};
  s.step.clamp_negative(f, alpha, speed);
  CHECK(alpha == std::vector<double>{0, 1, 0, 1, 0});
  CHECK(s.report.negative_alpha == 3);
  CHECK(s.report.clamped_alpha == 3);
  CHECK(s.report.clamped_front_end == 2);
  CHECK(s.report.clamped_ahead == 1);
  std::vector<double> slow_alpha{1, -1, 1, 1, 1};
  std::vector<double> slow_speed{1, 0.001, 1, 1, 1};
  s.step.clamp_negative(f, slow_alpha, slow_speed);
  CHECK(s.report.clamped_slow_flow == 1);
  CHECK(s.report.clamped_alpha ==
        s.report.clamped_slow_flow + s.report.clamped_front_end + s.report.clamped_ahead +
            s.report.clamped_infeasible_step);
}
