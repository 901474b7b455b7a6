#pragma once
/// Front samples (front_samples.h) taken ahead. A step stitches each advanced front on one
/// thread, and the second core has nothing to do meanwhile; the next step then begins by
/// sampling that front (v at its vertices, the α system from v and J at its segments' midpoints)
/// and solving its α system, again on one thread for a front below a few hundred vertices. So
/// the link stage starts a TBB task that samples a copy of the front's positions and solves the
/// system (alpha_step.h's solve_alpha_system), and the next step takes both if its front still
/// has exactly those positions (a rip or a stall cut changes it: then it does the work in place).
/// All of it is a function of the positions: the mesh never depends on whether, where or when it
/// was done.
#include <tbb/task_group.h>

#include <atomic>
#include <memory>
#include <vector>

#include "orthofront/engine/alpha_step.h"
#include "orthofront/engine/front.h"
#include "orthofront/engine/front_samples.h"
#include "orthofront/engine/options.h"
#include "orthofront/field/field.h"

namespace orthofront {

template <int N>
class SamplesAhead {
 public:
  struct Samples {
    VertexSamples<N> vertices;
    SegmentTerms<N> segments;
    AlphaSolution solution;
    /// Whether `segments` and `solution` are the front's: not where a vertex is not inside or a
    /// midpoint has no flow (the step cuts the front before its α, or finds the cut in place).
    bool has_segments = false;
  };

  /// `field` and `options` outlive this; the destructor waits for samples in flight. Disabled,
  /// start() does nothing.
  SamplesAhead(const Field<N>& field, const StreamSurfaceOptions& options, bool enabled);
  ~SamplesAhead();
  SamplesAhead(const SamplesAhead&) = delete;
  SamplesAhead& operator=(const SamplesAhead&) = delete;

  /// Whether start() starts anything: enabled, and TBB may run another thread.
  bool enabled() const { return enabled_; }

  /// Starts sampling `f` (a copy of its positions) as a TBB task.
  void start(const Front<N>& f);

  /// A new step: samples started during the last one become those take() finds; those of the
  /// step before that are dropped.
  void begin_step();

  /// The samples of a front with exactly `f`'s positions and closure, started during the last
  /// step: those a task has finished, or taken here if no task has begun them; null if there
  /// are none, a task is still at them (its thread may have been held up: the caller works in
  /// place rather than wait), or taking them failed (the caller works in place, where the error
  /// surfaces). The caller may swap their vectors with its own; they are valid until the next
  /// take() or begin_step().
  Samples* take(const Front<N>& f);

  /// Fronts start() queued, and those whose samples a task had finished when take() asked.
  std::size_t started() const { return started_; }
  std::size_t used() const { return used_; }

 private:
  enum State : int { pending, running, done, failed };
  struct Job {
    std::vector<Vec<N>> x;
    bool closed = false;
    Samples samples;
    AlphaSolver solver;
    std::atomic<int> state{pending};
  };
  /// Samples the job's positions (any thread).
  void sample(Job& job) const;
  /// A job for start(), with the vectors of one done with.
  std::shared_ptr<Job> fresh_job();
  /// A job no longer looked at: if pending it never starts; its vectors are reused once no
  /// task holds it.
  void retire(std::shared_ptr<Job> job);

  const Field<N>& field_;
  const StreamSurfaceOptions& opt_;
  bool enabled_;
  std::vector<std::shared_ptr<Job>> current_, next_;
  std::shared_ptr<Job> taken_;                ///< the last take()'s
  std::vector<std::shared_ptr<Job>> spare_;   ///< retired, not in flight
  std::size_t started_ = 0, used_ = 0;
  tbb::task_group group_;
};

extern template class SamplesAhead<3>;
extern template class SamplesAhead<4>;

}  // namespace orthofront
