#pragma once
/// One piece of work run beside the calling thread as a oneTBB task, waited for later: a streak
/// surface's frame finisher, its particles' move to the next break, the catch-up of particles
/// inserted meanwhile and the rows released meanwhile each run in one.
///
/// The work is enqueued in a task arena of its own. A thread that waits inside a parallel loop
/// takes other tasks of its arena meanwhile: in the caller's arena, the caller's loops would
/// pick up the work and stop there until it ends, and a move holding the backend's one-call lock
/// could pick up a catch-up that needs the same lock. In its own arena, the threads waiting
/// inside the work's loops take only the work's tasks. An enqueued task gets a worker thread
/// even where a global limit allows the caller's thread only, and runs in the arena's own
/// context, so a cancelled loop around the caller does not cancel it. wait() blocks until the
/// work is done rather than running it: the work never runs on the caller's thread (a frame's
/// sink is called from a thread of its own).
#include <tbb/task_arena.h>

#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>

namespace orthofront::spacetime {

class AsideTask {
 public:
  AsideTask() = default;
  /// Waits for work in flight; what it threw is dropped (the owner is unwinding, or has waited).
  ~AsideTask() { wait_dropping_errors(); }
  AsideTask(const AsideTask&) = delete;
  AsideTask& operator=(const AsideTask&) = delete;

  /// Starts `work` as a task. Work started before must have been waited for.
  void start(std::function<void()> work);
  /// Whether work was started and not waited for yet.
  bool started() const { return started_; }
  /// Waits for the work started, if any; rethrows what it threw.
  void wait();
  /// Waits for the work started, if any, dropping what it threw.
  void wait_dropping_errors();

 private:
  tbb::task_arena arena_;
  std::mutex mutex_;
  std::condition_variable finished_;
  bool done_ = false;       // under mutex_
  std::exception_ptr error_;  // the work's, set before done_
  bool started_ = false;    // the caller's view
};

}  // namespace orthofront::spacetime
