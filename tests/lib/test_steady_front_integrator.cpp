// The front advance of a stream surface of a gridded steady field by bulk advection
// (advect::SteadyFrontIntegrator): a linear field sampled on a grid is reproduced exactly by
// multilinear interpolation, so every vertex must lie on the exact stream surface y z = 0.2 of
// saddle3d; the surface matches the per-vertex one; a backend that cannot be had leaves the
// per-vertex surface, bit for bit.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>

#include "orthofront/advect/steady_front_integrator.h"
#include "orthofront/engine/stream_surface.h"
#include "orthofront/field/analytic.h"
#include "orthofront/field/sample_field.h"
#include "orthofront/seed/seed_curve.h"
#include "surface_checks.h"

using namespace orthofront;

namespace {

struct Saddle {
  std::shared_ptr<const VectorGrid> grid;
  std::unique_ptr<GridField> field;
  Seed<3> seed;
  StreamSurfaceOptions options;
};

Saddle saddle_on_a_grid() {
  Saddle s;
  const auto analytic = make_analytic_field("saddle3d");
  SampleOptions so;
  so.resolution = {33, 33, 33};
  s.grid = std::make_shared<const VectorGrid>(sample_field(*analytic, so));
  GridFieldOptions go;
  go.zero_is_no_data = false;  // the saddle's zero at the origin is a sample, not land
  s.field = std::make_unique<GridField>(s.grid, go);
  s.seed = make_seed(SeedCurve::line(Vec3(-1, 2, 0.1), Vec3(1, 2, 0.1)), 20);
  s.options.edge = 0.1;
  s.options.max_steps = 200;
  return s;
}

double worst_off_surface(const Mesh& m) {
  double worst = 0;
  for (const Vec3& p : m.positions) worst = std::max(worst, std::abs(p.y() * p.z() - 0.2));
  return worst;
}

}  // namespace

TEST_CASE("steady bulk front advance: the exact saddle surface from a grid, as per vertex",
          "[engine][advect]") {
  Saddle s = saddle_on_a_grid();
  const SurfaceResult per_vertex = build_stream_surface<3>(*s.field, s.seed, s.options);
  advect::MethodOptions method;
  method.absolute = s.options.tolerance * s.options.edge;
  method.relative = s.options.tolerance;
  std::shared_ptr<advect::BatchAdvector> cpu = advect::make_cpu_advector();
  advect::SteadyFrontIntegrator bulk(*s.field, [cpu] { return cpu; }, method, 0);
  const SurfaceResult r = build_stream_surface<3>(*s.field, s.seed, s.options, {}, {}, {}, &bulk);
  test_support::require_valid(r);
  REQUIRE(r.mesh.vertex_count() > 1000);
  CHECK(bulk.calls() >= static_cast<std::size_t>(r.report.steps));
  CHECK(bulk.backend_name() == "cpu");
  INFO("per vertex " << worst_off_surface(per_vertex.mesh) << ", bulk " << worst_off_surface(r.mesh));
  CHECK(worst_off_surface(r.mesh) < 1e-8);
  CHECK(worst_off_surface(per_vertex.mesh) < 1e-8);
  CHECK(r.mesh.vertex_count() == per_vertex.mesh.vertex_count());
  CHECK(r.report.quality.quad_share == Approx(per_vertex.report.quality.quad_share).margin(0.005));

  // No backend to be had (auto without CUDA): declined, the per-vertex surface bit for bit.
  int asked = 0;
  advect::SteadyFrontIntegrator none(
      *s.field,
      [&]() -> std::shared_ptr<advect::BatchAdvector> {
        ++asked;
        return nullptr;
      },
      method, 0);
  const SurfaceResult declined =
      build_stream_surface<3>(*s.field, s.seed, s.options, {}, {}, {}, &none);
  CHECK(asked == 1);
  CHECK(none.calls() == 0);
  CHECK(none.min_vertices() == std::numeric_limits<std::size_t>::max());
  REQUIRE(declined.mesh.vertex_count() == per_vertex.mesh.vertex_count());
  for (std::size_t i = 0; i < declined.mesh.vertex_count(); ++i)
    REQUIRE(std::memcmp(declined.mesh.positions[i].data(), per_vertex.mesh.positions[i].data(),
                        3 * sizeof(double)) == 0);
}
