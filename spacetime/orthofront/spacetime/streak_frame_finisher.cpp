#include "orthofront/spacetime/streak_frame_finisher.h"

#include <chrono>
#include <utility>

#include "orthofront/error.h"
#include "orthofront/quality/quality.h"
#include "orthofront/stage_timer.h"

namespace orthofront::spacetime {

Mesh StreakFrameFinisher::take_mesh() {
  wait();
  return std::move(spare_);
}

double StreakFrameFinisher::finish(StreakFrame frame, const StreakFrameRecord& record, double built) {
  if (task_.started()) throw Error("streak frames: a frame handed over before the last was waited for");
  frame_ = std::move(frame);
  record_ = record;
  if (aside_) {
    // It needs the mesh only: it runs while the particles move on (its parallel loops share the
    // threads with theirs).
    task_.start([this, built] { finish_frame(built); });
    return 0;
  }
  finish_frame(built);
  const double seconds = seconds_;
  collect();
  return seconds;
}

void StreakFrameFinisher::wait() {
  if (!task_.started()) return;
  task_.wait();  // finish_frame() keeps what the sink throws
  collect();
}

void StreakFrameFinisher::finish_frame(double built) {
  const auto t1 = std::chrono::steady_clock::now();
  try {
    frame_.quality = measure_quality(frame_.mesh);
    record_.quality = frame_.quality;
    record_.max_edge = frame_.quality.longest_edge;
    if (sink_) sink_(frame_);
  } catch (...) {
    error_ = std::current_exception();
    failed_ = true;
  }
  seconds_ = seconds_since(t1);
  record_.finish_seconds = seconds_;
  record_.seconds = built + seconds_;
}

void StreakFrameFinisher::collect() {
  if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
  finish_seconds_ += seconds_;
  records_.push_back(record_);
  spare_ = std::move(frame_.mesh);
}

}  // namespace orthofront::spacetime
