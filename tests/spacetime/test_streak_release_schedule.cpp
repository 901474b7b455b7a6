// StreakReleaseSchedule: the release times and the breaks of a streak surface.
#include <catch2/catch.hpp>

#include <vector>

#include "orthofront/spacetime/streak_release_schedule.h"

using namespace orthofront;
using namespace orthofront::spacetime;

namespace {

StreakOptions options() {
  StreakOptions o;
  o.release_begin = 0;
  o.release_end = 1;
  o.frames = {0.5, 1.5};
  o.edge = 0.1;
  return o;
}

}  // namespace

TEST_CASE("release schedule: a given step, rounded to whole steps of the interval, and frames inside "
          "the interval release a row too",
          "[spacetime][streak]") {
  StreakOptions o = options();
  o.release_step = 0.3;  // 1 / 0.3 rounds to 3 steps of 1/3
  o.frames = {0.5, 1.5};
  const StreakReleaseSchedule s(o, 2.0, {});
  CHECK(s.release_step() == 1.0 / 3);
  const std::vector<double> releases{0, 1.0 / 3, 0.5, 2.0 / 3, 1};
  CHECK(s.releases() == releases);
  // Every release breaks (one per break), and every frame; nothing after the last frame.
  const std::vector<double> breaks{0, 1.0 / 3, 0.5, 2.0 / 3, 1, 1.5};
  CHECK(s.breaks() == breaks);
}

TEST_CASE("release schedule: without a step, edge over the seed's median speed, or a hundredth "
          "of the interval where nothing moves",
          "[spacetime][streak]") {
  StreakOptions o = options();
  o.release_step = 0;
  const StreakReleaseSchedule by_speed(o, 0.5, {});  // 0.1 / 0.5 = 0.2: five steps
  CHECK(by_speed.release_step() == 0.2);
  CHECK(by_speed.releases().size() == 7);  // 0, 0.2, ..., 1 and the frame at 0.5
  const StreakReleaseSchedule at_rest(o, -1, {});
  CHECK(at_rest.release_step() == 0.01);
  CHECK(at_rest.releases().front() == 0);
  CHECK(at_rest.releases().back() == 1);
}

TEST_CASE("release schedule: releases per break, series steps as breaks, and taking releases",
          "[spacetime][streak]") {
  StreakOptions o = options();
  o.release_step = 0.125;  // releases at k/8
  o.frames = {0.5, 1.2};
  o.releases_per_break = 3;
  // Steps of a series: those inside (release_begin, last frame) break too.
  StreakReleaseSchedule s(o, 1.0, {0, 0.3, 1.1, 1.25, 2});
  std::vector<double> releases;
  for (int k = 0; k <= 8; ++k) releases.push_back(k / 8.0);
  REQUIRE(s.releases() == releases);
  // Releases 0, 3/8, 6/8 and the last (1) break; so do the frames and the steps 0.3 and 1.1.
  const std::vector<double> breaks{0, 0.3, 0.375, 0.5, 0.75, 1, 1.1, 1.2};
  CHECK(s.breaks() == breaks);

  CHECK(s.take_at(0));
  CHECK_FALSE(s.take_at(0));  // taken
  CHECK(s.take_before(0.3) == std::vector<double>{0.125, 0.25});
  CHECK(s.take_before(0.3).empty());
  CHECK_FALSE(s.take_at(0.5));  // 0.375 comes first
  CHECK(s.take_before(0.5) == std::vector<double>{0.375});
  CHECK(s.take_at(0.5));
  CHECK_FALSE(s.done());
  CHECK(s.take_before(10) == std::vector<double>{0.625, 0.75, 0.875, 1});
  CHECK(s.done());
}
