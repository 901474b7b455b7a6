// A surface saved between front steps and continued later builds the same mesh, bit for bit, as
// one that never stopped; the byte codec refuses every truncated or altered length.
#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "orthofront/engine/surface_builder.h"
#include "orthofront/field/analytic.h"
#include "orthofront/io/error.h"
#include "orthofront/io/state_codec.h"
#include "orthofront/seed/seed_curve.h"

using namespace orthofront;

namespace {

SurfaceResult uninterrupted(const Field<3>& field, const Seed<3>& seed,
                            const StreamSurfaceOptions& o) {
  return build_stream_surface(field, seed, o);
}

void require_same(const Mesh& a, const Mesh& b) {
  REQUIRE(a.vertex_count() == b.vertex_count());
  REQUIRE(a.faces == b.faces);
  REQUIRE(a.positions == b.positions);
  REQUIRE(a.time == b.time);
  REQUIRE(a.alpha == b.alpha);
  REQUIRE(a.s == b.s);
  REQUIRE(a.step == b.step);
}

}  // namespace

TEST_CASE("state codec: a surface continued from its encoded state equals the uninterrupted one",
          "[checkpoint]") {
  struct Case {
    const char* field;
    SeedCurve seed;
    int count;
    double edge;
    int steps;
    std::vector<int> stops;
    int shot_evaluations = StreamSurfaceOptions{}.shot_evaluations;
  };
  // Lorenz: seed shots miss the chaotic front and the vertices beside them count the misses
  // (FrontVertex::seed_misses), which the state must carry.
  const Case cases[] = {
      {"sinus", SeedCurve::line(Vec3(-8, 0, 0), Vec3(8, 0, 0)), 21, 0.2, 80, {0, 1, 17, 79}},
      {"lorenz:reverse=1", SeedCurve::circle(Vec3::Zero(), Vec3(1.283, 1, 0), 1), 10, 0.2, 300,
       {150, 299}},
      // Sinus with seed shots on a small budget: the time limit they set must be carried.
      {"sinus", SeedCurve::line(Vec3(-8, 0, 0), Vec3(8, 0, 0)), 21, 0.2, 80, {30, 79}, 60},
  };
  for (const Case& c : cases) {
    const auto field = make_analytic_field(c.field);
    const Seed<3> seed = make_seed(c.seed, c.count);
    StreamSurfaceOptions o;
    o.edge = c.edge;
    o.max_steps = c.steps;
    o.shot_evaluations = c.shot_evaluations;
    const SurfaceResult reference = uninterrupted(*field, seed, o);
    REQUIRE(reference.mesh.vertex_count() > 500);
    for (const int stop : c.stops) {
      SurfaceBuilder<3> first(*field, seed, o);
      for (int k = 0; k < stop && first.next(); ++k) first.step();
      io::ByteWriter out;
      io::write_engine_state(out, first.state());
      io::ByteReader in(out.bytes(), "memory");
      SurfaceBuilder<3> second(*field, seed, o, io::read_engine_state<3>(in));
      CHECK(in.left() == 0);
      while (second.next()) second.step();
      const SurfaceResult resumed = second.finish();
      INFO(c.field << ": saved after step " << stop);
      require_same(resumed.mesh, reference.mesh);
      CHECK(resumed.report.steps == reference.report.steps);
      CHECK(resumed.report.splits == reference.report.splits);
      CHECK(resumed.report.seed_shots_skipped == reference.report.seed_shots_skipped);
      CHECK(resumed.report.seed_shots_over_budget == reference.report.seed_shots_over_budget);
      CHECK(resumed.report.seed_shot_time_limit == reference.report.seed_shot_time_limit);
      CHECK(resumed.report.field_evaluations == reference.report.field_evaluations);
      CHECK(resumed.report.per_step.size() == reference.report.per_step.size());
    }
    if (c.shot_evaluations < StreamSurfaceOptions{}.shot_evaluations) {
      INFO(c.field << ": " << reference.report.seed_shots_over_budget << " shots over budget");
      CHECK(reference.report.seed_shots_over_budget > 0);
      CHECK(std::isfinite(reference.report.seed_shot_time_limit));
    }
    if (c.steps == 300) {
      INFO(c.field << ": " << reference.report.seed_shots_skipped << " seed shots skipped");
      CHECK(reference.report.seed_shots_skipped > 0);
    }
  }
}

TEST_CASE("state codec: truncated or altered bytes are refused, never read past the end",
          "[checkpoint]") {
  const auto field = make_analytic_field("saddle3d");
  const Seed<3> seed = make_seed(SeedCurve::line(Vec3(-3, 1, 1), Vec3(-3, 1, 3)), 8);
  StreamSurfaceOptions o;
  o.edge = 0.3;
  o.max_steps = 6;
  SurfaceBuilder<3> b(*field, seed, o);
  while (b.next()) b.step();
  io::ByteWriter out;
  io::write_engine_state(out, b.state());
  const std::string bytes = out.bytes();
  for (std::size_t n = 0; n < bytes.size(); n += 7) {
    io::ByteReader in(std::string_view(bytes).substr(0, n), "cut.state");
    CHECK_THROWS_AS(io::read_engine_state<3>(in), io::FormatError);
  }
  // A huge count where the number of fronts stands (after the dimension byte).
  std::string altered = bytes;
  for (int i = 1; i < 9; ++i) altered[static_cast<std::size_t>(i)] = '\x7f';
  io::ByteReader in(altered, "altered.state");
  CHECK_THROWS_WITH(io::read_engine_state<3>(in), Catch::Contains("altered.state"));
  // A state of the other dimension.
  io::ByteReader wrong(bytes, "wrong.state");
  CHECK_THROWS_AS(io::read_engine_state<4>(wrong), io::FormatError);
}
