#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>

#include "orthofront/field/unsteady.h"
#include "spacetime/reference_path.h"
#include "orthofront/quality/quality.h"
#include "orthofront/spacetime/spacetime_streak.h"
#include "orthofront/spacetime/streak_surface.h"

using namespace orthofront;
using namespace orthofront::spacetime;
using streak_test::reference_path;

namespace {


double distance_to_polyline(const Vec3& p, const std::vector<Vec3>& line) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i + 1 < line.size(); ++i) {
    const Vec3 a = line[i], d = line[i + 1] - line[i];
    const double w = d.squaredNorm() > 0 ? std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
    best = std::min(best, (a + w * d - p).norm());
  }
  return best;
}

}  // namespace

TEST_CASE("space-time streak surface: the flow-orthogonal route agrees with the direct route "
          "(double gyre)", "[spacetime][streak]") {
  const auto flow = make_unsteady_field("double-gyre");
  const Vec3 x0(0.3, 0.35, 0);
  SpacetimeStreakOptions o;
  o.release_begin = 0;
  o.release_end = 4;
  o.t_end = 6;
  o.engine.edge = 0.01;
  o.engine.max_steps = 100000;
  const SpacetimeStreakResult st = build_spacetime_streak_surface(*flow, x0, o);
  // Quality where the engine made the fronts orthogonal: in (x, y, c t).
  const QualityReport& q = st.report.quality;
  INFO("space-time surface: " << st.mesh.vertex_count() << " vertices, c = " << st.time_scale
                              << ", quads " << q.quad_share << ", within 10 deg "
                              << q.quad_angles_within_10);
  CHECK(q.non_manifold_edges == 0);
  CHECK(q.t_junctions == 0);
  CHECK(q.quad_share > 0.9);
  CHECK(q.quad_angles_within_10 > 0.8);
  // Each vertex lies on the path line that left x0 at its release time.
  double worst = 0;
  for (std::size_t i = 0; i < st.mesh.vertex_count(); i += 5) {
    const Vec3& p = st.mesh.positions[i];
    const Vec3 ref = reference_path(*flow, x0, release_time(o, st.mesh.s[i]), p.z());
    worst = std::max(worst, (Vec3(p.x(), p.y(), 0) - ref).norm());
  }
  INFO("worst distance to its own path line " << worst);
  CHECK(worst < 1e-6);

  // The direct route from a point (a seed segment of length 1e-9): rows of two coincident
  // particles, refined across rows, give the streak line at each frame.
  StreakOptions d;
  d.release_begin = 0;
  d.release_end = 4;
  d.frames = {3, 5, 5.9};  // the space-time surface ends just before t_end
  d.edge = 0.01;
  d.seed_count = 2;
  std::vector<std::vector<Vec3>> direct;
  build_streak_surface(*flow, SeedCurve::line(x0, x0 + Vec3(1e-9, 0, 0)), d,
                       [&](const StreakFrame& f) {
                         std::vector<std::pair<double, Vec3>> by_release;
                         for (std::size_t i = 0; i < f.mesh.vertex_count(); ++i)
                           if (f.mesh.s[i] == 0) by_release.push_back({f.mesh.release_time[i], f.mesh.positions[i]});
                         std::sort(by_release.begin(), by_release.end(),
                                   [](const auto& a, const auto& b) { return a.first < b.first; });
                         std::vector<Vec3> line;
                         for (const auto& [tau, x] : by_release) line.push_back(x);
                         direct.push_back(line);
                       });
  REQUIRE(direct.size() == 3);
  for (std::size_t k = 0; k < 3; ++k) {
    const std::vector<Vec3> slice = slice_at_time(st.mesh, d.frames[k]);
    REQUIRE(slice.size() > 10);
    double far = 0;
    for (const Vec3& p : slice) far = std::max(far, distance_to_polyline(Vec3(p.x(), p.y(), 0), direct[k]));
    INFO("t = " << d.frames[k] << ": " << slice.size() << " slice points, farthest from the direct "
                << "streak line " << far);
    CHECK(far < 0.02 * d.edge);  // measured: 4.5e-5 (0.0045 edge lengths)
  }
}

TEST_CASE("space-time streak surface: 3D flows and a still seed point are refused",
          "[spacetime][streak]") {
  SpacetimeStreakOptions o;
  CHECK_THROWS_WITH(build_spacetime_streak_surface(*make_unsteady_field("unsteady-abc"), Vec3(1, 1, 1), o),
                    Catch::Contains("needs a 2D flow"));
  CHECK_THROWS_WITH(build_spacetime_streak_surface(*make_unsteady_field("double-gyre"), Vec3(9, 9, 0), o),
                    Catch::Contains("outside the domain"));
}
