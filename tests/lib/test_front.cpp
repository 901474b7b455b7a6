// The front type's algorithms: cutting a front into parts, its Catmull-Rom points, its length.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <vector>

#include "orthofront/engine/front.h"

using namespace orthofront;

namespace {

Front<3> front_through(const std::vector<Vec3>& points, bool closed, std::int32_t id = 7) {
  Front<3> f;
  f.closed = closed;
  f.id = id;
  for (std::size_t i = 0; i < points.size(); ++i) {
    FrontVertex<3> fv;
    fv.x = points[i];
    fv.anchor = fv.x;
    fv.mesh = static_cast<std::int32_t>(i);
    f.v.push_back(fv);
  }
  return f;
}

std::vector<Vec3> row(int n) {
  std::vector<Vec3> p;
  for (int i = 0; i < n; ++i) p.emplace_back(i, 0, 0);
  return p;
}

std::vector<std::int32_t> mesh_ids(const Front<3>& f) {
  std::vector<std::int32_t> ids;
  for (const auto& fv : f.v) ids.push_back(fv.mesh);
  return ids;
}

}  // namespace

TEST_CASE("split_front removes vertices and cuts segments, parts keep order and get new ids",
          "[engine][front]") {
  FrontIds ids{100, 0};
  SECTION("nothing to cut: the front itself") {
    const auto parts = split_front(front_through(row(5), false), std::vector<char>(5, 1),
                                   std::vector<char>(5, 0), ids);
    REQUIRE(parts.size() == 1);
    CHECK(parts[0].v.size() == 5);
    CHECK(parts[0].id == 7);
    CHECK(ids.created == 0);
  }
  SECTION("an open front loses vertex 2 and is cut after vertex 4") {
    std::vector<char> keep(8, 1), cut(8, 0);
    keep[2] = 0;
    cut[4] = 1;
    const auto parts = split_front(front_through(row(8), false), keep, cut, ids);
    REQUIRE(parts.size() == 3);
    CHECK(mesh_ids(parts[0]) == std::vector<std::int32_t>{0, 1});
    CHECK(mesh_ids(parts[1]) == std::vector<std::int32_t>{3, 4});
    CHECK(mesh_ids(parts[2]) == std::vector<std::int32_t>{5, 6, 7});
    CHECK(parts[0].id == 7);
    CHECK(parts[1].id == 100);
    CHECK(parts[2].id == 101);
    CHECK(ids.next == 102);
    CHECK(ids.created == 2);
    for (const auto& p : parts) CHECK_FALSE(p.closed);
  }
  SECTION("parts of fewer than two vertices are dropped") {
    std::vector<char> keep(5, 1), cut(5, 0);
    keep[1] = 0;
    keep[3] = 0;
    const auto parts = split_front(front_through(row(5), false), keep, cut, ids);
    CHECK(parts.empty());
  }
  SECTION("a closed front cut once becomes one open front starting after the cut") {
    std::vector<char> keep(6, 1), cut(6, 0);
    cut[3] = 1;  // the segment 3 -> 4
    const auto parts = split_front(front_through(row(6), true), keep, cut, ids);
    REQUIRE(parts.size() == 1);
    CHECK(mesh_ids(parts[0]) == std::vector<std::int32_t>{4, 5, 0, 1, 2, 3});
    CHECK_FALSE(parts[0].closed);
  }
  SECTION("a closed front without a vertex runs from the one after it round to the one before") {
    std::vector<char> keep(6, 1), cut(6, 0);
    keep[1] = 0;
    const auto parts = split_front(front_through(row(6), true), keep, cut, ids);
    REQUIRE(parts.size() == 1);
    CHECK(mesh_ids(parts[0]) == std::vector<std::int32_t>{2, 3, 4, 5, 0});
  }
}

TEST_CASE("cubic_point interpolates the front's vertices", "[engine][front]") {
  SECTION("it passes through the ends of its segment") {
    const Front<3> f = front_through({Vec3(0, 0, 0), Vec3(1, 2, 0), Vec3(3, 1, 1), Vec3(4, 0, 2)},
                                     false);
    for (std::size_t i = 0; i < 3; ++i) {
      CHECK((cubic_point(f, i, 0.0) - f.v[i].x).norm() < 1e-15);
      CHECK((cubic_point(f, i, 1.0) - f.v[i + 1].x).norm() < 1e-14);
    }
  }
  SECTION("on evenly spaced points of a line it is the line, ends included") {
    const Front<3> f = front_through(row(4), false);
    for (std::size_t i = 0; i < 3; ++i)
      for (const double lambda : {0.25, 0.5, 0.75})
        CHECK((cubic_point(f, i, lambda) - Vec3(static_cast<double>(i) + lambda, 0, 0)).norm() <
              1e-14);
  }
  SECTION("on a closed front round a circle it stays near the circle, across the closing segment") {
    constexpr int n = 16;
    std::vector<Vec3> circle;
    for (int k = 0; k < n; ++k) {
      const double a = 2 * 3.141592653589793 * k / n;
      circle.emplace_back(std::cos(a), std::sin(a), 0);
    }
    const Front<3> f = front_through(circle, true);
    for (std::size_t i = 0; i < n; ++i) {
      const double r = cubic_point(f, i, 0.5).norm();
      CHECK(std::abs(r - 1) < 2e-3);  // the chord's midpoint would be 0.019 inside
    }
  }
}

TEST_CASE("front_shorter_than counts the closing segment of a closed front", "[engine][front]") {
  const std::vector<Vec3> square{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)};
  const Front<3> open = front_through(square, false), closed = front_through(square, true);
  CHECK(front_shorter_than(open, 3.5));
  CHECK_FALSE(front_shorter_than(open, 3));  // exactly as long
  CHECK_FALSE(front_shorter_than(open, 1));  // reached on the first segment
  CHECK(front_shorter_than(closed, 4.5));
  CHECK_FALSE(front_shorter_than(closed, 3.5));  // only with the closing segment
  // A NaN coordinate makes the length NaN, which is not shorter than anything.
  std::vector<Vec3> broken = square;
  broken[1][0] = std::numeric_limits<double>::quiet_NaN();
  CHECK_FALSE(front_shorter_than(front_through(broken, false), 100));
}
