// [gpu] A stream surface of a gridded steady field whose front advances on CUDA
// (advect::SteadyFrontIntegrator): the mesh of the CPU backend, bit for bit (both backends step
// the same particles with the same arithmetic: no FMA contraction, no library math).
#include <catch2/catch.hpp>

#include <cstring>
#include <memory>

#include "orthofront/advect/steady_front_integrator.h"
#include "orthofront/engine/stream_surface.h"
#include "orthofront/field/analytic.h"
#include "orthofront/field/sample_field.h"
#include "orthofront/seed/seed_curve.h"
#include "surface_checks.h"

using namespace orthofront;

TEST_CASE("cuda stream surface: the front advanced on the GPU gives the CPU backend's mesh",
          "[gpu][engine][advect]") {
  std::string why;
  if (!advect::cuda_available(&why)) {
    WARN("[gpu] skipped: " << why);  // a CUDA build on a machine without a GPU (CI)
    return;
  }
  SampleOptions so;
  so.resolution = {48, 48, 48};
  const auto grid =
      std::make_shared<const VectorGrid>(sample_field(*make_analytic_field("abc"), so));
  GridFieldOptions go;
  go.zero_is_no_data = false;
  const GridField field(grid, go);
  const Seed<3> seed = make_seed(SeedCurve::line(Vec3(0.5, 0.5, 0.5), Vec3(2.5, 0.5, 0.5)), 40);
  StreamSurfaceOptions options;
  options.edge = 0.05;
  options.max_steps = 80;
  advect::MethodOptions method;
  method.absolute = options.tolerance * options.edge;
  method.relative = options.tolerance;
  const auto build = [&](advect::Device device) {
    std::shared_ptr<advect::BatchAdvector> backend = advect::make_advector(device, 0);
    advect::SteadyFrontIntegrator bulk(field, [backend] { return backend; }, method, 0);
    SurfaceResult r = build_stream_surface<3>(field, seed, options, {}, {}, {}, &bulk);
    CHECK(bulk.calls() >= static_cast<std::size_t>(r.report.steps));
    return r;
  };
  const SurfaceResult cpu = build(advect::Device::cpu);
  const SurfaceResult cuda = build(advect::Device::cuda);
  test_support::require_valid(cuda);
  REQUIRE(cpu.mesh.vertex_count() > 2000);
  REQUIRE(cuda.mesh.vertex_count() == cpu.mesh.vertex_count());
  REQUIRE(cuda.mesh.face_count() == cpu.mesh.face_count());
  for (std::size_t i = 0; i < cpu.mesh.vertex_count(); ++i)
    REQUIRE(std::memcmp(cuda.mesh.positions[i].data(), cpu.mesh.positions[i].data(),
                        3 * sizeof(double)) == 0);
  for (std::size_t f = 0; f < cpu.mesh.face_count(); ++f)
    REQUIRE(cuda.mesh.faces[f].v == cpu.mesh.faces[f].v);
}
