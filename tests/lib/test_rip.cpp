// Rip detection: a sharp, slow peak of α marks a separating stream line; smooth or fast peaks and
// an open front's ends do not.
#include <catch2/catch.hpp>
#include <vector>

#include "orthofront/engine/rip.h"

using namespace orthofront;

namespace {

std::vector<char> rips(const std::vector<double>& alpha, const std::vector<double>& speed,
                       bool closed, std::size_t& count) {
  std::vector<char> keep(alpha.size(), 1);
  count = find_rips(alpha, speed, closed, RipThresholds{}, keep);
  return keep;
}

}  // namespace

TEST_CASE("find_rips marks sharp, slow peaks of alpha only", "[engine][rip]") {
  std::size_t count = 0;
  const std::vector<double> fast(7, 1.0);
  std::vector<double> slow_middle = fast;
  slow_middle[3] = 0.01;  // below 5 % of the median speed

  SECTION("a sharp peak where the flow is slow") {
    const auto keep = rips({1, 1, 1, 5, 1, 1, 1}, slow_middle, false, count);
    CHECK(count == 1);
    CHECK(keep == std::vector<char>{1, 1, 1, 0, 1, 1, 1});
  }
  SECTION("the same peak where the flow is fast is no rip") {
    rips({1, 1, 1, 5, 1, 1, 1}, fast, false, count);
    CHECK(count == 0);
  }
  SECTION("a smooth peak is no rip (sharpness 1 - (2 + 2) / (2 2.1) = 0.05 < 0.5)") {
    rips({1, 1.5, 2, 2.1, 2, 1.5, 1}, slow_middle, false, count);
    CHECK(count == 0);
  }
  SECTION("an open front's end is never a rip; a closed front's first vertex can be") {
    std::vector<double> slow_first = fast;
    slow_first[0] = 0.01;
    rips({5, 1, 1, 1, 1, 1, 1}, slow_first, false, count);
    CHECK(count == 0);
    const auto keep = rips({5, 1, 1, 1, 1, 1, 1}, slow_first, true, count);
    CHECK(count == 1);
    CHECK(keep[0] == 0);
  }
  SECTION("negative and zero alpha make no peak") {
    rips({-1, -1, -1, 0, -1, -1, -1}, slow_middle, false, count);
    CHECK(count == 0);
  }
}
