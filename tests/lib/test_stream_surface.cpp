// End-to-end checks of the stream-surface engine on analytic fields: exact surfaces, decay of the
// orthogonality error, ripping, mesh validity, unit invariance, closed fronts.
#include <catch2/catch.hpp>
#include <atomic>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "orthofront/engine/stream_surface.h"
#include "orthofront/field/analytic.h"
#include "orthofront/field/scaled.h"
#include "orthofront/seed/seed.h"
#include "lib/surface_checks.h"
#include "lib/uniform_field.h"

using namespace orthofront;
using orthofront::test_support::require_valid;

namespace {

SurfaceResult run(const Field3& field, const SeedCurve& curve, int count, double edge, int steps,
                  StreamSurfaceOptions o = {}) {
  o.edge = edge;
  o.max_steps = steps;
  return build_stream_surface<3>(field, make_seed(curve, count), o);
}

SeedCurve line(double x0, double y0, double z0, double x1, double y1, double z1) {
  return SeedCurve::line(Vec3(x0, y0, z0), Vec3(x1, y1, z1));
}

/// ∫_0^y sin(u)^7 du in closed form: sin^7 = (35 sin u - 21 sin 3u + 7 sin 5u - sin 7u) / 64.
double integral_sin7(double y) {
  const auto term = [y](double k, double c) { return c * (1 - std::cos(k * y)) / k; };
  return (term(1, 35) - term(3, 21) + term(5, 7) - term(7, 1)) / 64.0;
}

/// Number of closed loops formed by the boundary edges (every boundary vertex of degree 2).
int boundary_loops(const Mesh& mesh, bool& simple) {
  std::map<std::pair<int, int>, int> count;
  for (const Face& f : mesh.faces)
    for (int k = 0; k < f.size; ++k) {
      int a = f.v[static_cast<std::size_t>(k)];
      int b = f.v[static_cast<std::size_t>((k + 1) % f.size)];
      if (a > b) std::swap(a, b);
      ++count[{a, b}];
    }
  std::map<int, std::vector<int>> next;
  for (const auto& [edge, n] : count)
    if (n == 1) {
      next[edge.first].push_back(edge.second);
      next[edge.second].push_back(edge.first);
    }
  simple = true;
  for (const auto& [v, nb] : next) simple = simple && nb.size() == 2;
  std::set<int> seen;
  int loops = 0;
  for (const auto& [start, nb] : next) {
    if (seen.count(start)) continue;
    ++loops;
    std::vector<int> stack{start};
    while (!stack.empty()) {
      const int v = stack.back();
      stack.pop_back();
      if (!seen.insert(v).second) continue;
      for (int w : next[v]) stack.push_back(w);
    }
  }
  return loops;
}

/// v = (1, a sin(k x), 0): straight on average, wiggling fast along x, so DOPRI5 needs thousands
/// of evaluations for one front step of one vertex.
class Wiggle final : public Field3 {
 public:
  static constexpr double a = 1.0, k = 3e4;
  FieldStatus velocity(const Vec3& x, Vec3& v) const override {
    ++evaluations;
    v = Vec3(1, a * std::sin(k * x.x()), 0);
    return FieldStatus::inside;
  }
  FieldStatus velocity_jacobian(const Vec3& x, Vec3& v, Mat3& j) const override {
    velocity(x, v);
    j.setZero();
    j(1, 0) = a * k * std::cos(k * x.x());
    return FieldStatus::inside;
  }
  Box<3> domain() const override { return Box<3>{Vec3(-10, -10, -10), Vec3(10, 10, 10)}; }
  std::string describe() const override { return "wiggle"; }
  mutable std::atomic<long> evaluations{0};
};

}  // namespace

TEST_CASE("saddle3d: every vertex lies on the exact surface y z = 0.2", "[engine][exact]") {
  const auto field = make_analytic_field("saddle3d");
  const SurfaceResult r = run(*field, line(-1, 2, 0.1, 1, 2, 0.1), 20, 0.1, 200);
  REQUIRE(r.mesh.vertex_count() > 1000);
  double worst = 0;
  for (const Vec3& p : r.mesh.positions) worst = std::max(worst, std::abs(p.y() * p.z() - 0.2));
  INFO("max |y z - 0.2| = " << worst);
  CHECK(worst < 1e-4);
  // The cubic midpoint, for comparison, is clearly worse (that is why it is not the default).
  StreamSurfaceOptions cubic;
  cubic.insertion = Insertion::cubic;
  const SurfaceResult rc = run(*field, line(-1, 2, 0.1, 1, 2, 0.1), 20, 0.1, 200, cubic);
  double worst_cubic = 0;
  for (const Vec3& p : rc.mesh.positions)
    worst_cubic = std::max(worst_cubic, std::abs(p.y() * p.z() - 0.2));
  CHECK(worst < worst_cubic);
}

TEST_CASE("previous-row insertion: one step's integration, no fallback, near the exact surface",
          "[engine][insertion]") {
  const auto field = make_analytic_field("saddle3d");
  const SurfaceResult exact = run(*field, line(-1, 2, 0.1, 1, 2, 0.1), 20, 0.1, 200);
  StreamSurfaceOptions o;
  o.insertion = Insertion::previous_row;
  const SurfaceResult r = run(*field, line(-1, 2, 0.1, 1, 2, 0.1), 20, 0.1, 200, o);
  REQUIRE(r.mesh.vertex_count() > 1000);
  // The default integrates every inserted vertex from the seed, and succeeds here.
  CHECK(exact.report.streamline_insertions > 50);
  CHECK(exact.report.previous_row_insertions == 0);
  CHECK(exact.report.insertion_fallbacks == 0);
  CHECK(r.report.previous_row_insertions > 50);
  CHECK(r.report.streamline_insertions == 0);
  CHECK(r.report.insertion_fallbacks == 0);
  // Cheaper: a step's integration instead of one from the seed.
  CHECK(r.report.field_evaluations < exact.report.field_evaluations);
  // Not exact: the previous front's interpolation error is carried (and the saddle grows it):
  // measured 6.6e-4 against 3e-10 from the seed and 7.0e-4 for the cubic point.
  double worst = 0;
  for (const Vec3& p : r.mesh.positions) worst = std::max(worst, std::abs(p.y() * p.z() - 0.2));
  INFO("max |y z - 0.2| = " << worst);
  CHECK(worst < 2e-3);
}

TEST_CASE("sinus: every vertex lies on the stream line of its seed parameter", "[engine][exact]") {
  // Along a stream line of v = (5 sin^7 y + y, 1, 0): x - y^2/2 - 5 ∫_0^y sin^7 = x at y = 0.
  const auto field = make_analytic_field("sinus");
  const SurfaceResult r = run(*field, line(-1, 0, 0, 1, 0, 0), 20, 0.05, 200);
  REQUIRE(r.mesh.vertex_count() > 2000);
  double worst = 0;
  for (std::size_t i = 0; i < r.mesh.vertex_count(); ++i) {
    const Vec3& p = r.mesh.positions[i];
    const double invariant = p.x() - 0.5 * p.y() * p.y() - 5 * integral_sin7(p.y());
    REQUIRE(invariant >= -1 - 1e-6);
    REQUIRE(invariant <= 1 + 1e-6);
    worst = std::max(worst, std::abs(invariant - (-1 + 2 * r.mesh.s[i])));
  }
  INFO("max |invariant - x0(s)| = " << worst);
  CHECK(worst < 1e-5);
}

TEST_CASE("the orthogonality error decays from a badly tilted seed", "[engine][orthogonality]") {
  struct Case {
    const char* field;
    SeedCurve seed;
    double edge;
  };
  const Case cases[] = {
      {"focus-sink", line(1, -0.3, -1, 1, 0.3, 1), 0.05},  // tilted against the swirl
      {"sinus", line(-1, -0.5, 0, 1, 0.5, 0), 0.05},       // 27° off the flow normal
  };
  for (const Case& c : cases) {
    const auto field = make_analytic_field(c.field);
    // The lagging end needs about (tilt length) / ℓ steps to catch up: check after 60.
    const SurfaceResult r = run(*field, c.seed, 20, c.edge, 80);
    const auto& steps = r.report.per_step;
    REQUIRE(steps.size() > 60);
    INFO(c.field << ": first " << steps.front().orthogonality_mean << ", step 60 "
                 << steps[59].orthogonality_mean);
    CHECK(steps.front().orthogonality_mean > 0.2);
    CHECK(steps[59].orthogonality_mean < 0.1 * steps.front().orthogonality_mean);
  }
}

TEST_CASE("the planar saddle rips exactly once at every edge length", "[engine][rip]") {
  const auto field = make_analytic_field("saddle");
  for (const double edge : {0.1, 0.05, 0.025}) {
    const SurfaceResult r = run(*field, line(-1, 1, 0, 1, 1, 0), 21, edge, 2000);
    INFO("edge " << edge);
    CHECK(r.report.rips == 1);
    // The two halves go left and right: no vertex crosses the separating stream line x = 0.
    std::size_t left = 0, right = 0;
    for (const Vec3& p : r.mesh.positions) (p.x() < 0 ? left : right) += 1;
    CHECK(left > 100);
    CHECK(right > 100);
    require_valid(r);
  }
}

TEST_CASE("fields without separating stream lines never rip", "[engine][rip]") {
  struct Case {
    const char* field;
    SeedCurve seed;
    int count;
    double edge;
    int steps;
  };
  const Case cases[] = {
      {"sinus", line(-1, 0, 0, 1, 0, 0), 20, 0.1, 200},
      {"sinus", line(-1, 0, 0, 1, 0, 0), 20, 0.05, 200},
      {"saddle3d", line(-1, 2, 0.1, 1, 2, 0.1), 20, 0.1, 200},
      {"saddle3d", line(-1, 2, 0.1, 1, 2, 0.1), 20, 0.05, 200},
      {"lorenz:reverse=1", SeedCurve::circle(Vec3::Zero(), Vec3(1.283, 1, 0), 2), 10, 0.25, 300},
      {"lorenz:reverse=1", SeedCurve::circle(Vec3::Zero(), Vec3(1.283, 1, 0), 2), 10, 0.5, 300},
      {"lorenz:reverse=1", SeedCurve::circle(Vec3::Zero(), Vec3(1.283, 1, 0), 2), 10, 1.0, 300},
  };
  for (const Case& c : cases) {
    const auto field = make_analytic_field(c.field);
    const SurfaceResult r = run(*field, c.seed, c.count, c.edge, c.steps);
    INFO(c.field << " edge " << c.edge);
    CHECK(r.report.rips == 0);
  }
}

TEST_CASE("every analytic field gives a valid mesh in the default mode", "[engine][validity]") {
  struct Case {
    const char* field;
    SeedCurve seed;
    int count;
    double edge;
    int steps;
  };
  const Case cases[] = {
      {"saddle", line(-1, 1, 0, 1, 1, 0), 20, 0.05, 240},
      {"saddle3d", line(-1, 2, 0.1, 1, 2, 0.1), 20, 0.1, 100},
      {"sinus", line(-1, 0, 0, 1, 0, 0), 20, 0.05, 200},
      {"focus-sink", line(1, 0, -1, 1, 0, 1), 20, 0.05, 200},
      {"lorenz:reverse=1", SeedCurve::circle(Vec3::Zero(), Vec3(1.283, 1, 0), 1), 10, 0.5, 500},
      {"stalling", line(-2.5, -1, 0, -2.5, 1, 0), 20, 0.05, 300},
      {"repelling-node-saddle", SeedCurve::circle(Vec3::Zero(), Vec3::UnitZ(), 0.2), 20, 0.05,
       200},
      {"abc", line(0, 0, 0, 0, 1, 0), 20, 0.05, 200},
  };
  for (const Case& c : cases) {
    const auto field = make_analytic_field(c.field);
    const SurfaceResult r = run(*field, c.seed, c.count, c.edge, c.steps);
    INFO(c.field << ": " << r.report.quality.folds << " folds, "
                 << r.report.quality.degenerate_faces << " degenerate, "
                 << r.report.quality.quad_share << " quads");
    REQUIRE(r.mesh.face_count() > 500);
    require_valid(r);
    CHECK(r.report.quality.quad_share > 0.9);
    CHECK(r.report.quality.quad_angles_within_10 > 0.9);
    // Every clamped α and every insertion fallback has exactly one cause.
    const SurfaceReport& p = r.report;
    CHECK(p.clamped_slow_flow + p.clamped_front_end + p.clamped_infeasible_step +
              p.clamped_ahead ==
          p.clamped_alpha);
    CHECK(p.fallback_left_domain + p.fallback_far_from_front == p.insertion_fallbacks);
    // ... and every triangle of the mesh, counted face by face here.
    std::size_t triangles = 0;
    for (const Face& face : r.mesh.faces) triangles += face.is_quad() ? 0 : 1;
    CHECK(p.triangles_at_row_changes + p.triangles_at_waiting_vertices +
              p.triangles_closing_gaps ==
          triangles);
  }
}

TEST_CASE("triangles by cause: rows of different lengths, waiting vertices, closed gaps",
          "[engine][validity]") {
  // saddle3d stretches its front without compressing it: every inserted vertex lengthens a row
  // by a segment, which a triangle at least must take up.
  const auto saddle3d = make_analytic_field("saddle3d");
  const SurfaceResult stretched = run(*saddle3d, line(-1, 2, 0.1, 1, 2, 0.1), 21, 0.1, 200);
  REQUIRE(stretched.report.splits > 50);
  REQUIRE(stretched.report.merges == 0);
  CHECK(stretched.report.triangles_at_row_changes >= stretched.report.splits);

  // A uniform flow across a straight seed: no row changes length and no vertex waits.
  const test::UniformField uniform;
  const SurfaceResult plain = run(uniform, line(0, 0, 0, 0, 1, 0), 11, 0.1, 50);
  REQUIRE(plain.mesh.face_count() == 10 * 50);
  CHECK(plain.report.triangles_at_row_changes == 0);
  CHECK(plain.report.triangles_at_waiting_vertices == 0);
  CHECK(plain.report.triangles == 0);

  // Row skipping leaves a triangle where a waiting vertex meets a moving one (the reversed
  // Lorenz field's front creeps near its axis).
  const auto lorenz = make_analytic_field("lorenz:reverse=1");
  const SurfaceResult skipping =
      run(*lorenz, SeedCurve::circle(Vec3::Zero(), Vec3(1.283, 1, 0), 1), 10, 0.5, 500);
  CHECK(skipping.report.skipped_vertex_steps > 0);
  CHECK(skipping.report.triangles_at_waiting_vertices > 0);
  // Without it, a vertex waits only where α was clamped to 0: none on the sinus front.
  const auto sinus = make_analytic_field("sinus");
  StreamSurfaceOptions every_row;
  every_row.row_skip = RowSkip::off;
  const SurfaceResult moving = run(*sinus, line(-1, 0, 0, 1, 0, 0), 21, 0.1, 200, every_row);
  CHECK(moving.report.clamped_alpha == 0);
  CHECK(moving.report.triangles_at_waiting_vertices == 0);
  CHECK(moving.report.triangles > 0);
  CHECK(moving.report.triangles == moving.report.triangles_at_row_changes);
}

TEST_CASE("a lower join fraction trades waiting vertices' triangles for short edges",
          "[engine][validity]") {
  // The reversed Lorenz field at ℓ = 0.5: 851 of its 1,393 triangles are at waiting vertices
  // with the default 0.5, 28 with 0.1, while the edge spread goes from 0.324 to 0.447.
  const auto lorenz = make_analytic_field("lorenz:reverse=1");
  const SeedCurve circle = SeedCurve::circle(Vec3::Zero(), Vec3(1.283, 1, 0), 1);
  StreamSurfaceOptions o;
  std::size_t last_waiting = 0;
  double last_spread = 0;
  for (const double join : {0.5, 0.1}) {
    o.join_fraction = join;
    const SurfaceResult r = run(*lorenz, circle, 10, 0.5, 500, o);
    INFO("join fraction " << join << ": " << r.report.triangles_at_waiting_vertices
                          << " triangles at waiting vertices, spread "
                          << r.report.quality.edge_spread_median);
    require_valid(r);
    if (join < 0.5) {
      CHECK(2 * r.report.triangles_at_waiting_vertices < last_waiting);
      CHECK(r.report.quality.edge_spread_median > last_spread);
    }
    last_waiting = r.report.triangles_at_waiting_vertices;
    last_spread = r.report.quality.edge_spread_median;
  }
  // 1 lets only vertices that went the whole skip distance move, as RowSkip::vertex does, but
  // keeps the rules for short runs; beyond [0, 1] it means nothing.
  o.join_fraction = 1.5;
  CHECK_THROWS_WITH(run(*lorenz, circle, 10, 0.5, 10, o),
                    Catch::Contains("join fraction must lie in [0, 1], got 1.5"));
}

TEST_CASE("damping mode is invariant under changes of time unit, length unit and domain size",
          "[engine][invariance]") {
  const auto base = make_analytic_field("focus-sink");
  const Vec3 a(1, -0.3, -1), b(1, 0.3, 1);
  const double edge = 0.05;
  const SurfaceResult reference = run(*base, SeedCurve::line(a, b), 20, edge, 80);
  REQUIRE(reference.mesh.vertex_count() > 500);
  struct Scaling {
    double speed, length;
  };
  // v x 10 (time unit); lengths x 3 with speeds x 3 (length unit); domain x 2 at equal speeds.
  for (const Scaling sc : {Scaling{10, 1}, Scaling{3, 3}, Scaling{1, 2}}) {
    const ScaledField scaled(*base, sc.speed, sc.length);
    const SurfaceResult r =
        run(scaled, SeedCurve::line(a * sc.length, b * sc.length), 20, edge * sc.length, 80);
    INFO("speed x" << sc.speed << ", length x" << sc.length);
    REQUIRE(r.mesh.vertex_count() == reference.mesh.vertex_count());
    REQUIRE(r.mesh.face_count() == reference.mesh.face_count());
    double worst = 0;
    for (std::size_t i = 0; i < r.mesh.vertex_count(); ++i)
      worst = std::max(worst,
                       (r.mesh.positions[i] / sc.length - reference.mesh.positions[i]).norm());
    CHECK(worst < 1e-9 * edge);
    CHECK(r.mesh.faces == reference.mesh.faces);
  }
}

TEST_CASE("paper mode is not unit invariant (which is why damping is the default)",
          "[engine][invariance]") {
  const auto base = make_analytic_field("focus-sink");
  StreamSurfaceOptions paper;
  paper.mu_mode = MuMode::paper;
  const SurfaceResult reference = run(*base, line(1, -0.3, -1, 1, 0.3, 1), 20, 0.05, 80, paper);
  const ScaledField faster(*base, 10, 1);
  const SurfaceResult r = run(faster, line(1, -0.3, -1, 1, 0.3, 1), 20, 0.05, 80, paper);
  bool differs = r.mesh.vertex_count() != reference.mesh.vertex_count();
  for (std::size_t i = 0; !differs && i < r.mesh.vertex_count(); ++i)
    differs = (r.mesh.positions[i] - reference.mesh.positions[i]).norm() > 1e-6;
  CHECK(differs);
}

TEST_CASE("a closed circle on the reversed Lorenz field stays closed", "[engine][closed]") {
  const auto field = make_analytic_field("lorenz:reverse=1");
  const SeedCurve circle = SeedCurve::circle(Vec3::Zero(), Vec3(1.283, 1, 0), 1);
  const SurfaceResult r = run(*field, circle, 10, 0.5, 150);
  REQUIRE(r.report.closed_seed);
  CHECK_FALSE(r.report.closed_front_opened);
  CHECK(r.report.rips == 0);
  require_valid(r);
  // A closed band: exactly two boundary loops, the seed and the last front.
  bool simple = false;
  CHECK(boundary_loops(r.mesh, simple) == 2);
  CHECK(simple);
}

TEST_CASE("a spiral source has no closed orthogonal front: the front is opened and reported",
          "[engine][closed]") {
  // Focus sink integrated backwards = spiral source; a circle around its axis in the x-y plane.
  const auto sink = make_analytic_field("focus-sink");
  const ScaledField source(*sink, -1, 1);
  const SurfaceResult r = run(source, SeedCurve::circle(Vec3::Zero(), Vec3::UnitZ(), 0.3), 20,
                              0.05, 100);
  CHECK(r.report.closed_front_opened);
  CHECK_FALSE(r.report.message.empty());
  require_valid(r);
}

TEST_CASE("a stop request ends long integrations inside a front step", "[engine][stop]") {
  Wiggle field;
  StreamSurfaceOptions o;
  o.edge = 0.1;
  o.max_steps = 3;
  const Seed<3> seed = make_seed(line(0, 0, -0.5, 0, 0, 0.5), 11);
  const SurfaceResult full = build_stream_surface<3>(field, seed, o);
  const long full_evaluations = field.evaluations.exchange(0);
  REQUIRE(full.report.stop_reason == StopReason::steps);
  // Thousands of evaluations per vertex and step: what a stop between steps cannot cut short.
  REQUIRE(full_evaluations > 11L * 3 * kStopCheckEvaluations);

  // Asked first before step 1 (go on), then inside that step's integrations (stop).
  std::atomic<int> asked{0};
  const SurfaceResult stopped =
      build_stream_surface<3>(field, seed, o, {}, {}, [&] { return ++asked > 1; });
  const long stopped_evaluations = field.evaluations.exchange(0);
  CHECK(asked.load() >= 2);
  CHECK(stopped.report.stop_reason == StopReason::cancelled);
  CHECK_FALSE(stopped.report.complete);
  CHECK(stopped.report.steps == 1);
  // The first integration to reach a check stops; the other vertices of the step do not start.
  CHECK(stopped_evaluations < 2 * kStopCheckEvaluations + 200);
  CHECK(stopped.report.no_data_hits == 0);
  // What was built is a valid mesh: the seed row, and faces only between finished rows.
  CHECK(stopped.mesh.vertex_count() >= 11);
  for (const Face& f : stopped.mesh.faces)
    for (int c = 0; c < f.size; ++c)
      CHECK(static_cast<std::size_t>(f.v[static_cast<std::size_t>(c)]) <
            stopped.mesh.vertex_count());

  // Between steps it is asked too (whatever the integrator): stopped before the first step.
  StreamSurfaceOptions rk4 = o;
  rk4.integrator = IntegratorKind::rk4;
  const SurfaceResult at_once = build_stream_surface<3>(field, seed, rk4, {}, {}, [] { return true; });
  CHECK(at_once.report.stop_reason == StopReason::cancelled);
  CHECK(at_once.report.steps == 0);
  field.evaluations = 0;

  // The time budget is asked there too.
  StreamSurfaceOptions budget = o;
  budget.time_budget_seconds = 0;
  const SurfaceResult r = build_stream_surface<3>(field, seed, budget);
  CHECK(r.report.stop_reason == StopReason::time_budget);
  CHECK(field.evaluations.load() < 2 * kStopCheckEvaluations + 200);
}

TEST_CASE("the engine stops for the reason it reports", "[engine][stop]") {
  const auto saddle = make_analytic_field("saddle3d");
  SECTION("steps") {
    const SurfaceResult r = run(*saddle, line(-1, 2, 0.1, 1, 2, 0.1), 20, 0.1, 5);
    CHECK(r.report.stop_reason == StopReason::steps);
    CHECK(r.report.steps == 5);
  }
  SECTION("vertex budget") {
    StreamSurfaceOptions o;
    o.max_vertices = 300;
    const SurfaceResult r = run(*saddle, line(-1, 2, 0.1, 1, 2, 0.1), 20, 0.1, 1000, o);
    CHECK(r.report.stop_reason == StopReason::vertex_budget);
    CHECK(r.mesh.vertex_count() >= 300);
    CHECK(r.mesh.vertex_count() < 400);
  }
  SECTION("domain") {
    const SurfaceResult r = run(*saddle, line(-1, 2, 0.1, 1, 2, 0.1), 20, 0.1, 1000);
    CHECK(r.report.stop_reason == StopReason::left_domain);
  }
  SECTION("fronts exhausted in a sink") {
    const auto sink = make_analytic_field("focus-sink");
    const SurfaceResult r = run(*sink, line(1, 0, -1, 1, 0, 1), 20, 0.05, 5000);
    CHECK(r.report.stop_reason == StopReason::fronts_exhausted);
  }
  SECTION("cancelled") {
    StreamSurfaceOptions o;
    o.edge = 0.1;
    o.max_steps = 1000;
    int calls = 0;
    const SurfaceResult r =
        build_stream_surface<3>(*saddle, make_seed(line(-1, 2, 0.1, 1, 2, 0.1), 20), o,
                                [&](const Progress&) { return ++calls < 4; });
    CHECK(r.report.stop_reason == StopReason::cancelled);
    CHECK_FALSE(r.report.complete);
    CHECK(r.report.steps == 3);
    require_valid(r);
  }
}

TEST_CASE("the timeline baseline shears where the orthogonal method does not", "[engine][baseline]") {
  const auto field = make_analytic_field("sinus");
  StreamSurfaceOptions timeline;
  timeline.method = Method::timeline;
  const SurfaceResult t = run(*field, line(-1, 0, 0, 1, 0, 0), 20, 0.05, 200, timeline);
  const SurfaceResult o = run(*field, line(-1, 0, 0, 1, 0, 0), 20, 0.05, 200);
  CHECK(t.report.quality.quad_angles_within_10 < 0.3);
  CHECK(o.report.quality.quad_angles_within_10 > 0.95);
}
