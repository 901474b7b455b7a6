#include "orthofront/engine/seed_shot_legs.h"

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <cmath>

namespace orthofront {

namespace {

/// Tasks queued at most: beyond it no thread is free for them anyway.
constexpr int kMostQueued = 16;

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
  std::atomic<bool> retired{false};  ///< its legs not begun are not needed any more

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
                              const Tolerance& tolerance, const StopRequest& stop)
    : field_(field), seed_(seed), tol_(tolerance), stop_(stop),
      current_(std::make_shared<Batch>()), next_(std::make_shared<Batch>()) {}

template <int N>
SeedShotLegs<N>::~SeedShotLegs() {
  drop_pending();
  group_.wait();  // legs in flight finish; queued tasks find nothing to do
}

template <int N>
IntegrationResult<N> SeedShotLegs<N>::integrate(double s, double t1) const {
  const Vec<N> start = seed_.point(seed_.closed ? s - std::floor(s) : s);
  return integrate_dopri5(field_, start, t1, tol_, 0, &stop_);
}

template <int N>
IntegrationResult<N> SeedShotLegs<N>::leg(double s, double t1) const {
  const auto it = current_->by_s.find(s);
  if (it == current_->by_s.end() || it->second->t1 != t1) return integrate(s, t1);
  Leg& l = *it->second;
  int state = pending;
  if (l.state.compare_exchange_strong(state, running)) {
    l.result = integrate(s, t1);
    l.state = done;
    l.state.notify_all();
  } else {
    while (state == running) {
      l.state.wait(running);
      state = l.state.load();
    }
    if (state == dropped) return integrate(s, t1);  // (after drop_pending)
  }
  found_.fetch_add(1, std::memory_order_relaxed);
  return l.result;
}

template <int N>
bool SeedShotLegs<N>::can_run_ahead() const {
  return tbb::this_task_arena::max_concurrency() > 1 &&
         tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism) > 1;
}

template <int N>
void SeedShotLegs<N>::start_ahead(const std::vector<std::pair<double, double>>& legs) {
  if (legs.empty() || queued_.load() >= kMostQueued) return;
  std::vector<Leg*> mine;
  mine.reserve(legs.size());
  for (const auto& [s, t1] : legs) {
    if (next_->by_s.contains(s)) continue;
    Leg& l = next_->legs.emplace_back();
    l.s = s;
    l.t1 = t1;
    next_->by_s.emplace(s, &l);
    mine.push_back(&l);
  }
  started_ += mine.size();
  queued_.fetch_add(1);
  group_.run([this, batch = next_, mine = std::move(mine)] {
    queued_.fetch_sub(1);
    // From the last: split_long takes its insertions in front order, so where it gets here
    // first it claims legs from the other end (leg()), and the two meet.
    for (auto it = mine.rbegin(); it != mine.rend(); ++it) {
      Leg* l = *it;
      if (batch->retired) break;
      int expected = pending;
      if (!l->state.compare_exchange_strong(expected, running)) continue;
      l->result = integrate(l->s, l->t1);
      l->state = done;
      l->state.notify_all();
    }
  });
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
