#pragma once
/// Finishes a streak surface's frames once their vertices and faces are built: their quality
/// and longest edge, then the sink. Aside, each frame is finished as a task while the particles
/// move on, one frame at a time and in order; in line, before finish() returns. Each finished
/// frame's mesh is kept for the next frame to be built in: a frame of millions of vertices
/// written into fresh arrays spends most of its time in page faults and zero fills.
#include <atomic>
#include <exception>
#include <vector>

#include "orthofront/mesh/mesh.h"
#include "orthofront/spacetime/aside_task.h"
#include "orthofront/spacetime/streak_surface.h"

namespace orthofront::spacetime {

class StreakFrameFinisher {
 public:
  /// Non-owning: `sink` (may be empty) must outlive the finisher.
  StreakFrameFinisher(const StreakFrameSink& sink, bool aside) : sink_(sink), aside_(aside) {}
  /// Waits for a frame being finished; what its sink threw is dropped.
  ~StreakFrameFinisher() = default;
  StreakFrameFinisher(const StreakFrameFinisher&) = delete;
  StreakFrameFinisher& operator=(const StreakFrameFinisher&) = delete;

  /// The mesh of the last frame finished (empty before the first), for the next frame to be
  /// built in; waits for the frame being finished first (wait()).
  Mesh take_mesh();
  /// Finishes `frame` (`record`: its counts; `built`: the seconds its vertices and faces took).
  /// Aside, returns at once, and 0; in line, returns once the sink has it, and the seconds that
  /// took, after rethrowing what the sink threw. The frame before must have been waited for.
  double finish(StreakFrame frame, const StreakFrameRecord& record, double built);
  /// Whether the sink threw for the frame being finished aside (wait() rethrows it).
  bool failed() const { return failed_; }
  /// Waits for the frame being finished, if any, and files its record; rethrows what its sink
  /// threw.
  void wait();

  /// The records of the frames finished and waited for, in order.
  const std::vector<StreakFrameRecord>& records() const { return records_; }
  /// Seconds spent finishing them, summed.
  double finish_seconds() const { return finish_seconds_; }

 private:
  // Quality, longest edge and the sink of frame_; an exception is kept for collect().
  void finish_frame(double built);
  // Rethrows what the finished frame's sink threw; files its record; keeps its mesh as spare.
  void collect();

  const StreakFrameSink& sink_;
  bool aside_;
  Mesh spare_;
  StreakFrame frame_;            // being finished
  StreakFrameRecord record_;
  double seconds_ = 0;           // frame_'s finishing
  std::exception_ptr error_;
  std::atomic<bool> failed_{false};
  std::vector<StreakFrameRecord> records_;
  double finish_seconds_ = 0;
  // Last: destroyed first, so a frame in flight is waited for while what it uses is still there.
  AsideTask task_;
};

}  // namespace orthofront::spacetime
