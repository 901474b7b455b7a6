// Front samples taken ahead (engine/samples_ahead.h): the samples found are those taken in place,
// bit for bit, whichever thread took them; a front whose positions or closure differ, or samples
// of an older step, are not found; a failed sampling is found as none; and a surface built with
// samples ahead is the one built without.
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "lib/surface_checks.h"
#include "orthofront/engine/samples_ahead.h"
#include "orthofront/engine/stream_surface.h"
#include "orthofront/field/analytic.h"

using namespace orthofront;

namespace {

/// A front of n vertices round a circle in the Lorenz field's domain.
Front<3> circle_front(std::size_t n, bool closed) {
  Front<3> f;
  f.closed = closed;
  for (std::size_t i = 0; i < n; ++i) {
    const double a = 6.283185307179586 * static_cast<double>(i) / static_cast<double>(n);
    FrontVertex<3> fv;
    fv.x = Vec3(3 * std::cos(a), 3 * std::sin(a), 20 + std::sin(3 * a));
    fv.anchor = fv.x;
    f.v.push_back(fv);
  }
  return f;
}

template <typename T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

const StreamSurfaceOptions options;

/// The samples of `f` taken in place, as the engine takes them without samples ahead.
SamplesAhead<3>::Samples in_place(const Field3& field, const Front<3>& f) {
  SamplesAhead<3>::Samples s;
  const std::size_t n = f.v.size();
  const auto at = [&f](std::size_t i) -> const Vec3& { return f.v[i].x; };
  s.vertices.resize(n);
  sample_vertices(field, at, 0, n, s.vertices);
  const std::size_t segments = f.closed ? n : n - 1;
  s.segments.resize(segments);
  segment_terms(field, at, n, s.vertices.vel, 0, segments, s.segments);
  AlphaSolver solver;
  solve_alpha_system(s.segments.p, s.segments.q, s.segments.r, s.vertices.speed, n, f.closed,
                     true, options.edge / damping_step(options.damping), solver, s.solution);
  return s;
}

/// v = (0, 0, 1), but a sample above z = 4 throws (a reader's failure mid-run).
class FailingAbove final : public Field3 {
 public:
  FieldStatus velocity(const Vec3& x, Vec3& v) const override {
    if (x[2] > 4) throw std::runtime_error("no sample above z = 4");
    v = Vec3(0, 0, 1);
    return FieldStatus::inside;
  }
  FieldStatus velocity_jacobian(const Vec3& x, Vec3& v, Mat3& j) const override {
    j.setZero();
    return velocity(x, v);
  }
  Box<3> domain() const override { return Box<3>{Vec3(-10, -10, -10), Vec3(10, 10, 10)}; }
  std::string describe() const override { return "failing above z = 4"; }
};

/// Starts sampling `f` and takes the samples in the next step: null where the task was still
/// at work when asked (the caller then works in place), so it tries again, with longer pauses
/// for the task (a loaded machine may hold its thread up).
const SamplesAhead<3>::Samples* taken_in_the_next_step(SamplesAhead<3>& ahead,
                                                       const Front<3>& f) {
  for (int attempt = 0; attempt < 6; ++attempt) {
    ahead.start(f);
    std::this_thread::sleep_for(std::chrono::milliseconds(10 << attempt));
    ahead.begin_step();
    if (const SamplesAhead<3>::Samples* s = ahead.take(f)) return s;
  }
  return nullptr;
}

}  // namespace

TEST_CASE("samples taken ahead are those taken in place, bit for bit", "[engine][threads]") {
  const auto field = make_analytic_field("lorenz");
  tbb::task_arena arena(2);
  arena.execute([&] {
    for (const bool closed : {false, true}) {
      INFO((closed ? "closed" : "open"));
      const Front<3> f = circle_front(300, closed);
      SamplesAhead<3> ahead(*field, options, true);
      REQUIRE(ahead.enabled());
      const SamplesAhead<3>::Samples* s = taken_in_the_next_step(ahead, f);
      REQUIRE(s);
      const SamplesAhead<3>::Samples expected = in_place(*field, f);
      CHECK(same_bits(s->vertices.vel, expected.vertices.vel));
      CHECK(same_bits(s->vertices.speed, expected.vertices.speed));
      CHECK(s->vertices.status == expected.vertices.status);
      REQUIRE(s->has_segments);
      CHECK(s->segments.p.size() == (closed ? 300u : 299u));
      CHECK(same_bits(s->segments.p, expected.segments.p));
      CHECK(same_bits(s->segments.q, expected.segments.q));
      CHECK(same_bits(s->segments.r, expected.segments.r));
      CHECK(same_bits(s->segments.err, expected.segments.err));
      CHECK(s->segments.ok == expected.segments.ok);
      // ... and the system's solution.
      const AlphaSolution& a = s->solution;
      const AlphaSolution& b = expected.solution;
      REQUIRE(b.ok);
      CHECK(a.ok);
      CHECK(a.shift == b.shift);
      CHECK(a.negative == b.negative);
      CHECK(std::memcmp(&a.log_product, &b.log_product, sizeof(double)) == 0);
      CHECK(same_bits(a.aln, b.aln));
      CHECK(same_bits(a.kernel, b.kernel));
      CHECK(a.damped);
      CHECK(std::memcmp(&a.choice.mu, &b.choice.mu, sizeof(double)) == 0);
      CHECK(a.choice.feasible == b.choice.feasible);
      if (closed) CHECK(b.shift != 0);  // (a rotation the test sees: not the identity)
    }
  });
}

TEST_CASE("samples ahead are found only for the same positions and closure, in the next step",
          "[engine][threads]") {
  const auto field = make_analytic_field("lorenz");
  tbb::task_arena arena(2);
  arena.execute([&] {
    const Front<3> f = circle_front(200, true);
    SECTION("a vertex moved by one ulp, the other closure or another size: none") {
      SamplesAhead<3> ahead(*field, options, true);
      ahead.start(f);
      ahead.begin_step();
      Front<3> moved = f;
      moved.v[117].x[1] = std::nextafter(moved.v[117].x[1], 1e9);
      CHECK(ahead.take(moved) == nullptr);
      Front<3> opened = f;
      opened.closed = false;
      CHECK(ahead.take(opened) == nullptr);
      CHECK(ahead.take(circle_front(199, true)) == nullptr);
      CHECK(ahead.used() == 0);
      // Those of f itself are found; once taken, they are gone.
      CHECK(taken_in_the_next_step(ahead, f) != nullptr);
      CHECK(ahead.take(f) == nullptr);
    }
    SECTION("not before the next step, and not after it") {
      SamplesAhead<3> ahead(*field, options, true);
      ahead.start(f);
      CHECK(ahead.take(f) == nullptr);  // started this step: the next one takes them
      ahead.begin_step();
      ahead.begin_step();
      CHECK(ahead.take(f) == nullptr);  // dropped with their step
      CHECK(ahead.used() == 0);
    }
    SECTION("disabled, or with one thread allowed, nothing starts") {
      SamplesAhead<3> off(*field, options, false);
      off.start(f);
      off.begin_step();
      CHECK(off.take(f) == nullptr);
      CHECK(off.started() == 0);
      tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
      SamplesAhead<3> alone(*field, options, true);
      CHECK_FALSE(alone.enabled());
    }
  });
}

TEST_CASE("a sampling that throws ahead is found as none", "[engine][threads]") {
  const FailingAbove field;
  tbb::task_arena arena(2);
  arena.execute([&] {
    Front<3> f;
    for (int i = 0; i < 50; ++i) {
      FrontVertex<3> fv;
      fv.x = Vec3(0.1 * i, 0, i == 30 ? 5.0 : 0.0);
      fv.anchor = fv.x;
      f.v.push_back(fv);
    }
    SamplesAhead<3> ahead(field, options, true);
    ahead.start(f);
    ahead.begin_step();
    CHECK(ahead.take(f) == nullptr);  // the caller samples in place, where the error surfaces
    CHECK_THROWS_WITH(in_place(field, f), "no sample above z = 4");
  });
}

TEST_CASE("a surface built with samples ahead is the one built without",
          "[engine][threads]") {
  // A closed Lorenz front (rotated every step), a closed focus-sink front that has no closed
  // orthogonal front and is opened, a stretching saddle3d front, and abc, whose fronts rip and
  // whose strips the fold guard undoes (their samples are not used).
  const test_support::SurfaceCase cases[] = {
      {"lorenz:reverse=1", SeedCurve::circle(Vec3::Zero(), Vec3(1.283, 1, 0), 1), 0.5, 200},
      {"focus-sink", SeedCurve::circle(Vec3(0, 0, 1), Vec3::UnitZ(), 2), 0.05, 100},
      {"saddle3d", SeedCurve::line(Vec3(-1, 2, 0.1), Vec3(1, 2, 0.1)), 0.01, 60},
      {"abc", SeedCurve::line(Vec3(1, 1, 0), Vec3(1, 1, 6)), 0.2, 150},
  };
  for (const test_support::SurfaceCase& c : cases) {
    INFO(c.field);
    StreamSurfaceOptions o;
    o.parallel_threshold = 32;  // fronts of a few dozen vertices are sampled ahead too
    o.shots_ahead = false;      // (legs ahead move chaotic surfaces by rounding: abc)
    const auto [ahead, in_place_run] =
        test_support::built_with_and_without(c, o, &StreamSurfaceOptions::samples_ahead);
    INFO(ahead.report.samples_started_ahead << " fronts sampled ahead, "
                                            << ahead.report.samples_used_ahead << " used");
    // The next step took each front's samples from the idle thread's task, or sampled it in
    // take() where no task had begun (a loaded machine), or in place where one was still at it:
    // the same mesh every way.
    CHECK(ahead.report.samples_started_ahead > 20);
    CHECK(ahead.report.samples_used_ahead <= ahead.report.samples_started_ahead);
    CHECK(in_place_run.report.samples_started_ahead == 0);
    test_support::check_identical(ahead, in_place_run);
    CHECK(ahead.report.field_evaluations == in_place_run.report.field_evaluations);
    CHECK(ahead.report.rips == in_place_run.report.rips);
    CHECK(ahead.report.closed_front_opened == in_place_run.report.closed_front_opened);
    if (c.field == std::string("focus-sink")) CHECK(ahead.report.closed_front_opened);
    CHECK(ahead.report.fold_rips == in_place_run.report.fold_rips);
  }
}
