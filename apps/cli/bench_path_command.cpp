// `orthofront-bench path`: a path surface through a series far larger than the cache budget,
// streamed through the space-time brick cache (with and without prefetch), against the old
// whole-step cache, the I/O floor (read + decode of exactly the bricks the surface needs) and the
// compute time with every needed brick in memory. Each run is a child `orthofront path` process,
// so its peak RSS is its own, and the meshes they write are compared byte for byte.
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <tbb/parallel_for.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>

#include "cli/app_main.h"
#include "cli/commands.h"
#include "orthofront/error.h"
#include "orthofront/io/hdf5_layout.h"
#include "orthofront/io/report_json.h"
#include "orthofront/spacetime/brick_cache.h"
#include "orthofront/spacetime/sampled_series.h"
#include "orthofront/spacetime/streamed_field.h"

extern char** environ;

namespace orthofront::cli {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

struct BenchArgs {
  std::string dir = ".";
  std::string budget = "256MiB";
  std::string json;
  std::string series;  // reuse an existing series (not deleted)
  std::vector<std::int64_t> grid{512, 256, 256};
  std::size_t steps = 48;
  double dt = 0.25;
  double t1 = 0;  // 0: the last step
  double edge = 0.004;
  int seed_count = 40;
  std::string codec = "lz4";
  std::string whole_step_budget = "12GiB";
  std::int64_t brick = 32;
  bool keep = false;
  bool layout_sweep = false;
};

struct Run {
  std::string name, note;
  int exit_code = 0;
  double rss_mib = 0, wall = 0;
  nlohmann::json report;
  std::string mesh;
};

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string text;
  if (!in) return text;
  in.seekg(0, std::ios::end);
  text.resize(static_cast<std::size_t>(std::max<std::streamoff>(in.tellg(), 0)));
  in.seekg(0);
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  return text;
}

// Drops the file's pages from the page cache, so every run reads from the disk.
void drop_page_cache(const std::filesystem::path& file) {
  const int fd = ::open(file.c_str(), O_RDONLY);
  if (fd < 0) return;
  ::fdatasync(fd);
  ::posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);
  ::close(fd);
}

// Runs `orthofront path ARGS` as a child process; returns its exit code and peak RSS.
Run run_child(const std::string& name, const std::vector<std::string>& args,
              const std::filesystem::path& work) {
  Run r;
  r.name = name;
  const std::filesystem::path report = work / (name + ".json");
  const std::filesystem::path mesh = work / (name + ".vtp");
  const std::filesystem::path log = work / (name + ".log");
  const std::string program = program_beside("orthofront");
  std::vector<std::string> argv{program, "path"};
  argv.insert(argv.end(), args.begin(), args.end());
  for (const char* extra : {"--quiet", "--out"}) argv.emplace_back(extra);
  argv.push_back(mesh.string());
  argv.emplace_back("--report");
  argv.push_back(report.string());
  std::vector<char*> cargv;
  for (auto& a : argv) cargv.push_back(a.data());
  cargv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 2, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = 0;
  const auto t0 = Clock::now();
  if (posix_spawn(&pid, program.c_str(), &actions, nullptr, cargv.data(), environ) != 0)
    throw Error("orthofront-bench path: cannot start a child process for run '" + name + "'");
  posix_spawn_file_actions_destroy(&actions);
  int status = 0;
  waitpid(pid, &status, 0);
  r.wall = since(t0);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.note = read_file(log);
  while (!r.note.empty() && (r.note.back() == '\n' || r.note.back() == '\r')) r.note.pop_back();
  if (const auto cut = r.note.rfind('\r'); cut != std::string::npos) r.note = r.note.substr(cut + 1);
  if (std::filesystem::exists(report)) r.report = nlohmann::json::parse(read_file(report));
  // The child's own high-water mark (getrusage's ru_maxrss would carry the parent's over exec).
  if (r.report.contains("process"))
    r.rss_mib = r.report["process"].value("peak_rss_bytes", 0.0) / (1024.0 * 1024.0);
  r.mesh = read_file(mesh);
  return r;
}

io::Hdf5Codec parse_codec(const std::string& text) {
  if (text == "none") return io::Hdf5Codec::none;
  if (text == "gzip") return io::Hdf5Codec::gzip;
  if (text == "lz4") return io::Hdf5Codec::lz4;
  if (text == "zstd") return io::Hdf5Codec::zstd;
  throw InvalidArgument("--codec '" + text + "' is not none, gzip, lz4 or zstd");
}

// Cost of one evaluation through bricks (corners gathered from up to 8 bricks where a cell
// straddles a border) and through whole steps (one array: what halo layers would give every cell).
void sampling_cost(const io::TimeSeries& series, nlohmann::json& out) {
  const GridGeometry& g = series.geometry();
  const Box<3> box = g.bounds();
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double t0 = series.time(0), t1 = series.time(1);
  std::vector<std::pair<Vec3, double>> points(2'000'000);
  std::size_t straddling = 0;
  const io::BrickLayout bricks = series.bricks();
  for (auto& [x, t] : points) {
    bool straddles = false;
    for (int a = 0; a < 3; ++a) {
      x[a] = box.lo[a] + u(rng) * (box.hi[a] - box.lo[a]);
      const auto i = static_cast<std::int64_t>((x[a] - g.origin[a]) / g.spacing[a]);
      straddles = straddles || i % bricks.size[static_cast<std::size_t>(a)] ==
                                   bricks.size[static_cast<std::size_t>(a)] - 1;
    }
    straddling += straddles ? 1 : 0;
    t = t0 + u(rng) * (t1 - t0);
  }
  const auto time = [&](bool whole) {
    spacetime::CacheOptions o;
    o.budget_bytes = std::size_t{4} << 30;
    o.whole_steps = whole;
    o.prefetch = false;
    spacetime::BrickCache cache(series, o);
    spacetime::StreamedField field(cache);
    field.update_band(t0, t1);
    Vec3 v, dvdt;
    Mat3 J;
    double sum = 0;
    const auto start = Clock::now();
    for (const auto& [x, t] : points) {
      field.velocity_jacobian(x, t, v, J, dvdt);
      sum += v[0] + J(0, 0);
    }
    const double ns = since(start) * 1e9 / static_cast<double>(points.size());
    return sum != 0 ? ns : ns;  // keeps the loop's result alive
  };
  out["bricked_ns"] = time(false);
  out["whole_step_ns"] = time(true);
  out["straddling_percent"] = 100.0 * static_cast<double>(straddling) / static_cast<double>(points.size());
}

// --layout-sweep: the same (smaller) series written with each codec and brick size; size on disk,
// write time, cold read and parallel decode rates of every brick, and a path surface through it.
void layout_sweep(const BenchArgs& a) {
  const auto flow = make_unsteady_field("double-gyre-3d");
  GridGeometry grid = spacetime::uniform_grid(flow->domain(), 3, 2);
  const std::array<std::int64_t, 3> size{256, 128, 128};
  for (std::size_t i = 0; i < 3; ++i) {
    grid.size[i] = size[i];
    grid.spacing[static_cast<int>(i)] =
        flow->domain().extent()[static_cast<int>(i)] / static_cast<double>(size[i] - 1);
  }
  const std::size_t steps = 24;
  const std::vector<double> times = spacetime::uniform_times(0, 0.5 * (steps - 1), steps - 1);
  const spacetime::SampledTimeSeries source(*flow, grid, times);
  const std::filesystem::path work =
      std::filesystem::path(a.dir) / ("orthofront-layout-sweep-" + std::to_string(::getpid()));
  std::filesystem::create_directories(work);
  struct Layout {
    std::string codec;
    std::int64_t brick;
  };
  const std::vector<Layout> layouts{{"none", 32}, {"gzip", 32}, {"zstd", 32},
                                    {"lz4", 32},  {"lz4", 16},  {"lz4", 64}};
  nlohmann::json out = nlohmann::json::array();
  nlohmann::json out_sampling;
  std::printf("series: %zu steps of 256x128x128 (%s of floats); path surface as orthofront-bench path's, "
              "budget %s\n\n", steps,
              spacetime::format_bytes(source.step_bytes() * steps).c_str(), a.budget.c_str());
  std::printf("%-6s %6s %10s %7s %8s %12s %14s %9s %8s %9s\n", "codec", "brick", "on disk", "ratio",
              "write s", "read MB/s", "decode MB/s", "path s", "wait s", "read/need");
  try {
    for (const Layout& l : layouts) {
      const std::filesystem::path file = work / (l.codec + "-" + std::to_string(l.brick) + ".h5");
      auto t = Clock::now();
      {
        io::Hdf5WriteOptions w;
        w.codec = parse_codec(l.codec);
        w.gzip_level = l.codec == "gzip" ? 1 : 0;
        w.brick_size = l.brick;
        w.zero_is_no_data = false;
        w.xdmf = false;
        io::Hdf5SeriesWriter writer(file, grid, 3, times, w);
        std::vector<float> values(source.step_floats());
        for (std::size_t k = 0; k < steps; ++k) {
          source.sample(k, values.data());
          writer.write_step(values);
        }
        writer.commit();
      }
      const double write = since(t);
      const auto stored = std::filesystem::file_size(file);
      const auto series = io::open_hdf5_series(file);
      const io::BrickLayout bricks = series->bricks();
      // Cold serial reads of every brick of 8 steps, then their decode on all threads.
      drop_page_cache(file);
      std::vector<io::RawStep> raw;
      std::size_t raw_bytes = 0;
      t = Clock::now();
      for (std::size_t k = 0; k < 8; ++k)
        for (std::size_t b = 0; b < bricks.bricks(); ++b) {
          raw.push_back(series->read_raw_brick(k, b));
          raw_bytes += raw.back().bytes.size();
        }
      const double read = since(t);
      t = Clock::now();
      tbb::parallel_for(std::size_t{0}, raw.size(), [&](std::size_t i) {
        std::vector<float> values(series->brick_floats());
        series->decode_brick(raw[i], values);
      });
      const double decode = since(t);
      raw.clear();
      const double decoded_mb = static_cast<double>(series->brick_floats() * sizeof(float) *
                                                    bricks.bricks() * 8) / 1e6;
      drop_page_cache(file);
      const Run r = run_child(
          l.codec + "-" + std::to_string(l.brick),
          {"--field", file.string(), "--seed", "line:0.3,0.25,0.3:0.9,0.7,0.6", "--seed-count",
           std::to_string(a.seed_count), "--t0", "0", "--t1", std::to_string(times.back()),
           "--edge", std::to_string(a.edge), "--steps", "1000000", "--cache-budget", a.budget},
          work);
      double total = 0, wait = 0, amplification = 0;
      if (r.report.contains("path")) {
        total = r.report["path"]["seconds"]["total"];
        wait = r.report["path"]["seconds"]["wait"];
        amplification = r.report["path"]["cache"]["read_amplification"];
      }
      std::printf("%-6s %6lld %10s %7.2f %8.1f %12.0f %14.0f %9.2f %8.2f %9.3f%s\n", l.codec.c_str(),
                  static_cast<long long>(l.brick), spacetime::format_bytes(stored).c_str(),
                  static_cast<double>(source.step_bytes() * steps) / static_cast<double>(stored),
                  write, static_cast<double>(raw_bytes) / 1e6 / read, decoded_mb / decode, total,
                  wait, amplification, r.exit_code == 0 ? "" : (" failed: " + r.note).c_str());
      std::fflush(stdout);
      out.push_back({{"codec", l.codec}, {"brick", l.brick}, {"stored_bytes", stored},
                     {"write_seconds", write}, {"read_mb_per_s", static_cast<double>(raw_bytes) / 1e6 / read},
                     {"decode_mb_per_s", decoded_mb / decode}, {"path_seconds", total},
                     {"path_wait_seconds", wait}, {"read_amplification", amplification},
                     {"exit_code", r.exit_code}});
      if (l.codec == "lz4" && l.brick == 32) sampling_cost(*series, out_sampling);
      std::filesystem::remove(file);
    }
    std::printf("\nsampling (one thread, 2M points, all data resident): bricked %.1f ns, whole "
                "steps %.1f ns per evaluation with Jacobian; %.1f %% of cells straddle bricks\n",
                out_sampling["bricked_ns"].get<double>(), out_sampling["whole_step_ns"].get<double>(),
                out_sampling["straddling_percent"].get<double>());
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove_all(work, ignored);
    throw;
  }
  std::error_code ignored;
  std::filesystem::remove_all(work, ignored);
  if (!a.json.empty())
    io::write_json(nlohmann::json{{"layout_sweep", out}, {"sampling", out_sampling}}, a.json);
}

}  // namespace

void add_bench_path_command(CLI::App& app) {
  auto a = std::make_shared<BenchArgs>();
  CLI::App* c = app.add_subcommand(
      "path", "Benchmark path surfaces streamed through the brick cache: writes a "
                    "double-gyre-3d series (18 GiB of floats by default), runs brick cache with "
                    "and without prefetch, the whole-step cache and in-memory compute, then "
                    "deletes the series");
  c->add_option("--dir", a->dir, "Folder for the generated series and the runs' outputs")
      ->capture_default_str();
  c->add_option("--grid", a->grid, "Samples along x, y, z")->expected(3)->capture_default_str();
  c->add_option("--steps", a->steps, "Time steps")->capture_default_str();
  c->add_option("--dt", a->dt, "Time between steps")->capture_default_str();
  c->add_option("--t1", a->t1, "End time of the surface (0: the last step)")->capture_default_str();
  c->add_option("--cache-budget", a->budget, "Cache budget of the streamed runs")
      ->capture_default_str();
  c->add_option("--edge", a->edge, "Edge length")->capture_default_str();
  c->add_option("--seed-count", a->seed_count, "Seed vertices")->capture_default_str();
  c->add_option("--codec", a->codec, "Compression of the series: none, gzip, lz4, zstd")
      ->capture_default_str();
  c->add_option("--brick", a->brick, "Brick edge in points")->capture_default_str();
  c->add_option("--whole-step-budget", a->whole_step_budget,
                "Budget of a second whole-step run that states what that cache needs")
      ->capture_default_str();
  c->add_option("--series", a->series, "Use this existing series instead of generating one");
  c->add_option("--json", a->json, "Write the results as JSON here");
  c->add_flag("--keep", a->keep, "Keep the generated series and the runs' outputs");
  c->add_flag("--layout-sweep", a->layout_sweep,
              "Instead: compare codecs (none, gzip, zstd, lz4) and brick sizes (16, 32, 64) on a "
              "1.1 GiB series: size, write, read and decode rates, path surface time");
  c->callback([a]() {
    if (a->layout_sweep) return layout_sweep(*a);
    const auto flow = make_unsteady_field("double-gyre-3d");
    GridGeometry grid = spacetime::uniform_grid(flow->domain(), 3, 2);
    for (std::size_t i = 0; i < 3; ++i) {
      if (a->grid[i] < 2) throw InvalidArgument("--grid needs at least 2 samples per axis");
      grid.size[i] = a->grid[i];
      grid.spacing[static_cast<int>(i)] =
          flow->domain().extent()[static_cast<int>(i)] / static_cast<double>(a->grid[i] - 1);
    }
    if (a->steps < 2) throw InvalidArgument("--steps must be at least 2");
    const std::vector<double> times =
        spacetime::uniform_times(0, a->dt * static_cast<double>(a->steps - 1), a->steps - 1);
    const spacetime::SampledTimeSeries source(*flow, grid, times);
    const std::size_t budget = spacetime::parse_bytes(a->budget);
    const std::filesystem::path dir = a->dir;
    std::filesystem::create_directories(dir);
    const std::filesystem::path work = dir / ("orthofront-bench-path-" + std::to_string(::getpid()));
    std::filesystem::create_directories(work);
    const bool generated = a->series.empty();
    const std::filesystem::path file = generated ? work / "series.h5" : std::filesystem::path(a->series);
    const std::size_t data_bytes = source.step_bytes() * a->steps;
    nlohmann::json out;
    auto cleanup = [&] {
      if (a->keep) return;
      std::error_code ignored;
      if (generated) std::filesystem::remove(file, ignored);
      std::filesystem::remove_all(work, ignored);
    };
    try {
      double generate = 0;
      if (generated) {
        const auto space = std::filesystem::space(dir);
        const io::Hdf5Codec codec = parse_codec(a->codec);
        // Compressed size is unknown before writing: ask for the raw size (the worst case).
        if (space.available < data_bytes + (std::size_t{1} << 30))
          throw InvalidArgument("orthofront-bench path: " + dir.string() + " has " +
                                spacetime::format_bytes(space.available) + " free; the series needs up to " +
                                spacetime::format_bytes(data_bytes) +
                                " (choose --dir, or a smaller --grid/--steps)");
        std::printf("series: %zu steps of %lldx%lldx%lld (%s each, %s of floats, %.1fx the %s "
                    "budget), %s, bricks of %lld^3\n",
                    a->steps, static_cast<long long>(grid.size[0]),
                    static_cast<long long>(grid.size[1]), static_cast<long long>(grid.size[2]),
                    spacetime::format_bytes(source.step_bytes()).c_str(),
                    spacetime::format_bytes(data_bytes).c_str(),
                    static_cast<double>(data_bytes) / static_cast<double>(budget),
                    spacetime::format_bytes(budget).c_str(), a->codec.c_str(),
                    static_cast<long long>(a->brick));
        std::fflush(stdout);
        const auto t = Clock::now();
        io::Hdf5WriteOptions w;
        w.codec = codec;
        w.brick_size = a->brick;
        w.zero_is_no_data = false;
        w.xdmf = false;
        io::Hdf5SeriesWriter writer(file, grid, 3, times, w);
        std::vector<float> values(source.step_floats());
        for (std::size_t k = 0; k < a->steps; ++k) {
          source.sample(k, values.data());
          writer.write_step(values);
        }
        writer.commit();
        generate = since(t);
      }
      const auto stored = std::filesystem::file_size(file);
      const auto series = io::open_hdf5_series(file);
      std::printf("series %s: %s on disk (%.2fx smaller than the floats)%s\n", file.c_str(),
                  spacetime::format_bytes(stored).c_str(),
                  static_cast<double>(series->step_bytes() * series->step_count()) /
                      static_cast<double>(stored),
                  generated ? (", generated in " + std::to_string(generate) + " s").c_str() : "");
      const double t1 = a->t1 > 0 ? a->t1 : series->time(series->step_count() - 1);
      char seed[160];
      std::snprintf(seed, sizeof seed, "line:0.3,0.25,0.3:0.9,0.7,0.6");
      const std::vector<std::string> common{
          "--field", file.string(), "--seed", seed, "--seed-count", std::to_string(a->seed_count),
          "--t0", "0", "--t1", std::to_string(t1), "--edge", std::to_string(a->edge),
          "--steps", "1000000"};
      std::vector<Run> runs;
      auto with = [&](std::vector<std::string> extra) {
        std::vector<std::string> v = common;
        v.insert(v.end(), extra.begin(), extra.end());
        return v;
      };
      std::printf("running: brick cache + prefetch, brick cache on demand, whole-step cache, "
                  "in memory ...\n");
      std::fflush(stdout);
      const auto cold_run = [&](const std::string& name, const std::vector<std::string>& extra) {
        drop_page_cache(file);
        runs.push_back(run_child(name, with(extra), work));
      };
      cold_run("brick+prefetch", {"--cache-budget", a->budget});
      cold_run("brick on-demand", {"--cache-budget", a->budget, "--no-prefetch"});
      cold_run("whole-step", {"--cache-budget", a->budget, "--cache-unit", "step"});
      // In memory: every brick the surface touches, kept; the second build reads nothing.
      const double touched_bytes =
          runs[0].report.contains("path")
              ? runs[0].report["path"]["cache"].value("units_touched", 0.0) *
                    runs[0].report["path"]["cache"].value("unit_bytes", 0.0)
              : 0.0;
      const auto memory_budget = static_cast<std::size_t>(touched_bytes * 1.2) + (std::size_t{1} << 30);
      cold_run("in-memory", {"--cache-budget", std::to_string(memory_budget), "--warm"});
      cold_run("whole-step " + a->whole_step_budget,
               {"--cache-budget", a->whole_step_budget, "--cache-unit", "step"});

      // The I/O floor: read + decode of exactly the bricks the surface needs, from the streamed
      // run's own measurement of each brick read once.
      const nlohmann::json& first = runs[0].report;
      std::printf("\n%-16s %8s %8s %8s %8s %8s %8s %10s %8s %10s %10s %9s  %s\n", "run", "total s",
                  "I/O fl.", "compute", "wait s", "read s", "decode s", "read/need", "bricks",
                  "peak cache", "peak RSS", "vertices", "mesh");
      for (Run& r : runs) {
        nlohmann::json row = {{"name", r.name}, {"exit_code", r.exit_code},
                              {"peak_rss_mib", r.rss_mib}, {"wall_seconds", r.wall}};
        if (r.exit_code != 0 || !r.report.contains("path")) {
          std::printf("%-16s failed (exit %d): %s\n", r.name.c_str(), r.exit_code, r.note.c_str());
          row["error"] = r.note;
          out["runs"].push_back(row);
          continue;
        }
        const nlohmann::json& p = r.report["path"];
        const nlohmann::json& cache = p["cache"];
        const double total = p["seconds"]["total"], wait = p["seconds"]["wait"];
        const double io_s = p["seconds"]["io"], decode = p["seconds"]["decode"];
        // Read + decode of the bricks this run read (the bricks it needed, when read/need = 1);
        // the in-memory run's figures are those of its first, untimed build.
        const bool warm = r.name == "in-memory";
        const double floor = warm ? 0.0 : io_s + decode;
        const std::string same =
            runs[0].mesh.empty() ? "-" : (r.mesh == runs[0].mesh ? "identical" : "DIFFERS");
        std::printf("%-16s %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f %10.3f %8zu %10s %7.0f MiB %9zu  %s\n",
                    r.name.c_str(), total, floor, total - wait, wait, io_s, decode,
                    cache["read_amplification"].get<double>(), cache["units_touched"].get<std::size_t>(),
                    spacetime::format_bytes(cache["peak_bytes"].get<std::size_t>()).c_str(),
                    r.rss_mib, r.report["counts"]["vertices"].get<std::size_t>(), same.c_str());
        row["total_seconds"] = total;
        row["io_floor_seconds"] = floor;
        row["compute_seconds"] = total - wait;
        row["wait_seconds"] = wait;
        row["read_seconds"] = io_s;
        row["decode_seconds"] = decode;
        row["bytes_read"] = cache["bytes_read"];
        row["bytes_needed"] = cache["bytes_needed"];
        row["read_amplification"] = cache["read_amplification"];
        row["bricks_touched"] = cache["units_touched"];
        row["peak_cache_bytes"] = cache["peak_bytes"];
        row["vertices"] = r.report["counts"]["vertices"];
        row["time_reached"] = p["time_reached"];
        row["complete"] = p["complete"];
        row["mesh_identical_to_first"] = same == "identical";
        out["runs"].push_back(row);
      }
      if (first.contains("path")) {
        const nlohmann::json& p = first["path"];
        // I/O floor: the on-demand run reads exactly the bricks needed, each once.
        const nlohmann::json& demand = runs[1].report.contains("path") ? runs[1].report["path"] : p;
        const double floor =
            demand["seconds"]["io"].get<double>() + demand["seconds"]["decode"].get<double>();
        const double compute = runs[3].report.contains("path")
                                   ? runs[3].report["path"]["seconds"]["total"].get<double>()
                                   : 0.0;
        std::printf("\nbrick+prefetch: reached t = %.4g of %.4g; total %.2f s = %.2fx max(I/O floor "
                    "%.2f s, in-memory compute %.2f s); peak RSS %.0f MiB vs budget %s + 200 MiB\n",
                    p["time_reached"].get<double>(), t1, p["seconds"]["total"].get<double>(),
                    p["seconds"]["total"].get<double>() / std::max({floor, compute, 1e-9}), floor,
                    compute, runs[0].rss_mib, spacetime::format_bytes(budget).c_str());
      }
      out["series"] = {{"file", file.string()},      {"steps", series->step_count()},
                       {"step_bytes", series->step_bytes()},
                       {"data_bytes", series->step_bytes() * series->step_count()},
                       {"stored_bytes", stored},     {"codec", a->codec},
                       {"brick", a->brick},          {"generate_seconds", generate},
                       {"budget_bytes", budget},     {"t1", t1},
                       {"edge", a->edge},            {"seed_count", a->seed_count}};
    } catch (...) {
      cleanup();
      throw;
    }
    cleanup();
    if (!a->json.empty()) io::write_json(out, a->json);
    std::cout << out.dump(1) << "\n";
  });
}

}  // namespace orthofront::cli
