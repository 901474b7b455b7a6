// The front advance of a path surface by bulk advection (PathSurfaceOptions::device): every
// vertex on the path line of its seed point through the sampled series (an independent RK4),
// close to the per-vertex surface, the same bits through bricks under a tiny budget as in memory,
// and the per-vertex surface bit for bit where no front reaches the backend's minimum.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstring>
#include <limits>

#include "io/grid_test_support.h"
#include "orthofront/io/hdf5_layout.h"
#include "orthofront/spacetime/bulk_flow_map.h"
#include "orthofront/spacetime/bulk_front_integrator.h"
#include "orthofront/spacetime/path_surface.h"
#include "orthofront/spacetime/sampled_series.h"
#include "orthofront/spacetime/streamed_field.h"

#include "bricked_series.h"
#include "mesh_equality.h"
#include "reference_path.h"

using namespace orthofront;
using namespace orthofront::spacetime;
using spacetime_test::same_mesh;
using spacetime_test::write_bricked;
using grid_test::TempDir;

namespace {

struct Case {
  std::unique_ptr<UnsteadyField> flow;
  std::unique_ptr<SampledTimeSeries> memory;
  SeedCurve seed;
  PathSurfaceOptions options;
};

Case gyre_case() {
  Case c;
  c.flow = make_unsteady_field("double-gyre-3d");
  c.memory = std::make_unique<SampledTimeSeries>(*c.flow, uniform_grid(c.flow->domain(), 3, 17),
                                                 uniform_times(0, 6, 60));
  c.seed = SeedCurve::line(Vec3(0.3, 0.25, 0.3), Vec3(0.9, 0.7, 0.6));
  c.options.t0 = 0;
  c.options.t1 = 4;
  c.options.engine.edge = 0.05;
  c.options.engine.max_steps = 100000;
  return c;
}

CacheOptions everything() {
  CacheOptions all;
  all.budget_bytes = 1 << 30;
  return all;
}

}  // namespace

TEST_CASE("bulk front advance: every vertex on its path line through the series, close to the "
          "per-vertex surface",
          "[spacetime][path][advect]") {
  Case c = gyre_case();
  BrickCache cache(*c.memory, everything());
  const PathSurfaceResult per_vertex = build_path_surface(cache, c.seed, 8, c.options);
  PathSurfaceOptions bulk_options = c.options;
  bulk_options.device = advect::Device::cpu;
  const PathSurfaceResult bulk = build_path_surface(cache, c.seed, 8, bulk_options);
  REQUIRE(per_vertex.path.complete);
  REQUIRE(bulk.path.complete);
  CHECK(bulk.report.quality.non_manifold_edges == 0);
  CHECK(bulk.report.quality.degenerate_faces == 0);
  CHECK(bulk.report.quality.t_junctions == 0);
  CHECK(bulk.path.device == "cpu");
  CHECK(bulk.path.device_calls >= static_cast<std::size_t>(bulk.report.steps));
  CHECK(bulk.path.device_statistics.particles >= bulk.mesh.vertex_count() / 2);
  CHECK(per_vertex.path.device.empty());
  // The same surface up to the integrators' differences (the bulk one stops at every time step).
  const double n0 = static_cast<double>(per_vertex.mesh.vertex_count());
  CHECK(std::abs(static_cast<double>(bulk.mesh.vertex_count()) - n0) < 0.02 * n0);
  CHECK(std::abs(bulk.report.quality.quad_share - per_vertex.report.quality.quad_share) < 0.01);
  CHECK(bulk.path.time_reached == Approx(per_vertex.path.time_reached).margin(1e-9));

  // Each vertex (x, t) with seed parameter s lies on the path line of seed(s) from t0 to t
  // through the same multilinear series.
  StreamedField field(cache);
  field.update_band(0, 6);
  double worst = 0;
  const std::size_t stride = std::max<std::size_t>(1, bulk.mesh.vertex_count() / 400);
  for (std::size_t i = 0; i < bulk.mesh.vertex_count(); i += stride) {
    const Vec3 want = streak_test::reference_path(field, c.seed.point(bulk.mesh.s[i]), c.options.t0,
                                                  bulk.mesh.time[i]);
    worst = std::max(worst, (bulk.mesh.positions[i] - want).norm());
  }
  INFO("worst distance to the reference path line " << worst);
  CHECK(worst < 1e-5);
}

TEST_CASE("bulk front advance: through bricks under a tiny budget, the in-memory surface bit for "
          "bit, below the minimum front size, the per-vertex surface bit for bit",
          "[spacetime][path][advect][bricks]") {
  TempDir dir("bulk-front");
  Case c = gyre_case();
  c.options.device = advect::Device::cpu;
  BrickCache in_memory(*c.memory, everything());
  const PathSurfaceResult reference = build_path_surface(in_memory, c.seed, 8, c.options);
  REQUIRE(reference.path.complete);

  const auto series = write_bricked(dir.path() / "gyre.h5", *c.memory, 4);
  CacheOptions tiny;
  tiny.budget_bytes = 400 * 768;  // 400 bricks of 7,500: the band plus one step gathered
  tiny.max_live_tokens = 4;       // the room left for the band whatever the machine's cores
  BrickCache cache(*series, tiny);
  const PathSurfaceResult streamed = build_path_surface(cache, c.seed, 8, c.options);
  INFO(streamed.path.message);
  REQUIRE(streamed.path.complete);
  CHECK(streamed.path.cache.peak_bytes <= tiny.budget_bytes);
  CHECK(same_mesh(streamed.mesh, reference.mesh));

  PathSurfaceOptions never = c.options;
  never.device_min_vertices = 1'000'000;  // no front is this large
  const PathSurfaceResult below = build_path_surface(in_memory, c.seed, 8, never);
  PathSurfaceOptions plain = c.options;
  plain.device.reset();
  const PathSurfaceResult per_vertex = build_path_surface(in_memory, c.seed, 8, plain);
  CHECK(below.path.device_calls == 0);
  CHECK(same_mesh(below.mesh, per_vertex.mesh));
}

TEST_CASE("whole steps gathered from bricks of which some are resident already equal the step",
          "[spacetime][advect][bricks]") {
  // The cache hands resident units back first: each brick must go to its own place.
  TempDir dir("gather-resident");
  Case c = gyre_case();
  const auto series = write_bricked(dir.path() / "gyre.h5", *c.memory, 4);
  BrickCache cache(*series, everything());
  std::vector<BrickCache::Handle> some;
  for (std::uint32_t b = 7; b < cache.layout().bricks(); b += 11) some.push_back(cache.acquire({3, b}));
  REQUIRE(some.size() > 5);
  CachedSteps steps(cache);
  const float* gathered = steps.acquire(3);
  std::vector<float> want(c.memory->step_floats());
  c.memory->sample(3, want.data());
  std::size_t wrong = 0;
  for (std::size_t i = 0; i < want.size(); ++i) wrong += gathered[i] != want[i];
  CHECK(wrong == 0);
}

TEST_CASE("bulk front advance: integrator seam calls and spans", "[spacetime][advect]") {
  // Straight through a uniform flow v = (1, 0.5): a lifted vertex (x, y, c t) moved by τ lands
  // on (x + τ, y + τ / 2, c (t + τ)); one stopped by t1 reports outside and how far it got.
  const GridGeometry g = uniform_grid(Box<3>{Vec3(0, 0, 0), Vec3(4, 4, 0)}, 2, 9);
  std::vector<std::vector<float>> steps;
  for (int k = 0; k < 3; ++k) {
    std::vector<float> v(g.point_count() * 2);
    for (std::size_t p = 0; p < g.point_count(); ++p) v[2 * p] = 1.0f, v[2 * p + 1] = 0.5f;
    steps.push_back(std::move(v));
  }
  advect::ResidentSteps source(g, 2, {0, 1, 2}, std::move(steps));
  BulkFrontOptions o;
  o.time_scale = 2;
  o.times = {0, 1.5};
  BulkFrontIntegrator<3> integrator(source, advect::make_cpu_advector(), o);
  const std::vector<Vec<3>> x{Vec<3>(1, 1, 0.5), Vec<3>(1, 2, 2.0), Vec<3>(2, 2, 1.0)};
  const std::vector<double> tau{0.5, 0.75, 0};
  std::vector<IntegrationResult<3>> out(3);
  REQUIRE(integrator.integrate(x, tau, out));
  CHECK(integrator.backend_name() == "cpu");
  CHECK(out[0].status == FieldStatus::inside);
  CHECK(out[0].reached == 0.5);
  CHECK((out[0].x - Vec<3>(1.5, 1.25, 1.5)).norm() < 1e-12);
  CHECK(out[1].status == FieldStatus::outside);  // t = 1 + 0.75 passes t1 = 1.5
  CHECK(out[1].reached == Approx(0.5));
  CHECK((out[1].x - Vec<3>(1.5, 2.25, 3.0)).norm() < 1e-12);
  CHECK(out[2].status == FieldStatus::inside);  // τ = 0: not moved
  CHECK(out[2].x == x[2]);
  CHECK(integrator.calls() == 1);
  const auto [lo, hi] = integrator.take_time_range();
  CHECK(lo == 0.25);
  CHECK(hi == 1.5);

  // A backend that cannot be had: declined once asked, and never asked again.
  int asked = 0;
  BulkFrontIntegrator<3> none(source, [&]() -> std::shared_ptr<advect::BatchAdvector> {
    ++asked;
    return nullptr;
  }, o);
  CHECK_FALSE(none.integrate(x, tau, out));
  CHECK_FALSE(none.integrate(x, tau, out));
  CHECK(asked == 1);
  CHECK(none.backend_name().empty());
  CHECK(none.min_vertices() == std::numeric_limits<std::size_t>::max());
}
