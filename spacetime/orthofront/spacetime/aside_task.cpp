#include "orthofront/spacetime/aside_task.h"

#include <utility>

#include "orthofront/error.h"

namespace orthofront::spacetime {

void AsideTask::start(std::function<void()> work) {
  if (started_) throw Error("aside task: started again before its work was waited for");
  started_ = true;
  done_ = false;
  error_ = nullptr;
  arena_.enqueue([this, work = std::move(work)] {
    std::exception_ptr error;
    try {
      work();
    } catch (...) {
      error = std::current_exception();
    }
    const std::lock_guard lock(mutex_);
    error_ = std::move(error);
    done_ = true;
    finished_.notify_all();
  });
}

void AsideTask::wait() {
  if (!started_) return;
  started_ = false;
  std::unique_lock lock(mutex_);
  finished_.wait(lock, [this] { return done_; });
  if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
}

void AsideTask::wait_dropping_errors() {
  try {
    wait();
  } catch (...) {
  }
}

}  // namespace orthofront::spacetime
