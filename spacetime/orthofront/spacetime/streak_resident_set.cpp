#include "orthofront/spacetime/streak_resident_set.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <exception>
#include <span>
#include <string>
#include <utility>

#include "orthofront/error.h"
#include "orthofront/stage_timer.h"

namespace orthofront::spacetime {

namespace {

using Clock = std::chrono::steady_clock;

// Counts a particle's stop: [0] left the domain, [1] no data.
void count_stop(ParticleStatus status, std::array<std::size_t, 2>& stopped) {
  if (status == ParticleStatus::left_domain) ++stopped[0];
  if (status == ParticleStatus::no_data) ++stopped[1];
}

}  // namespace

StreakResidentSet::StreakResidentSet(const BulkFlowMap& bulk) : bulk_(bulk), set_(bulk.make_resident()) {}

std::size_t StreakResidentSet::advance(std::vector<StreakRow>& rows, double t_from, double t_to,
                                       Stops& stopped) {
  counts_.evaluations += bulk_.advance(*set_, t_from, t_to);
  return take(rows, stopped);
}

std::size_t StreakResidentSet::take(std::vector<StreakRow>& rows, Stops& stopped,
                                    std::vector<std::vector<std::uint32_t>>* fresh_at) {
  const auto t0 = Clock::now();
  const advect::ResidentParticles::View v = set_->view();
  const std::size_t nr = rows.size();
  std::vector<std::size_t> moved(nr, 0), unplaced(nr, 0);
  std::vector<std::vector<std::uint32_t>> freed(nr);  // slots of particles that stopped
  for_each_row(nr, [&](std::size_t r) {
    std::vector<StreakParticle>& row = rows[r].p;
    for (std::size_t i = 0; i < row.size(); ++i) {
      StreakParticle& p = row[i];
      if (!p.alive()) continue;
      if (fresh(p)) {
        if (fresh_at) (*fresh_at)[r].push_back(static_cast<std::uint32_t>(i));
        continue;
      }
      if (p.slot() >= v.size) {
        ++unplaced[r];
        continue;
      }
      ++moved[r];
      p.x = Vec3(v.x[0][p.slot()], v.x[1][p.slot()], v.x[2][p.slot()]);
      p.set_status(v.status[p.slot()]);
      if (p.alive()) continue;
      count_stop(p.status(), stopped[r]);
      freed[r].push_back(p.slot());  // stopped there: nothing moves it again
      p.set_slot(kNoSlot);
    }
  });
  std::size_t n = 0;
  for (std::size_t r = 0; r < nr; ++r) {
    if (unplaced[r] > 0)
      throw Error("streak surface: " + std::to_string(unplaced[r]) +
                  " moving particles of a row have no place in the resident set");
    n += moved[r];
    free_slots_.insert(free_slots_.end(), freed[r].begin(), freed[r].end());
  }
  counts_.take_seconds += seconds_since(t0);
  return n;
}

void StreakResidentSet::enter(const std::vector<StreakParticle*>& ps) {
  if (ps.empty()) return;
  // The k-th moving particle takes the k-th slot: the free slots from the back, then new ones.
  // Counted in blocks, then handed out block by block in parallel.
  constexpr std::size_t kBlock = 1 << 14;
  const std::size_t blocks = (ps.size() + kBlock - 1) / kBlock;
  std::vector<std::size_t> before(blocks + 1, 0);  // moving particles before each block
  const auto block_range = [&](std::size_t b) {
    return std::pair(b * kBlock, std::min(ps.size(), (b + 1) * kBlock));
  };
  const bool parallel = ps.size() >= kParallelParticles;
  for_each_row(blocks, [&](std::size_t b) {
    const auto [lo, hi] = block_range(b);
    before[b + 1] = static_cast<std::size_t>(std::count_if(ps.begin() + static_cast<std::ptrdiff_t>(lo),
                                                           ps.begin() + static_cast<std::ptrdiff_t>(hi),
                                                           [](const StreakParticle* p) { return p->alive(); }));
  }, parallel);
  for (std::size_t b = 0; b < blocks; ++b) before[b + 1] += before[b];
  const std::size_t moving = before[blocks];
  if (moving == 0) return;
  if (in_flight_ && catching_up_) throw Error("streak surface: a particle entered after its catch-up started");
  const std::size_t free = free_slots_.size();
  if (moving > free && next_slot_ + (moving - free) > StreakParticle::kSlots)
    throw Error("streak surface: " + std::to_string(next_slot_ + (moving - free)) +
                " slots of the resident set in use at once, more than the " +
                std::to_string(StreakParticle::kSlots) + " it can number");
  const auto slot_of = [&](std::size_t k) {
    return k < free ? free_slots_[free - 1 - k] : next_slot_ + static_cast<std::uint32_t>(k - free);
  };
  // Where the moving particles go: the fresh lists while a move is in flight (they catch up and
  // are placed when it lands), else the set, in one call.
  const std::size_t base = fresh_slots_.size();
  std::vector<std::uint32_t> slots;
  std::vector<std::array<double, 3>> at;
  if (in_flight_) {
    fresh_slots_.resize(base + moving);
    fresh_x_.resize(base + moving);
  } else {
    slots.resize(moving);
    at.resize(moving);
  }
  for_each_row(blocks, [&](std::size_t b) {
    const auto [lo, hi] = block_range(b);
    std::size_t k = before[b];
    for (std::size_t i = lo; i < hi; ++i) {
      StreakParticle& p = *ps[i];
      if (!p.alive()) continue;
      p.set_slot(slot_of(k));
      if (in_flight_) {
        fresh_slots_[base + k] = p.slot();
        fresh_x_[base + k] = p.x;
      } else {
        slots[k] = p.slot();
        at[k] = {p.x.x(), p.x.y(), p.x.z()};
      }
      ++k;
    }
  }, parallel);
  free_slots_.resize(free - std::min(free, moving));
  if (moving > free) next_slot_ += static_cast<std::uint32_t>(moving - free);
  if (in_flight_) {
    if (fresh_.size() < next_slot_) fresh_.resize(next_slot_, 0);
    for_each_row(blocks, [&](std::size_t b) {
      const std::size_t lo = base + std::min(moving, b * kBlock), hi = base + std::min(moving, (b + 1) * kBlock);
      for (std::size_t k = lo; k < hi; ++k) fresh_[fresh_slots_[k]] = static_cast<std::uint32_t>(k + 1);
    }, parallel);
  } else {
    set_->place(slots, at);
  }
}

void StreakResidentSet::leave(StreakParticle& p) {
  if (p.slot() == kNoSlot) return;
  if (!in_flight_) {
    const std::uint32_t slot = p.slot();
    set_->park(std::span<const std::uint32_t>(&slot, 1));
    free_slots_.push_back(p.slot());
  } else {
    // The set is moving: a fresh particle was never placed; an old one is parked on landing. The
    // slot is not handed out again before then.
    if (fresh(p)) {
      fresh_[p.slot()] = 0;
    } else {
      flight_parks_.push_back(p.slot());
    }
    flight_freed_.push_back(p.slot());
  }
  p.set_slot(kNoSlot);
}

void StreakResidentSet::launch(double t_from, double t_to) {
  in_flight_ = true;
  flight_from_ = t_from;
  flight_to_ = t_to;
  flight_evaluations_ = 0;
  flight_error_ = nullptr;
  flight_.start([this, t_from, t_to] {
    try {
      flight_evaluations_ = bulk_.advance(*set_, t_from, t_to);
    } catch (...) {
      flight_error_ = std::current_exception();
    }
  });
}

void StreakResidentSet::start_catch_up() {
  catching_up_ = true;
  catch_up_evaluations_ = 0;
  catch_up_call_seconds_ = 0;
  catch_up_error_ = nullptr;
  catch_x_.swap(fresh_x_);
  fresh_x_.clear();
  const std::size_t n = catch_x_.size();
  if (n == 0) return;
  catch_from_.assign(n, flight_from_);
  catch_status_.assign(n, ParticleStatus::moving);
  ++counts_.catch_up_calls;
  counts_.catch_up_particles += n;
  // Each moves as it would have in the set (a call of particles with no step size yet: the same
  // bits).
  catch_up_.start([this, t_to = flight_to_] {
    const auto call = Clock::now();
    try {
      catch_up_evaluations_ = bulk_.advect_all(catch_x_, catch_from_, t_to, catch_status_);
    } catch (...) {
      catch_up_error_ = std::current_exception();
    }
    catch_up_call_seconds_ = seconds_since(call);
  });
}

void StreakResidentSet::wait_flight() {
  flight_.wait();  // the tasks keep what they throw for land()
  catch_up_.wait();
}

std::size_t StreakResidentSet::land(std::vector<StreakRow>& rows, Stops& stopped) {
  if (!catching_up_) start_catch_up();
  flight_.wait();
  const auto c0 = Clock::now();
  catch_up_.wait();
  in_flight_ = false;
  catching_up_ = false;
  // The move's error first (the catch-up may have waited for the move's call to end).
  if (flight_error_) std::rethrow_exception(std::exchange(flight_error_, nullptr));
  if (catch_up_error_) std::rethrow_exception(std::exchange(catch_up_error_, nullptr));
  counts_.evaluations += flight_evaluations_ + catch_up_evaluations_;
  counts_.catch_up_call_seconds += catch_up_call_seconds_;
  double catch_up_seconds = seconds_since(c0);
  const std::size_t nr = rows.size();
  std::vector<std::vector<std::uint32_t>> fresh_at(nr);  // [row]: its fresh particles
  std::size_t moved = take(rows, stopped, &fresh_at);
  if (!flight_parks_.empty()) set_->park(flight_parks_);
  flight_parks_.clear();

  // The fresh particles still in the rows take their catch-up positions; those still moving go
  // into the set, the slots of those that stopped are free.
  const auto c1 = Clock::now();
  std::size_t n = 0;
  for (const std::vector<std::uint32_t>& f : fresh_at) n += f.size();
  if (n > 0) {
    std::vector<std::size_t> with;  // only the rows with fresh particles
    for (std::size_t r = 0; r < nr; ++r)
      if (!fresh_at[r].empty()) with.push_back(r);
    // Millions after a late break: the rows in parallel, the moving ones written where a count of
    // those before them puts them (no pass in turn over them), into arrays kept from the last.
    const bool parallel = n >= kParallelParticles;
    std::vector<std::size_t> kept(with.size() + 1, 0);  // [w + 1]: moving fresh particles of with[w]
    std::vector<std::vector<std::uint32_t>> freed(with.size());
    for_each_row(with.size(), [&](std::size_t w) {
      const std::size_t r = with[w];
      for (const std::uint32_t i : fresh_at[r]) {
        StreakParticle& p = rows[r].p[i];
        const std::size_t c = fresh_[p.slot()] - 1;
        p.x = catch_x_[c];
        p.set_status(catch_status_[c]);
        if (p.alive()) {
          ++kept[w + 1];
          continue;
        }
        count_stop(p.status(), stopped[r]);
        freed[w].push_back(p.slot());
        p.set_slot(kNoSlot);
      }
    }, parallel);
    for (std::size_t w = 0; w < with.size(); ++w) kept[w + 1] += kept[w];
    const std::size_t placed = kept.back();
    if (place_slots_.size() < placed) {
      place_slots_.resize(placed);
      place_at_.resize(placed);
    }
    for_each_row(with.size(), [&](std::size_t w) {
      const std::size_t r = with[w];
      std::size_t k = kept[w];
      for (const std::uint32_t i : fresh_at[r]) {
        const StreakParticle& p = rows[r].p[i];
        if (!p.alive()) continue;
        place_slots_[k] = p.slot();
        place_at_[k++] = {p.x.x(), p.x.y(), p.x.z()};
      }
    }, parallel);
    for (const std::vector<std::uint32_t>& f : freed) free_slots_.insert(free_slots_.end(), f.begin(), f.end());
    set_->place(std::span(place_slots_.data(), placed), std::span(place_at_.data(), placed));
    moved += n;
  }
  // (A range below one grain runs on this thread.)
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, fresh_slots_.size(), 16384),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t k = range.begin(); k != range.end(); ++k) fresh_[fresh_slots_[k]] = 0;
                    });
  fresh_slots_.clear();
  free_slots_.insert(free_slots_.end(), flight_freed_.begin(), flight_freed_.end());
  flight_freed_.clear();
  catch_up_seconds += seconds_since(c1);
  counts_.catch_up_seconds += catch_up_seconds;
  return moved;
}

}  // namespace orthofront::spacetime
