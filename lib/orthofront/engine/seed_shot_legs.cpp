#include "orthofront/engine/seed_shot_legs.h"

#include <cmath>

#include "orthofront/engine/for_range.h"

namespace orthofront {

namespace {

/// Legs queued at most (not begun): beyond it no thread is free for them anyway.
constexpr int kMostQueued = 256;

enum LegState : int { pending, running, done, dropped };

}  // namespace

template <int N>
struct SeedShotLegs<N>::Leg {
  double s = 0, t1 = 0;
  IntegrationResult<N> result{};
  std::atomic<int> state{pending};
};

template <int N>
struct SeedShotLegs<N>::Batch {
  std::deque<Leg> legs;  // a deque: legs keep their addresses while more are added
  std::unordered_map<double, Leg*> by_s;
  std::atomic<bool> retired{false};  ///< nothing looks here any more: legs in flight stop

  void drop_pending() {
    retired = true;
    for (Leg& l : legs) {
      int expected = pending;
      l.state.compare_exchange_strong(expected, dropped);
    }
  }
};

template <int N>
SeedShotLegs<N>::SeedShotLegs(const Field<N>& field, const Seed<N>& seed,
                              const Tolerance& tolerance, const StopRequest& stop,
                              int max_evaluations)
    : field_(field), seed_(seed), tol_(tolerance), stop_(stop), max_evaluations_(max_evaluations),
      current_(std::make_shared<Batch>()), next_(std::make_shared<Batch>()) {}

template <int N>
SeedShotLegs<N>::~SeedShotLegs() {
  drop_pending();
  try {
    group_.wait();  // legs in flight stop; queued tasks find nothing to do
  } catch (...) {
    // (Tasks keep their exceptions to themselves: nothing to rethrow here.)
  }
}

template <int N>
IntegrationResult<N> SeedShotLegs<N>::integrate(double s, double t1,
                                                const StopRequest& stop) const {
  const Vec<N> start = seed_.point(seed_.closed ? s - std::floor(s) : s);
  return integrate_dopri5(field_, start, t1, tol_, 0, &stop, max_evaluations_);
}

template <int N>
IntegrationResult<N> SeedShotLegs<N>::leg(double s, double t1) const {
  const auto it = current_->by_s.find(s);
  if (it == current_->by_s.end() || it->second->t1 != t1) return integrate(s, t1, stop_);
  Leg& l = *it->second;
  for (;;) {
    int state = l.state.load();
    if (state == done) {
      used_.fetch_add(1, std::memory_order_relaxed);
      return l.result;
    }
    if (state == dropped) return integrate(s, t1, stop_);
    if (state == running) {
      l.state.wait(running);  // a task integrates it (and may hand it back as pending)
      continue;
    }
    if (!l.state.compare_exchange_strong(state, running)) continue;
    try {
      l.result = integrate(s, t1, stop_);
    } catch (...) {
      l.state = pending;
      l.state.notify_all();
      throw;
    }
    l.state = done;
    l.state.notify_all();
    return l.result;  // integrated here: not counted as used ahead
  }
}

template <int N>
bool SeedShotLegs<N>::can_run_ahead() const {
  return another_thread_may_run();
}

template <int N>
void SeedShotLegs<N>::start_ahead(const std::vector<std::pair<double, double>>& legs) {
  // One task a leg, spawned last first: an idle thread steals the oldest task, so it works from
  // the last leg while split_long, in front order, claims from the first (leg()).
  for (auto key = legs.rbegin(); key != legs.rend(); ++key) {
    const auto [s, t1] = *key;
    if (queued_.load() >= kMostQueued) return;
    if (next_->by_s.contains(s)) continue;
    Leg& l = next_->legs.emplace_back();
    l.s = s;
    l.t1 = t1;
    next_->by_s.emplace(s, &l);
    ++started_;
    queued_.fetch_add(1);
    group_.run([this, batch = next_, leg = &l] {
      queued_.fetch_sub(1);
      int expected = pending;
      if (batch->retired || !leg->state.compare_exchange_strong(expected, running)) return;
      // A leg nobody will look at any more (the step ended, or the surface) stops early.
      const StopRequest stop = [this, &batch] { return batch->retired.load() || stop_(); };
      try {
        leg->result = integrate(leg->s, leg->t1, stop);
        leg->state = batch->retired ? dropped : done;
      } catch (...) {
        leg->state = pending;  // leg() integrates it in place, where the error surfaces
      }
      leg->state.notify_all();
    });
  }
}

template <int N>
void SeedShotLegs<N>::begin_step() {
  current_->drop_pending();
  current_ = std::move(next_);
  next_ = std::make_shared<Batch>();
}

template <int N>
void SeedShotLegs<N>::drop_pending() {
  current_->drop_pending();
  next_->drop_pending();
}

template class SeedShotLegs<3>;
template class SeedShotLegs<4>;

}  // namespace orthofront
