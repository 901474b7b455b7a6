// [gpu] A path surface whose front advances on CUDA (PathSurfaceOptions::device) is the one the
// CPU backend builds, byte for byte (the backends share their arithmetic: particle_step.h), and
// `auto` below the break-even size is the per-vertex surface. Built only with CUDA; without a
// device each test says so and does nothing.
#include <catch2/catch.hpp>

#include "orthofront/spacetime/bulk_front_integrator.h"
#include "orthofront/spacetime/path_surface.h"
#include "orthofront/spacetime/sampled_series.h"

#include "mesh_equality.h"

using namespace orthofront;
using namespace orthofront::spacetime;
using spacetime_test::same_mesh;

TEST_CASE("cuda front advance: the CPU backend's path surface byte for byte", "[gpu][path]") {
  std::string why;
  if (!advect::cuda_available(&why)) {
    WARN("[gpu] skipped: " << why);
    return;
  }
  for (const char* name : {"double-gyre", "unsteady-abc"}) {
    INFO(name);
    const auto flow = make_unsteady_field(name);
    const int dimension = flow->dimension();
    const SampledTimeSeries memory(*flow, uniform_grid(flow->domain(), dimension, dimension == 2 ? 129 : 33),
                                   uniform_times(0, 4, 40));
    CacheOptions co;
    co.budget_bytes = std::size_t{1} << 30;
    BrickCache cache(memory, co);
    PathSurfaceOptions o;
    o.t0 = 0;
    o.t1 = 3;
    o.engine.edge = dimension == 2 ? 0.01 : 0.1;
    o.engine.max_steps = 100000;
    const SeedCurve seed = dimension == 2 ? SeedCurve::line(Vec3(0.2, 0.2, 0), Vec3(0.8, 0.8, 0))
                                          : SeedCurve::line(Vec3(1, 1, 2), Vec3(5, 5, 2));
    o.device = advect::Device::cpu;
    const PathSurfaceResult on_cpu = build_path_surface(cache, seed, 20, o);
    o.device = advect::Device::cuda;
    const PathSurfaceResult on_cuda = build_path_surface(cache, seed, 20, o);
    REQUIRE(on_cpu.path.complete);
    REQUIRE(on_cuda.path.complete);
    CHECK(on_cuda.path.device.rfind("cuda", 0) == 0);
    CHECK(on_cuda.path.device_calls > 0);
    CHECK(on_cpu.mesh.vertex_count() > 1000);
    CHECK(same_mesh(on_cpu.mesh, on_cuda.mesh));

    // auto with a minimum no front reaches: the per-vertex surface.
    o.device = advect::Device::auto_select;
    o.device_min_vertices = 1'000'000;
    const PathSurfaceResult automatic = build_path_surface(cache, seed, 20, o);
    o.device.reset();
    const PathSurfaceResult per_vertex = build_path_surface(cache, seed, 20, o);
    CHECK(automatic.path.device_calls == 0);
    CHECK(same_mesh(automatic.mesh, per_vertex.mesh));
  }
}
