// AsideTask: work run as a oneTBB task in an arena of its own, waited for later.
#include <catch2/catch.hpp>

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include <atomic>
#include <stdexcept>
#include <thread>

#include "orthofront/error.h"
#include "orthofront/spacetime/aside_task.h"

using namespace orthofront;
using namespace orthofront::spacetime;

TEST_CASE("aside task: wait() returns once the work has run and rethrows what it threw",
          "[spacetime][streak]") {
  AsideTask task;
  CHECK_FALSE(task.started());
  task.wait();  // nothing started: nothing to wait for
  int value = 0;
  task.start([&] { value = 42; });
  CHECK(task.started());
  task.wait();
  CHECK_FALSE(task.started());
  CHECK(value == 42);

  task.start([] { throw std::runtime_error("disk full at frame 3"); });
  CHECK_THROWS_WITH(task.wait(), "disk full at frame 3");
  CHECK_FALSE(task.started());
  // Usable again after an error: the error is not thrown twice.
  task.start([&] { value = 7; });
  task.wait();
  CHECK(value == 7);
  task.wait();

  task.start([] { throw std::runtime_error("dropped"); });
  task.wait_dropping_errors();
  CHECK_FALSE(task.started());
}

TEST_CASE("aside task: a second start before the first is waited for is refused",
          "[spacetime][streak]") {
  AsideTask task;
  task.start([] {});
  CHECK_THROWS_AS(task.start([] {}), Error);
  task.wait();
}

TEST_CASE("aside task: the work never runs on the caller's thread, its own loops run in full",
          "[spacetime][streak]") {
  const std::thread::id caller = std::this_thread::get_id();
  for (int trial = 0; trial < 20; ++trial) {
    AsideTask task;
    std::atomic<bool> ran_on_caller{false};
    std::atomic<long> inner{0};
    task.start([&] {
      if (std::this_thread::get_id() == caller) ran_on_caller = true;
      tbb::parallel_for(tbb::blocked_range<int>(0, 1000), [&](const tbb::blocked_range<int>& r) {
        inner += r.end() - r.begin();
      });
    });
    // The caller's own loop, right after the start: where the work shared its arena, the
    // caller's thread would take it from its own queue while waiting for the loop's last items.
    std::atomic<long> outer{0};
    tbb::parallel_for(tbb::blocked_range<int>(0, 20000, 1), [&](const tbb::blocked_range<int>& r) {
      outer += r.end() - r.begin();
    });
    task.wait();
    CHECK(outer == 20000);
    CHECK(inner == 1000);
    CHECK_FALSE(ran_on_caller);
  }
}

TEST_CASE("aside task: work started inside a parallel loop that is cancelled still runs",
          "[spacetime][streak]") {
  AsideTask task;
  std::atomic<bool> ran{false};
  tbb::task_group_context outer;
  tbb::task_group group(outer);
  group.run([&] {
    outer.cancel_group_execution();
    task.start([&] { ran = true; });
  });
  group.wait();
  task.wait();
  CHECK(ran);
}

TEST_CASE("aside task: with TBB limited to one thread, the work still runs, on a thread of its own",
          "[spacetime][streak]") {
  const tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  AsideTask task;
  std::thread::id ran_on;
  task.start([&] { ran_on = std::this_thread::get_id(); });
  task.wait();
  CHECK(ran_on != std::thread::id());
  CHECK(ran_on != std::this_thread::get_id());
}
