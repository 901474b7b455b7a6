#pragma once
/// One loop body for the serial and the parallel path of the engine's per-vertex stages.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <cstddef>

namespace orthofront {

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

}  // namespace orthofront
