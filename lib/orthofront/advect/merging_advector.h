#pragma once
/// One backend shared by threads that each advance their own particles (the surfaces of a batch
/// pass): calls run at once up to what the backend allows (BatchAdvector::max_concurrent_calls:
/// a CUDA device runs small calls side by side on streams of their own); calls that arrive while
/// that many run wait and are then run together, as one call of the backend over all their
/// particles, so a device gets few large calls instead of many small ones in turn. Each particle's result is the one a call of its own would give: a
/// merged call gives every particle its own end time (ParticleBatch::stop), and the backends
/// move each particle independently of the others.
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <memory>
#include <mutex>
#include <string>

#include "orthofront/advect/batch_advector.h"

namespace orthofront::advect {

/// What the merging did, summed since construction.
struct MergeStatistics {
  std::size_t requests = 0;          ///< advect() calls made to the merging advector
  std::size_t backend_calls = 0;     ///< calls of the backend that ran them
  std::size_t largest_merge = 0;     ///< most requests run in one backend call
  std::size_t particles = 0;
  double backend_seconds = 0;  ///< wall time inside backend calls (summed over calls at once)
  double kernel_seconds = 0;   ///< of which kernels or the parallel loops (the backend's compute)
  double host_seconds = 0;     ///< of which reading steps and staging them (the backend's host)
  double wait_seconds = 0;     ///< requests' time from arrival to result, summed over requests
};

class MergingAdvector final : public BatchAdvector {
 public:
  /// `merge` false: calls take turns one at a time, unmerged (the baseline to measure against).
  /// `concurrent_calls`: backend calls at once (0: what the backend allows; merge false: 1).
  explicit MergingAdvector(std::unique_ptr<BatchAdvector> backend, bool merge = true,
                           std::size_t concurrent_calls = 0);
  ~MergingAdvector() override;
  std::string name() const override { return backend_->name(); }
  /// Thread-safe. Requests are merged when they share the source, the method and the direction
  /// and every particle lies on its call's side of t_end with its own end between (a request that
  /// does not runs alone, so nothing changes for it). The statistics returned are the merged
  /// call's, shared out by particle count; evaluations are the request's own.
  AdvectionStatistics advect(StepSource& source, ParticleBatch& particles, double t_end,
                             const MethodOptions& options) override;
  MergeStatistics merge_statistics() const;
  /// Backend calls that may run at once.
  std::size_t concurrent_calls() const { return limit_; }

 private:
  struct Request;
  /// Runs queued requests, the first and those that merge with it, as one backend call.
  void serve(std::unique_lock<std::mutex>& lock);

  std::unique_ptr<BatchAdvector> backend_;
  bool merge_;
  std::size_t limit_;  ///< backend calls at once
  mutable std::mutex mutex_;
  std::condition_variable served_;
  std::deque<Request*> queue_;
  std::size_t running_ = 0;  ///< backend calls running
  MergeStatistics statistics_;
};

}  // namespace orthofront::advect
