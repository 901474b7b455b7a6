// `orthofront-bench grid`: (1) surface throughput on sampled grids against the analytic fields
// they come from, (2) read throughput of one time step for each HDF5 storage and compression,
// against the raw disk bandwidth that `dd` measures on the same files. Prints tables and JSON.
#include <fcntl.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "orthofront/engine/stream_surface.h"
#include "orthofront/error.h"
#include "orthofront/field/analytic.h"
#include "orthofront/field/grid_field.h"
#include "orthofront/field/sample_field.h"
#include "orthofront/io/hdf5_layout.h"
#include "orthofront/io/report_json.h"
#include "orthofront/seed/seed.h"

namespace orthofront::cli {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

struct BenchGridArgs {
  std::int64_t resolution = 256;
  std::int64_t read_resolution = 256;
  std::size_t steps = 3;
  std::string dir = "/tmp";
  std::string json;
  int threads = 0;
  bool skip_surfaces = false;
  bool skip_reads = false;
  bool keep = false;
};

// --- surfaces --------------------------------------------------------------------------------

struct SurfaceCase {
  const char* field;
  SeedCurve seed;
  int seed_count;
  double edge;
  int max_steps;
};

struct SurfaceRow {
  std::string field, source;
  std::size_t vertices = 0, evaluations = 0;
  double seconds = 0;
  double vertices_per_second() const { return static_cast<double>(vertices) / seconds; }
};

SurfaceRow run_surface_case(const SurfaceCase& c, const Field3& field, const std::string& source) {
  StreamSurfaceOptions options;
  options.edge = c.edge;
  options.max_steps = c.max_steps;
  options.measure_quality = false;
  const Seed<3> seed = make_seed(c.seed, c.seed_count);
  build_stream_surface(field, seed, options);  // warm caches and pages
  const auto t0 = Clock::now();
  const SurfaceResult r = build_stream_surface(field, seed, options);
  SurfaceRow row{c.field, source, r.mesh.vertex_count(), r.report.field_evaluations, since(t0)};
  return row;
}

// --- reads -------------------------------------------------------------------------------------

struct ReadCase {
  io::Hdf5Storage storage;
  int gzip;
  std::size_t chunk_mib;  // 0: one chunk per step
};

struct ReadRow {
  std::string name;
  double file_mib = 0, ratio = 0;
  double write_s = 0;
  double raw_cold = 0;         // MB/s of logical step bytes: read_raw, page cache dropped
  double raw_bytes_cold = 0;   // MB/s of bytes actually read from disk
  double decode_serial = 0;    // MB/s: one step decoded alone
  double decode_parallel = 0;  // MB/s: all steps decoded at once (a pipeline's decode stage)
  double read_cold = 0;        // MB/s: read() = read_raw + decode, page cache dropped
  double hdf5_cold = 0;        // MB/s: HDF5's own decoding (H5Dread), page cache dropped
  double read_warm = 0;        // MB/s: read(), file in the page cache
};

void drop_page_cache(const fs::path& file) {
  const int fd = ::open(file.c_str(), O_RDONLY);
  if (fd < 0) return;
  ::fdatasync(fd);
  ::posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);
  ::close(fd);
}

double mb(double bytes) {
  return bytes / 1e6;
}

std::string case_name(const ReadCase& c) {
  std::string name = to_string(c.storage);
  name += c.gzip > 0 ? ", gzip " + std::to_string(c.gzip) : ", none";
  if (c.chunk_mib >= 4096)
    name += ", 1 chunk/step";
  else if (c.gzip > 0 || c.storage == io::Hdf5Storage::chunked)
    name += ", 16 MiB chunks";
  else
    name += ", contiguous";
  return name;
}

ReadRow run_read_case(const ReadCase& c, const GridGeometry& geometry, int components,
                      const std::vector<std::vector<float>>& steps, const fs::path& file) {
  ReadRow row;
  row.name = case_name(c);
  io::Hdf5WriteOptions options;
  options.storage = c.storage;
  options.gzip_level = c.gzip;
  if (c.chunk_mib > 0) options.max_chunk_bytes = c.chunk_mib << 20;
  options.zero_is_no_data = false;
  std::vector<double> times;
  for (std::size_t s = 0; s < steps.size(); ++s) times.push_back(static_cast<double>(s));
  auto t0 = Clock::now();
  {
    io::Hdf5SeriesWriter writer(file, geometry, components, times, options);
    for (const auto& step : steps) writer.write_step(step);
    writer.commit();
  }
  ::sync();
  row.write_s = since(t0);
  const double step_bytes = static_cast<double>(steps[0].size() * sizeof(float));
  row.file_mib = static_cast<double>(fs::file_size(file)) / (1 << 20);
  row.ratio =
      step_bytes * static_cast<double>(steps.size()) / static_cast<double>(fs::file_size(file));

  const auto series = io::open_hdf5_series(file);
  io::Hdf5ReadOptions plain_options;
  plain_options.raw_chunks = false;
  const auto plain = io::open_hdf5_series(file, "/", plain_options);
  std::vector<float> values(series->step_floats());
  const double n = static_cast<double>(steps.size());

  // read_raw, cold, every step.
  std::vector<io::RawStep> raws;
  double raw_s = 0, raw_bytes = 0;
  drop_page_cache(file);
  for (std::size_t s = 0; s < steps.size(); ++s) {
    t0 = Clock::now();
    raws.push_back(series->read_raw(s));
    raw_s += since(t0);
    raw_bytes += static_cast<double>(raws.back().bytes.size());
  }
  row.raw_cold = mb(step_bytes * n) / raw_s;
  row.raw_bytes_cold = mb(raw_bytes) / raw_s;
  // decode: one step alone, then all steps at once.
  t0 = Clock::now();
  series->decode(raws[0], values);
  row.decode_serial = mb(step_bytes) / since(t0);
  std::vector<std::vector<float>> decoded(steps.size(), std::vector<float>(series->step_floats()));
  t0 = Clock::now();
  tbb::parallel_for(std::size_t{0}, steps.size(),
                    [&](std::size_t s) { series->decode(raws[s], decoded[s]); });
  row.decode_parallel = mb(step_bytes * n) / since(t0);
  for (std::size_t s = 0; s < steps.size(); ++s)
    if (std::memcmp(decoded[s].data(), steps[s].data(), decoded[s].size() * sizeof(float)) != 0)
      throw Error("orthofront-bench grid: step " + std::to_string(s) + " of " + file.string() +
                  " did not read back exactly");
  raws.clear();
  decoded.clear();
  // read() cold, HDF5's own decoding cold, read() warm.
  const auto time_reads = [&](const io::TimeSeries& s, bool cold) {
    double seconds = 0;
    if (cold) drop_page_cache(file);
    for (std::size_t k = 0; k < steps.size(); ++k) {
      const auto start = Clock::now();
      s.read(k, values);
      seconds += since(start);
    }
    return mb(step_bytes * n) / seconds;
  };
  row.read_cold = time_reads(*series, true);
  row.hdf5_cold = time_reads(*plain, true);
  row.read_warm = time_reads(*series, false);
  return row;
}

struct DdResult {
  double mb_per_s = 0;
  std::string line;
};

// `dd if=FILE of=/dev/null bs=16M [iflag=direct]`; parses dd's summary line.
DdResult run_dd(const fs::path& file, const std::string& flags) {
  const fs::path log = file.string() + ".dd.txt";
  const std::string command =
      "dd if='" + file.string() + "' of=/dev/null bs=16M " + flags + " 2> '" + log.string() + "'";
  DdResult result;
  if (std::system(command.c_str()) != 0) return result;
  std::ifstream in(log);
  std::string line, last;
  while (std::getline(in, line))
    if (line.find("copied") != std::string::npos) last = line;
  fs::remove(log);
  result.line = last;
  // "... bytes (...) copied, 0.1234 s, 1.6 GB/s": bytes first, seconds after "copied, ".
  std::istringstream words(last);
  double bytes = 0;
  words >> bytes;
  const auto at = last.find("copied, ");
  if (at != std::string::npos) {
    const double seconds = std::stod(last.substr(at + 8));
    if (seconds > 0) result.mb_per_s = mb(bytes) / seconds;
  }
  return result;
}

void run_bench(const BenchGridArgs& a) {
  std::unique_ptr<tbb::global_control> threads;
  if (a.threads > 0)
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    static_cast<std::size_t>(a.threads));
  const std::size_t cores =
      tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
  nlohmann::json report;
  report["threads"] = cores;
  char line[512];

  if (!a.skip_surfaces) {
    const std::vector<SurfaceCase> cases = {
        {"saddle3d", SeedCurve::line(Vec3(-3.5, 3.5, 0.1), Vec3(3.5, 3.5, 0.1)), 200, 0.01, 400},
        {"lorenz", SeedCurve::line(Vec3(-15, -15, 20), Vec3(15, 15, 20)), 200, 0.1, 300},
    };
    std::vector<SurfaceRow> rows;
    std::cout << "Surface throughput (" << cores << " threads), grids " << a.resolution << "^3, "
              << "float32, trilinear\n";
    std::snprintf(line, sizeof line, "%-10s %-22s %10s %8s %12s %12s\n", "field", "source",
                  "vertices", "time s", "vertices/s", "evals/vertex");
    std::cout << line;
    for (const SurfaceCase& c : cases) {
      const auto analytic = make_analytic_field(c.field);
      SampleOptions sampling;
      sampling.resolution = {a.resolution, a.resolution, a.resolution};
      auto t0 = Clock::now();
      auto grid = std::make_shared<const VectorGrid>(sample_field(*analytic, sampling));
      const double sample_s = since(t0);
      GridFieldOptions grid_options;
      grid_options.zero_is_no_data = false;
      const GridField sampled(grid, grid_options);
      for (int which = 0; which < 2; ++which) {
        SurfaceRow row =
            which == 0
                ? run_surface_case(c, *analytic, "analytic")
                : run_surface_case(c, sampled, "grid " + std::to_string(a.resolution) + "^3");
        std::snprintf(line, sizeof line, "%-10s %-22s %10zu %8.3f %12.0f %12.1f\n",
                      row.field.c_str(), row.source.c_str(), row.vertices, row.seconds,
                      row.vertices_per_second(),
                      static_cast<double>(row.evaluations) / static_cast<double>(row.vertices));
        std::cout << line;
        report["surfaces"].push_back({{"field", row.field},
                                      {"source", row.source},
                                      {"vertices", row.vertices},
                                      {"seconds", row.seconds},
                                      {"vertices_per_second", row.vertices_per_second()},
                                      {"field_evaluations", row.evaluations},
                                      {"sampling_seconds", which == 1 ? sample_s : 0.0}});
      }
    }
    std::cout << "\n";
  }

  if (!a.skip_reads) {
    const fs::path dir = fs::path(a.dir) / ("orthofront-bench-grid-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    try {
      const auto lorenz = make_analytic_field("lorenz");
      SampleOptions sampling;
      sampling.resolution = {a.read_resolution, a.read_resolution, a.read_resolution};
      const GridGeometry geometry = sampling_geometry(sampling, lorenz->domain());
      // Steps differ (a shifted box per step) so no step is a copy of another.
      std::vector<std::vector<float>> steps;
      for (std::size_t s = 0; s < a.steps; ++s) {
        GridGeometry g = geometry;
        g.origin.z() += 0.37 * static_cast<double>(s);
        steps.emplace_back(g.point_count() * 3);
        sample_field_into(*lorenz, g, 3, steps.back());
      }
      const double step_mib = static_cast<double>(steps[0].size() * sizeof(float)) / (1 << 20);
      // chunk_mib: 0 = the writer's default (16 MiB), 4096 = one chunk per step.
      const std::vector<ReadCase> cases = {
          {io::Hdf5Storage::chunked, 0, 0},    {io::Hdf5Storage::per_step, 0, 0},
          {io::Hdf5Storage::chunked, 1, 4096}, {io::Hdf5Storage::per_step, 1, 4096},
          {io::Hdf5Storage::chunked, 1, 0},    {io::Hdf5Storage::per_step, 1, 0},
          {io::Hdf5Storage::chunked, 6, 0},    {io::Hdf5Storage::per_step, 6, 0},
      };
      std::vector<ReadRow> rows;
      fs::path plain_file;
      for (std::size_t k = 0; k < cases.size(); ++k) {
        const fs::path file = dir / ("case" + std::to_string(k) + ".h5");
        rows.push_back(run_read_case(cases[k], geometry, 3, steps, file));
        if (k == 0)
          plain_file = file;
        else if (!a.keep) {
          fs::remove(file);
          fs::remove(io::xdmf_path(file));
        }
      }
      drop_page_cache(plain_file);
      const DdResult dd_direct = run_dd(plain_file, "iflag=direct");
      drop_page_cache(plain_file);
      const DdResult dd_cold = run_dd(plain_file, "");
      const DdResult dd_warm = run_dd(plain_file, "");

      std::cout << "Read throughput of lorenz " << a.read_resolution << "^3 x 3 float32 ("
                << step_mib << " MiB a step, " << a.steps << " steps per file, under "
                << dir.string() << "), MB/s of decoded step data\n";
      std::snprintf(line, sizeof line, "%-30s %8s %6s %8s %9s %9s %9s %9s %9s %9s %9s\n", "storage",
                    "file MiB", "ratio", "write s", "raw cold", "disk MB/s", "dec 1", "dec all",
                    "read cold", "hdf5 cold", "read warm");
      std::cout << line;
      for (const ReadRow& r : rows) {
        std::snprintf(line, sizeof line,
                      "%-30s %8.1f %6.2f %8.2f %9.0f %9.0f %9.0f %9.0f %9.0f %9.0f %9.0f\n",
                      r.name.c_str(), r.file_mib, r.ratio, r.write_s, r.raw_cold, r.raw_bytes_cold,
                      r.decode_serial, r.decode_parallel, r.read_cold, r.hdf5_cold, r.read_warm);
        std::cout << line;
        report["reads"].push_back({{"storage", r.name},
                                   {"file_mib", r.file_mib},
                                   {"compression_ratio", r.ratio},
                                   {"write_seconds", r.write_s},
                                   {"read_raw_cold_mb_s", r.raw_cold},
                                   {"disk_bytes_cold_mb_s", r.raw_bytes_cold},
                                   {"decode_one_step_mb_s", r.decode_serial},
                                   {"decode_all_steps_parallel_mb_s", r.decode_parallel},
                                   {"read_cold_mb_s", r.read_cold},
                                   {"hdf5_decode_cold_mb_s", r.hdf5_cold},
                                   {"read_warm_mb_s", r.read_warm}});
      }
      std::cout << "dd on the uncompressed chunked file: O_DIRECT " << dd_direct.mb_per_s
                << " MB/s, page cache dropped " << dd_cold.mb_per_s << " MB/s, cached "
                << dd_warm.mb_per_s << " MB/s\n";
      std::cout << "(raw cold: read_raw of every step after dropping the file from the page "
                   "cache; disk MB/s: the bytes it read; dec 1: decode of one step; dec all: "
                   "all steps decoded at once; read cold/warm: read() = read_raw + decode; "
                   "hdf5 cold: H5Dread doing the decoding)\n";
      report["dd"] = {{"direct_mb_s", dd_direct.mb_per_s},
                      {"cold_mb_s", dd_cold.mb_per_s},
                      {"cached_mb_s", dd_warm.mb_per_s},
                      {"direct_line", dd_direct.line}};
      report["read_step_mib"] = step_mib;
    } catch (...) {
      if (!a.keep) fs::remove_all(dir);
      throw;
    }
    if (!a.keep) fs::remove_all(dir);
  }
  if (!a.json.empty()) io::write_json(report, a.json);
  std::cout << "JSON: " << report.dump() << "\n";
}

}  // namespace

void add_bench_grid_command(CLI::App& app) {
  auto a = std::make_shared<BenchGridArgs>();
  CLI::App* c =
      app.add_subcommand("grid",
                         "Benchmark grid fields (surface vertices/s, sampled vs analytic) and HDF5 "
                         "step reads per storage and compression against dd");
  c->add_option("--resolution", a->resolution, "Samples per axis of the surface grids")
      ->capture_default_str();
  c->add_option("--read-resolution", a->read_resolution, "Samples per axis of the read tests")
      ->capture_default_str();
  c->add_option("--steps", a->steps, "Steps per file in the read tests")->capture_default_str();
  c->add_option("--dir", a->dir, "Folder for the test files (removed afterwards)")
      ->capture_default_str();
  c->add_option("--threads", a->threads, "Worker threads (0: all cores)")->capture_default_str();
  c->add_option("--json", a->json, "Also write the results here");
  c->add_flag("--skip-surfaces", a->skip_surfaces, "Only the read tests");
  c->add_flag("--skip-reads", a->skip_reads, "Only the surface tests");
  c->add_flag("--keep", a->keep, "Keep the test files");
  c->callback([a]() {
    if (a->resolution < 2 || a->read_resolution < 2 || a->steps < 1)
      throw InvalidArgument("orthofront-bench grid: resolutions must be >= 2 and --steps >= 1");
    run_bench(*a);
  });
}

}  // namespace orthofront::cli
