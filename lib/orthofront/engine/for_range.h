#pragma once
/// One loop body for the serial and the parallel path of the engine's per-vertex stages.
#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <cstddef>

namespace orthofront {

/// Whether TBB may run a task on another thread than the caller's (the arena has room and no
/// global limit allows one thread only): work started ahead on an idle thread can run at all.
inline bool another_thread_may_run() {
  return tbb::this_task_arena::max_concurrency() > 1 &&
         tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism) > 1;
}

/// Runs body(begin, end) over [0, n): serially below `threshold` items, else in TBB tasks of at
/// least `grain` items (64 cheap vertex updates; 1 for costly items such as insertions).
template <typename Body>
void for_range(std::size_t n, std::size_t threshold, const Body& body, std::size_t grain = 64) {
  if (n < threshold) {
    body(std::size_t{0}, n);
    return;
  }
  // Isolated: while it waits for the last items, the calling thread takes none of the other
  // tasks in the arena (seed-shot legs started ahead, seed_shot_legs.h).
  tbb::this_task_arena::isolate([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain),
                      [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
  });
}

/// for_range() for loops of cheap items (a field evaluation or two each): they split into TBB
/// tasks only where the loop, timed where it last ran serially, takes long enough to pay for the
/// split (oneTBB's guide: a loop of under a million cycles rarely pays). A front of a few
/// hundred vertices runs such a loop in a few microseconds, where splitting it costs about as
/// much as it saves, and which of the two wins changes with the load on the machine: hence the
/// timing instead of a fixed size (figures: docs/benchmarks/measurements.md). The choice
/// changes no result: the items are independent.
class CheapLoop {
 public:
  /// A loop that takes less than this serially runs serially.
  static constexpr double kMinParallelSeconds = 40e-6;
  /// After this many loops split into tasks, the next one runs serially to measure again.
  static constexpr unsigned kRemeasureAfter = 64;

  /// Whether run(n, threshold, ...) would split the loop into tasks now.
  bool splits(std::size_t n, std::size_t threshold) const {
    return n >= threshold && seconds_per_item_ >= 0 && split_since_measured_ < kRemeasureAfter &&
           static_cast<double>(n) * seconds_per_item_ >= kMinParallelSeconds;
  }

  /// body(begin, end) over [0, n), as for_range(n, threshold, body) where splits() says so,
  /// else serially (timed, when n reaches the threshold).
  template <typename Body>
  void run(std::size_t n, std::size_t threshold, const Body& body) {
    if (splits(n, threshold)) {
      ++split_since_measured_;
      for_range(n, threshold, body);
      return;
    }
    const auto start = std::chrono::steady_clock::now();
    body(std::size_t{0}, n);
    if (n == 0 || n < threshold) return;
    const std::chrono::duration<double> took = std::chrono::steady_clock::now() - start;
    seconds_per_item_ = took.count() / static_cast<double>(n);
    split_since_measured_ = 0;
  }

 private:
  double seconds_per_item_ = -1;  ///< unknown until a loop at the threshold ran serially
  unsigned split_since_measured_ = 0;
};

}  // namespace orthofront
