// Bulk advection on cached series: a slab samples the values of StreamedField bit for bit, whole
// steps gathered from bricks equal the whole-step series, and a streak surface moved by bulk
// advection lies on its particles' path lines, streamed or resident alike.
#include <catch2/catch.hpp>

#include <array>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <set>
#include <thread>
#include <random>
#include <vector>

#include "orthofront/advect/batch_advector.h"
#include "orthofront/advect/dispatch.h"
#include "orthofront/error.h"
#include "orthofront/field/unsteady.h"
#include "orthofront/spacetime/bulk_flow_map.h"
#include "orthofront/spacetime/sampled_series.h"
#include "orthofront/spacetime/streak_surface.h"
#include "orthofront/spacetime/streamed_field.h"
#include "spacetime/reference_path.h"

using namespace orthofront;
using namespace orthofront::spacetime;
using streak_test::reference_path;

TEST_CASE("bulk advection: a slab samples StreamedField's values bit for bit",
          "[spacetime][advect]") {
  const auto flow = make_unsteady_field("unsteady-abc");
  const GridGeometry grid = uniform_grid(flow->domain(), 3, 21);
  const SampledTimeSeries series(*flow, grid, uniform_times(0, 2, 4));
  CacheOptions whole;
  whole.whole_steps = true;
  BrickCache whole_cache(series, whole);
  StreamedField field(whole_cache);
  field.update_band(0, 2);
  CachedSteps whole_steps(whole_cache);
  const advect::GridTables tables(grid, 3, false);
  std::mt19937_64 rng(3);
  const Box<3> box = flow->domain();
  std::uniform_real_distribution<double> u(0, 1);
  std::size_t compared = 0;
  for (std::size_t k = 0; k + 1 < series.step_count(); ++k) {
    for (CachedSteps* steps : {&whole_steps}) {
      advect::SlabView slab;
      slab.grid = tables.view();
      slab.step0 = steps->acquire(k);
      slab.step1 = steps->acquire(k + 1);
      slab.t0 = series.time(k);
      slab.t1 = series.time(k + 1);
      for (int i = 0; i < 300; ++i) {
        const Vec3 x = box.lo + (box.hi - box.lo).cwiseProduct(Vec3(u(rng), u(rng), u(rng)));
        const double t = slab.t0 + (slab.t1 - slab.t0) * u(rng);
        Vec3 want;
        REQUIRE(field.velocity(x, t, want) == FieldStatus::inside);
        double got[3];
        REQUIRE((advect::sample_slab<3, 3, false>(slab, x.data(), t, got)) == advect::SampleStatus::inside);
        for (int d = 0; d < 3; ++d) REQUIRE(got[d] == want[d]);
        ++compared;
      }
      steps->release(k);
      steps->release(k + 1);
    }
  }
  CHECK(compared == 4 * 300);  // 5 steps: 4 slabs
}

namespace {

// The CPU backend, saying that calls may run at once (as CUDA's lanes do). Each call marks its
// particle arrays busy while it runs (two calls given the same arrays are counted) and waits
// for a second call to be in flight, so that calls the map lets through overlap.
class OverlappingBackend final : public advect::BatchAdvector {
 public:
  std::string name() const override { return "cpu, calls at once"; }
  std::size_t max_concurrent_calls() const override { return 4; }
  advect::AdvectionStatistics advect(advect::StepSource& source, advect::ParticleBatch& particles,
                                     double t_end, const advect::MethodOptions& o) override {
    {
      std::unique_lock lock(mutex_);
      if (!busy_.insert(&particles).second) ++shared_arrays;
      max_in_flight = std::max(max_in_flight, ++in_flight_);
      arrived_.notify_all();
      arrived_.wait_for(lock, std::chrono::seconds(2), [&] { return in_flight_ >= 2; });
    }
    advect::AdvectionStatistics s;
    {
      std::lock_guard one(cpu_mutex_);  // the CPU backend and the source: one call at a time
      s = cpu_->advect(source, particles, t_end, o);
    }
    std::lock_guard lock(mutex_);
    busy_.erase(&particles);
    --in_flight_;
    return s;
  }
  std::size_t max_in_flight = 0, shared_arrays = 0;  // read after the calls

 private:
  std::unique_ptr<advect::BatchAdvector> cpu_ = advect::make_cpu_advector();
  std::mutex mutex_, cpu_mutex_;
  std::condition_variable arrived_;
  std::set<const advect::ParticleBatch*> busy_;
  std::size_t in_flight_ = 0;
};

}  // namespace

TEST_CASE("bulk advection: the flow map lets calls run at once where the backend allows it, each "
          "with its own particle arrays, and gives the results of calls one at a time",
          "[spacetime][advect]") {
  const auto flow = make_unsteady_field("unsteady-abc");
  const GridGeometry grid = uniform_grid(flow->domain(), 3, 17);
  const SampledTimeSeries series(*flow, grid, uniform_times(0, 2, 5));
  BrickCache cache(series, CacheOptions{});
  CachedSteps steps(cache);
  advect::MethodOptions method;
  method.method = advect::Method::dopri5;
  auto owned = std::make_unique<OverlappingBackend>();
  OverlappingBackend& backend = *owned;
  const BulkFlowMap at_once(steps, std::move(owned), method);
  const BulkFlowMap in_turn(steps, advect::make_cpu_advector(), method);
  std::mt19937_64 rng(11);
  const Box<3> box = flow->domain();
  std::uniform_real_distribution<double> u(0, 1);
  constexpr std::size_t kCalls = 2, kParticles = 500;
  std::array<std::vector<Vec3>, kCalls> x, want;
  std::array<std::vector<ParticleStatus>, kCalls> status, want_status;
  for (std::size_t c = 0; c < kCalls; ++c) {
    for (std::size_t i = 0; i < kParticles; ++i)
      x[c].push_back(box.lo + (box.hi - box.lo).cwiseProduct(Vec3(u(rng), u(rng), u(rng))));
    want[c] = x[c];
    status[c].assign(kParticles, ParticleStatus::moving);
    want_status[c] = status[c];
  }
  const std::vector<double> t0(kParticles, 0.25);
  for (std::size_t c = 0; c < kCalls; ++c) in_turn.advect_all(want[c], t0, 1.5 + 0.25 * c, want_status[c]);
  std::vector<std::thread> threads;
  for (std::size_t c = 0; c < kCalls; ++c)
    threads.emplace_back([&, c] { at_once.advect_all(x[c], t0, 1.5 + 0.25 * c, status[c]); });
  for (auto& t : threads) t.join();
  CHECK(backend.max_in_flight == 2);
  CHECK(backend.shared_arrays == 0);
  for (std::size_t c = 0; c < kCalls; ++c)
    for (std::size_t i = 0; i < kParticles; ++i) {
      REQUIRE(status[c][i] == want_status[c][i]);
      REQUIRE(x[c][i] == want[c][i]);
    }
  // Both calls' figures are in the totals, and in the batch calls' own.
  CHECK(at_once.statistics().particles == in_turn.statistics().particles);
  CHECK(at_once.statistics().evaluations == in_turn.statistics().evaluations);
  CHECK(at_once.batch_statistics().evaluations == at_once.statistics().evaluations);
  // A resident set's advance counts in the totals only.
  const auto set = in_turn.make_resident();
  const std::uint32_t slot = 0;
  const std::array<double, 3> p{x[0][0].x(), x[0][0].y(), x[0][0].z()};
  set->place(std::span<const std::uint32_t>(&slot, 1), std::span<const std::array<double, 3>>(&p, 1));
  const std::size_t batch_evaluations = in_turn.batch_statistics().evaluations;
  const std::size_t moved = in_turn.advance(*set, 0.25, 0.5);
  CHECK(moved > 0);
  CHECK(in_turn.batch_statistics().evaluations == batch_evaluations);
  CHECK(in_turn.statistics().evaluations == batch_evaluations + moved);
}

namespace {

// The double gyre's streak surface of these tests: a row every 0.5 from t = 0 to 3 off a short
// seed line, frames at 1.5, 3 and 4.5, moved by the CPU backend.
const SeedCurve kGyreSeed = SeedCurve::line(Vec3(0.3, 0.3, 0), Vec3(0.3, 0.45, 0));
StreakOptions gyre_options(ParticleInsertion insertion) {
  StreakOptions o;
  o.release_begin = 0;
  o.release_end = 3;
  o.frames = {1.5, 3, 4.5};
  o.edge = 0.03;
  o.release_step = 0.5;
  o.insertion = insertion;
  o.device = advect::Device::cpu;
  return o;
}

}  // namespace

TEST_CASE("bulk advection: a streak surface on the CPU backend follows its path lines, a small "
          "budget, particles sent up and down each interval instead of kept by the backend, and "
          "moves in turn with refinement instead of beside it give the same frames bit for bit",
          "[spacetime][advect][streak][heavy]") {
  const auto flow = make_unsteady_field("double-gyre");
  const GridGeometry grid = uniform_grid(flow->domain(), 2, 201);
  const SampledTimeSeries series(*flow, grid, uniform_times(0, 5, 50));
  const SeedCurve& seed = kGyreSeed;
  struct Run {
    std::size_t budget;
    bool resident;
    bool overlap = true;
  };
  // Also with rows released between breaks (every third release stops the particles; 0.25 is
  // not a step time of the series, 0.5 is): they go to the next break in a call of their own.
  for (const int per_break : {1, 3})
  for (const auto insertion : {ParticleInsertion::exact, ParticleInsertion::interpolate}) {
  INFO(to_string(insertion) << " insertion, " << per_break << " releases per break");
  StreakOptions o = gyre_options(insertion);
  o.merge = 0.75;  // particles and rows removed where the flow compresses the surface
  o.releases_per_break = per_break;
  if (per_break > 1) o.release_step = 0.25;
  std::vector<std::vector<StreakFrame>> runs;
  for (const Run run : {Run{std::size_t{1} << 30, true}, Run{std::size_t{8} << 20, true},
                        Run{std::size_t{1} << 30, false}, Run{std::size_t{1} << 30, true, false},
                        Run{std::size_t{8} << 20, true, false}}) {
    CacheOptions co;
    co.budget_bytes = run.budget;
    co.whole_steps = true;
    BrickCache cache(series, co);
    std::vector<StreakFrame> frames;
    o.resident_particles = run.resident;
    o.overlap_advection = run.overlap;
    const StreakReport r =
        build_streak_surface(cache, seed, o, [&](const StreakFrame& f) { frames.push_back(f); });
    REQUIRE(r.complete);
    CHECK(r.device == "cpu");
    CHECK(r.bulk.slabs > 0);
    CHECK(r.bulk.particle_steps > 0);
    CHECK(r.s_insertions + r.rows_inserted > 0);
    INFO("removals " << r.s_removals << " rows " << r.rows_removed << " left " << r.left_domain);
    CHECK(r.s_removals + r.rows_removed > 0);  // slots were given back
    // Overlapped: the particles released or inserted while the set moved on caught up.
    CHECK((r.catch_up_particles > 0) == (run.resident && run.overlap));
    if (run.resident && run.overlap) CHECK(r.catch_up_calls <= r.intervals);
    REQUIRE(frames.size() == 3);
    runs.push_back(std::move(frames));
  }
  for (std::size_t run = 1; run < runs.size(); ++run)
    for (std::size_t f = 0; f < 3; ++f) {
      INFO("run " << run << ", frame " << f);
      const Mesh& a = runs[0][f].mesh;
      const Mesh& b = runs[run][f].mesh;
      REQUIRE(a.vertex_count() == b.vertex_count());
      CHECK(a.faces == b.faces);
      CHECK(a.particle_id == b.particle_id);
      CHECK(std::memcmp(a.positions.data(), b.positions.data(), a.vertex_count() * sizeof(Vec3)) == 0);
    }
  if (insertion == ParticleInsertion::interpolate) continue;
  // Against the analytic flow: the sampled grid (201 x 101) differs from it by its interpolation
  // error, about 1e-4 over these times; the integration adds far less.
  double worst = 0;
  for (const StreakFrame& f : runs[1])
    for (std::size_t i = 0; i < f.mesh.vertex_count(); i += 5) {
      const Vec3 ref = reference_path(*flow, seed.point(f.mesh.s[i]), f.mesh.release_time[i], f.time);
      worst = std::max(worst, (f.mesh.positions[i] - ref).norm());
    }
  INFO("largest distance from the analytic path lines: " << worst);
  CHECK(worst < 2e-3);
  }
}

TEST_CASE("bulk advection: an overlapped streak surface stopped while its particles move on keeps "
          "the frames before, and a sink that throws with a move in flight stops the run",
          "[spacetime][advect][streak]") {
  const auto flow = make_unsteady_field("double-gyre");
  const GridGeometry grid = uniform_grid(flow->domain(), 2, 101);
  const SampledTimeSeries series(*flow, grid, uniform_times(0, 5, 50));
  const StreakOptions o = gyre_options(ParticleInsertion::interpolate);
  const auto run = [&](const StreakOptions& options, const StreakFrameSink& sink) {
    BrickCache cache(series, CacheOptions{});
    return build_streak_surface(cache, kGyreSeed, options, sink);
  };
  std::vector<StreakFrame> whole;
  const StreakReport full = run(o, [&](const StreakFrame& f) { whole.push_back(f); });
  REQUIRE(full.complete);
  REQUIRE(whole.size() == 3);

  // Stopped by the progress callback at t = 3.7: a move to the next break is in flight then.
  StreakOptions stopping = o;
  stopping.progress = [](const StreakProgress& p) { return p.t < 3.7; };
  std::vector<StreakFrame> kept;
  const StreakReport r = run(stopping, [&](const StreakFrame& f) { kept.push_back(f); });
  CHECK_FALSE(r.complete);
  CHECK(r.message.find("interrupted") != std::string::npos);
  CHECK(r.time_reached >= 3.7);
  CHECK(r.time_reached < 4.5);
  CHECK(r.intervals < full.intervals);
  REQUIRE(kept.size() == 2);
  for (std::size_t f = 0; f < 2; ++f) {
    CHECK(kept[f].mesh.faces == whole[f].mesh.faces);
    CHECK(kept[f].mesh.positions == whole[f].mesh.positions);
  }

  // A sink that throws: the run ends with its exception, the move in flight waited for.
  std::vector<int> handed;
  CHECK_THROWS_WITH(run(o,
                        [&](const StreakFrame& f) {
                          handed.push_back(f.index);
                          if (f.index == 1) throw Error("frame 1: disk full");
                        }),
                    Catch::Contains("disk full"));
  CHECK(handed == std::vector<int>{0, 1});
}
