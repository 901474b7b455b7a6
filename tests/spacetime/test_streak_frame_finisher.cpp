// StreakFrameFinisher: frames finished aside or in line, in order, with their records, their
// meshes reused, and a sink's exception handed back.
#include <catch2/catch.hpp>

#include <atomic>
#include <vector>

#include "orthofront/error.h"
#include "orthofront/spacetime/streak_frame_finisher.h"

using namespace orthofront;
using namespace orthofront::spacetime;

namespace {

// A frame of one quad of side `side`.
StreakFrame square(int index, double side) {
  StreakFrame f;
  f.index = index;
  f.time = index;
  f.mesh.positions = {Vec3(0, 0, 0), Vec3(side, 0, 0), Vec3(side, side, 0), Vec3(0, side, 0)};
  f.mesh.faces = {Face{{0, 1, 2, 3}, 4}};
  return f;
}

StreakFrameRecord record_of(const StreakFrame& f) {
  StreakFrameRecord r;
  r.index = f.index;
  r.time = f.time;
  r.vertices = f.mesh.vertex_count();
  r.faces = f.mesh.face_count();
  return r;
}

}  // namespace

TEST_CASE("frame finisher: aside and in line, every frame reaches the sink in order with its "
          "quality, and its record is filed",
          "[spacetime][streak]") {
  for (const bool aside : {true, false}) {
    INFO((aside ? "aside" : "in line"));
    std::vector<int> handed;
    std::vector<double> longest;
    const StreakFrameSink sink = [&](const StreakFrame& f) {
      handed.push_back(f.index);
      longest.push_back(f.quality.longest_edge);
    };
    StreakFrameFinisher finisher(sink, aside);
    CHECK(finisher.take_mesh().vertex_count() == 0);  // nothing finished yet
    for (int i = 0; i < 4; ++i) {
      StreakFrame f = square(i, 1.0 + i);
      const StreakFrameRecord rec = record_of(f);
      if (i > 0) {
        // The mesh of the frame before comes back for this one to be built in.
        const Mesh spare = finisher.take_mesh();
        CHECK(spare.vertex_count() == 4);
        CHECK(spare.positions[1].x() == i);
      }
      const double in_line = finisher.finish(std::move(f), rec, 0.25);
      if (aside) CHECK(in_line == 0);
    }
    finisher.wait();
    CHECK(handed == std::vector<int>{0, 1, 2, 3});
    CHECK(longest == std::vector<double>{1, 2, 3, 4});
    REQUIRE(finisher.records().size() == 4);
    for (int i = 0; i < 4; ++i) {
      const StreakFrameRecord& r = finisher.records()[static_cast<std::size_t>(i)];
      CHECK(r.index == i);
      CHECK(r.max_edge == 1.0 + i);
      CHECK(r.quality.longest_edge == 1.0 + i);
      CHECK(r.seconds == r.finish_seconds + 0.25);
    }
    CHECK_FALSE(finisher.failed());
  }
}

TEST_CASE("frame finisher: a sink that throws fails the finisher and wait() rethrows it, aside "
          "or in line, and a frame handed over before the last is waited for is refused",
          "[spacetime][streak]") {
  const StreakFrameSink sink = [](const StreakFrame& f) {
    if (f.index == 1) throw Error("frame 1: disk full");
  };
  {
    StreakFrameFinisher finisher(sink, true);
    finisher.finish(square(0, 1), record_of(square(0, 1)), 0);
    CHECK_THROWS_AS(finisher.finish(square(1, 1), record_of(square(1, 1)), 0), Error);  // not waited
    finisher.wait();
    finisher.finish(square(1, 1), record_of(square(1, 1)), 0);
    CHECK_THROWS_WITH(finisher.wait(), "frame 1: disk full");
    CHECK(finisher.failed());
    CHECK(finisher.records().size() == 1);
  }
  {
    StreakFrameFinisher finisher(sink, false);
    finisher.finish(square(0, 1), record_of(square(0, 1)), 0);
    CHECK_THROWS_WITH(finisher.finish(square(1, 1), record_of(square(1, 1)), 0), "frame 1: disk full");
    CHECK(finisher.records().size() == 1);
  }
}
