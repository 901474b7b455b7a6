#include "orthofront/advect/merging_advector.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <utility>
#include <vector>

namespace orthofront::advect {

struct MergingAdvector::Request {
  StepSource* source = nullptr;
  ParticleBatch* particles = nullptr;
  double t_end = 0;
  const MethodOptions* options = nullptr;
  bool forward = true;
  bool mergeable = false;
  bool taken = false;  ///< in a group a backend call runs
  bool done = false;
  AdvectionStatistics statistics;
  std::exception_ptr error;
};

namespace {

/// Whether the request's particles keep their results in a merged call: every moving particle on
/// one side of t_end (the side plan_slabs would move it to), its own end between. Sets `forward`.
bool mergeable(const ParticleBatch& p, double t_end, bool& forward) {
  bool before = false, after = false;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.status[i] != ParticleStatus::moving) continue;
    const double t = p.t[i];
    if (std::isnan(t) || std::isnan(t_end)) return false;  // let a call of its own say so
    if (t < t_end) before = true;
    if (t > t_end) after = true;
    if (!p.stop.empty()) {
      const double s = p.stop[i];
      if (!(s >= std::min(t, t_end) && s <= std::max(t, t_end))) return false;
    }
  }
  if (before && after) return false;
  forward = !after;
  return true;
}

/// Appends `from`'s particles to `to`, each ending at its own end (or the request's t_end).
void append(ParticleBatch& to, const ParticleBatch& from, double t_end) {
  for (std::size_t a = 0; a < 3; ++a)
    to.x[a].insert(to.x[a].end(), from.x[a].begin(), from.x[a].end());
  to.t.insert(to.t.end(), from.t.begin(), from.t.end());
  if (from.stop.empty())
    to.stop.insert(to.stop.end(), from.size(), t_end);
  else
    to.stop.insert(to.stop.end(), from.stop.begin(), from.stop.end());
  to.h.insert(to.h.end(), from.h.begin(), from.h.end());
  to.evaluations.insert(to.evaluations.end(), from.evaluations.begin(), from.evaluations.end());
  to.status.insert(to.status.end(), from.status.begin(), from.status.end());
}

/// Copies the merged results [offset, offset + to.size()) back (stop stays as the caller set it).
void extract(ParticleBatch& to, const ParticleBatch& from, std::size_t offset) {
  const auto first = static_cast<std::ptrdiff_t>(offset);
  const auto last = static_cast<std::ptrdiff_t>(offset + to.size());
  for (std::size_t a = 0; a < 3; ++a)
    std::copy(from.x[a].begin() + first, from.x[a].begin() + last, to.x[a].begin());
  std::copy(from.t.begin() + first, from.t.begin() + last, to.t.begin());
  std::copy(from.h.begin() + first, from.h.begin() + last, to.h.begin());
  std::copy(from.evaluations.begin() + first, from.evaluations.begin() + last,
            to.evaluations.begin());
  std::copy(from.status.begin() + first, from.status.begin() + last, to.status.begin());
}

/// A merged call's figures for one of its requests: counts and times by its share of the
/// particles, evaluations its own.
AdvectionStatistics share_of(const AdvectionStatistics& all, std::size_t particles,
                             std::size_t total, std::size_t evaluations) {
  const double f = total ? static_cast<double>(particles) / static_cast<double>(total) : 0.0;
  const auto part = [f](std::size_t v) {
    return static_cast<std::size_t>(static_cast<double>(v) * f + 0.5);
  };
  AdvectionStatistics s;
  s.particles = particles;
  s.slabs = all.slabs;
  s.particle_steps = part(all.particle_steps);
  s.evaluations = evaluations;
  s.steps_loaded = part(all.steps_loaded);
  s.steps_read_ahead = part(all.steps_read_ahead);
  s.bytes_uploaded = part(all.bytes_uploaded);
  s.bytes_downloaded = part(all.bytes_downloaded);
  s.total_seconds = all.total_seconds * f;
  s.compute_seconds = all.compute_seconds * f;
  s.upload_seconds = all.upload_seconds * f;
  s.host_seconds = all.host_seconds * f;
  s.overlap_seconds = all.overlap_seconds * f;
  s.download_seconds = all.download_seconds * f;
  s.pinned_seconds = all.pinned_seconds * f;
  return s;
}

}  // namespace

MergingAdvector::MergingAdvector(std::unique_ptr<BatchAdvector> backend, bool merge,
                                 std::size_t concurrent_calls)
    : backend_(std::move(backend)), merge_(merge),
      limit_(!merge ? 1
                    : std::clamp<std::size_t>(concurrent_calls ? concurrent_calls
                                                               : backend_->max_concurrent_calls(),
                                              1, backend_->max_concurrent_calls())) {}

MergingAdvector::~MergingAdvector() = default;

AdvectionStatistics MergingAdvector::advect(StepSource& source, ParticleBatch& particles,
                                            double t_end, const MethodOptions& options) {
  Request request;
  request.source = &source;
  request.particles = &particles;
  request.t_end = t_end;
  request.options = &options;
  request.mergeable = merge_ && mergeable(particles, t_end, request.forward);
  const auto arrived = std::chrono::steady_clock::now();
  std::unique_lock lock(mutex_);
  ++statistics_.requests;
  queue_.push_back(&request);
  while (!request.done) {
    // Any queued request may be served by this thread: the queue goes in order. (The backend
    // may allow fewer calls at once than asked for, e.g. a device holding few steps.)
    if (!request.taken && running_ < std::min(limit_, backend_->max_concurrent_calls()))
      serve(lock);
    else
      served_.wait(lock);
  }
  statistics_.wait_seconds +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - arrived).count();
  if (request.error) std::rethrow_exception(request.error);
  return request.statistics;
}

void MergingAdvector::serve(std::unique_lock<std::mutex>& lock) {
  // Take the first request and every queued one that merges with it (room first: nothing
  // below throws once requests leave the queue).
  std::vector<Request*> group;
  group.reserve(queue_.size());
  group.push_back(queue_.front());
  queue_.pop_front();
  const Request& first = *group.front();
  if (first.mergeable) {
    for (auto it = queue_.begin(); it != queue_.end();) {
      const Request& r = **it;
      if (r.mergeable && r.source == first.source && r.forward == first.forward &&
          *r.options == *first.options) {
        group.push_back(*it);
        it = queue_.erase(it);
      } else {
        ++it;
      }
    }
  }
  for (Request* r : group) r->taken = true;
  ++running_;
  ++statistics_.backend_calls;
  statistics_.largest_merge = std::max(statistics_.largest_merge, group.size());
  lock.unlock();
  const auto start = std::chrono::steady_clock::now();
  double kernels = 0, host = 0;

  // The backend's parallel loops must not pick up other tasks of the caller's (another
  // surface's step would call in here and wait for this very call).
  tbb::this_task_arena::isolate([&] {
    if (group.size() == 1) {
      Request& r = *group.front();
      try {
        r.statistics = backend_->advect(*r.source, *r.particles, r.t_end, *r.options);
        kernels = r.statistics.compute_seconds;
        host = r.statistics.host_seconds;
      } catch (...) {
        r.error = std::current_exception();
      }
      return;
    }
    try {
      ParticleBatch merged;
      double t_end = first.t_end;
      std::size_t total = 0;
      for (const Request* r : group) {
        append(merged, *r->particles, r->t_end);
        t_end = first.forward ? std::max(t_end, r->t_end) : std::min(t_end, r->t_end);
        total += r->particles->size();
      }
      const AdvectionStatistics all = backend_->advect(*first.source, merged, t_end, *first.options);
      kernels = all.compute_seconds;
      host = all.host_seconds;
      std::size_t offset = 0;
      for (Request* r : group) {
        const std::size_t n = r->particles->size();
        std::size_t evaluations = 0;
        for (std::size_t i = 0; i < n; ++i)
          evaluations += merged.evaluations[offset + i] - r->particles->evaluations[i];
        extract(*r->particles, merged, offset);
        r->statistics = share_of(all, n, total, evaluations);
        offset += n;
      }
    } catch (...) {
      for (Request* r : group) r->error = std::current_exception();
    }
  });

  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  lock.lock();
  statistics_.backend_seconds += seconds;
  statistics_.kernel_seconds += kernels;
  statistics_.host_seconds += host;
  for (Request* r : group) {
    statistics_.particles += r->particles->size();
    r->done = true;
  }
  --running_;
  served_.notify_all();
}

MergeStatistics MergingAdvector::merge_statistics() const {
  std::lock_guard lock(mutex_);
  return statistics_;
}

}  // namespace orthofront::advect
