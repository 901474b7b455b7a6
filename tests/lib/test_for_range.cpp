// The engine's loops over front vertices: for_range() and CheapLoop, which splits a loop into
// tasks only where its serial time pays for that.
#include <tbb/task_arena.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <cstddef>
#include <vector>

#include "orthofront/engine/for_range.h"

using namespace orthofront;

namespace {

/// Busy for about `seconds` (a sleep would let the clock run without the work being there).
void spin_for(double seconds) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < until) {
  }
}

/// Runs `loop` over n items that each take `item_seconds`; returns each item's visit count.
std::vector<int> visit(CheapLoop& loop, std::size_t n, std::size_t threshold,
                       double item_seconds) {
  std::vector<std::atomic<int>> counts(n);
  loop.run(n, threshold, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      if (item_seconds > 0) spin_for(item_seconds);
      ++counts[i];
    }
  });
  std::vector<int> out;
  for (auto& c : counts) out.push_back(c.load());
  return out;
}

/// Whether `try_once` returns true within `attempts` tries. CheapLoop measures wall time: a
/// thread descheduled while a loop runs makes a cheap loop look dear, so a timed check gets a
/// few fresh loops; a CheapLoop that split cheap items would fail every one.
template <class Try>
bool within_attempts(int attempts, Try&& try_once) {
  for (int attempt = 0; attempt < attempts; ++attempt)
    if (try_once()) return true;
  return false;
}

}  // namespace

TEST_CASE("CheapLoop splits a loop only once its serial time would pay for that",
          "[engine][threads]") {
  const std::vector<int> once_each(600, 1);
  constexpr int kAttempts = 5;
  SECTION("cheap items stay serial") {
    CHECK(within_attempts(kAttempts, [&] {
      CheapLoop loop;
      CHECK_FALSE(loop.splits(600, 128));  // nothing measured yet
      CHECK(visit(loop, 600, 128, 0.0) == once_each);
      // 600 increments take far less than 40 µs: still serial.
      return !loop.splits(600, 128);
    }));
  }
  SECTION("costly items split, below the threshold never") {
    CHECK(within_attempts(kAttempts, [&] {
      CheapLoop loop;
      CHECK(visit(loop, 600, 128, 1e-6) == once_each);  // measured: about 600 µs in all
      CHECK(loop.splits(600, 128));
      CHECK_FALSE(loop.splits(100, 128));  // under the threshold
      return !loop.splits(1, 0);           // about 1 µs: not worth a split
    }));
  }
  SECTION("after kRemeasureAfter split loops one runs serially and measures again") {
    CHECK(within_attempts(kAttempts, [&] {
      CheapLoop loop;
      visit(loop, 600, 128, 1e-6);
      for (unsigned k = 0; k < CheapLoop::kRemeasureAfter; ++k) {
        REQUIRE(loop.splits(600, 128));
        CHECK(visit(loop, 600, 128, 0.0) == once_each);
      }
      CHECK_FALSE(loop.splits(600, 128));
      CHECK(visit(loop, 600, 128, 0.0) == once_each);  // serial: now measured as cheap
      return !loop.splits(600, 128);
    }));
  }
  SECTION("a split loop visits every item once") {
    tbb::task_arena arena(2);
    arena.execute([&] {
      CheapLoop loop;
      visit(loop, 600, 128, 1e-6);
      REQUIRE(loop.splits(600, 128));
      CHECK(visit(loop, 600, 128, 1e-6) == once_each);
    });
  }
}
