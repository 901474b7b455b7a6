#include "orthofront/engine/samples_ahead.h"

#include <algorithm>

#include "orthofront/engine/for_range.h"

namespace orthofront {

namespace {

/// Retired jobs kept for their vectors (a step rarely has more fronts).
constexpr std::size_t kMostSpare = 8;

}  // namespace

template <int N>
SamplesAhead<N>::SamplesAhead(const Field<N>& field, const StreamSurfaceOptions& options,
                              bool enabled)
    : field_(field), opt_(options), enabled_(enabled && another_thread_may_run()) {}

template <int N>
SamplesAhead<N>::~SamplesAhead() {
  for (auto& job : current_) retire(std::move(job));
  for (auto& job : next_) retire(std::move(job));
  try {
    group_.wait();  // queued tasks find their jobs retired
  } catch (...) {
    // (Tasks keep their exceptions to themselves: nothing to rethrow here.)
  }
}

template <int N>
void SamplesAhead<N>::sample(Job& job) const {
  const std::size_t n = job.x.size();
  const auto at = [&job](std::size_t i) -> const Vec<N>& { return job.x[i]; };
  Samples& s = job.samples;
  s.vertices.resize(n);
  sample_vertices(field_, at, 0, n, s.vertices);
  s.has_segments = std::all_of(s.vertices.status.begin(), s.vertices.status.end(),
                               [](FieldStatus st) { return st == FieldStatus::inside; });
  if (!s.has_segments || n < 2) {
    s.has_segments = false;
    return;
  }
  const std::size_t segments = job.closed ? n : n - 1;
  s.segments.resize(segments);
  segment_terms(field_, at, n, s.vertices.vel, 0, segments, s.segments);
  s.has_segments = std::all_of(s.segments.ok.begin(), s.segments.ok.end(),
                               [](char ok) { return ok != 0; });
  if (!s.has_segments) return;
  solve_alpha_system(s.segments.p, s.segments.q, s.segments.r, s.vertices.speed, n, job.closed,
                     opt_.mu_mode == MuMode::damping, opt_.edge / damping_step(opt_.damping),
                     job.solver, s.solution);
}

template <int N>
std::shared_ptr<typename SamplesAhead<N>::Job> SamplesAhead<N>::fresh_job() {
  std::shared_ptr<Job> job;
  if (spare_.empty()) {
    job = std::make_shared<Job>();
  } else {
    job = std::move(spare_.back());
    spare_.pop_back();
  }
  job->samples.has_segments = false;
  job->state.store(pending);
  return job;
}

template <int N>
void SamplesAhead<N>::retire(std::shared_ptr<Job> job) {
  if (!job) return;
  int expected = pending;
  job->state.compare_exchange_strong(expected, failed);  // a queued task leaves it alone
  // Reused only once no task holds it: the one that ran it has finished with its vectors.
  const int state = job->state.load(std::memory_order_acquire);
  if (state != running && job.use_count() == 1 && spare_.size() < kMostSpare)
    spare_.push_back(std::move(job));
}

template <int N>
void SamplesAhead<N>::start(const Front<N>& f) {
  if (!enabled_) return;
  std::shared_ptr<Job> job = fresh_job();
  job->closed = f.closed;
  job->x.resize(f.v.size());
  for (std::size_t i = 0; i < f.v.size(); ++i) job->x[i] = f.v[i].x;
  next_.push_back(job);
  ++started_;
  group_.run([this, job] {
    int expected = pending;
    if (!job->state.compare_exchange_strong(expected, running)) return;
    try {
      sample(*job);
      job->state.store(done, std::memory_order_release);
    } catch (...) {
      job->state.store(failed, std::memory_order_release);  // the step works in place
    }
  });
}

template <int N>
void SamplesAhead<N>::begin_step() {
  retire(std::move(taken_));
  for (auto& job : current_) retire(std::move(job));
  current_.clear();
  current_.swap(next_);
}

template <int N>
typename SamplesAhead<N>::Samples* SamplesAhead<N>::take(const Front<N>& f) {
  retire(std::move(taken_));
  const std::size_t n = f.v.size();
  for (auto it = current_.begin(); it != current_.end(); ++it) {
    Job& job = **it;
    if (job.x.size() != n || job.closed != f.closed) continue;
    bool same = true;
    for (std::size_t i = 0; i < n && same; ++i) same = job.x[i] == f.v[i].x;
    if (!same) continue;
    taken_ = std::move(*it);
    current_.erase(it);
    int state = job.state.load(std::memory_order_acquire);
    if (state == pending && job.state.compare_exchange_strong(state, running)) {
      // No task has begun it: taken here, as in place (the caller's path is the same either way).
      try {
        sample(job);
      } catch (...) {
        job.state.store(failed);
        return nullptr;  // the caller samples in place, where the error surfaces
      }
      job.state.store(done);
      return &job.samples;
    }
    // Being taken: the task's thread may have been held up (a machine shared with others), and
    // waiting could then cost more than the work; the caller does it in place.
    if (state != done) return nullptr;
    ++used_;
    return &job.samples;
  }
  return nullptr;
}

template class SamplesAhead<3>;
template class SamplesAhead<4>;

}  // namespace orthofront
