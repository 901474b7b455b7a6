// `orthofront-bench batch`: 64 path surfaces (a seed rake) over one streamed series many times
// the cache budget, built one process at a time, in one shared pass (`batch`), and in one shared
// pass that checkpoints; total time, bytes read, peak RSS, checkpoint overhead, side by side.
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>
#include <tuple>

#include "cli/app_main.h"
#include "cli/commands.h"
#include "jobs/process_memory.h"
#include "cli/work_sharing.h"
#include "orthofront/error.h"
#include "orthofront/io/report_json.h"
#include "orthofront/spacetime/brick_cache.h"

extern char** environ;

namespace orthofront::cli {

using namespace jobs;

namespace {

using Clock = std::chrono::steady_clock;
using json = nlohmann::json;

struct BenchBatchArgs {
  int surfaces = 64;
  std::string resolution = "128,64,32";
  int steps = 301;
  double t1 = 30, edge = 0.05;
  double max_band = 1.0;  // the fronts of 64 surfaces then share a band a budget can hold
  std::string budget;     // empty: the series' raw size / 16
  std::string work, json_out;
  bool keep = false;
  std::string device;  // non-empty: the front advance table instead (per vertex, turns, merged)
};

std::string read_file(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

struct Child {
  int exit_code = 0;
  double seconds = 0;
  std::string log;
};

// Runs `program` (searched on PATH) with `args`, stdout and stderr into `log`.
Child run_program(const std::string& program, const std::vector<std::string>& args,
                  const std::filesystem::path& log) {
  std::vector<std::string> argv{program};
  argv.insert(argv.end(), args.begin(), args.end());
  std::vector<char*> cargv;
  for (auto& a : argv) cargv.push_back(a.data());
  cargv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  pid_t pid = 0;
  const auto t0 = Clock::now();
  if (posix_spawnp(&pid, program.c_str(), &actions, nullptr, cargv.data(), environ) != 0)
    throw Error("orthofront-bench batch: cannot start " + program);
  posix_spawn_file_actions_destroy(&actions);
  int status = 0;
  waitpid(pid, &status, 0);
  Child c;
  c.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  c.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  c.log = read_file(log);
  return c;
}

// Runs `orthofront` with `args`.
Child run_orthofront(const std::vector<std::string>& args, const std::filesystem::path& log) {
  return run_program(program_beside("orthofront"), args, log);
}

void require_ok(const Child& c, const std::string& what) {
  if (c.exit_code != 0)
    throw Error("orthofront-bench batch: " + what + " failed (exit " + std::to_string(c.exit_code) +
                "): " + c.log);
}

struct Row {
  std::string way;
  double seconds = 0;
  std::size_t bytes_read = 0;
  std::size_t peak_rss = 0;
  std::size_t identical = 0;  // meshes equal to the one-by-one run's
  std::size_t max_reads = 0;  // most reads of one brick
  int data_passes = 0;        // passes over the series (the shared ways)
  std::size_t checkpoints = 0;
  double checkpoint_seconds = 0;  // spent writing them (the run's own timer)
  double run_seconds = 0;         // the run's own total
};

/// The mesh a batch run writes for member k of the rake "r": r-K.vtp, K zero-padded to the width
/// of the last index.
std::string member_file(int k, int surfaces) {
  const int width = static_cast<int>(std::to_string(surfaces - 1).size());
  char member[64];
  std::snprintf(member, sizeof member, "r-%0*d.vtp", width, k);
  return member;
}

/// Fills r from a batch run's OUT/summary.json (passes, bytes, reads, peak RSS; the run's own
/// timers) and counts the members r-K.vtp equal to the one-by-one run's in `alone_dir`.
void read_batch_summary(Row& r, const std::filesystem::path& out,
                        const std::filesystem::path& alone_dir, int surfaces) {
  const json s = json::parse(read_file(out / "summary.json"));
  r.checkpoints = s.value("checkpoints_written", std::size_t{0});
  r.checkpoint_seconds = s.value("checkpoint_seconds", 0.0);
  r.run_seconds = s.value("seconds", 0.0);
  r.peak_rss = s.value("peak_rss_bytes", std::size_t{0});  // rank 0's under MPI
  for (const json& p : s["passes"])
    if (p.contains("cache")) {
      r.data_passes += p.value("data_passes", 0);
      r.bytes_read += p["cache"].value("bytes_read", std::size_t{0});
      r.max_reads = std::max(r.max_reads, p["cache"].value("max_reads_of_a_unit", std::size_t{0}));
    }
  for (int k = 0; k < surfaces; ++k)
    if (read_file(out / member_file(k, surfaces)) ==
        read_file(alone_dir / ("r-" + std::to_string(k) + ".vtp")))
      ++r.identical;
}


/// `orthofront-bench batch --device D`: the rake's shared pass with the front advance per vertex, on D with
/// the fronts taking turns (one backend call each), on D with the fronts that come during a call
/// merged into the next (one call at a time), and merged with calls running at once (the
/// default); the merged meshes against the turns' (they must be equal), backend calls and time.
void device_table(const BenchBatchArgs& a, const std::filesystem::path& work) {
  namespace fs = std::filesystem;
  struct Way {
    std::string name;
    std::vector<std::string> options;
    double seconds = 0;
    json device;
  };
  std::vector<Way> ways{{"per vertex (no --device)", {}, 0, json()},
                        {"--device " + a.device + ", fronts take turns",
                         {"--device", a.device, "--no-merge-fronts"}, 0, json()},
                        {"--device " + a.device + ", merged, one call at a time",
                         {"--device", a.device, "--device-calls", "1"}, 0, json()},
                        {"--device " + a.device + ", merged, calls at once",
                         {"--device", a.device}, 0, json()}};
  for (Way& w : ways) {
    const fs::path out = work / ("device-" + std::to_string(&w - ways.data()));
    fs::remove_all(out);
    std::vector<std::string> args{"batch", (work / "job.toml").string(), "--out", out.string(),
                                  "--checkpoint-every", "0", "--quiet"};
    args.insert(args.end(), w.options.begin(), w.options.end());
    const Child ch = run_orthofront(args, out.string() + ".log");
    require_ok(ch, w.name);
    w.seconds = ch.seconds;
    const json s = json::parse(read_file(out / "summary.json"));
    for (const json& p : s["passes"])
      if (p.contains("device")) w.device = p["device"];
    std::printf("  %s: %.2f s\n", w.name.c_str(), w.seconds);
    std::fflush(stdout);
  }
  // Merged (one call at a time or several at once) and turns must write the same meshes.
  std::size_t identical = 0;
  for (int k = 0; k < a.surfaces; ++k) {
    const std::string member = member_file(k, a.surfaces);
    const std::string turns = read_file(work / "device-1" / member);
    if (read_file(work / "device-2" / member) == turns &&
        read_file(work / "device-3" / member) == turns)
      ++identical;
  }
  std::printf("\n%-40s %10s %12s %14s %14s %14s %10s %10s %10s %10s\n", "front advance",
              "seconds", "front calls", "backend calls", "largest merge", "particles", "backend s",
              "kernels s", "steps s", "waited s");
  json rows = json::array();
  for (const Way& w : ways) {
    const auto field = [&](const char* key) {
      return w.device.is_null() ? std::string("-") : std::to_string(w.device.value(key, 0ul));
    };
    const auto seconds = [&](const char* key) {
      if (w.device.is_null()) return std::string("-");
      char text[32];
      std::snprintf(text, sizeof text, "%.2f", w.device.value(key, 0.0));
      return std::string(text);
    };
    std::printf("%-40s %10.2f %12s %14s %14s %14s %10s %10s %10s %10s\n", w.name.c_str(),
                w.seconds, field("front_calls").c_str(), field("backend_calls").c_str(),
                field("largest_merge").c_str(), field("particles").c_str(),
                seconds("backend_seconds").c_str(), seconds("kernel_seconds").c_str(),
                seconds("host_seconds").c_str(), seconds("wait_seconds").c_str());
    rows.push_back({{"way", w.name}, {"seconds", w.seconds}, {"device", w.device}});
  }
  std::printf("merged (both ways) vs turns: %zu/%d meshes identical; time %.3f and %.3f of the "
              "turns'\n",
              identical, a.surfaces, ways[2].seconds / std::max(ways[1].seconds, 1e-9),
              ways[3].seconds / std::max(ways[1].seconds, 1e-9));
  if (!a.json_out.empty())
    io::write_json({{"surfaces", a.surfaces},
                    {"resolution", a.resolution},
                    {"steps", a.steps},
                    {"device", a.device},
                    {"rows", rows},
                    {"identical_meshes", identical}},
                   a.json_out);
}

}  // namespace

void add_bench_batch_command(CLI::App& app) {
  auto a = std::make_shared<BenchBatchArgs>();
  CLI::App* c = app.add_subcommand(
      "batch",
      "Benchmark batch jobs: a rake of path surfaces over one streamed series, one process per "
      "surface vs one shared pass (with and without checkpoints)");
  c->add_option("--surfaces", a->surfaces, "Path surfaces in the rake")
      ->check(CLI::Range(2, 10000))
      ->capture_default_str();
  c->add_option("--resolution", a->resolution, "Grid of the double-gyre-3d series NX,NY,NZ")
      ->capture_default_str();
  c->add_option("--steps", a->steps, "Time steps of the series")
      ->check(CLI::Range(2, 100000))
      ->capture_default_str();
  c->add_option("--t1", a->t1, "Last time of the series (surfaces run from 0 to t1 / 2)")
      ->capture_default_str();
  c->add_option("--edge", a->edge, "Edge length of the surfaces")->capture_default_str();
  c->add_option("--max-band", a->max_band,
                "Time band bound of every surface (path --max-band; 0: none). Without it the "
                "fronts of slow seed lines lag by several time units, and the band of all "
                "surfaces is deeper than the budget holds: the pass is split")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  c->add_option("--cache-budget", a->budget,
                "Cache budget of every run (default: the series' decoded size / 16)");
  c->add_option("--work", a->work,
                "Folder for the series and the outputs (default: a temporary one)");
  c->add_flag("--keep", a->keep, "Keep the work folder");
  c->add_option("--device", a->device,
                "Instead: the shared pass with the front advance per vertex, on this device with "
                "the fronts taking turns, and with them merged (backend calls, time, equal meshes)")
      ->check(CLI::IsMember({"cpu", "cuda", "auto"}));
  c->add_option("--json", a->json_out, "Write the results as JSON here");
  c->callback([a]() {
    namespace fs = std::filesystem;
    const fs::path work =
        a->work.empty()
            ? fs::temp_directory_path() / ("orthofront-bench-batch-" + std::to_string(getpid()))
            : fs::path(a->work);
    fs::create_directories(work);
    const fs::path series = work / "gyre3d.h5";
    std::printf("orthofront-bench batch: double-gyre-3d %s x %d steps into %s\n", a->resolution.c_str(),
                a->steps, series.string().c_str());
    std::fflush(stdout);
    require_ok(run_orthofront({"generate", "--field", "double-gyre-3d", "--resolution", a->resolution,
                         "--steps", std::to_string(a->steps), "--t1", std::to_string(a->t1),
                         "--brick", "16", "--out", series.string(), "--quiet"},
                        work / "generate.log"),
               "generating the series");
    // Decoded size: points x 3 components x 4 bytes x steps.
    std::size_t points = 1;
    {
      std::stringstream in(a->resolution);
      std::string part;
      while (std::getline(in, part, ',')) points *= static_cast<std::size_t>(std::stoul(part));
    }
    const std::size_t series_bytes = points * 3 * 4 * static_cast<std::size_t>(a->steps);
    const std::size_t budget =
        a->budget.empty() ? series_bytes / 16 : spacetime::parse_bytes(a->budget);
    const std::string budget_text = std::to_string(budget);
    const double t_end = a->t1 / 2;
    // The rake: seed lines across y at z = 0.5, spread over x in [0.05, 1.95].
    const double step_x = 1.9 / (a->surfaces - 1);
    const auto seed_of = [&](int k) {
      char text[128];
      const double x = 0.05 + step_x * k;
      std::snprintf(text, sizeof text, "line:%.17g,0.1,0.5:%.17g,0.9,0.5", x, x);
      return std::string(text);
    };
    std::printf(
        "series: %s decoded (%s on disk), cache budget %s (%.1fx smaller), %d path "
        "surfaces from t = 0 to %g, edge %g, max band %g\n",
        spacetime::format_bytes(series_bytes).c_str(),
        spacetime::format_bytes(fs::file_size(series)).c_str(),
        spacetime::format_bytes(budget).c_str(),
        static_cast<double>(series_bytes) / static_cast<double>(budget), a->surfaces, t_end,
        a->edge, a->max_band);
    std::fflush(stdout);

    // The rake as a batch job.
    char job[1024];
    std::snprintf(job, sizeof job,
                  "[job]\nfield = \"%s\"\ncache_budget = \"%zu\"\n[defaults]\nedge = %.17g\n"
                  "max_band = %.17g\nt0 = 0.0\nt1 = %.17g\n[[rake]]\nname = \"r\"\nseed = "
                  "\"%s\"\ncount = %d\n"
                  "offset = [%.17g, 0.0, 0.0]\n",
                  series.string().c_str(), budget, a->edge, a->max_band, t_end, seed_of(0).c_str(),
                  a->surfaces, step_x);
    {
      std::ofstream out(work / "job.toml");
      out << job;
    }
    if (!a->device.empty()) {
      device_table(*a, work);
      if (!a->keep && a->work.empty()) fs::remove_all(work);
      return;
    }
    std::vector<Row> rows;
    // 1. One process per surface.
    Row alone{"one process per surface"};
    const fs::path alone_dir = work / "alone";
    fs::create_directories(alone_dir);
    for (int k = 0; k < a->surfaces; ++k) {
      const std::string name = "r-" + std::to_string(k);
      const Child ch = run_orthofront({"path",
                                 "--field",
                                 series.string(),
                                 "--seed",
                                 seed_of(k),
                                 "--t0",
                                 "0",
                                 "--t1",
                                 std::to_string(t_end),
                                 "--edge",
                                 std::to_string(a->edge),
                                 "--cache-budget",
                                 budget_text,
                                 "--max-band",
                                 std::to_string(a->max_band),
                                 "--quiet",
                                 "--out",
                                 (alone_dir / (name + ".vtp")).string(),
                                 "--report",
                                 (alone_dir / (name + ".json")).string()},
                                alone_dir / (name + ".log"));
      alone.seconds += ch.seconds;
      if (!fs::exists(alone_dir / (name + ".json"))) require_ok(ch, "path surface " + name);
      const json report = json::parse(read_file(alone_dir / (name + ".json")));
      alone.bytes_read += report["path"]["cache"].value("bytes_read", std::size_t{0});
      alone.max_reads = std::max(
          alone.max_reads, report["path"]["cache"].value("max_reads_of_a_unit", std::size_t{0}));
      alone.peak_rss =
          std::max(alone.peak_rss, report["process"].value("peak_rss_bytes", std::size_t{0}));
      alone.identical += 1;
    }
    rows.push_back(alone);
    std::printf("  one by one: %.2f s\n", alone.seconds);
    std::fflush(stdout);

    // 2. One shared pass, without checkpoints and with them every 10 s and every 1 s.
    double shared_seconds = 0;
    const std::vector<std::pair<std::string, std::string>> ways{
        {"one shared pass", "0"},
        {"shared pass, checkpoint every 10 s", "10"},
        {"shared pass, checkpoint every 1 s", "1"}};
    // Three rounds of the three ways, interleaved (the page cache's writeback of one run's files
    // slows the next), the least time of each: the differences sought are a few percent.
    std::vector<double> best(ways.size(), 0);
    for (int repeat = 0; repeat < 3; ++repeat)
      for (std::size_t w = 0; w < ways.size(); ++w) {
        const fs::path out = work / ("shared-" + ways[w].second);
        fs::remove_all(out);
        const Child ch = run_orthofront({"batch", (work / "job.toml").string(), "--out", out.string(),
                                   "--checkpoint-every", ways[w].second, "--quiet"},
                                  work / ("shared-" + ways[w].second + ".log"));
        require_ok(ch, ways[w].first);
        best[w] = repeat == 0 ? ch.seconds : std::min(best[w], ch.seconds);
      }
    for (std::size_t w = 0; w < ways.size(); ++w) {
      const auto& [way, every] = ways[w];
      const fs::path out = work / ("shared-" + every);
      Row r{way};
      r.seconds = best[w];
      read_batch_summary(r, out, alone_dir, a->surfaces);
      if (every == "0") shared_seconds = r.seconds;
      rows.push_back(r);
      std::printf("  %s: %.2f s\n", way.c_str(), r.seconds);
      std::fflush(stdout);
    }

    // 3. MPI: the same job over 2 ranks of this machine (rank 0 hands out pieces of the rake),
    // and, to see how ranks scale where the work is CPU-bound, 1 and 2 ranks of one thread each.
    double mpi_one_thread[2] = {0, 0};
    if (have_mpi()) {
      const std::string self = program_beside("orthofront");
      // mpirun as root needs these two; oversubscribe: any rank count on any core count.
      ::setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 0);
      ::setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 0);
      for (const auto& [way, ranks, threads] :
           std::vector<std::tuple<std::string, int, int>>{{"MPI, 2 ranks", 2, 0},
                                                          {"MPI, 1 rank of 1 thread", 1, 1},
                                                          {"MPI, 2 ranks of 1 thread", 2, 1}}) {
        const fs::path out =
            work / ("mpi-" + std::to_string(ranks) + "-" + std::to_string(threads));
        fs::remove_all(out);
        const Child ch =
            run_program(mpi_launcher(),
                        {"-np", std::to_string(ranks), "--oversubscribe", self, "batch",
                         (work / "job.toml").string(), "--out", out.string(), "--checkpoint-every",
                         "0", "--threads", std::to_string(threads), "--quiet"},
                        out.string() + ".log");
        require_ok(ch, way);
        Row r{way};
        r.seconds = ch.seconds;
        read_batch_summary(r, out, alone_dir, a->surfaces);
        if (threads == 1) mpi_one_thread[ranks - 1] = r.seconds;
        rows.push_back(r);
        std::printf("  %s: %.2f s\n", r.way.c_str(), r.seconds);
        std::fflush(stdout);
      }
    }

    std::printf("\n%-38s %10s %12s %10s %10s %7s %7s %10s %10s\n", "way", "seconds", "read",
                "read/one", "max reads", "passes", "ckpts", "peak RSS", "identical");
    const double one_surface_bytes = static_cast<double>(alone.bytes_read) / a->surfaces;
    json out_rows = json::array();
    for (const Row& r : rows) {
      std::printf("%-38s %10.2f %12s %10.2f %10zu %7d %7zu %10s %7zu/%d\n", r.way.c_str(),
                  r.seconds, spacetime::format_bytes(r.bytes_read).c_str(),
                  static_cast<double>(r.bytes_read) / one_surface_bytes, r.max_reads, r.data_passes,
                  r.checkpoints, format_memory(r.peak_rss).c_str(), r.identical, a->surfaces);
      out_rows.push_back({{"way", r.way},
                          {"seconds", r.seconds},
                          {"bytes_read", r.bytes_read},
                          {"max_reads_of_a_brick", r.max_reads},
                          {"data_passes", r.data_passes},
                          {"checkpoints_written", r.checkpoints},
                          {"peak_rss_bytes", r.peak_rss},
                          {"identical_meshes", r.identical}});
    }
    const double ratio = shared_seconds / alone.seconds;
    const double overhead10 = rows[2].seconds / shared_seconds - 1;
    const double overhead1 = rows[3].seconds / shared_seconds - 1;
    std::printf(
        "\nshared pass / one by one: time %.3f (goal <= 0.25), bytes read %.2fx one "
        "surface's pass (goal <= 1.1; the series holds %.2fx)\n",
        ratio, static_cast<double>(rows[1].bytes_read) / one_surface_bytes,
        static_cast<double>(series_bytes) / one_surface_bytes);
    std::printf(
        "checkpoint overhead: wall clock (least of 3 runs each, runs vary by ~10%%) "
        "%+.1f%% every 10 s (%zu written), %+.1f%% every 1 s (%zu written); time spent "
        "writing them: %.2f%% and %.2f%% of the run (goal <= 3%%)\n",
        100 * overhead10, rows[2].checkpoints, 100 * overhead1, rows[3].checkpoints,
        100 * rows[2].checkpoint_seconds / std::max(rows[2].run_seconds, 1e-9),
        100 * rows[3].checkpoint_seconds / std::max(rows[3].run_seconds, 1e-9));
    if (rows[3].checkpoints > 0)
      std::printf(
          "one checkpoint of the %d surfaces takes %.3f s: %.2f%% of the time at one "
          "every 10 s\n",
          a->surfaces, rows[3].checkpoint_seconds / rows[3].checkpoints,
          10.0 * rows[3].checkpoint_seconds / rows[3].checkpoints);
    if (have_mpi())
      std::printf(
          "MPI: 2 ranks vs one process of every core: %.2fx; 2 ranks vs 1 rank, one "
          "thread each: %.2fx (goal >= 1.8 on CPU-bound jobs; this machine has %u "
          "cores)\n",
          shared_seconds / rows[4].seconds, mpi_one_thread[0] / mpi_one_thread[1],
          std::thread::hardware_concurrency());
    else
      std::printf("MPI: this build has no MPI (install libopenmpi-dev and reconfigure)\n");
    if (!a->json_out.empty())
      io::write_json({{"surfaces", a->surfaces},
                      {"resolution", a->resolution},
                      {"steps", a->steps},
                      {"series_bytes", series_bytes},
                      {"cache_budget_bytes", budget},
                      {"rows", out_rows},
                      {"shared_over_one_by_one", ratio},
                      {"checkpoint_overhead_10s", overhead10},
                      {"checkpoint_overhead_1s", overhead1},
                      {"checkpoint_writing_share_10s",
                       rows[2].checkpoint_seconds / std::max(rows[2].run_seconds, 1e-9)},
                      {"checkpoint_writing_share_1s",
                       rows[3].checkpoint_seconds / std::max(rows[3].run_seconds, 1e-9)}},
                     a->json_out);
    if (!a->keep && a->work.empty()) fs::remove_all(work);
  });
}

}  // namespace orthofront::cli
