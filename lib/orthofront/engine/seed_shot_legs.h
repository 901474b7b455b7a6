#pragma once
/// The first legs of seed shots (adapt.h): the stream line from the seed point of parameter s,
/// integrated for t1, the previous front's time between an insertion's ends. An insertion
/// integrates from the seed over the surface's whole age, and a step leaves a core idle through
/// its serial stretches (sampling, α, rips, merges; all of it on a front below the parallel
/// threshold). So a step starts the legs of the insertions the next step will likely make, as
/// TBB tasks, and split_long finds them done. The engine's own waits are isolated (for_range, the fold guard): they never run a
/// leg meanwhile. A leg is a function of (s, t1) alone: one taken ahead and one integrated in
/// place are the same bits, and the mesh never depends on whether, where or when a leg ran.
#include <tbb/task_group.h>

#include <atomic>
#include <cstddef>
#include <deque>
#include <memory>
#include <unordered_map>
#include <utility>
#include <vector>

#include "orthofront/field/field.h"
#include "orthofront/integrate/runge_kutta.h"
#include "orthofront/seed/seed.h"

namespace orthofront {

template <int N>
class SeedShotLegs {
 public:
  /// All are owned by the engine and outlive this; the destructor waits for legs in flight.
  /// A leg gives up after max_evaluations field evaluations (IntegrationResult::exhausted).
  SeedShotLegs(const Field<N>& field, const Seed<N>& seed, const Tolerance& tolerance,
               const StopRequest& stop, int max_evaluations = kMaxEvaluations);
  ~SeedShotLegs();
  SeedShotLegs(const SeedShotLegs&) = delete;
  SeedShotLegs& operator=(const SeedShotLegs&) = delete;

  /// The seed point of parameter s (modulo 1 on a closed seed) integrated for t1: the leg
  /// started during the last step with exactly this (s, t1) if there is one (waiting for it
  /// where it is being integrated), else integrated here. Thread-safe.
  IntegrationResult<N> leg(double s, double t1) const;

  /// Whether legs can run ahead: another thread is allowed (TBB's parallelism limit).
  bool can_run_ahead() const;

  /// Starts legs (s, t1) for the next step. Skipped while earlier ones still wait for a thread.
  void start_ahead(const std::vector<std::pair<double, double>>& legs);

  /// A new step: legs started during the last one become those leg() finds; legs of the step
  /// before that which have not started are dropped.
  void begin_step();

  /// Drops every leg not begun (the surface is finished).
  void drop_pending();

  /// Legs started ahead so far, and those leg() used as a task had integrated them (or was
  /// integrating them). Both depend on thread timing, unlike the mesh.
  std::size_t started() const { return started_; }
  std::size_t used() const { return used_.load(std::memory_order_relaxed); }

 private:
  struct Leg;
  struct Batch;

  IntegrationResult<N> integrate(double s, double t1, const StopRequest& stop) const;

  const Field<N>& field_;
  const Seed<N>& seed_;
  const Tolerance& tol_;
  const StopRequest& stop_;
  const int max_evaluations_;
  std::shared_ptr<Batch> current_;   ///< started during the last step: leg() looks here
  std::shared_ptr<Batch> next_;      ///< started during this step
  std::size_t started_ = 0;
  mutable std::atomic<std::size_t> used_{0};
  std::atomic<int> queued_{0};  ///< tasks not begun
  /// Its own context: the engine may step inside a parallel loop (batch jobs) whose context
  /// ends with the loop, and a task group binds to the context it is first used in.
  tbb::task_group_context context_{tbb::task_group_context::isolated};
  tbb::task_group group_{context_};
};

extern template class SeedShotLegs<3>;
extern template class SeedShotLegs<4>;

}  // namespace orthofront
