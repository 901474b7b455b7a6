// Insertion on hand-made fronts in a uniform flow: a vertex goes on the stream line from the
// seed where that meets the front, from the previous row where it missed; the vertices beside
// count the misses in a row, and where they kept missing later insertions skip the seed's shot;
// a shot that costs more than its budget sets the leg length from which shots are skipped.
#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "lib/uniform_field.h"
#include "orthofront/engine/adapt.h"

using namespace orthofront;

namespace {

FrontVertex<3> vertex(const Vec3& x, double s, double t, std::int32_t origin) {
  FrontVertex<3> fv;
  fv.x = fv.anchor = x;
  fv.s = s;
  fv.t = t;
  fv.origin = origin;
  return fv;
}

/// The seed runs along y from (0, 0, 0) to (0, 2, 0); ℓ = 0.5, so a segment 2 long gets three
/// vertices. The previous front stands at x = 0.9 (t = 0.9), the front at x = 1 (t = 1), both
/// shifted by `shift` in y: 0 puts them on the seed's stream lines, 1 off them (as a front that
/// drifted from its exact place would be).
struct Setup {
  explicit Setup(double shift) {
    options.edge = 0.5;
    old.v = {vertex(Vec3(0.9, shift, 0), 0, 0.9, 0), vertex(Vec3(0.9, 2 + shift, 0), 1, 0.9, 1)};
    front.v = {vertex(Vec3(1, shift, 0), 0, 1, 0), vertex(Vec3(1, 2 + shift, 0), 1, 1, 1)};
  }
  test::UniformField field;
  Seed<3> seed = make_seed(SeedCurve::line(Vec3(0, 0, 0), Vec3(0, 2, 0)), 2);
  StreamSurfaceOptions options;
  Tolerance tolerance;
  StopRequest stop = [] { return false; };
  Mesh mesh;
  SurfaceReport report;
  Front<3> old, front;

  void split() {
    FrontAdapter<3> adapter(field, seed, options, tolerance, stop, mesh, report);
    std::vector<char> cut;
    REQUIRE_FALSE(adapter.split_long(front, &old, 1, cut));
    REQUIRE(front.v.size() == 5);
  }
};

}  // namespace

TEST_CASE("insertion: on the seed's stream line where it meets the front", "[engine][adapt]") {
  Setup s(0.0);
  s.front.v[1].seed_misses = kSeedMissesBeforeRowFirst - 1;  // a hit clears misses in a row
  s.split();
  CHECK(s.report.splits == 3);
  CHECK(s.report.streamline_insertions == 3);
  CHECK(s.report.previous_row_insertions == 0);
  CHECK(s.report.seed_shots_skipped == 0);
  for (std::size_t i = 0; i < 5; ++i) {
    INFO("vertex " << i);
    CHECK(s.front.v[i].x.isApprox(Vec3(1, 0.5 * static_cast<double>(i), 0), 1e-9));
    CHECK(s.front.v[i].seed_misses == 0);
  }
}

TEST_CASE("insertion: seed shots that miss the front are counted by the vertices beside them",
          "[engine][adapt]") {
  Setup s(1.0);
  s.front.v[0].seed_misses = 1;
  s.split();
  // Each seed shot ends a whole segment length off (y 0.5 where the front has 1.5): the previous
  // row's point carried over the step lands on the front instead.
  CHECK(s.report.streamline_insertions == 0);
  CHECK(s.report.previous_row_insertions == 3);
  CHECK(s.report.insertion_fallbacks == 0);
  CHECK(s.report.seed_shots_skipped == 0);  // one miss before: each shot was tried
  for (std::size_t i = 0; i < 5; ++i) {
    INFO("vertex " << i);
    CHECK(s.front.v[i].seed_misses == 2);  // the segment's misses in a row, and this one
    CHECK(s.front.v[i].x.isApprox(Vec3(1, 1 + 0.5 * static_cast<double>(i), 0), 1e-9));
  }
}

TEST_CASE("insertion: where seed shots kept missing, the seed's shot is skipped",
          "[engine][adapt]") {
  for (const std::size_t marked : {0, 1}) {
    Setup s(0.0);
    s.front.v[marked].seed_misses = kSeedMissesBeforeRowFirst;
    s.split();
    INFO("marked end " << marked);
    // The previous row gives the same points here (the flow is uniform), at a step's cost.
    CHECK(s.report.streamline_insertions == 0);
    CHECK(s.report.previous_row_insertions == 3);
    CHECK(s.report.seed_shots_skipped == 3);
    for (std::size_t i = 1; i < 4; ++i)
      CHECK(s.front.v[i].x.isApprox(Vec3(1, 0.5 * static_cast<double>(i), 0), 1e-9));
    // No shot was tried: the marked end keeps its count and the new vertices take it on.
    CHECK(s.front.v[0].seed_misses == (marked == 0 ? kSeedMissesBeforeRowFirst : 0));
    CHECK(s.front.v[4].seed_misses == (marked == 1 ? kSeedMissesBeforeRowFirst : 0));
    for (std::size_t i = 1; i < 4; ++i) CHECK(s.front.v[i].seed_misses == kSeedMissesBeforeRowFirst);
  }
  // One miss short of it, the shot is tried (and hits).
  Setup s(0.0);
  s.front.v[0].seed_misses = kSeedMissesBeforeRowFirst - 1;
  s.split();
  CHECK(s.report.streamline_insertions == 3);
  CHECK(s.report.seed_shots_skipped == 0);
}

TEST_CASE("insertion: a seed shot that costs too much sets the time from which insertions start "
          "from the previous row",
          "[engine][adapt]") {
  // A leg gives up past one evaluation: each insertion goes on from the previous row (the same
  // points here, the flow being uniform), and the leg's length (0.9) becomes the limit.
  Setup s(0.0);
  s.options.shot_evaluations = 1;
  s.split();
  CHECK(s.report.streamline_insertions == 0);
  CHECK(s.report.previous_row_insertions == 3);
  CHECK(s.report.insertion_fallbacks == 0);
  CHECK(s.report.seed_shots_over_budget == 3);
  CHECK(s.report.seed_shots_skipped == 0);
  CHECK(s.report.seed_shot_time_limit == 0.9);
  for (std::size_t i = 0; i < 5; ++i) {
    INFO("vertex " << i);
    CHECK(s.front.v[i].x.isApprox(Vec3(1, 0.5 * static_cast<double>(i), 0), 1e-9));
    CHECK(s.front.v[i].seed_misses == 0);  // too costly is no miss
  }
  // With that limit a later surface step tries no shot whose leg is as long, whatever the
  // budget now: all three insertions start from the previous row, counted as over budget.
  for (const double limit : {0.9, 0.5}) {
    Setup later(0.0);
    later.report.seed_shot_time_limit = limit;
    later.split();
    INFO("limit " << limit);
    CHECK(later.report.streamline_insertions == 0);
    CHECK(later.report.previous_row_insertions == 3);
    CHECK(later.report.seed_shots_over_budget == 3);
    CHECK(later.report.seed_shot_time_limit == limit);
  }
  // A limit beyond the leg: the shots from the seed are tried, and hit.
  Setup shorter(0.0);
  shorter.report.seed_shot_time_limit = 0.95;
  shorter.split();
  CHECK(shorter.report.streamline_insertions == 3);
  CHECK(shorter.report.seed_shots_over_budget == 0);
  // No limit (0) and the default budget: every shot is tried.
  for (const int budget : {0, StreamSurfaceOptions{}.shot_evaluations}) {
    Setup unlimited(0.0);
    unlimited.options.shot_evaluations = budget;
    unlimited.split();
    CHECK(unlimited.report.streamline_insertions == 3);
    CHECK(unlimited.report.seed_shots_over_budget == 0);
    CHECK(std::isinf(unlimited.report.seed_shot_time_limit));
  }
}

TEST_CASE("insertion: in previous-row mode nothing counts as a skipped seed shot",
          "[engine][adapt]") {
  Setup s(0.0);
  s.options.insertion = Insertion::previous_row;
  s.front.v[0].seed_misses = kSeedMissesBeforeRowFirst;
  s.split();
  CHECK(s.report.previous_row_insertions == 3);
  CHECK(s.report.seed_shots_skipped == 0);
}

TEST_CASE("insertion: the front's own vertices keep their order around the inserted ones",
          "[engine][adapt]") {
  // Segments 0.8, 0.4 and 0.8 long (ℓ 0.5: split above 0.75): one vertex goes into the first
  // and the last, none into the middle one. The vertices between go over in blocks.
  Setup s(0.0);
  s.old.v.clear();
  s.front.v.clear();
  const std::vector<double> ys = {0, 0.8, 1.2, 2.0};
  for (std::size_t i = 0; i < ys.size(); ++i) {
    const auto id = static_cast<std::int32_t>(i);
    s.old.v.push_back(vertex(Vec3(0.9, ys[i], 0), ys[i] / 2, 0.9, id));
    s.front.v.push_back(vertex(Vec3(1, ys[i], 0), ys[i] / 2, 1, id));
  }
  FrontAdapter<3> adapter(s.field, s.seed, s.options, s.tolerance, s.stop, s.mesh, s.report);
  std::vector<char> cut;
  REQUIRE_FALSE(adapter.split_long(s.front, &s.old, 1, cut));
  const std::vector<double> y = {0, 0.4, 0.8, 1.2, 1.6, 2.0};
  const std::vector<std::int32_t> origin = {0, -1, 1, 2, -1, 3};
  REQUIRE(s.front.v.size() == y.size());
  for (std::size_t i = 0; i < y.size(); ++i) {
    INFO("vertex " << i);
    CHECK(s.front.v[i].origin == origin[i]);
    CHECK(s.front.v[i].x.isApprox(Vec3(1, y[i], 0), 1e-9));
  }
  // The inserted vertices are mesh vertices, in front order.
  CHECK(s.front.v[1].mesh == 0);
  CHECK(s.front.v[4].mesh == 1);
}
