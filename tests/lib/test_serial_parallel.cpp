// The engine's result does not depend on the number of threads: a surface built inside a oneTBB
// arena of one thread and inside one of two threads has the same vertices (bit for bit, with
// every attribute) and the same faces.
#include <tbb/task_arena.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <limits>
#include <string>
#include <vector>

#include "lib/surface_checks.h"
#include "orthofront/engine/stream_surface.h"
#include "orthofront/field/analytic.h"
#include "orthofront/seed/seed.h"

using namespace orthofront;
using test_support::check_identical;

namespace {

SurfaceResult build_in_arena(int threads, const Field3& field, const SeedCurve& curve, int count,
                             const StreamSurfaceOptions& o) {
  tbb::task_arena arena(threads);
  SurfaceResult result;
  arena.execute([&] { result = build_stream_surface<3>(field, make_seed(curve, count), o); });
  return result;
}

StreamSurfaceOptions surface_options(double edge, int steps, std::size_t parallel_threshold) {
  StreamSurfaceOptions o;
  o.edge = edge;
  o.max_steps = steps;
  o.parallel_threshold = parallel_threshold;
  return o;
}

}  // namespace

TEST_CASE("serial and parallel runs build the same mesh, bit for bit", "[engine][threads]") {
  struct Case {
    const char* name;
    std::string field;
    SeedCurve seed;
    int count;
    double edge;
    int steps;
    std::size_t parallel_threshold;  // fronts of at least this many vertices run in parallel
  };
  const Case cases[] = {
      // Every front step through the parallel advance, however short the front (the loops of
      // cheap items split only where they take 40 µs or more: CheapLoop, test_for_range).
      {"saddle3d, open line, threshold 0", "saddle3d",
       SeedCurve::line(Vec3(-1, 2, 0.1), Vec3(1, 2, 0.1)), 20, 0.05, 60, 0},
      {"sinus, open line, threshold 0", "sinus", SeedCurve::line(Vec3(-1, 0, 0), Vec3(1, 0, 0)),
       20, 0.05, 120, 0},
      // A closed front that starts serial and grows past the threshold (parallel from then on).
      {"lorenz, closed circle, threshold 256", "lorenz:reverse=1",
       SeedCurve::circle(Vec3(0, 0, 0), Vec3(1.283, 1, 0), 1), 10, 0.5, 400, 256},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    const auto field = make_analytic_field(c.field);
    const StreamSurfaceOptions o = surface_options(c.edge, c.steps, c.parallel_threshold);
    const SurfaceResult serial = build_in_arena(1, *field, c.seed, c.count, o);
    const SurfaceResult parallel = build_in_arena(2, *field, c.seed, c.count, o);
    REQUIRE(serial.mesh.face_count() > 500);
    if (c.parallel_threshold > 0) {
      // Some front step made more vertices than the threshold: the parallel path ran.
      std::vector<std::size_t> per_step(static_cast<std::size_t>(c.steps) + 1, 0);
      for (const std::int32_t step : serial.mesh.step) ++per_step[static_cast<std::size_t>(step)];
      CHECK(*std::max_element(per_step.begin(), per_step.end()) > c.parallel_threshold);
    }
    check_identical(serial, parallel);
    // And two parallel runs agree with each other (no order that depends on scheduling).
    check_identical(parallel, build_in_arena(2, *field, c.seed, c.count, o));
  }
}

TEST_CASE("surfaces the fold guard rips are the same with the per-vertex stages in parallel",
          "[engine][threads][fold]") {
  // Surfaces that fold: the guard rips vertices out and stitches strips again. With threshold 0
  // every front's per-vertex stages run in tasks (in an arena of one thread, one after
  // another); with a threshold above every front, in line.
  const test_support::SurfaceCase cases[] = {
      {"abc", SeedCurve::line(Vec3(0, 0, 1), Vec3(3, 3, 1)), 0.1, 120},
      {"abc", SeedCurve::line(Vec3(1, 1, 0), Vec3(1, 1, 6)), 0.2, 120},
      {"lorenz", SeedCurve::line(Vec3(-10, -10, 20), Vec3(10, 10, 20)), 1.0, 120},
  };
  for (const test_support::SurfaceCase& c : cases) {
    INFO(c.field);
    const auto field = make_analytic_field(c.field);
    StreamSurfaceOptions o =
        surface_options(c.edge, c.steps, std::numeric_limits<std::size_t>::max());
    const SurfaceResult in_line = build_in_arena(2, *field, c.seed, 20, o);
    CHECK(in_line.report.fold_rips > 0);
    o.parallel_threshold = 0;
    const SurfaceResult in_tasks = build_in_arena(2, *field, c.seed, 20, o);
    INFO("fold rips " << in_line.report.fold_rips << " in line, " << in_tasks.report.fold_rips
                      << " in tasks");
    check_identical(in_line, in_tasks);
    check_identical(in_line, build_in_arena(1, *field, c.seed, 20, o));
  }
}
