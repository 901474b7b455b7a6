#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>

#include "orthofront/error.h"
#include "orthofront/field/unsteady.h"
#include "orthofront/quality/mesh_distance.h"
#include "orthofront/spacetime/streak_line_field.h"
#include "orthofront/spacetime/streak_surface.h"
#include "spacetime/reference_path.h"

using namespace orthofront;
using namespace orthofront::spacetime;
using streak_test::reference_path;

namespace {

double distance_to_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 d = b - a;
  const double w = std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
  return (a + w * d - p).norm();
}

}  // namespace

TEST_CASE(
    "flow map gradient: the variational equations against differences of independent "
    "path lines",
    "[spacetime][streak]") {
  const auto flow = make_unsteady_field("double-gyre");
  const Vec3 x(0.7, 0.4, 0);
  const double t0 = 5, t1 = 2;  // backward, as the streak-line field uses it
  const FlowMapGradient g = flow_map_gradient(*flow, x, t0, t1, Tolerance{1e-11, 1e-11});
  REQUIRE(g.status == FieldStatus::inside);
  CHECK((g.x - reference_path(*flow, x, t0, t1)).norm() < 1e-8);
  const double h = 1e-5;
  for (int c = 0; c < 2; ++c) {
    Vec3 e = Vec3::Zero();
    e[c] = h;
    const Vec3 column =
        (reference_path(*flow, x + e, t0, t1) - reference_path(*flow, x - e, t0, t1)) / (2 * h);
    INFO("column " << c << ": " << g.gradient.col(c).transpose() << " vs " << column.transpose());
    CHECK((g.gradient.col(c) - column).norm() < 1e-5 * std::max(1.0, column.norm()));
  }
  CHECK(g.gradient.row(2).norm() == 0);
}

TEST_CASE("streak-line field: its value is the tangent of the streak line with respect to age",
          "[spacetime][streak]") {
  const auto flow = make_unsteady_field("double-gyre");
  const double t = 6;
  const StreakLineField s(*flow, t, 5, Tolerance{1e-11, 1e-11});
  const Vec3 x0(0.3, 0.4, 0);
  for (const double age : {0.5, 2.0, 4.5}) {
    // The particle released at t - a from x0, and its neighbours on the streak line.
    const auto at = [&](double a) { return reference_path(*flow, x0, t - a, t); };
    const double h = 1e-4;
    const Vec3 tangent = (at(age + h) - at(age - h)) / (2 * h);
    Vec3 value;
    REQUIRE(s.velocity(at(age), age, value) == FieldStatus::inside);
    INFO("age " << age << ": s = " << value.transpose() << ", streak tangent "
                << tangent.transpose());
    CHECK((value - tangent).norm() < 1e-5 * std::max(1.0, tangent.norm()));
  }
  // Outside its age range it is outside; a 3D flow's field is 3D.
  Vec3 v;
  CHECK(s.velocity(x0, 5.5, v) == FieldStatus::outside);
  CHECK_THROWS_WITH(StreakLineField(*flow, 2, 0, Tolerance{}), Catch::Contains("ages [0, 0]"));
}

TEST_CASE(
    "streak surface by the streak-line field: every vertex is a particle of the seed, and "
    "the surface is the direct route's (double gyre)",
    "[spacetime][streak]") {
  const auto flow = make_unsteady_field("double-gyre");
  const Vec3 a(0.3, 0.3, 0), b(0.3, 0.45, 0);
  const SeedCurve seed = SeedCurve::line(a, b);
  const double edge = 0.02;
  for (const double t : {3.0, 5.0}) {
    StreakLineSurfaceOptions o;
    o.release_begin = 0;
    o.release_end = 4;
    o.observation_time = t;
    o.path.engine.edge = edge;
    o.path.engine.max_steps = 100000;
    const StreakLineSurface w = build_streak_line_surface(*flow, seed, o);
    const QualityReport& q = w.report.quality;
    INFO("t = " << t << ": " << w.mesh.vertex_count() << " vertices, quads " << q.quad_share
                << ", within 10 deg " << q.quad_angles_within_10 << ", folds " << q.folds << ", "
                << w.derived_evaluations << " values of s, " << w.seconds << " s");
    REQUIRE(w.path.complete);
    REQUIRE(w.mesh.vertex_count() > 100);
    REQUIRE(w.lifted.size() == w.mesh.vertex_count());
    CHECK(q.non_manifold_edges == 0);
    CHECK(q.t_junctions == 0);
    CHECK(q.degenerate_faces == 0);
    CHECK(q.quad_share > 0.9);
    // The oldest particles: released at the start of the release interval.
    double oldest = 0;
    for (const double age : w.mesh.age) oldest = std::max(oldest, age);
    // The oldest particles left at the start of the release: their front ends within a step of
    // its age (measured 3.6e-4 and 5.7e-3 short).
    CHECK(oldest > t - 0.01);
    CHECK(oldest <= t + 1e-9);

    // Each vertex (x, a), followed back a time units, is on the seed segment at its release.
    double worst = 0;
    for (std::size_t i = 0; i < w.mesh.vertex_count(); i += 3) {
      const Vec3 back = reference_path(*flow, w.mesh.positions[i], t, w.mesh.release_time[i]);
      worst = std::max(worst, distance_to_segment(back, a, b));
    }
    INFO("farthest release point from the seed " << worst);
    // After the release ended, the seed row is a polyline through the youngest particles; its
    // chord error, carried back through the flow, is what the bound admits (measured 1.8e-11
    // at t = 3 and 2.0e-6 at t = 5).
    CHECK(worst < (t <= o.release_end ? 1e-8 : 2e-5));

    // The direct route's frame at t, lifted by age, holds the same surface.
    StreakOptions d;
    d.release_begin = 0;
    d.release_end = 4;
    d.frames = {t};
    d.edge = edge / 2;
    Mesh direct;
    build_streak_surface(*flow, seed, d, [&](const StreakFrame& f) { direct = f.mesh; });
    std::vector<Vec3> lifted(direct.positions.begin(), direct.positions.end());
    for (std::size_t i = 0; i < lifted.size(); ++i) lifted[i].z() = direct.age[i];
    const auto triangles = triangles_of(lifted, direct.faces);
    double farthest = 0;
    for (std::size_t i = 0; i < w.lifted.size(); i += 3)
      farthest = std::max(farthest, distance_to(w.lifted[i], triangles));
    INFO("farthest vertex from the direct route's surface in (x, y, age): " << farthest);
    CHECK(farthest < 0.01 * edge);  // measured 4.6e-5 and 4.7e-5 (0.0023 edge lengths)
    // And the other way: the direct route's particles lie on this surface, so it covers all of
    // it but the oldest end. There the last front, orthogonal to the streak lines in (x, y, c a)
    // and so not a line of one age, stops where its first vertex reaches the oldest age; the
    // rest of it is up to a step short, where the streak lines are stretched most.
    const auto own = triangles_of(w.lifted, w.mesh.faces);
    double uncovered = 0;
    std::size_t compared = 0;
    for (std::size_t i = 0; i < lifted.size(); ++i)
      if (direct.age[i] <= 0.95 * t) {
        uncovered = std::max(uncovered, distance_to(lifted[i], own));
        ++compared;
      }
    INFO(compared << " of " << lifted.size() << " direct particles of age <= 0.95 t: farthest "
                  << "from this surface " << uncovered);
    CHECK(compared > lifted.size() * 8 / 10);
    CHECK(uncovered < 0.04 * edge);  // measured 2.4e-4 and 3.9e-4 (0.012 and 0.019 edges)
  }
}

TEST_CASE("streak surface by the streak-line field: bad input names the value",
          "[spacetime][streak]") {
  const SeedCurve seed = SeedCurve::line(Vec3(0.3, 0.3, 0), Vec3(0.3, 0.45, 0));
  StreakLineSurfaceOptions o;
  o.release_begin = 2;
  o.release_end = 1;
  CHECK_THROWS_WITH(build_streak_line_surface(*make_unsteady_field("double-gyre"), seed, o),
                    Catch::Contains("release 2:1"));
  o.release_end = 3;
  CHECK_THROWS_WITH(build_streak_line_surface(*make_unsteady_field("unsteady-abc"), seed, o),
                    Catch::Contains("needs a 2D flow"));
}
