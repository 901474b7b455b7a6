// `orthofront bench-path`: a path surface through a time series many times larger than the
// cache budget, against the I/O floor, the in-memory compute time and load-on-demand.
#include <sys/resource.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "cli/commands.h"
#include "orthofront/error.h"
#include "orthofront/io/hdf5_layout.h"
#include "orthofront/io/report_json.h"
#include "orthofront/spacetime/path_command_json.h"
#include "orthofront/spacetime/path_surface.h"
#include "orthofront/spacetime/sampled_series.h"

namespace orthofront::cli {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

double peak_rss_mib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;
}

struct BenchArgs {
  std::string dir = "/tmp";
  std::string budget = "64MiB";
  std::string json;
  std::int64_t grid = 64;
  std::size_t steps = 330;
  double dt = 0.1;
  double t1 = 0;  // 0: the whole series
  double edge = 0.06;
  int seed_count = 10;
  int gzip = 1;
  bool keep = false;
};

struct Row {
  std::string name;
  double total = 0, wait = 0, io = 0, decode = 0;
  std::size_t bytes_read = 0, peak_cache = 0, vertices = 0;
  double rss_mib = 0;
};

}  // namespace

void add_bench_path_command(CLI::App& app) {
  auto a = std::make_shared<BenchArgs>();
  CLI::App* c = app.add_subcommand(
      "bench-path", "Benchmark path surfaces streamed through the cache (writes, then deletes, "
                    "a double-gyre-3d HDF5 series)");
  c->add_option("--dir", a->dir, "Folder for the generated series")->capture_default_str();
  c->add_option("--grid", a->grid, "Samples per axis")->capture_default_str();
  c->add_option("--steps", a->steps, "Time steps")->capture_default_str();
  c->add_option("--dt", a->dt, "Time between steps")->capture_default_str();
  c->add_option("--t1", a->t1, "End time of the surface (0: the last step)")->capture_default_str();
  c->add_option("--cache-budget", a->budget, "Cache budget")->capture_default_str();
  c->add_option("--edge", a->edge, "Edge length")->capture_default_str();
  c->add_option("--seed-count", a->seed_count, "Seed vertices")->capture_default_str();
  c->add_option("--gzip", a->gzip, "gzip level of the series (0: none)")->capture_default_str();
  c->add_option("--json", a->json, "Write the results as JSON here");
  c->add_flag("--keep", a->keep, "Keep the generated series");
  c->callback([a]() {
    const auto flow = make_unsteady_field("double-gyre-3d");
    const GridGeometry grid = spacetime::uniform_grid(flow->domain(), 3, a->grid);
    const std::vector<double> times =
        spacetime::uniform_times(0, a->dt * static_cast<double>(a->steps - 1), a->steps - 1);
    const spacetime::SampledTimeSeries source(*flow, grid, times);
    const std::size_t budget = spacetime::parse_bytes(a->budget);
    const std::filesystem::path file =
        std::filesystem::path(a->dir) / ("orthofront-bench-path-" + std::to_string(::getpid()) + ".h5");
    const std::size_t data_bytes = source.step_bytes() * a->steps;
    std::printf("series: %zu steps of %s (%s in all, %.1fx the %s budget), gzip %d\n", a->steps,
                spacetime::format_bytes(source.step_bytes()).c_str(),
                spacetime::format_bytes(data_bytes).c_str(),
                static_cast<double>(data_bytes) / static_cast<double>(budget),
                spacetime::format_bytes(budget).c_str(), a->gzip);
    auto t = Clock::now();
    {
      io::Hdf5WriteOptions w;
      w.gzip_level = a->gzip;
      w.zero_is_no_data = false;
      w.xdmf = false;
      io::Hdf5SeriesWriter writer(file, grid, 3, times, w);
      std::vector<float> values(source.step_floats());
      for (std::size_t k = 0; k < a->steps; ++k) {
        source.sample(k, values.data());
        writer.write_step(values);
      }
      writer.commit();
    }
    const double generate = since(t);
    const auto stored = std::filesystem::file_size(file);
    std::printf("generated %s on disk in %.1f s\n", spacetime::format_bytes(stored).c_str(), generate);
    nlohmann::json out;
    std::vector<Row> rows;
    try {
      const auto series = io::open_hdf5_series(file);
      const double t1 = a->t1 > 0 ? a->t1 : times.back();
      spacetime::PathSurfaceOptions o;
      o.t0 = 0;
      o.t1 = t1;
      o.engine.edge = a->edge;
      o.engine.max_steps = 1'000'000;
      o.engine.insertion = Insertion::cubic;
      const SeedCurve seed = SeedCurve::line(Vec3(0.3, 0.25, 0.3), Vec3(0.9, 0.7, 0.6));
      std::size_t needed_steps = 0;
      for (double time : times) needed_steps += time <= t1 + a->dt ? 1 : 0;
      needed_steps = std::min(needed_steps, a->steps);

      // I/O floor: read the needed steps serially; decode serially and in parallel.
      double read = 0, decode_serial = 0, decode_parallel = 0;
      std::size_t raw_bytes = 0;
      {
        std::vector<float> values(series->step_floats());
        for (std::size_t k = 0; k < needed_steps; ++k) {
          t = Clock::now();
          const io::RawStep raw = series->read_raw(k);
          read += since(t);
          raw_bytes += raw.bytes.size();
          if (k < 8) {  // decoding: a sample of steps each way
            t = Clock::now();
            tbb::task_arena(1).execute([&] { series->decode(raw, values); });
            decode_serial += since(t);
            t = Clock::now();
            series->decode(raw, values);
            decode_parallel += since(t);
          }
        }
        const double sampled = static_cast<double>(std::min<std::size_t>(8, needed_steps));
        decode_serial *= static_cast<double>(needed_steps) / sampled;
        decode_parallel *= static_cast<double>(needed_steps) / sampled;
      }
      std::printf("I/O floor: read %zu steps (%s) in %.2f s; decode serial %.2f s, parallel "
                  "%.2f s (%d threads)\n",
                  needed_steps, spacetime::format_bytes(raw_bytes).c_str(), read, decode_serial,
                  decode_parallel, tbb::this_task_arena::max_concurrency());
      out["io_floor"] = {{"steps", needed_steps},   {"raw_bytes", raw_bytes},
                         {"read_seconds", read},    {"decode_serial_seconds", decode_serial},
                         {"decode_parallel_seconds", decode_parallel},
                         {"threads", tbb::this_task_arena::max_concurrency()}};

      auto run = [&](const char* name, bool prefetch, std::size_t run_budget, bool preload) {
        spacetime::CacheOptions co;
        co.budget_bytes = run_budget;
        co.prefetch = prefetch;
        spacetime::TimeStepCache cache(*series, co);
        std::vector<spacetime::TimeStepCache::Handle> all;
        if (preload) all = cache.acquire_range(0, needed_steps - 1);
        const spacetime::PathSurfaceResult r = spacetime::build_path_surface(cache, seed, a->seed_count, o);
        Row row;
        row.name = name;
        row.total = r.path.total_seconds;
        row.wait = r.path.wait_seconds;
        row.io = r.path.io_seconds;
        row.decode = r.path.decode_seconds;
        row.bytes_read = r.path.cache.bytes_read;
        row.peak_cache = r.path.cache.peak_bytes;
        row.vertices = r.mesh.vertex_count();
        row.rss_mib = peak_rss_mib();
        rows.push_back(row);
        nlohmann::json j = spacetime::to_json(r.path);
        j.erase("band");
        j["cache"].erase("reads_per_step");
        j["vertices"] = r.mesh.vertex_count();
        j["steps"] = r.report.steps;
        j["peak_rss_mib"] = row.rss_mib;
        out["runs"][name] = j;
        if (!r.path.complete) throw Error(std::string(name) + ": " + r.path.message);
      };
      run("streamed", true, budget, false);
      run("on-demand", false, budget, false);
      run("in-memory", false, (needed_steps + 4) * series->step_bytes(), true);
      std::printf("\n%-10s %9s %9s %9s %9s %12s %12s %10s %9s\n", "run", "total s", "wait s",
                  "read s", "decode s", "read", "peak cache", "peak RSS", "vertices");
      for (const Row& r : rows)
        std::printf("%-10s %9.2f %9.2f %9.2f %9.2f %12s %12s %7.0f MiB %9zu\n", r.name.c_str(),
                    r.total, r.wait, r.io, r.decode, spacetime::format_bytes(r.bytes_read).c_str(),
                    spacetime::format_bytes(r.peak_cache).c_str(), r.rss_mib, r.vertices);
      std::printf("bytes read / bytes needed (streamed): %.3f; in-memory compute %.2f s vs "
                  "streamed total %.2f s vs I/O floor %.2f s\n",
                  static_cast<double>(rows[0].bytes_read) / static_cast<double>(raw_bytes),
                  rows[2].total - rows[2].wait, rows[0].total, read + decode_parallel);
      out["series"] = {{"steps", a->steps},         {"step_bytes", source.step_bytes()},
                       {"data_bytes", data_bytes},  {"stored_bytes", stored},
                       {"budget_bytes", budget},    {"gzip", a->gzip},
                       {"generate_seconds", generate}};
    } catch (...) {
      if (!a->keep) std::filesystem::remove(file);
      throw;
    }
    if (!a->keep) std::filesystem::remove(file);
    if (!a->json.empty()) io::write_json(out, a->json);
    std::cout << out.dump(1) << "\n";
  });
}

}  // namespace orthofront::cli
