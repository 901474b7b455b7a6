// `orthofront-bench gpu`: bulk particle advection through a slab of a 256³ grid (unsteady ABC
// sampled at two times), particle-steps per second for 10^4 … 10^8 particles, the CUDA backend
// (RK4 and DOPRI5) beside the same binary's CPU backend, in one run. Prints a table and JSON.
// Without a CUDA device the CPU rows run alone and the table says why.
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

#include "cli/commands.h"
#include "cli/count_list.h"
#include "orthofront/advect/batch_advector.h"
#include "orthofront/error.h"
#include "orthofront/field/unsteady.h"

namespace orthofront::cli {

namespace {

struct BenchGpuArgs {
  std::string field = "unsteady-abc";
  int resolution = 256;
  std::string particles = "1e4,1e5,1e6,1e7,1e8";
  int threads = 0;               // CPU backend threads (0: all cores)
  double rk4_steps = 4;          // RK4 steps per particle over the slab
  double tolerance = 1e-6;       // DOPRI5
  double cpu_seconds = 60;       // skip a CPU row predicted to take longer
  std::string device = "auto";
  bool json_only = false;
};

advect::ResidentSteps sample_slab_series(const UnsteadyField& flow, int n) {
  GridGeometry g;
  g.dimension = 3;
  const Box<3> box = flow.domain();
  for (int a = 0; a < 3; ++a) {
    g.size[static_cast<std::size_t>(a)] = n;
    g.origin[a] = box.lo[a];
    g.spacing[a] = (box.hi[a] - box.lo[a]) / (n - 1);
  }
  std::vector<std::vector<float>> steps;
  const std::vector<double> times{0, 1};
  for (const double t : times) {
    std::vector<float> v(g.point_count() * 3);
    tbb::parallel_for(std::int64_t{0}, g.size[2], [&](std::int64_t k) {
      for (std::int64_t j = 0; j < g.size[1]; ++j)
        for (std::int64_t i = 0; i < g.size[0]; ++i) {
          Vec3 u = Vec3::Zero();
          flow.velocity(Vec3(g.coordinate(0, i), g.coordinate(1, j), g.coordinate(2, k)), t, u);
          for (int c = 0; c < 3; ++c) v[g.index(i, j, k) * 3 + static_cast<std::size_t>(c)] = static_cast<float>(u[c]);
        }
    });
    steps.push_back(std::move(v));
  }
  return advect::ResidentSteps(g, 3, times, std::move(steps));
}

advect::ParticleBatch random_particles(const GridGeometry& g, std::size_t n) {
  advect::ParticleBatch b;
  b.resize(n);
  const Box<3> box = g.bounds();
  tbb::parallel_for(std::size_t{0}, n, std::size_t{1} << 16, [&](std::size_t i) {
    // Per-index generator: the same particles whatever the threads.
    std::mt19937_64 rng(0x9e3779b97f4a7c15ull ^ i);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int d = 0; d < 3; ++d)
      b.x[static_cast<std::size_t>(d)][i] = box.lo[d] + (box.hi[d] - box.lo[d]) * (0.05 + 0.9 * u(rng));
  });
  return b;
}

struct Row {
  std::string backend, method;
  std::size_t particles = 0;
  advect::AdvectionStatistics stats;
  bool skipped = false;
  std::string note;
};

}  // namespace

void add_bench_gpu_command(CLI::App& app) {
  auto a = std::make_shared<BenchGpuArgs>();
  CLI::App* c = app.add_subcommand(
      "gpu", "Benchmark bulk particle advection: CUDA backend beside the CPU backend");
  c->add_option("--field", a->field, "Unsteady 3D analytic field sampled at t = 0 and 1")->capture_default_str();
  c->add_option("--resolution", a->resolution, "Grid points per axis")->capture_default_str();
  c->add_option("--particles", a->particles, "Particle counts, comma-separated")->capture_default_str();
  c->add_option("--threads", a->threads, "CPU backend threads (0: all cores)")->capture_default_str();
  c->add_option("--rk4-steps", a->rk4_steps, "RK4 steps per particle across the slab")->capture_default_str();
  c->add_option("--tolerance", a->tolerance, "DOPRI5 tolerance (absolute and relative)")->capture_default_str();
  c->add_option("--cpu-seconds", a->cpu_seconds, "Skip a CPU row predicted to take longer")->capture_default_str();
  c->add_option("--device", a->device, "cuda, cpu (CPU rows only) or auto")->capture_default_str();
  c->add_flag("--json", a->json_only, "Print only the JSON");
  c->callback([a]() {
    const auto flow = make_unsteady_field(a->field);
    if (flow->dimension() != 3) throw InvalidArgument("orthofront-bench gpu: --field must be a 3D flow");
    if (a->resolution < 8 || a->resolution > 2048)
      throw InvalidArgument("orthofront-bench gpu: --resolution must lie in [8, 2048]");
    if (!(a->rk4_steps >= 1) || !(a->tolerance > 0) || a->threads < 0)
      throw InvalidArgument("orthofront-bench gpu: --rk4-steps >= 1, --tolerance > 0, --threads >= 0");
    const std::vector<std::size_t> counts = parse_count_list(a->particles, "--particles", 1, 1e9);
    const advect::Device device = advect::parse_device(a->device);
    std::string why;
    const bool cuda = device != advect::Device::cpu && advect::cuda_available(&why);
    if (device == advect::Device::cuda && !cuda) throw InvalidArgument("orthofront-bench gpu --device cuda: " + why);
    const int threads = a->threads > 0 ? a->threads : tbb::info::default_concurrency();
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                              static_cast<std::size_t>(threads));

    const auto t_sample = std::chrono::steady_clock::now();
    advect::ResidentSteps series = sample_slab_series(*flow, a->resolution);
    const double sample_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t_sample).count();
    const auto gpu = cuda ? advect::make_advector(advect::Device::cuda) : nullptr;
    const auto cpu = advect::make_cpu_advector();

    std::vector<Row> rows;
    // Per method: particle-steps per second and per particle of the last CPU row (the prediction
    // that skips a row too long for --cpu-seconds).
    double cpu_rate[2] = {0, 0}, cpu_steps_per_particle[2] = {0, 0};
    for (const std::size_t n : counts) {
      const advect::ParticleBatch start = random_particles(series.geometry(), n);
      for (const advect::Method method : {advect::Method::rk4, advect::Method::dopri5}) {
        advect::MethodOptions o;
        o.method = method;
        o.rk4_step = 1.0 / a->rk4_steps;
        o.absolute = o.relative = a->tolerance;
        const char* method_name = method == advect::Method::rk4 ? "RK4" : "DOPRI5";
        if (gpu) {
          advect::ParticleBatch p = start;
          gpu->advect(series, p, 0.0, o);  // warm-up: context, module load
          p = start;
          rows.push_back({gpu->name(), method_name, n, gpu->advect(series, p, 1.0, o), false, ""});
        }
        const int m = static_cast<int>(method);
        const double predicted =
            cpu_rate[m] > 0 ? static_cast<double>(n) * cpu_steps_per_particle[m] / cpu_rate[m] : 0;
        if (predicted > a->cpu_seconds) {
          Row r{"cpu (" + std::to_string(threads) + " threads)", method_name, n, {}, true, ""};
          char note[96];
          std::snprintf(note, sizeof note, "skipped: about %.3g s predicted (--cpu-seconds %g)",
                        predicted, a->cpu_seconds);
          r.note = note;
          rows.push_back(r);
          continue;
        }
        advect::ParticleBatch p = start;
        Row r{"cpu (" + std::to_string(threads) + " threads)", method_name, n, cpu->advect(series, p, 1.0, o), false, ""};
        cpu_rate[m] = static_cast<double>(r.stats.particle_steps) / r.stats.total_seconds;
        cpu_steps_per_particle[m] = static_cast<double>(r.stats.particle_steps) / static_cast<double>(n);
        rows.push_back(r);
      }
    }

    nlohmann::json out = {{"benchmark", "bench-gpu"},
                          {"field", a->field},
                          {"grid", {a->resolution, a->resolution, a->resolution}},
                          {"grid_bytes_per_step", series.geometry().point_count() * 3 * sizeof(float)},
                          {"sample_seconds", sample_seconds},
                          {"cpu_threads", threads},
                          {"cuda", cuda ? gpu->name() : "unavailable: " + why},
                          {"rk4_steps_per_particle", a->rk4_steps},
                          {"dopri5_tolerance", a->tolerance},
                          {"rows", nlohmann::json::array()}};
    for (const Row& r : rows) {
      const auto& s = r.stats;
      nlohmann::json j = {{"backend", r.backend}, {"method", r.method}, {"particles", r.particles}};
      if (r.skipped) {
        j["skipped"] = r.note;
      } else {
        j.update({{"particle_steps", s.particle_steps},
                  {"evaluations", s.evaluations},
                  {"total_seconds", s.total_seconds},
                  {"compute_seconds", s.compute_seconds},
                  {"upload_seconds", s.upload_seconds},
                  {"bytes_uploaded", s.bytes_uploaded},
                  {"particle_steps_per_second_compute", s.particle_steps / s.compute_seconds},
                  {"particle_steps_per_second_total", s.particle_steps / s.total_seconds}});
      }
      out["rows"].push_back(j);
    }
    if (!a->json_only) {
      std::printf("orthofront-bench gpu: %s sampled on %d^3 (%.0f MiB a step, 2 steps), particles uniform at "
                  "random, t 0 -> 1; RK4 %g steps a particle, DOPRI5 tolerance %g\n",
                  a->field.c_str(), a->resolution,
                  static_cast<double>(series.geometry().point_count() * 3 * sizeof(float)) / 1048576.0,
                  a->rk4_steps, a->tolerance);
      std::printf("CUDA: %s\n\n", cuda ? gpu->name().c_str() : ("unavailable (" + why + ")").c_str());
      std::printf("%-30s %-7s %11s %12s %10s %10s %14s %14s %9s\n", "backend", "method",
                  "particles", "p-steps", "compute s", "total s", "p-steps/s comp",
                  "p-steps/s total", "vs CPU");
      for (const Row& r : rows) {
        if (r.skipped) {
          std::printf("%-30s %-7s %11zu   %s\n", r.backend.c_str(), r.method.c_str(), r.particles,
                      r.note.c_str());
          continue;
        }
        const auto& s = r.stats;
        const double rate = static_cast<double>(s.particle_steps) / s.compute_seconds;
        // The CPU row of the same count and method, when it ran.
        double speedup = 0;
        for (const Row& o : rows)
          if (!o.skipped && o.particles == r.particles && o.method == r.method &&
              o.backend.rfind("cpu", 0) == 0 && r.backend.rfind("cpu", 0) != 0)
            speedup = rate / (static_cast<double>(o.stats.particle_steps) / o.stats.compute_seconds);
        char vs[32] = "";
        if (speedup > 0) std::snprintf(vs, sizeof vs, "%.1fx", speedup);
        std::printf("%-30s %-7s %11zu %12zu %10.4f %10.4f %14.3e %14.3e %9s\n", r.backend.c_str(),
                    r.method.c_str(), r.particles, s.particle_steps, s.compute_seconds,
                    s.total_seconds, rate, static_cast<double>(s.particle_steps) / s.total_seconds, vs);
      }
      std::printf("\nColumns: p-steps = accepted integration steps of all particles; compute s = "
                  "kernel time (CUDA events) or the parallel loop (CPU); total s = the call with "
                  "particle and step transfers; vs CPU = compute rate over the CPU row's.\n");
    }
    std::cout << out.dump(1) << "\n";
  });
}

}  // namespace orthofront::cli
