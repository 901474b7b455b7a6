// `orthofront-bench front`: one front advance of a path surface, n vertices moved by one front
// step (τ = ℓ / c) through a series sampled on a grid: per vertex through the streamed field (the
// engine's default, TBB threads) beside one call of the bulk front advance on the CPU backend and
// on CUDA, for n from 64 up. The smallest n from which CUDA stays faster than per vertex is the
// break-even front size that `path --device auto` uses (spacetime::kCudaFrontBreakEven).
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "cli/commands.h"
#include "cli/count_list.h"
#include "orthofront/error.h"
#include "orthofront/integrate/runge_kutta.h"
#include "orthofront/spacetime/brick_cache.h"
#include "orthofront/spacetime/bulk_flow_map.h"
#include "orthofront/spacetime/bulk_front_integrator.h"
#include "orthofront/spacetime/lifted_field.h"
#include "orthofront/spacetime/sampled_series.h"
#include "orthofront/spacetime/streamed_field.h"

namespace orthofront::cli {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

struct BenchFrontArgs {
  std::string field = "unsteady-abc";
  int resolution = 128;
  int steps = 40;                  // time steps over [0, 4]
  std::string sizes = "64,256,1024,4096,16384,65536";
  double edge = 0.05;              // ℓ: a front step moves a vertex by about ℓ
  double band = 0.3;               // the front's vertices spread over this much time
  double tolerance = 1e-9;         // the engine's default
  int repeats = 5;                 // fastest of
  int threads = 0;
  std::string device = "auto";
};

struct Row {
  std::size_t vertices = 0;
  double per_vertex = 0, bulk_cpu = 0, bulk_cuda = 0;  // seconds, fastest of the repeats
  double cuda_compute = 0;
  double max_difference = 0;                            // |bulk CUDA - per vertex|, world units
};

}  // namespace

void add_bench_front_command(CLI::App& app) {
  auto a = std::make_shared<BenchFrontArgs>();
  CLI::App* c = app.add_subcommand(
      "front",
      "Benchmark one front advance of a path surface: per vertex beside bulk advection (CPU, "
      "CUDA), by front size: the break-even size of --device auto");
  c->add_option("--field", a->field, "Unsteady 3D analytic field, sampled on a grid")->capture_default_str();
  c->add_option("--resolution", a->resolution, "Grid points per axis")->capture_default_str();
  c->add_option("--steps", a->steps, "Time steps sampled over t in [0, 4]")->capture_default_str();
  c->add_option("--sizes", a->sizes, "Front sizes, comma-separated")->capture_default_str();
  c->add_option("--edge", a->edge, "Edge length: a front step moves a vertex by about this")->capture_default_str();
  c->add_option("--band", a->band, "Time over which the front's vertices spread")->capture_default_str();
  c->add_option("--tolerance", a->tolerance, "DOPRI5 tolerance (the engine's)")->capture_default_str();
  c->add_option("--repeats", a->repeats, "Runs per cell; the fastest counts")->capture_default_str();
  c->add_option("--threads", a->threads, "CPU threads (0: all cores)")->capture_default_str();
  c->add_option("--device", a->device, "cuda, cpu (no CUDA column) or auto")->capture_default_str();
  c->callback([a]() {
    const auto flow = make_unsteady_field(a->field);
    if (flow->dimension() != 3) throw InvalidArgument("orthofront-bench front: --field must be a 3D flow");
    if (a->resolution < 8 || a->resolution > 1024 || a->steps < 4 || a->repeats < 1 ||
        !(a->edge > 0) || !(a->band >= 0 && a->band < 3) || !(a->tolerance > 0))
      throw InvalidArgument("orthofront-bench front: need --resolution in [8, 1024], --steps >= 4, "
                            "--repeats >= 1, --edge > 0, --band in [0, 3), --tolerance > 0");
    const std::vector<std::size_t> sizes = parse_count_list(a->sizes, "--sizes", 2, 1e8);
    const advect::Device device = advect::parse_device(a->device);
    std::string why;
    const bool cuda = device != advect::Device::cpu && advect::cuda_available(&why);
    if (device == advect::Device::cuda && !cuda) throw InvalidArgument("orthofront-bench front --device cuda: " + why);
    const int threads = a->threads > 0 ? a->threads : tbb::info::default_concurrency();
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                              static_cast<std::size_t>(threads));

    // The series in memory behind a cache that holds all of it (no I/O in the timings).
    const Box<3> domain = flow->domain();
    const spacetime::SampledTimeSeries series(*flow, spacetime::uniform_grid(domain, 3, a->resolution),
                                              spacetime::uniform_times(0, 4, static_cast<std::size_t>(a->steps)));
    spacetime::CacheOptions co;
    co.budget_bytes = std::size_t{64} << 30;
    co.prefetch = false;
    spacetime::BrickCache cache(series, co);
    spacetime::StreamedField streamed(cache);
    const double t_lo = 1.0, t_hi = 1.0 + a->band;
    streamed.update_band(0.0, 4.0);
    // c as a path surface picks it: about the median speed (ABC: ~ 2).
    const double c_scale = 2.0;
    const spacetime::LiftedField<4> lifted(streamed, c_scale, TimeRange{0.0, 4.0});
    spacetime::CachedSteps steps(cache);
    spacetime::BulkFrontOptions bo;
    bo.time_scale = c_scale;
    bo.times = {0.0, 4.0};
    bo.method.method = advect::Method::dopri5;
    bo.method.absolute = a->tolerance * a->edge;
    bo.method.relative = a->tolerance;
    spacetime::BulkFrontIntegrator<4> bulk_cpu(steps, advect::make_cpu_advector(), bo);
    std::unique_ptr<spacetime::BulkFrontIntegrator<4>> bulk_gpu;
    if (cuda)
      bulk_gpu = std::make_unique<spacetime::BulkFrontIntegrator<4>>(
          steps, advect::make_advector(advect::Device::cuda), bo);
    const bool gpu = bulk_gpu != nullptr;
    const std::string gpu_name = gpu ? bulk_gpu->backend_name() : std::string();
    Tolerance tol;
    tol.absolute = a->tolerance * a->edge;
    tol.relative = a->tolerance;

    std::vector<Row> rows;
    for (const std::size_t n : sizes) {
      // A front: points inside the middle of the box, times over the band, τ = ℓ / c.
      std::vector<Vec<4>> x(n);
      std::vector<double> tau(n, a->edge / c_scale);
      std::mt19937_64 rng(n);
      std::uniform_real_distribution<double> u(0.0, 1.0);
      for (Vec<4>& p : x) {
        for (int d = 0; d < 3; ++d) p[d] = domain.lo[d] + (domain.hi[d] - domain.lo[d]) * (0.3 + 0.4 * u(rng));
        p[3] = c_scale * (t_lo + (t_hi - t_lo) * u(rng));
      }
      std::vector<IntegrationResult<4>> per_vertex(n), out(n);
      Row r;
      r.vertices = n;
      r.per_vertex = r.bulk_cpu = r.bulk_cuda = 1e300;
      for (int k = 0; k < a->repeats; ++k) {
        auto t0 = Clock::now();
        tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
          per_vertex[i] = integrate_dopri5(lifted, x[i], tau[i], tol);
        });
        r.per_vertex = std::min(r.per_vertex, since(t0));
        t0 = Clock::now();
        bulk_cpu.integrate(x, tau, out);
        r.bulk_cpu = std::min(r.bulk_cpu, since(t0));
        if (bulk_gpu) {
          const double before = bulk_gpu->statistics().compute_seconds;
          t0 = Clock::now();
          bulk_gpu->integrate(x, tau, out);
          const double s = since(t0);
          if (s < r.bulk_cuda) r.cuda_compute = bulk_gpu->statistics().compute_seconds - before;
          r.bulk_cuda = std::min(r.bulk_cuda, s);
        }
      }
      if (!bulk_gpu) bulk_cpu.integrate(x, tau, out);
      for (std::size_t i = 0; i < n; ++i)
        r.max_difference = std::max(r.max_difference, (out[i].x - per_vertex[i].x).norm());
      rows.push_back(r);
    }
    // Break-even: the smallest size from which CUDA is faster at every larger size measured.
    std::size_t break_even = 0;
    if (gpu)
      for (std::size_t k = rows.size(); k-- > 0;) {
        if (rows[k].bulk_cuda >= rows[k].per_vertex) break;
        break_even = rows[k].vertices;
      }

    nlohmann::json j = {{"benchmark", "bench-front"},
                        {"field", a->field},
                        {"grid", a->resolution},
                        {"time_steps", a->steps + 1},
                        {"edge", a->edge},
                        {"band", a->band},
                        {"cpu_threads", threads},
                        {"cuda", cuda ? gpu_name : "unavailable: " + why},
                        {"break_even_vertices", break_even},
                        {"rows", nlohmann::json::array()}};
    std::printf("orthofront-bench front: %s on %d^3, %d time steps over [0, 4]; front vertices spread over "
                "t in [%g, %g], each moved by one front step (l = %g, c = %g); DOPRI5 %g; %d CPU "
                "threads; fastest of %d\nCUDA: %s\n\n",
                a->field.c_str(), a->resolution, a->steps + 1, t_lo, t_hi, a->edge, c_scale,
                a->tolerance, threads, a->repeats,
                cuda ? gpu_name.c_str() : ("unavailable (" + why + ")").c_str());
    std::printf("%10s %14s %14s %14s %14s %10s %14s\n", "vertices", "per vertex ms", "bulk cpu ms",
                "bulk cuda ms", "cuda kernels ms", "cuda x", "max |diff|");
    for (const Row& r : rows) {
      const bool g = gpu;
      std::printf("%10zu %14.3f %14.3f %14s %14s %10s %14.2e\n", r.vertices, 1e3 * r.per_vertex,
                  1e3 * r.bulk_cpu, g ? std::to_string(1e3 * r.bulk_cuda).substr(0, 8).c_str() : "-",
                  g ? std::to_string(1e3 * r.cuda_compute).substr(0, 8).c_str() : "-",
                  g ? std::to_string(r.per_vertex / r.bulk_cuda).substr(0, 6).c_str() : "-",
                  r.max_difference);
      nlohmann::json row = {{"vertices", r.vertices},
                            {"per_vertex_seconds", r.per_vertex},
                            {"bulk_cpu_seconds", r.bulk_cpu},
                            {"max_difference", r.max_difference}};
      if (g) row.update({{"bulk_cuda_seconds", r.bulk_cuda}, {"cuda_kernel_seconds", r.cuda_compute}});
      j["rows"].push_back(row);
    }
    if (gpu)
      std::printf("\nBreak-even (CUDA faster from this size on): %s (path --device auto uses %zu)\n",
                  break_even ? std::to_string(break_even).c_str() : "none measured",
                  spacetime::kCudaFrontBreakEven);
    std::printf("max |diff|: bulk result (CUDA where present) against the per-vertex one.\n");
    std::cout << j.dump(1) << "\n";
  });
}

}  // namespace orthofront::cli
