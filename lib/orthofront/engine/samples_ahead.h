#pragma once
/// Front samples (front_samples.h) taken ahead. A step stitches each advanced front on one
/// thread, and the second core has nothing to do meanwhile; the next step then begins by
/// sampling that front (v at its vertices, the α system from v and J at its segments' midpoints),
/// again on one thread for a front below a few hundred vertices. So the link stage starts a TBB
/// task that samples a copy of the front's positions, and the next step takes the samples if its
/// front still has exactly those positions (a rip or a stall cut changes it: then it samples in
/// place). The samples are a function of the positions: the mesh never depends on whether,
/// where or when they were taken.
#include <tbb/task_group.h>

#include <atomic>
#include <memory>
#include <vector>

#include "orthofront/engine/front.h"
#include "orthofront/engine/front_samples.h"
#include "orthofront/field/field.h"

namespace orthofront {

template <int N>
class SamplesAhead {
 public:
  struct Samples {
    VertexSamples<N> vertices;
    /// Left empty where a vertex is not inside (the step cuts the front before its α).
    SegmentTerms<N> segments;
    bool has_segments = false;
  };

  /// `field` outlives this; the destructor waits for samples in flight. Disabled, start() does
  /// nothing.
  SamplesAhead(const Field<N>& field, bool enabled);
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
  /// step: waited for while a task takes them, taken here if none has begun; null if there are
  /// none (or taking them failed: the caller samples in place, where the error surfaces). The
  /// caller may swap their vectors with its own; they are valid until the next take() or
  /// begin_step().
  Samples* take(const Front<N>& f);

  /// Fronts start() queued, and those whose samples a task had taken (or was taking) when
  /// take() asked.
  std::size_t started() const { return started_; }
  std::size_t used() const { return used_; }

 private:
  enum State : int { pending, running, done, failed };
  struct Job {
    std::vector<Vec<N>> x;
    bool closed = false;
    Samples samples;
    std::atomic<int> state{pending};
  };
  /// Samples the job's positions (any thread).
  void sample(Job& job) const;
  /// A job for start(), with the vectors of one done with.
  std::shared_ptr<Job> fresh_job();
  /// Jobs no longer looked at: pending ones never start, the others' vectors are reused.
  void retire(std::vector<std::shared_ptr<Job>>& jobs);

  const Field<N>& field_;
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
