#pragma once
// A resident particle set driven as a streak surface drives it: particles placed, parked, their
// slots reused (parked and placed again, placed twice, placed and parked before the next move) and
// new slots beyond the set's size, between intervals; with `bulk`, one call placing that many
// (new slots, and slots changed already since the last move) in the second interval, and the
// same with a slot given twice (the last placement holds) in the third. Each interval's view is
// recorded, and checked against a reference backend's advect() of the moving particles, bit for
// bit.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <map>
#include <random>
#include <vector>

#include "orthofront/advect/resident_particles.h"

namespace orthofront::test_support {

struct ResidentRecord {
  std::array<std::vector<double>, 3> x;
  std::vector<advect::ParticleStatus> status;
};

/// `intervals` moves of equal length over [t0, t1]; particles drawn in [lo, hi] per axis (2D: z
/// stays 0). Returns each interval's view (every slot placed and not parked since).
inline std::vector<ResidentRecord> run_resident_scenario(
    advect::ResidentParticles& set, advect::StepSource& source, const advect::MethodOptions& o,
    const std::array<double, 3>& lo, const std::array<double, 3>& hi, int dimension, std::size_t n,
    double t0, double t1, int intervals, advect::BatchAdvector* reference, std::size_t bulk = 0) {
  using advect::ParticleStatus;
  std::mt19937_64 rng(12345);
  const auto draw = [&] {
    std::array<double, 3> p{0, 0, 0};
    for (int d = 0; d < dimension; ++d)
      p[static_cast<std::size_t>(d)] =
          std::uniform_real_distribution<double>(lo[static_cast<std::size_t>(d)], hi[static_cast<std::size_t>(d)])(rng);
    return p;
  };
  // What the set should hold: slot -> position and status (absent: parked or never placed).
  std::map<std::uint32_t, std::pair<std::array<double, 3>, ParticleStatus>> held;
  const auto place = [&](std::uint32_t slot, const std::array<double, 3>& x) {
    set.place(std::span<const std::uint32_t>(&slot, 1), std::span<const std::array<double, 3>>(&x, 1));
    held[slot] = {x, ParticleStatus::moving};
  };
  const auto park = [&](std::uint32_t slot) {
    set.park(std::span<const std::uint32_t>(&slot, 1));
    held.erase(slot);
  };
  {
    std::vector<std::uint32_t> slots(n);
    std::vector<std::array<double, 3>> x(n);
    for (std::size_t i = 0; i < n; ++i) {
      slots[i] = static_cast<std::uint32_t>(i);
      x[i] = draw();
      held[slots[i]] = {x[i], ParticleStatus::moving};
    }
    set.place(slots, x);  // all at once
  }
  std::uint32_t next = static_cast<std::uint32_t>(n);
  std::vector<ResidentRecord> records;
  for (int k = 0; k < intervals; ++k) {
    if (k > 0) {
      std::vector<std::uint32_t> parked;
      std::size_t i = 0;
      for (auto it = held.begin(); it != held.end(); ++i) {
        const std::uint32_t slot = it->first;
        ++it;
        if ((i + static_cast<std::size_t>(k)) % 7 == 0) {
          park(slot);
          parked.push_back(slot);
        }
      }
      for (std::size_t j = 0; j < parked.size(); j += 2) place(parked[j], draw());  // reused
      if (!parked.empty()) place(parked.front(), draw());                        // placed twice
      for (int j = 0; j < 40; ++j) place(next++, draw());                          // new slots
      place(next, draw());                                                          // placed, then
      park(next++);                                                                 // parked again
      park(next + 5000);                                                            // never placed
      if (bulk > 0 && (k == 1 || k == 2)) {
        std::vector<std::uint32_t> slots;
        std::vector<std::array<double, 3>> x;
        for (std::size_t j = 1; j < parked.size(); j += 2) slots.push_back(parked[j]);  // parked just now
        for (std::size_t j = 0; j < bulk; ++j) slots.push_back(next++);
        if (k == 2) slots.push_back(slots[slots.size() / 2]);  // given twice
        std::reverse(slots.begin(), slots.end());            // the largest slot first
        for (const std::uint32_t slot : slots) {
          x.push_back(draw());
          held[slot] = {x.back(), ParticleStatus::moving};
        }
        set.place(slots, x);
      }
    }
    const double a = t0 + (t1 - t0) * k / intervals, b = t0 + (t1 - t0) * (k + 1) / intervals;
    set.advance(source, a, b, o);
    const advect::ResidentParticles::View v = set.view();
    ResidentRecord r;
    for (std::size_t d = 0; d < 3; ++d) r.x[d].assign(v.x[d], v.x[d] + v.size);
    r.status.assign(v.status, v.status + v.size);
    REQUIRE(v.size >= (held.empty() ? 0 : held.rbegin()->first + 1));
    // The reference: the moving particles in one advect() from a, stopped ones as they were.
    std::vector<std::uint32_t> moving;
    advect::ParticleBatch batch;
    for (const auto& [slot, state] : held)
      if (state.second == ParticleStatus::moving) moving.push_back(slot);
    batch.resize(moving.size());
    for (std::size_t m = 0; m < moving.size(); ++m) {
      for (std::size_t d = 0; d < 3; ++d) batch.x[d][m] = held[moving[m]].first[d];
      batch.t[m] = a;
    }
    if (reference) reference->advect(source, batch, b, o);
    for (std::size_t m = 0; m < moving.size(); ++m) {
      auto& state = held[moving[m]];
      const std::uint32_t s = moving[m];
      if (reference) {
        for (std::size_t d = 0; d < 3; ++d) state.first[d] = batch.x[d][m];
        state.second = batch.status[m];
      } else {
        for (std::size_t d = 0; d < 3; ++d) state.first[d] = r.x[d][s];
        state.second = r.status[s];
      }
    }
    std::size_t differing = 0;
    for (const auto& [slot, state] : held) {
      bool same = r.status[slot] == state.second;
      for (std::size_t d = 0; d < 3; ++d) same = same && std::memcmp(&r.x[d][slot], &state.first[d], sizeof(double)) == 0;
      differing += !same;
    }
    INFO("interval " << k << ": " << held.size() << " particles held, " << moving.size() << " moved");
    CHECK(differing == 0);
    records.push_back(std::move(r));
  }
  return records;
}

}  // namespace orthofront::test_support
