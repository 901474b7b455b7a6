// Calls merged by advect::MergingAdvector: requests that arrive while the backend is busy go
// together in one backend call, and each particle ends exactly where a call of its own puts it.
#include <catch2/catch.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <random>
#include <thread>
#include <vector>

#include "orthofront/advect/batch_advector.h"
#include "orthofront/advect/merging_advector.h"

using namespace orthofront;
using namespace orthofront::advect;

namespace {

// A swirl with a time-dependent shear on [-1, 1]^3, sampled at 5 times.
ResidentSteps swirl_series() {
  GridGeometry g;
  g.dimension = 3;
  g.size = {17, 17, 17};
  g.origin = Vec3(-1, -1, -1);
  g.spacing = Vec3(0.125, 0.125, 0.125);
  std::vector<double> times{0, 0.25, 0.5, 0.75, 1};
  std::vector<std::vector<float>> steps;
  for (const double t : times) {
    std::vector<float> v(g.point_count() * 3);
    for (std::int64_t k = 0; k < g.size[2]; ++k)
      for (std::int64_t j = 0; j < g.size[1]; ++j)
        for (std::int64_t i = 0; i < g.size[0]; ++i) {
          const double x = g.coordinate(0, i), y = g.coordinate(1, j), z = g.coordinate(2, k);
          const std::size_t at = g.index(i, j, k) * 3;
          v[at] = static_cast<float>(-y + 0.3 * t * std::sin(3 * z));
          v[at + 1] = static_cast<float>(x);
          v[at + 2] = static_cast<float>(0.5 * std::cos(2 * x) - 0.2 * z);
        }
    steps.push_back(std::move(v));
  }
  return ResidentSteps(g, 3, times, std::move(steps));
}

struct Call {
  ParticleBatch particles;
  double t_end = 0;
};

// n particles from time t0 (some near the edge, so they leave the grid), optionally each with its
// own end between t0 and t_end.
Call make_call(std::mt19937& rng, std::size_t n, double t0, double t_end, bool own_ends) {
  std::uniform_real_distribution<double> u(-0.98, 0.98), w(0, 1);
  Call c;
  c.t_end = t_end;
  c.particles.resize(n);
  if (own_ends) c.particles.stop.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (auto& axis : c.particles.x) axis[i] = u(rng);
    c.particles.t[i] = t0;
    if (own_ends) c.particles.stop[i] = t0 + w(rng) * (t_end - t0);
  }
  return c;
}

void require_same(const ParticleBatch& a, const ParticleBatch& b) {
  REQUIRE(a.size() == b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    INFO("particle " << i);
    for (std::size_t d = 0; d < 3; ++d) REQUIRE(a.x[d][i] == b.x[d][i]);
    REQUIRE(a.t[i] == b.t[i]);
    REQUIRE(a.h[i] == b.h[i]);
    REQUIRE(a.evaluations[i] == b.evaluations[i]);
    REQUIRE(a.status[i] == b.status[i]);
  }
}

// Each call from a thread of its own through `merging`; the particles as they came back.
std::vector<ParticleBatch> advect_from_threads(MergingAdvector& merging, StepSource& series,
                                               const std::vector<Call>& calls,
                                               const MethodOptions& options) {
  std::vector<ParticleBatch> out(calls.size());
  std::vector<std::thread> threads;
  for (std::size_t k = 0; k < calls.size(); ++k) {
    out[k] = calls[k].particles;
    threads.emplace_back([&, k] { merging.advect(series, out[k], calls[k].t_end, options); });
  }
  for (auto& t : threads) t.join();
  return out;
}

// Every call's particles in `out` are those of a call of its own on the plain CPU backend.
void require_as_alone(StepSource& series, const std::vector<Call>& calls,
                      const std::vector<ParticleBatch>& out, const MethodOptions& options) {
  const auto cpu = make_cpu_advector();
  for (std::size_t k = 0; k < calls.size(); ++k) {
    INFO("call " << k);
    ParticleBatch p = calls[k].particles;
    cpu->advect(series, p, calls[k].t_end, options);
    require_same(out[k], p);
  }
}

// The CPU backend, whose first call waits until `expected` requests have come in, so that the
// others queue behind it and must be merged.
class GatedBackend final : public BatchAdvector {
 public:
  GatedBackend(const MergingAdvector* const& owner, std::size_t expected)
      : owner_(owner), expected_(expected), cpu_(make_cpu_advector()) {}
  std::string name() const override { return "gated cpu"; }
  AdvectionStatistics advect(StepSource& source, ParticleBatch& particles, double t_end,
                             const MethodOptions& options) override {
    if (calls_++ == 0)
      while (owner_->merge_statistics().requests < expected_)
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    sizes_.push_back(particles.size());
    return cpu_->advect(source, particles, t_end, options);
  }
  const std::vector<std::size_t>& sizes() const { return sizes_; }

 private:
  const MergingAdvector* const& owner_;
  std::size_t expected_;
  std::unique_ptr<BatchAdvector> cpu_;
  std::size_t calls_ = 0;
  std::vector<std::size_t> sizes_;
};

// The CPU backend (on resident steps: safe from several threads) declaring `limit` calls at once;
// each of the first `together` calls waits until that many are inside, so the test sees them run
// side by side; it counts the most calls inside at one time.
class ConcurrentBackend final : public BatchAdvector {
 public:
  ConcurrentBackend(std::size_t limit, std::size_t together)
      : limit_(limit), together_(together), cpu_(make_cpu_advector()) {}
  std::string name() const override { return "concurrent cpu"; }
  std::size_t max_concurrent_calls() const override { return limit_; }
  AdvectionStatistics advect(StepSource& source, ParticleBatch& particles, double t_end,
                             const MethodOptions& options) override {
    const std::size_t inside = ++inside_;
    std::size_t most = most_.load();
    while (inside > most && !most_.compare_exchange_weak(most, inside)) {
    }
    if (started_++ < together_) {
      const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
      while (most_.load() < together_ && std::chrono::steady_clock::now() < give_up)
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    const AdvectionStatistics s = cpu_->advect(source, particles, t_end, options);
    --inside_;
    return s;
  }
  std::size_t most_at_once() const { return most_.load(); }

 private:
  std::size_t limit_, together_;
  std::unique_ptr<BatchAdvector> cpu_;
  std::atomic<std::size_t> inside_{0}, most_{0}, started_{0};
};

}  // namespace

TEST_CASE("merged calls: calls queued behind a busy backend run as one, each particle exactly "
          "as in a call of its own",
          "[advect]") {
  ResidentSteps series = swirl_series();
  MethodOptions dopri;
  dopri.absolute = dopri.relative = 1e-8;
  std::mt19937 rng(11);
  // The first call holds the backend; then four forward calls of different sizes and ends (two
  // with ends of their own), a backward one, and one whose particles lie on both sides of its
  // t_end (it cannot be merged and runs alone).
  std::vector<Call> calls;
  calls.push_back(make_call(rng, 50, 0.0, 0.4, false));
  calls.push_back(make_call(rng, 300, 0.1, 0.9, false));
  calls.push_back(make_call(rng, 20, 0.3, 0.55, true));
  calls.push_back(make_call(rng, 1000, 0.0, 1.0, true));
  calls.push_back(make_call(rng, 7, 0.6, 0.7, false));
  calls.push_back(make_call(rng, 200, 0.9, 0.2, false));
  Call mixed = make_call(rng, 40, 0.2, 0.5, false);
  for (std::size_t i = 0; i < 20; ++i) mixed.particles.t[i] = 0.8;
  calls.push_back(mixed);

  // Each call alone on a plain backend: the reference.
  const auto cpu = make_cpu_advector();
  std::vector<ParticleBatch> alone;
  std::vector<AdvectionStatistics> alone_stats;
  for (const Call& c : calls) {
    ParticleBatch p = c.particles;
    alone_stats.push_back(cpu->advect(series, p, c.t_end, dopri));
    alone.push_back(std::move(p));
  }

  const MergingAdvector* owner = nullptr;
  auto gated = std::make_unique<GatedBackend>(owner, calls.size());
  const GatedBackend& backend = *gated;
  MergingAdvector merging(std::move(gated));
  owner = &merging;
  std::vector<ParticleBatch> merged(calls.size());
  std::vector<AdvectionStatistics> merged_stats(calls.size());
  {
    std::vector<std::thread> threads;
    // The first call starts (and holds the backend) before the others come.
    merged[0] = calls[0].particles;
    threads.emplace_back([&] { merged_stats[0] = merging.advect(series, merged[0], calls[0].t_end, dopri); });
    while (merging.merge_statistics().requests < 1) std::this_thread::yield();
    for (std::size_t k = 1; k < calls.size(); ++k) {
      merged[k] = calls[k].particles;
      threads.emplace_back([&, k] {
        merged_stats[k] = merging.advect(series, merged[k], calls[k].t_end, dopri);
      });
    }
    for (auto& t : threads) t.join();
  }
  for (std::size_t k = 0; k < calls.size(); ++k) {
    INFO("call " << k);
    require_same(merged[k], alone[k]);
    CHECK(merged_stats[k].particles == calls[k].particles.size());
    CHECK(merged_stats[k].evaluations == alone_stats[k].evaluations);
  }
  // The held call, the four forward calls together, the backward call, the mixed one.
  const MergeStatistics s = merging.merge_statistics();
  CHECK(s.requests == 7);
  CHECK(s.backend_calls == 4);
  CHECK(s.largest_merge == 4);
  CHECK(backend.sizes().size() == 4);
  CHECK(std::count(backend.sizes().begin(), backend.sizes().end(), 300 + 20 + 1000 + 7) == 1);
  // Some particles left the grid and some ended early at their own ends: the cases were there.
  std::size_t left = 0;
  for (const ParticleBatch& p : merged)
    left += static_cast<std::size_t>(std::count(p.status.begin(), p.status.end(),
                                                ParticleStatus::left_domain));
  CHECK(left > 0);
}

TEST_CASE("merged calls: without merging, calls take turns one at a time, an error reaches its "
          "caller",
          "[advect]") {
  ResidentSteps series = swirl_series();
  MethodOptions dopri;
  std::mt19937 rng(5);
  MergingAdvector turns(make_cpu_advector(), /*merge=*/false);
  std::vector<Call> calls;
  for (int k = 0; k < 6; ++k) calls.push_back(make_call(rng, 100, 0.0, 0.5 + 0.05 * k, false));
  require_as_alone(series, calls, advect_from_threads(turns, series, calls, dopri), dopri);
  CHECK(turns.merge_statistics().backend_calls == 6);
  CHECK(turns.merge_statistics().largest_merge == 1);
  // A method the backend refuses: the caller gets the backend's exception.
  MethodOptions bad;
  bad.absolute = -1;
  ParticleBatch p = calls[0].particles;
  CHECK_THROWS(turns.advect(series, p, 0.5, bad));
}

TEST_CASE("merged calls: a backend that takes calls at once runs that many side by side, never "
          "more, each particle exactly as in a call of its own",
          "[advect]") {
  ResidentSteps series = swirl_series();
  MethodOptions dopri;
  dopri.absolute = dopri.relative = 1e-8;
  std::mt19937 rng(23);
  std::vector<Call> calls;
  for (int k = 0; k < 9; ++k)
    calls.push_back(make_call(rng, 50 + 40 * static_cast<std::size_t>(k), 0.05 * k,
                              0.5 + 0.05 * k, k % 2 == 0));
  for (const std::size_t limit : {std::size_t{3}, std::size_t{1}}) {
    auto backend = std::make_unique<ConcurrentBackend>(3, limit);
    const ConcurrentBackend& concurrent = *backend;
    MergingAdvector merging(std::move(backend), true, limit);
    CHECK(merging.concurrent_calls() == limit);
    INFO("limit " << limit);
    require_as_alone(series, calls, advect_from_threads(merging, series, calls, dopri), dopri);
    CHECK(concurrent.most_at_once() == limit);
    CHECK(merging.merge_statistics().requests == calls.size());
  }
}
