// [gpu] The CUDA backend against the CPU backend on the same inputs: random particles in analytic
// flows sampled on 2D and 3D, uniform and rectilinear grids, crossing cells, leaving the domain
// and entering cells without data; uploads that overlap the kernels; a resident set on the
// device, and the page-locked memory it gives back reused by the next. Built only with CUDA; on
// a machine without a CUDA device each test says so and does nothing.
#include <catch2/catch.hpp>

#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <random>
#include <thread>
#include <vector>

#include "orthofront/advect/batch_advector.h"
#include "orthofront/advect/merging_advector.h"
#include "orthofront/field/unsteady.h"
#include "lib/resident_scenario.h"

using namespace orthofront;
using namespace orthofront::advect;

namespace {

// The double gyre (2D) or unsteady ABC (3D) flow sampled on a grid over `steps` times; samples in
// a disc (2D) or ball (3D) are NaN (no data).
ResidentSteps sampled(int dimension, bool rectilinear, std::int64_t n, std::size_t steps,
                      bool hole) {
  const auto flow = make_unsteady_field(dimension == 2 ? "double-gyre" : "unsteady-abc");
  const Box<3> box = flow->domain();
  const std::array<double, 3> lo{box.lo[0], box.lo[1], box.lo[2]}, hi{box.hi[0], box.hi[1], box.hi[2]};
  GridGeometry g;
  g.dimension = dimension;
  for (std::size_t a = 0; a < 3; ++a) {
    const bool used = static_cast<int>(a) < dimension;
    g.size[a] = used ? n : 1;
    g.origin[static_cast<int>(a)] = used ? lo[a] : 0;
    g.spacing[static_cast<int>(a)] = used ? (hi[a] - lo[a]) / static_cast<double>(n - 1) : 1;
    if (!rectilinear) continue;
    // Cells widening along the axis (quadratic spacing).
    for (std::int64_t i = 0; i < g.size[a]; ++i) {
      const double s = used ? static_cast<double>(i) / static_cast<double>(n - 1) : 0;
      g.axes[a].push_back(used ? lo[a] + (hi[a] - lo[a]) * (0.5 * s + 0.5 * s * s) : 0);
    }
  }
  std::vector<double> times;
  std::vector<std::vector<float>> data;
  const int c = dimension;
  for (std::size_t k = 0; k < steps; ++k) {
    const double t = 0.1 * static_cast<double>(k);
    times.push_back(t);
    std::vector<float> v(g.point_count() * static_cast<std::size_t>(c));
    for (std::int64_t z = 0; z < g.size[2]; ++z)
      for (std::int64_t y = 0; y < g.size[1]; ++y)
        for (std::int64_t x = 0; x < g.size[0]; ++x) {
          const Vec3 p(g.coordinate(0, x), g.coordinate(1, y), dimension == 3 ? g.coordinate(2, z) : 0.0);
          Vec3 u = Vec3::Zero();
          flow->velocity(p, t, u);
          // A disc (ball) around the centre, radius 15 % of the box's diagonal.
          double r2 = 0, diagonal2 = 0;
          for (int d = 0; d < dimension; ++d) {
            const double centre = 0.5 * (box.lo[d] + box.hi[d]), width = box.hi[d] - box.lo[d];
            r2 += (p[d] - centre) * (p[d] - centre);
            diagonal2 += width * width;
          }
          const bool in_hole = hole && r2 < 0.0225 * diagonal2;
          for (int d = 0; d < c; ++d)
            v[g.index(x, y, z) * static_cast<std::size_t>(c) + static_cast<std::size_t>(d)] =
                in_hole ? std::nanf("") : static_cast<float>(u[d]);
        }
    data.push_back(std::move(v));
  }
  return ResidentSteps(g, c, times, std::move(data));
}

ParticleBatch random_batch(const GridGeometry& g, std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  ParticleBatch b;
  b.resize(n);
  const Box<3> box = g.bounds();
  for (std::size_t i = 0; i < n; ++i) {
    for (int d = 0; d < g.dimension; ++d) {
      // Some start just outside the box.
      std::uniform_real_distribution<double> u(box.lo[d] - 0.02 * (box.hi[d] - box.lo[d]),
                                               box.hi[d] + 0.02 * (box.hi[d] - box.lo[d]));
      b.x[static_cast<std::size_t>(d)][i] = u(rng);
    }
    b.t[i] = 0.05 * static_cast<double>(i % 7);
  }
  return b;
}

// A CUDA build on a machine without a GPU (CI): the test says so and does nothing.
bool skip_without_gpu() {
  std::string why;
  if (cuda_available(&why)) return false;
  WARN("[gpu] skipped: " << why);
  return true;
}

}  // namespace

TEST_CASE("cuda advection agrees with the CPU backend", "[gpu][advect]") {
  if (skip_without_gpu()) return;
  const auto cpu = make_cpu_advector();
  const auto gpu = make_advector(Device::cuda);
  for (const int dimension : {2, 3})
    for (const bool rectilinear : {false, true})
      for (const Method method : {Method::rk4, Method::dopri5}) {
        INFO("dimension " << dimension << (rectilinear ? " rectilinear" : " uniform")
                          << (method == Method::rk4 ? " RK4" : " DOPRI5"));
        ResidentSteps series = sampled(dimension, rectilinear, dimension == 2 ? 129 : 33, 9, true);
        MethodOptions o;
        o.method = method;
        o.rk4_step = 0.005;
        o.absolute = o.relative = 1e-9;
        const ParticleBatch start = random_batch(series.geometry(), 20000, 3);
        ParticleBatch a = start, b = start;
        const AdvectionStatistics sa = cpu->advect(series, a, 0.8, o);
        const AdvectionStatistics sb = gpu->advect(series, b, 0.8, o);
        CHECK(sa.slabs == sb.slabs);
        std::size_t differing_status = 0, moved = 0, left = 0, no_data = 0;
        double worst = 0;
        for (std::size_t i = 0; i < start.size(); ++i) {
          if (a.status[i] != b.status[i]) ++differing_status;
          moved += a.status[i] == ParticleStatus::moving;
          left += a.status[i] == ParticleStatus::left_domain;
          no_data += a.status[i] == ParticleStatus::no_data;
          for (std::size_t d = 0; d < 3; ++d) {
            const double scale = std::max(1.0, std::abs(a.x[d][i]));
            worst = std::max(worst, std::abs(a.x[d][i] - b.x[d][i]) / scale);
          }
        }
        INFO("moving " << moved << ", left " << left << ", no data " << no_data
                       << ", largest relative difference " << worst);
        CHECK(differing_status == 0);
        CHECK(moved > 0);
        CHECK(left > 0);
        CHECK(no_data > 0);
        // Same arithmetic (FMA contraction off, no library math in the step controller): the
        // same bits.
        CHECK(worst == 0.0);
        CHECK(sa.particle_steps == sb.particle_steps);
      }
}

TEST_CASE("cuda advection: the upload of the next step overlaps the kernels of this slab",
          "[gpu][advect]") {
  if (skip_without_gpu()) return;
  const auto gpu = make_advector(Device::cuda);
  ResidentSteps series = sampled(3, false, 160, 8, false);
  ParticleBatch b = random_batch(series.geometry(), 2'000'000, 9);
  for (std::size_t i = 0; i < b.size(); ++i) b.t[i] = 0;
  MethodOptions o;
  o.method = Method::rk4;
  o.rk4_step = 0.002;
  const AdvectionStatistics s = gpu->advect(series, b, 0.7, o);
  INFO("kernels " << s.compute_seconds << " s, uploads " << s.upload_seconds << " s, overlap "
                  << s.overlap_seconds << " s");
  CHECK(s.slabs == 7);
  CHECK(s.bytes_uploaded == 8 * series.geometry().point_count() * 3 * sizeof(float));
  // Six of the eight uploads are issued while a slab computes; most of their time overlaps.
  CHECK(s.overlap_seconds > 0.5 * s.upload_seconds * 6.0 / 8.0);
}

TEST_CASE("cuda advection: steps stay on the device between calls on the same source",
          "[gpu][advect]") {
  if (skip_without_gpu()) return;
  const auto cpu = make_cpu_advector();
  const auto gpu = make_advector(Device::cuda);
  ResidentSteps series = sampled(2, false, 257, 11, false);
  const std::size_t step_bytes = series.geometry().point_count() * 2 * sizeof(float);
  const ParticleBatch start = random_batch(series.geometry(), 5000, 4);
  ParticleBatch a = start, b = start;
  MethodOptions o;
  // One interval a call, as a streak surface advances: each call after the first finds one of
  // its two steps on the device already.
  std::size_t uploaded = 0;
  for (int k = 1; k <= 10; ++k) {
    const double t = 0.1 * k;
    cpu->advect(series, a, t, o);
    const AdvectionStatistics s = gpu->advect(series, b, t, o);
    uploaded += s.bytes_uploaded;
  }
  INFO("uploaded " << uploaded << " bytes, a step is " << step_bytes);
  CHECK(uploaded == 11 * step_bytes);  // every step once
  for (std::size_t i = 0; i < start.size(); ++i) {
    REQUIRE(a.status[i] == b.status[i]);
    for (std::size_t d = 0; d < 3; ++d) REQUIRE(a.x[d][i] == b.x[d][i]);
  }
  // Another source (even with the same contents) is uploaded again.
  ResidentSteps copy = series;
  ParticleBatch c = start;
  const AdvectionStatistics s = gpu->advect(copy, c, 0.1, o);
  CHECK(s.bytes_uploaded == 2 * step_bytes);
}

TEST_CASE("cuda advection: own end times and a device budget give the CPU's bits, steps within "
          "the budget are not uploaded again",
          "[gpu][advect]") {
  if (skip_without_gpu()) return;
  const auto cpu = make_cpu_advector();
  ResidentSteps series = sampled(3, false, 65, 11, true);
  const std::size_t step_bytes = series.geometry().point_count() * 3 * sizeof(float);
  ParticleBatch start = random_batch(series.geometry(), 20000, 9);
  start.stop.resize(start.size());
  for (std::size_t i = 0; i < start.size(); ++i) {
    start.t[i] = 0.05 * static_cast<double>(i % 7);          // 0 … 0.3
    start.stop[i] = start.t[i] + 0.1 * static_cast<double>(1 + i % 5);  // up to 0.8
  }
  MethodOptions o;
  o.absolute = o.relative = 1e-8;
  for (const std::size_t budget : {3 * step_bytes, std::size_t{0}}) {
    INFO("device budget " << budget << " bytes");
    const auto gpu = make_advector(Device::cuda, budget);
    ParticleBatch a = start, b = start;
    cpu->advect(series, a, 0.8, o);
    const AdvectionStatistics first = gpu->advect(series, b, 0.8, o);
    CHECK(first.bytes_uploaded == 9 * step_bytes);  // steps 0 … 8
    for (std::size_t i = 0; i < start.size(); ++i) {
      REQUIRE(a.status[i] == b.status[i]);
      REQUIRE(a.t[i] == b.t[i]);
      for (std::size_t d = 0; d < 3; ++d) REQUIRE(a.x[d][i] == b.x[d][i]);
    }
    // The same span again: with three steps on the device (least recently used out) every step
    // goes up again; with the default budget (half the free memory) none does.
    ParticleBatch c = start;
    const AdvectionStatistics again = gpu->advect(series, c, 0.8, o);
    CHECK(again.bytes_uploaded == (budget ? 9 * step_bytes : 0));
  }
}

TEST_CASE("cuda advection: calls merged from several threads, one at a time or running at once, "
          "give each particle the bits of a call of its own",
          "[gpu][advect]") {
  if (skip_without_gpu()) return;
  ResidentSteps series = sampled(3, true, 49, 11, true);
  const std::size_t step_bytes = series.geometry().point_count() * 3 * sizeof(float);
  MethodOptions o;
  o.absolute = o.relative = 1e-8;
  // Twelve fronts' worth of particles, each call with its own start and end (up to 9 slabs).
  constexpr std::size_t calls = 12;
  std::vector<ParticleBatch> start(calls);
  std::vector<double> t_end(calls);
  for (std::size_t k = 0; k < calls; ++k) {
    start[k] = random_batch(series.geometry(), 500 + 300 * k, static_cast<unsigned>(k + 1));
    for (std::size_t i = 0; i < start[k].size(); ++i) start[k].t[i] = 0.02 * static_cast<double>(k);
    t_end[k] = 0.4 + 0.04 * static_cast<double>(k);
  }
  const auto alone = make_advector(Device::cuda);
  std::vector<ParticleBatch> expected = start;
  for (std::size_t k = 0; k < calls; ++k) alone->advect(series, expected[k], t_end[k], o);

  struct Way {
    const char* name;
    std::size_t concurrent_calls;  // 0: the backend's
    std::size_t device_steps;      // 0: the default budget
  };
  // Seven steps on the device: three calls at once ((7 - 1) / 2), evicting each other's steps
  // as their slabs move on; three steps: one call at a time.
  const Way ways[] = {{"one call at a time", 1, 0},
                      {"calls at once", 0, 0},
                      {"calls at once, 7 steps on the device", 0, 7},
                      {"calls at once, 3 steps on the device", 0, 3}};
  for (const Way& way : ways) {
    SECTION(way.name) {
      MergingAdvector merging(make_advector(Device::cuda, way.device_steps * step_bytes), true,
                              way.concurrent_calls);
      CHECK(merging.concurrent_calls() == (way.concurrent_calls == 1 ? 1 : 16));
      std::vector<ParticleBatch> merged = start;
      std::vector<std::thread> threads;
      for (std::size_t k = 0; k < calls; ++k)
        threads.emplace_back([&, k] {
          for (int repeat = 0; repeat < 4; ++repeat) {
            ParticleBatch p = start[k];
            merging.advect(series, p, t_end[k], o);
            if (repeat == 0) merged[k] = std::move(p);
          }
        });
      for (auto& t : threads) t.join();
      for (std::size_t k = 0; k < calls; ++k) {
        const ParticleBatch& a = expected[k];
        for (std::size_t i = 0; i < a.size(); ++i) {
          REQUIRE(a.status[i] == merged[k].status[i]);
          REQUIRE(a.t[i] == merged[k].t[i]);
          REQUIRE(a.evaluations[i] == merged[k].evaluations[i]);
          for (std::size_t d = 0; d < 3; ++d) REQUIRE(a.x[d][i] == merged[k].x[d][i]);
        }
      }
      const MergeStatistics s = merging.merge_statistics();
      CHECK(s.requests == 4 * calls);
      CHECK(s.backend_calls <= s.requests);
      WARN(way.name << ": " << s.requests << " calls ran as " << s.backend_calls
                    << " backend calls (largest " << s.largest_merge << "), backend "
                    << s.backend_seconds << " s summed over calls, kernels " << s.kernel_seconds
                    << " s");
    }
  }
}

TEST_CASE("cuda advection: a resident set on the device gives the CPU backend's bits, interval "
          "after interval, as slots are parked, reused and added",
          "[gpu][advect]") {
  if (skip_without_gpu()) return;
  const auto cpu = make_cpu_advector();
  const auto gpu = make_advector(Device::cuda);
  for (const int dimension : {2, 3}) {
    INFO("dimension " << dimension);
    ResidentSteps series = sampled(dimension, false, dimension == 2 ? 129 : 33, 9, true);
    MethodOptions o;
    o.method = Method::dopri5;
    o.absolute = o.relative = 1e-8;
    const Box<3> box = series.geometry().bounds();
    std::array<double, 3> lo{}, hi{};
    for (std::size_t d = 0; d < 3; ++d) {
      const double w = box.hi[static_cast<int>(d)] - box.lo[static_cast<int>(d)];
      lo[d] = box.lo[static_cast<int>(d)] - 0.02 * w;  // some start outside
      hi[d] = box.hi[static_cast<int>(d)] + 0.02 * w;
    }
    const auto set = gpu->make_resident();
    const auto records = test_support::run_resident_scenario(*set, series, o, lo, hi, dimension, 20000,
                                                             0.05, 0.75, 5, cpu.get(), kParallelPlacements + 500);
    std::size_t moving = 0;
    for (const ParticleStatus s : records.back().status) moving += s == ParticleStatus::moving;
    CHECK(moving > 1000);
  }
}

TEST_CASE("cuda advection: a resident set's next step is read between calls, each step is "
          "uploaded once and counted by the call that uses it, the CPU backend's bits",
          "[gpu][advect]") {
  if (skip_without_gpu()) return;
  const auto cpu = make_cpu_advector();
  const auto gpu = make_advector(Device::cuda);
  ResidentSteps series = sampled(2, false, 257, 11, false);  // steps 0.1 apart
  const std::size_t step_bytes = series.geometry().point_count() * 2 * sizeof(float);
  const ParticleBatch start = random_batch(series.geometry(), 4000, 9);
  std::vector<std::uint32_t> slots;
  std::vector<std::array<double, 3>> at;
  for (std::size_t i = 0; i < start.size(); ++i) {
    slots.push_back(static_cast<std::uint32_t>(i));
    at.push_back({start.x[0][i], start.x[1][i], 0});
  }
  MethodOptions o;
  o.method = Method::dopri5;
  const auto on_gpu = gpu->make_resident();
  const auto on_cpu = cpu->make_resident();
  on_gpu->place(slots, at);
  on_cpu->place(slots, at);
  // Four intervals a step, as a streak surface's are shorter than a step: the step after the
  // last a call read is staged for a later call while the caller waits (here: sleeps).
  std::size_t loaded = 0, ahead = 0, uploaded = 0, calls_reading = 0;
  for (int k = 1; k <= 40; ++k) {
    const double t0 = 0.025 * (k - 1), t1 = 0.025 * k;
    const AdvectionStatistics g = on_gpu->advance(series, t0, t1, o);
    on_cpu->advance(series, t0, t1, o);
    loaded += g.steps_loaded;
    ahead += g.steps_read_ahead;
    uploaded += g.bytes_uploaded;
    calls_reading += g.steps_loaded > 0;
    CHECK(g.steps_read_ahead <= g.steps_loaded);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  CHECK(loaded == 11);  // every step once: read ahead or in the call
  CHECK(uploaded == 11 * step_bytes);
  CHECK(ahead == 9);    // all but the first call's two
  CHECK(calls_reading == 10);  // the first, then each first call in a new step
  // (The host set grows by half its size: slots past those placed are parked.)
  const ResidentParticles::View a = on_cpu->view(), b = on_gpu->view();
  REQUIRE(a.size >= start.size());
  REQUIRE(b.size == start.size());
  std::size_t moving = 0;
  for (std::size_t i = 0; i < start.size(); ++i) {
    REQUIRE(a.status[i] == b.status[i]);
    for (std::size_t d = 0; d < 2; ++d) REQUIRE(a.x[d][i] == b.x[d][i]);
    moving += a.status[i] == ParticleStatus::moving;
  }
  CHECK(moving > 1000);
}

TEST_CASE("cuda advection: a resident set's slot placed and parked again before any advance, at "
          "the end of its arrays, is never written, a set with nothing moving reads no step",
          "[gpu][advect]") {
  if (skip_without_gpu()) return;
  const auto gpu = make_advector(Device::cuda);
  ResidentSteps series = sampled(2, false, 65, 3, false);
  MethodOptions o;
  o.method = Method::rk4;
  o.rk4_step = 0.05;
  const Box<3> box = series.geometry().bounds();
  const std::array<double, 3> centre{0.5 * (box.lo[0] + box.hi[0]), 0.5 * (box.lo[1] + box.hi[1]), 0};
  {
    // A fresh set: nothing is placed in the end, so it holds no slot at all.
    const auto set = gpu->make_resident();
    const std::uint32_t slot = 0;
    set->place(std::span<const std::uint32_t>(&slot, 1), std::span<const std::array<double, 3>>(&centre, 1));
    set->park(std::span<const std::uint32_t>(&slot, 1));
    set->advance(series, 0, 0.1, o);
    CHECK(set->view().size == 0);
    // A particle outside the grid stops at once; then nothing moves and no step is read.
    const std::array<double, 3> outside{box.hi[0] + 1, centre[1], 0};
    set->place(std::span<const std::uint32_t>(&slot, 1), std::span<const std::array<double, 3>>(&outside, 1));
    CHECK(set->advance(series, 0, 0.1, o).particles == 1);
    CHECK(set->view().status[0] == ParticleStatus::left_domain);
    const AdvectionStatistics idle = set->advance(series, 0.1, 0.2, o);
    CHECK(idle.particles == 0);
    CHECK(idle.steps_loaded == 0);
    CHECK(idle.slabs == 0);
  }
  {
    // The first growth holds exactly the slots placed (2^20); the slot after them is placed and
    // parked: it lies past the arrays' end.
    const auto set = gpu->make_resident();
    const std::size_t n = std::size_t{1} << 20;
    std::vector<std::uint32_t> slots(n);
    std::vector<std::array<double, 3>> x(n, centre);
    for (std::size_t i = 0; i < n; ++i) slots[i] = static_cast<std::uint32_t>(i);
    set->place(slots, x);
    const auto last = static_cast<std::uint32_t>(n);
    set->place(std::span<const std::uint32_t>(&last, 1), std::span<const std::array<double, 3>>(&centre, 1));
    set->park(std::span<const std::uint32_t>(&last, 1));
    set->advance(series, 0, 0.1, o);
    const ResidentParticles::View v = set->view();
    REQUIRE(v.size == n);
    CHECK(v.status[n - 1] == ParticleStatus::moving);
    // The device is still usable: another advance runs.
    set->advance(series, 0.1, 0.2, o);
    CHECK(set->view().status[0] == ParticleStatus::moving);
  }
}

TEST_CASE("cuda advection: page-locked memory a set gave back is reused by the next set on the "
          "same backend (none made in its calls), with the CPU backend's bits",
          "[gpu][advect]") {
  if (skip_without_gpu()) return;
  const auto cpu = make_cpu_advector();
  const auto gpu = make_advector(Device::cuda);
  ResidentSteps series = sampled(3, false, 17, 4, true);
  MethodOptions o;
  o.method = Method::dopri5;
  o.absolute = o.relative = 1e-8;
  // Positions and statuses of n particles (drawn with `seed`) after two intervals, and the
  // seconds the set's calls spent making page-locked memory.
  struct Moved {
    std::vector<double> x[3];
    std::vector<ParticleStatus> status;
    double pinned_seconds = 0;
  };
  const auto move = [&](BatchAdvector& backend, std::size_t n, unsigned seed) {
    const ParticleBatch start = random_batch(series.geometry(), n, seed);
    std::vector<std::uint32_t> slots(n);
    std::vector<std::array<double, 3>> x(n);
    for (std::size_t i = 0; i < n; ++i) {
      slots[i] = static_cast<std::uint32_t>(i);
      x[i] = {start.x[0][i], start.x[1][i], start.x[2][i]};
    }
    const auto set = backend.make_resident();
    set->place(slots, x);
    Moved m;
    m.pinned_seconds += set->advance(series, 0, 0.1, o).pinned_seconds;
    m.pinned_seconds += set->advance(series, 0.1, 0.25, o).pinned_seconds;
    // The placed slots (the CPU's set may hold more, parked).
    const ResidentParticles::View v = set->view();
    REQUIRE(v.size >= n);
    for (int d = 0; d < 3; ++d) m.x[d].assign(v.x[d], v.x[d] + n);
    m.status.assign(v.status, v.status + n);
    return m;
  };
  const auto same = [](const Moved& a, const Moved& b) {
    bool bits = a.status == b.status;
    for (int d = 0; d < 3; ++d)
      bits = bits && a.x[d].size() == b.x[d].size() &&
             std::memcmp(a.x[d].data(), b.x[d].data(), a.x[d].size() * sizeof(double)) == 0;
    return bits;
  };
  // The second set moves other particles, fewer: it takes the first's buffers, larger than it
  // asks for and holding the first's results, and must write its own.
  const Moved first = move(*gpu, 5000, 11);
  const Moved second = move(*gpu, 4000, 12);
  CHECK(first.pinned_seconds > 0);    // the first set's mirror and changes were made
  CHECK(second.pinned_seconds == 0);  // the second took them back
  CHECK(same(first, move(*cpu, 5000, 11)));
  CHECK(same(second, move(*cpu, 4000, 12)));
  std::size_t moving = 0;
  for (const ParticleStatus s : second.status) moving += s == ParticleStatus::moving;
  CHECK(moving > 1000);
}
