// Bulk advection on cached series: a slab samples the values of StreamedField bit for bit, whole
// steps gathered from bricks equal the whole-step series, and a streak surface moved by bulk
// advection lies on its particles' path lines, streamed or resident alike.
#include <catch2/catch.hpp>

#include <cstring>
#include <random>

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

TEST_CASE("bulk advection: a streak surface on the CPU backend follows its path lines; a small "
          "budget, particles sent up and down each interval instead of kept by the backend, and "
          "moves in turn with refinement instead of beside it give the same frames bit for bit",
          "[spacetime][advect][streak]") {
  const auto flow = make_unsteady_field("double-gyre");
  const GridGeometry grid = uniform_grid(flow->domain(), 2, 201);
  const SampledTimeSeries series(*flow, grid, uniform_times(0, 5, 50));
  const SeedCurve& seed = kGyreSeed;
  struct Run {
    std::size_t budget;
    bool resident;
    bool overlap = true;
  };
  for (const auto insertion : {ParticleInsertion::exact, ParticleInsertion::interpolate}) {
  INFO(to_string(insertion) << " insertion");
  StreakOptions o = gyre_options(insertion);
  o.merge = 0.75;  // particles and rows removed where the flow compresses the surface
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
