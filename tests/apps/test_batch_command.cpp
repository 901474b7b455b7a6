// `orthofront batch`: a job's surfaces equal separate runs byte for byte, the shared pass reads
// each brick once, kill -9 and --resume give the same files, and bad job files are refused
// naming the file, the line and the key.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <thread>

#include "cli_run.h"
#include "temp_dir.h"

namespace fs = std::filesystem;
using cli_test::quoted;
using cli_test::run;
using test_support::read_text;
using test_support::TempDir;

namespace {

void write_text(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary);
  out << text;
}

// A small double-gyre series: 64 x 32 points, 41 steps over [0, 8], bricks of 16 points.
fs::path make_series(const TempDir& dir) {
  const fs::path file = dir / "gyre.h5";
  const auto r =
      run("generate --field double-gyre --resolution 64,32 --steps 41 --t1 8 --brick 16 "
          "--out " +
          quoted(file) + " --quiet");
  REQUIRE(r.status == 0);
  return file;
}

// Three surfaces: a stream surface, an analytic path surface and a streamed one.
std::string three_surface_job(const fs::path& series) {
  return R"([job]
field = "double-gyre"
cache_budget = "8MiB"

[defaults]
edge = 0.04
seed_count = 12
t0 = 0.0
t1 = 4.0

[[surface]]
name = "saddle"
kind = "stream"
field = "saddle3d"
seed = "line:-3,1,1:-3,1,3"
edge = 0.1
steps = 60

[[surface]]
name = "gyre"
seed = "line:0.3,0.2,0:0.3,0.8,0"

[[surface]]
name = "streamed"
field = ")" +
         series.string() + R"("
seed = "line:1.2,0.2,0:1.2,0.8,0"
t0 = 1.0
t1 = 5.0
)";
}

// The same surfaces through the single-surface commands.
void separate_runs(const fs::path& series, const TempDir& dir) {
  REQUIRE(run("stream --field saddle3d --seed line:-3,1,1:-3,1,3 --seed-count 12 --edge 0.1 "
              "--steps 60 --quiet --out " +
              quoted(dir / "saddle.vtp"))
              .status == 0);
  REQUIRE(run("path --field double-gyre --seed line:0.3,0.2,0:0.3,0.8,0 --seed-count 12 --edge "
              "0.04 --t0 0 --t1 4 --quiet --out " +
              quoted(dir / "gyre.vtp"))
              .status == 0);
  REQUIRE(run("path --field " + quoted(series) +
              " --cache-budget 8MiB --seed line:1.2,0.2,0:1.2,0.8,0 "
              "--seed-count 12 --edge 0.04 --t0 1 --t1 5 --quiet --out " +
              quoted(dir / "streamed.vtp"))
              .status == 0);
}

void require_same_meshes(const TempDir& expected, const fs::path& out) {
  for (const char* name : {"saddle.vtp", "gyre.vtp", "streamed.vtp"}) {
    INFO(name);
    REQUIRE(fs::exists(out / name));
    REQUIRE(read_text(out / name) == read_text(expected / name));
  }
}

nlohmann::json summary(const fs::path& out) {
  return nlohmann::json::parse(read_text(out / "summary.json"));
}

}  // namespace

TEST_CASE("batch: a job of three surfaces writes the meshes of three separate runs, byte for byte",
          "[batch]") {
  TempDir dir("batch");
  const fs::path series = make_series(dir);
  TempDir expected("batch-expected");
  separate_runs(series, expected);
  write_text(dir / "job.toml", three_surface_job(series));
  const auto r = run("batch " + quoted(dir / "job.toml") + " --out " + quoted(dir / "out"));
  INFO(r.output);
  REQUIRE(r.status == 0);
  require_same_meshes(expected, dir / "out");
  const auto s = summary(dir / "out");
  REQUIRE(s["surfaces"].size() == 3);
  for (const auto& row : s["surfaces"]) {
    CHECK(row["status"] == "done");
    CHECK(row["vertices"].get<int>() > 50);
    CHECK(fs::exists(dir / "out" / (row["name"].get<std::string>() + ".json")));
  }
  CHECK(read_text(dir / "out" / "summary.txt").find("streamed") != std::string::npos);
}

TEST_CASE("batch: the surfaces of one series share one pass that reads each brick once",
          "[batch]") {
  TempDir dir("batch-pass");
  const fs::path series = make_series(dir);
  // A rake of four path surfaces across the gyres.
  write_text(dir / "rake.toml", "[job]\nfield = \"" + series.string() +
                                    "\"\ncache_budget = \"64MiB\"\n[defaults]\nedge = 0.04\n"
                                    "seed_count = 12\nt0 = 0.0\nt1 = 6.0\n[[rake]]\nname = \"r\"\n"
                                    "seed = \"line:0.2,0.2,0:0.2,0.8,0\"\ncount = 4\n"
                                    "offset = [0.45, 0.0]\n");
  const auto r =
      run("batch " + quoted(dir / "rake.toml") + " --out " + quoted(dir / "out") + " --quiet");
  INFO(r.output);
  REQUIRE(r.status == 0);
  const auto s = summary(dir / "out");
  REQUIRE(s["passes"].size() == 1);
  const auto& cache = s["passes"][0]["cache"];
  CHECK(cache["max_reads_of_a_unit"] == 1);
  CHECK(cache["loads"] == cache["units_touched"]);
  // And each of them equals its own single-surface run.
  for (int k = 0; k < 4; ++k) {
    const double x = 0.2 + 0.45 * k;
    const std::string seed = "line:" + std::to_string(x) + ",0.2,0:" + std::to_string(x) + ",0.8,0";
    const fs::path alone = dir / ("alone-" + std::to_string(k) + ".vtp");
    REQUIRE(run("path --field " + quoted(series) + " --seed " + seed +
                " --seed-count 12 --edge 0.04 --t0 0 --t1 6 --quiet --out " + quoted(alone))
                .status == 0);
    INFO(k);
    CHECK(read_text(alone) == read_text(dir / "out" / ("r-" + std::to_string(k) + ".vtp")));
  }
}

TEST_CASE("batch: killed at any point and resumed, a job writes the files of an uninterrupted run",
          "[batch]") {
  TempDir dir("batch-kill");
  const fs::path series = make_series(dir);
  TempDir expected("batch-kill-expected");
  separate_runs(series, expected);
  write_text(dir / "job.toml", three_surface_job(series));
  const std::string job = quoted(dir / "job.toml");

  SECTION("at chosen front steps: inside the first surface, between surfaces, inside the pass") {
    // The stream surface takes its steps first (its own pass); the two path surfaces follow.
    for (const int steps : {5, 23, 25, 60, 90, 110}) {
      const fs::path out = dir / ("out-" + std::to_string(steps));
      const auto killed =
          run("batch " + job + " --out " + quoted(out) +
              " --checkpoint-every 0.000001 --quiet --fail-after-steps " + std::to_string(steps));
      INFO("killed after " << steps << " steps: " << killed.output);
      REQUIRE(killed.status == 9);
      REQUIRE_FALSE(fs::exists(out / "summary.json"));
      const auto resumed = run("batch " + job + " --out " + quoted(out) + " --resume --quiet");
      INFO(resumed.output);
      REQUIRE(resumed.status == 0);
      require_same_meshes(expected, out);
      // Something was continued from a checkpoint, not built again from its seed.
      bool continued = false;
      const nlohmann::json resumed_summary = summary(out);
      for (const auto& row : resumed_summary.at("surfaces"))
        continued = continued || row.value("resumed_at_step", -1) > 0 || row.contains("resumed");
      CHECK(continued);
    }
  }

  SECTION("by SIGKILL at random moments, also while checkpoints are written") {
    const fs::path out = dir / "out-signal";
    // Kill moments within an uninterrupted run's time, measured here: on a fast machine the whole
    // job is over so soon that fixed delays could outlast it and kill nothing.
    const auto begin = std::chrono::steady_clock::now();
    REQUIRE(run("batch " + job + " --out " + quoted(dir / "out-timed") +
                " --checkpoint-every 0.000001 --quiet")
                .status == 0);
    const auto whole_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                              std::chrono::steady_clock::now() - begin)
                              .count();
    std::mt19937 random(12345);
    // The timed run may be slower than the runs killed (a cold start): one that finishes before
    // any kill starts over with kill moments half as late.
    int latest_ms = std::max(2, static_cast<int>(whole_ms * 4 / 5));
    int kills = 0;
    for (int attempt = 0; attempt < 40; ++attempt) {
      std::vector<std::string> args{"batch",      (dir / "job.toml").string(), "--out",
                                    out.string(), "--checkpoint-every",        "0.000001",
                                    "--quiet"};
      if (kills > 0) args.push_back("--resume");
      const pid_t pid = cli_test::start(args, (dir / "log.txt").string());
      std::this_thread::sleep_for(
          std::chrono::milliseconds(std::uniform_int_distribution<int>(1, latest_ms)(random)));
      ::kill(pid, SIGKILL);
      int status = 0;
      ::waitpid(pid, &status, 0);
      if (WIFEXITED(status)) {
        INFO(read_text(dir / "log.txt"));
        REQUIRE(WEXITSTATUS(status) == 0);
        if (kills > 0) break;  // finished before the kill
        fs::remove_all(out);
        latest_ms = std::max(2, latest_ms / 2);
        continue;
      }
      ++kills;
      // Whatever the moment, every mesh present is whole: the one the uninterrupted run writes.
      for (const char* name : {"saddle.vtp", "gyre.vtp", "streamed.vtp"})
        if (fs::exists(out / name)) {
          INFO(name << " after kill " << kills);
          REQUIRE(read_text(out / name) == read_text(expected / name));
        }
    }
    CHECK(kills > 0);
    const auto resumed = run("batch " + job + " --out " + quoted(out) + " --resume --quiet");
    INFO(resumed.output);
    REQUIRE(resumed.status == 0);
    require_same_meshes(expected, out);
  }
}

TEST_CASE(
    "batch: SIGTERM checkpoints the unfinished surfaces, --resume never rebuilds the finished",
    "[batch]") {
  TempDir dir("batch-term");
  // Two stream surfaces in one pass: a quick one, and a slow one still running when the quick
  // one's file appears. Checkpoints only on the signal.
  write_text(dir / "job.toml",
             "[job]\nfield = \"abc\"\ncheckpoint_every = 0\n[defaults]\nkind = \"stream\"\n"
             "seed = \"line:0,0,0:0,1,1\"\n[[surface]]\nname = \"quick\"\nedge = 0.2\n"
             "steps = 10\n[[surface]]\nname = \"slow\"\nedge = 0.05\nsteps = 1200\n");
  const std::string job = quoted(dir / "job.toml");
  REQUIRE(run("batch " + job + " --out " + quoted(dir / "reference") + " --quiet").status == 0);
  const fs::path out = dir / "out";
  const pid_t pid =
      cli_test::start({"batch", (dir / "job.toml").string(), "--out", out.string(), "--quiet"},
                      (dir / "log.txt").string());
  for (int waited = 0; !fs::exists(out / "quick.vtp") && waited < 20000; waited += 5)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ::kill(pid, SIGTERM);
  int status = 0;
  ::waitpid(pid, &status, 0);
  INFO(read_text(dir / "log.txt"));
  REQUIRE(WIFEXITED(status));
  REQUIRE(WEXITSTATUS(status) == 2);
  CHECK(read_text(dir / "log.txt").find("continue with --resume") != std::string::npos);
  REQUIRE(fs::exists(out / ".checkpoint" / "slow.state"));
  CHECK_FALSE(fs::exists(out / "slow.vtp"));
  const auto quick_time = fs::last_write_time(out / "quick.vtp");

  const auto resumed = run("batch " + job + " --out " + quoted(out) + " --resume --quiet");
  INFO(resumed.output);
  REQUIRE(resumed.status == 0);
  CHECK(fs::last_write_time(out / "quick.vtp") == quick_time);  // not rewritten
  for (const char* name : {"quick.vtp", "slow.vtp"}) {
    INFO(name);
    CHECK(read_text(out / name) == read_text(dir / "reference" / name));
  }
  const nlohmann::json s = summary(out);
  CHECK(s["surfaces"][0]["resumed"] == "finished before");
  CHECK(s["surfaces"][1]["resumed_at_step"].get<int>() > 0);
}

TEST_CASE("batch: checkpoints of another job or version, or corrupt ones, are refused by name",
          "[batch]") {
  TempDir dir("batch-owner");
  write_text(dir / "a.toml",
             "[job]\nfield = \"saddle3d\"\n[[surface]]\nname = \"s\"\nkind = "
             "\"stream\"\nseed = \"line:-3,1,1:-3,1,3\"\nsteps = 400\n"
             "edge = 0.02\n");
  write_text(dir / "b.toml",
             "[job]\nfield = \"saddle3d\"\n[[surface]]\nname = \"s\"\nkind = "
             "\"stream\"\nseed = \"line:-3,1,1:-3,1,3\"\nsteps = 400\n"
             "edge = 0.03\n");
  const fs::path out = dir / "out";
  REQUIRE(run("batch " + quoted(dir / "a.toml") + " --out " + quoted(out) +
              " --checkpoint-every 0.000001 --quiet --fail-after-steps 10")
              .status == 9);
  REQUIRE(fs::exists(out / ".checkpoint" / "s.state"));

  const auto other = run("batch " + quoted(dir / "b.toml") + " --out " + quoted(out) + " --resume");
  CHECK(other.status == 2);
  CHECK(other.output.find("belongs to another job") != std::string::npos);

  const auto fresh = run("batch " + quoted(dir / "a.toml") + " --out " + quoted(out));
  CHECK(fresh.status == 2);
  CHECK(fresh.output.find("--resume") != std::string::npos);

  // One flipped bit in the state: refused naming the file, and nothing written.
  const fs::path state = out / ".checkpoint" / "s.state";
  const std::string bytes = read_text(state);
  std::string flipped = bytes;
  flipped[flipped.size() / 2] = static_cast<char>(flipped[flipped.size() / 2] ^ 0x10);
  write_text(state, flipped);
  const auto bit = run("batch " + quoted(dir / "a.toml") + " --out " + quoted(out) + " --resume");
  CHECK(bit.status == 2);
  CHECK(bit.output.find("s.state") != std::string::npos);
  CHECK(bit.output.find("checksum") != std::string::npos);
  CHECK_FALSE(fs::exists(out / "s.vtp"));
  // A state file cut short: refused naming it, and nothing written.
  write_text(state, bytes.substr(0, bytes.size() / 2));
  const auto corrupt =
      run("batch " + quoted(dir / "a.toml") + " --out " + quoted(out) + " --resume");
  CHECK(corrupt.status == 2);
  CHECK(corrupt.output.find("s.state") != std::string::npos);
  CHECK_FALSE(fs::exists(out / "s.vtp"));

  // --restart starts afresh over it.
  const auto restart =
      run("batch " + quoted(dir / "a.toml") + " --out " + quoted(out) + " --restart --quiet");
  INFO(restart.output);
  CHECK(restart.status == 0);
  CHECK(fs::exists(out / "s.vtp"));
}

TEST_CASE("batch: a job is not resumed over input data that changed since its checkpoint",
          "[batch]") {
  TempDir dir("batch-inputs");
  const fs::path series = make_series(dir);
  write_text(dir / "job.toml", "[job]\nfield = " + nlohmann::json(series.string()).dump() +
                                   "\ncache_budget = \"8MiB\"\n[[surface]]\nname = \"p\"\n"
                                   "seed = \"line:1.2,0.2,0:1.2,0.8,0\"\nedge = 0.02\n"
                                   "seed_count = 12\nt0 = 1.0\nt1 = 7.0\n");
  const fs::path out = dir / "out";
  const std::string job = "batch " + quoted(dir / "job.toml") + " --out " + quoted(out);
  REQUIRE(run(job + " --checkpoint-every 0.000001 --quiet --fail-after-steps 20").status == 9);
  REQUIRE(fs::exists(out / ".checkpoint" / "p.state"));
  const std::string inputs = read_text(out / ".checkpoint" / "inputs-0.json");
  CHECK(inputs.find("gyre.h5") != std::string::npos);

  // The series made anew from another flow (same grid and size, other values): refused.
  REQUIRE(run("generate --field double-gyre:A=0.2 --resolution 64,32 --steps 41 --t1 8 --brick 16 "
              "--out " +
              quoted(series) + " --quiet")
              .status == 0);
  const auto resumed = run(job + " --resume");
  INFO(resumed.output);
  CHECK(resumed.status == 2);
  CHECK(resumed.output.find("input '" + fs::absolute(series).lexically_normal().string() +
                            "'") != std::string::npos);
  CHECK(resumed.output.find("has changed since it was read") != std::string::npos);
  CHECK_FALSE(fs::exists(out / "p.vtp"));
}

TEST_CASE("batch: a surface that fails is reported and the others are built", "[batch]") {
  TempDir dir("batch-fail");
  write_text(dir / "job.toml",
             "[job]\nfield = \"double-gyre\"\n[defaults]\nedge = 0.05\nt0 = 0.0\nt1 = 2.0\n"
             "[[surface]]\nname = \"outside\"\nseed = \"line:5,5,0:6,6,0\"\n"
             "[[surface]]\nname = \"inside\"\nseed = \"line:0.3,0.2,0:0.3,0.8,0\"\n");
  const auto r = run("batch " + quoted(dir / "job.toml") + " --out " + quoted(dir / "out"));
  INFO(r.output);
  CHECK(r.status == 2);
  CHECK(r.output.find("1 of 2 surfaces failed") != std::string::npos);
  const auto s = summary(dir / "out");
  CHECK(s["surfaces"][0]["status"] == "failed");
  CHECK(s["surfaces"][0]["message"].get<std::string>().find("outside the domain") !=
        std::string::npos);
  CHECK(s["surfaces"][1]["status"] == "done");
  CHECK(fs::exists(dir / "out" / "inside.vtp"));
  CHECK_FALSE(fs::exists(dir / "out" / "outside.vtp"));
}

TEST_CASE("batch: a surface cut short by its vertex cap is written, marked, and fails the job",
          "[batch]") {
  TempDir dir("batch-capped");
  write_text(dir / "job.toml",
             "[job]\nfield = \"double-gyre\"\n[defaults]\nedge = 0.02\nt0 = 0.0\nt1 = 8.0\n"
             "[[surface]]\nname = \"capped\"\nseed = \"line:0.3,0.2,0:0.3,0.8,0\"\n"
             "max_vertices = 200\n");
  const auto r = run("batch " + quoted(dir / "job.toml") + " --out " + quoted(dir / "out"));
  INFO(r.output);
  CHECK(r.status == 2);
  CHECK(r.output.find("1 of 1 surfaces are incomplete") != std::string::npos);
  CHECK(fs::exists(dir / "out" / "capped.vtp"));
  const auto s = nlohmann::json::parse(read_text(dir / "out" / "summary.json"));
  CHECK(s["incomplete"] == 1);
  CHECK(s["surfaces"][0]["status"] == "incomplete");
}

TEST_CASE("batch: job file errors name the file, the line and the key", "[batch]") {
  TempDir dir("batch-errors");
  const auto refused = [&](const std::string& file, const std::string& text) {
    write_text(dir / file, text);
    const auto r = run("batch " + quoted(dir / file) + " --out " + quoted(dir / "out"));
    CHECK(r.status == 2);
    CHECK_FALSE(fs::exists(dir / "out" / "summary.json"));
    return r.output;
  };
  std::string m = refused("typo.toml",
                          "[job]\nfield = \"saddle3d\"\n\n[[surface]]\nname = \"a\"\n"
                          "seed = \"line:0,0,0:1,0,0\"\nedgee = 0.1\n");
  CHECK(m.find("typo.toml:7: surface[0].edgee: unknown key") != std::string::npos);
  m = refused("type.toml", "[defaults]\nedge = \"fine\"\n");
  CHECK(m.find("type.toml:2: defaults.edge: must be a number") != std::string::npos);
  m = refused("negative.toml",
              "[job]\nfield = \"saddle3d\"\n[[rake]]\nname = \"r\"\n"
              "seed = \"line:0,0,0:1,0,0\"\ncount = -2\noffset = [0, 1]\n");
  CHECK(m.find("negative.toml:6: rake[0].count: must lie in [1, 100000]") != std::string::npos);
  m = refused("syntax.toml", "[job]\nfield = \"saddle3d\n");
  CHECK(m.find("syntax.toml:2: not valid TOML") != std::string::npos);
  m = refused("noseed.json",
              "{\"job\": {\"field\": \"saddle3d\"},\n \"surface\": [{\"name\": \"a\"}]}");
  CHECK(m.find("noseed.json:2: surface[0]: needs a seed") != std::string::npos);
  m = refused("range.json",
              "{\"job\": {\"field\": \"saddle3d\"},\n \"surface\": [\n  {\"name\": \"a\", "
              "\"seed\": \"line:0,0,0:1,0,0\"},\n  {\"name\": \"b\",\n   \"edge\": -1}]}");
  CHECK(m.find("range.json:5: surface[1].edge: -1 is not a positive number") != std::string::npos);
  m = refused("budget.toml",
              "[job]\nfield = \"saddle3d\"\n[[surface]]\nname = \"a\"\n"
              "seed = \"line:0,0,0:1,0,0\"\nshot_evaluations = -5\n");
  CHECK(m.find("budget.toml:6: surface[0].shot_evaluations: -5 is below 0") != std::string::npos);
  // Each kind takes its own options: a streak surface's keys are not a stream surface's.
  m = refused("kinds.toml",
              "[job]\nfield = \"saddle3d\"\n[[surface]]\nname = \"a\"\nkind = \"stream\"\n"
              "seed = \"line:0,0,0:1,0,0\"\nflat_split = 0.1\n");
  CHECK(m.find("kinds.toml:7: surface[0].flat_split: flat_split is a streak surface's key, not a "
               "stream surface's") != std::string::npos);
  // What the whole job shares is not a surface's.
  m = refused("memory.toml",
              "[job]\nfield = \"saddle3d\"\n[[surface]]\nname = \"a\"\n"
              "seed = \"line:0,0,0:1,0,0\"\ncache_budget = \"1GiB\"\n");
  CHECK(m.find("memory.toml:6: surface[0].cache_budget: the cache budget is the job's") !=
        std::string::npos);
  m = refused("flag.toml",
              "[job]\nfield = \"saddle3d\"\n[[surface]]\nname = \"a\"\nkind = \"stream\"\n"
              "seed = \"line:0,0,0:1,0,0\"\nno_rip = 1\n");
  CHECK(m.find("flag.toml:7: surface[0].no_rip: must be true or false, got 1") != std::string::npos);
  // Checks after the keys are read name the surface once.
  m = refused("order.toml",
              "[job]\nfield = \"double-gyre\"\n[[surface]]\nname = \"a\"\n"
              "seed = \"line:0.3,0.2,0:0.3,0.8,0\"\nt0 = 2\nt1 = 1\n");
  CHECK(m.find("order.toml:3: surface[0]: needs t0 < t1, got t0 = 2, t1 = 1") != std::string::npos);
  CHECK(m.find("surface[0]: order.toml") == std::string::npos);
  m = refused("norelease.toml",
              "[job]\nfield = \"double-gyre\"\n[[surface]]\nname = \"a\"\nkind = \"streak\"\n"
              "seed = \"line:0.3,0.2,0:0.3,0.8,0\"\n");
  CHECK(m.find("norelease.toml:3: surface[0]: a streak surface needs release") != std::string::npos);
  CHECK(m.find("surface[0]: norelease.toml") == std::string::npos);
  m = refused("both.toml",
              "[job]\nfield = \"double-gyre\"\n[[surface]]\nname = \"a\"\nkind = \"streak\"\n"
              "seed = \"line:0.3,0.3,0:0.3,0.45,0\"\nrelease = \"0:1\"\nframes = \"1\"\n"
              "insert = \"exact\"\ninsertion = \"interpolate\"\n");
  CHECK(m.find("both.toml:10: surface[0].insertion: insertion and insert are one key") !=
        std::string::npos);
  m = refused("time.toml",
              "[job]\nfield = \"double-gyre\"\n[[surface]]\nname = \"a\"\n"
              "seed = \"line:0.3,0.2,0:0.3,0.8,0\"\nt1 = \"30 days\"\n");
  CHECK(m.find("time.toml:3: surface[0]: t1 must be a number in the field's time unit, got '30 days'") !=
        std::string::npos);
  m = refused("bad.json", "{\"job\": {\"field\": \"saddle3d\"},\n \"surface\": [{\"name\": }]}");
  CHECK(m.find("bad.json:2: not valid JSON") != std::string::npos);
  m = refused("twice.toml",
              "[job]\nfield = \"saddle3d\"\n[[surface]]\nname = \"a\"\nseed = "
              "\"line:0,0,0:1,0,0\"\n[[surface]]\nname = \"a\"\nseed = "
              "\"line:0,0,0:1,0,0\"\n");
  CHECK(m.find("two surfaces are named 'a'") != std::string::npos);
  // Its report would be the job summary's file.
  m = refused("summary.toml",
              "[job]\nfield = \"saddle3d\"\n[[surface]]\nname = \"summary\"\nseed = "
              "\"line:0,0,0:1,0,0\"\n");
  CHECK(m.find("summary.toml:") != std::string::npos);
  CHECK(m.find("the name 'summary' is reserved") != std::string::npos);
  // insert is a streak surface's key (as `streak --insert`); stream surfaces take insertion.
  m = refused("insert.toml",
              "[job]\nfield = \"saddle3d\"\n[[surface]]\nname = \"a\"\nseed = "
              "\"line:0,0,0:1,0,0\"\ninsert = \"cubic\"\n");
  CHECK(m.find("insert.toml:6: surface[0].insert: insert is a streak surface's key, not a path "
               "surface's") != std::string::npos);
  m = refused("missing.toml.nothere", "");
  CHECK(m.find("expected .toml or .json") != std::string::npos);
}

TEST_CASE("batch: a surface's seed-shot budget is the one `stream --shot-evaluations` takes",
          "[batch]") {
  // Sinus across its waves makes insertions from the seed; a budget of one evaluation sends
  // them to the previous row, which moves the vertices inserted.
  TempDir dir("batch-shots");
  const std::string args =
      "stream --field sinus --seed line:-1,0,0:1,0,0 --seed-count 21 --edge 0.1 --steps 200 "
      "--quiet";
  REQUIRE(run(args + " --shot-evaluations 1 --out " + quoted(dir / "one.vtp")).status == 0);
  REQUIRE(run(args + " --out " + quoted(dir / "default.vtp")).status == 0);
  write_text(dir / "job.toml",
             "[job]\nfield = \"sinus\"\n[[surface]]\nname = \"s\"\nkind = \"stream\"\n"
             "seed = \"line:-1,0,0:1,0,0\"\nseed_count = 21\nedge = 0.1\nsteps = 200\n"
             "shot_evaluations = 1\n");
  const auto r = run("batch " + quoted(dir / "job.toml") + " --out " + quoted(dir / "out"));
  INFO(r.output);
  REQUIRE(r.status == 0);
  CHECK(read_text(dir / "out" / "s.vtp") == read_text(dir / "one.vtp"));
  CHECK(read_text(dir / "one.vtp") != read_text(dir / "default.vtp"));
  const auto report = nlohmann::json::parse(read_text(dir / "out" / "s.json"));
  CHECK(report["parameters"]["shot_evaluations"] == 1);
  CHECK(report["counts"]["seed_shots_over_budget"].get<int>() > 0);
  CHECK(report["counts"]["seed_shot_time_limit"].is_number());
}

TEST_CASE("batch: a streak surface of a job writes the frames of `streak`, byte for byte",
          "[batch]") {
  TempDir dir("batch-streak");
  // As `streak` defaults (a remeshed mesh), and as `streak --mesh rows --releases-per-break 3`.
  for (const int k : {1, 3}) {
    INFO(k << " releases per break");
    const std::string tag = std::to_string(k);
    write_text(dir / ("job" + tag + ".toml"),
               "[job]\nfield = \"double-gyre\"\n[[surface]]\nname = \"dye\"\nkind = \"streak\"\n"
               "seed = \"line:0.3,0.3,0:0.3,0.45,0\"\nrelease = \"0:2\"\nframes = \"0.5:3:4\"\n"
               "edge = 0.03\n" + (k == 1 ? std::string() : "mesh = \"rows\"\nreleases_per_break = " + tag + "\n"));
    const fs::path out = dir / ("out" + tag), alone = dir / ("alone" + tag);
    const auto r = run("batch " + quoted(dir / ("job" + tag + ".toml")) + " --out " + quoted(out) + " --quiet");
    INFO(r.output);
    REQUIRE(r.status == 0);
    fs::create_directories(alone);
    const auto a = run("streak --field double-gyre --seed line:0.3,0.3,0:0.3,0.45,0 --release "
                       "0:2 --frames 0.5:3:4 --edge 0.03 --quiet" +
                       (k == 1 ? std::string() : " --mesh rows --releases-per-break " + tag) + " --out " +
                       quoted(alone / "dye.pvd"));
    INFO(a.output);
    REQUIRE(a.status == 0);
    CHECK(read_text(out / "dye.pvd") == read_text(alone / "dye.pvd"));
    std::size_t frames = 0;
    for (const auto& entry : fs::directory_iterator(alone / "dye")) {
      INFO(entry.path());
      CHECK(read_text(out / "dye" / entry.path().filename()) == read_text(entry.path()));
      ++frames;
    }
    CHECK(frames == 4);
    const nlohmann::json s = summary(out);
    CHECK(s["surfaces"][0]["status"] == "done");
    CHECK(s["surfaces"][0]["frames"] == 4);
  }
  CHECK(read_text(dir / "out1" / "dye" / "dye_0003.vtp") != read_text(dir / "out3" / "dye" / "dye_0003.vtp"));
  // insert (the option's name) and insertion (the older key) are the same surface.
  for (const char* key : {"insert", "insertion"}) {
    write_text(dir / (std::string(key) + ".toml"),
               std::string("[job]\nfield = \"double-gyre\"\n[[surface]]\nname = \"dye\"\n"
                           "kind = \"streak\"\nseed = \"line:0.3,0.3,0:0.3,0.45,0\"\n"
                           "release = \"0:1\"\nframes = \"0.5:1:2\"\nedge = 0.05\n") +
                   key + " = \"interpolate\"\n");
    const auto r = run("batch " + quoted(dir / (std::string(key) + ".toml")) + " --out " +
                       quoted(dir / (std::string("by-") + key)));
    INFO(r.output);
    REQUIRE(r.status == 0);
  }
  CHECK(read_text(dir / "by-insert" / "dye" / "dye_0001.vtp") ==
        read_text(dir / "by-insertion" / "dye" / "dye_0001.vtp"));
  write_text(dir / "zero.toml",
             "[job]\nfield = \"double-gyre\"\n[[surface]]\nname = \"dye\"\nkind = \"streak\"\n"
             "seed = \"line:0.3,0.3,0:0.3,0.45,0\"\nrelease = \"0:2\"\nframes = \"0.5:3:4\"\n"
             "releases_per_break = 0\n");
  const auto zero = run("batch " + quoted(dir / "zero.toml") + " --out " + quoted(dir / "zero"));
  CHECK(zero.status == 2);
  CHECK(zero.output.find("zero.toml:9: surface[0].releases_per_break: 0 is below 1") !=
        std::string::npos);
}

TEST_CASE("batch --device: the surfaces of a pass share one bulk backend and give the meshes of "
          "`path --device`, byte for byte",
          "[batch][advect]") {
  TempDir dir("batch-device");
  const fs::path series = make_series(dir);
  write_text(dir / "rake.toml", "[job]\nfield = \"" + series.string() +
                                    "\"\ncache_budget = \"64MiB\"\n[defaults]\nedge = 0.04\n"
                                    "seed_count = 12\nt0 = 0.0\nt1 = 6.0\n[[rake]]\nname = \"r\"\n"
                                    "seed = \"line:0.2,0.2,0:0.2,0.8,0\"\ncount = 3\n"
                                    "offset = [0.6, 0.0]\n");
  const auto r = run("batch " + quoted(dir / "rake.toml") + " --out " + quoted(dir / "out") +
                     " --device cpu --threads 2 --quiet");
  INFO(r.output);
  REQUIRE(r.status == 0);
  for (int k = 0; k < 3; ++k) {
    INFO(k);
    const double x = 0.2 + 0.6 * k;
    const std::string seed = "line:" + std::to_string(x) + ",0.2,0:" + std::to_string(x) + ",0.8,0";
    const fs::path alone = dir / ("alone-" + std::to_string(k) + ".vtp");
    REQUIRE(run("path --field " + quoted(series) + " --seed " + seed +
                " --seed-count 12 --edge 0.04 --t0 0 --t1 6 --device cpu --quiet --out " +
                quoted(alone))
                .status == 0);
    CHECK(read_text(alone) == read_text(dir / "out" / ("r-" + std::to_string(k) + ".vtp")));
    const auto report =
        nlohmann::json::parse(read_text(dir / "out" / ("r-" + std::to_string(k) + ".json")));
    CHECK(report["path"]["device"]["backend"] == "cpu");
    CHECK(report["path"]["device"]["calls"].get<std::size_t>() > 0);
  }
  // The pass's fronts went through one merging backend: every front call is counted, and no
  // more backend calls than front calls ran.
  const nlohmann::json pass = summary(dir / "out")["passes"][0];
  REQUIRE(pass.contains("device"));
  CHECK(pass["device"]["merged"] == true);
  CHECK(pass["device"]["front_calls"].get<std::size_t>() > 0);
  CHECK(pass["device"]["backend_calls"].get<std::size_t>() <=
        pass["device"]["front_calls"].get<std::size_t>());
  CHECK(pass["device"]["largest_merge"].get<std::size_t>() >= 1);
  // The fronts taking turns write the same meshes.
  REQUIRE(run("batch " + quoted(dir / "rake.toml") + " --out " + quoted(dir / "turns") +
              " --device cpu --no-merge-fronts --threads 2 --quiet")
              .status == 0);
  for (int k = 0; k < 3; ++k) {
    const std::string member = "r-" + std::to_string(k) + ".vtp";
    CHECK(read_text(dir / "turns" / member) == read_text(dir / "out" / member));
  }
  CHECK(summary(dir / "turns")["passes"][0]["device"]["largest_merge"] == 1);
  // Per vertex (no --device) the meshes differ: the front really went through the backend.
  REQUIRE(run("batch " + quoted(dir / "rake.toml") + " --out " + quoted(dir / "plain") + " --quiet")
              .status == 0);
  CHECK(read_text(dir / "plain" / "r-0.vtp") != read_text(dir / "out" / "r-0.vtp"));
  // A device that cannot be had is named before anything runs.
  const auto cuda = run("batch " + quoted(dir / "rake.toml") + " --out " + quoted(dir / "cuda") +
                        " --device cuda --quiet");
  if (cuda.status != 0) CHECK(cuda.output.find("--device cuda:") != std::string::npos);
  // A negative number of calls at once is refused by name, before any file is written.
  const auto calls = run("batch " + quoted(dir / "rake.toml") + " --out " +
                         quoted(dir / "calls") + " --device cpu --device-calls -1 --quiet");
  CHECK(calls.status != 0);
  CHECK(calls.output.find("--device-calls") != std::string::npos);
  CHECK(!fs::exists(dir / "calls"));
  // The pass says how many backend calls could run at once (the CPU backend: one).
  CHECK(pass["device"]["concurrent_calls"] == 1);
}

TEST_CASE("batch: on real data a surface without edge takes the grid cell size as `stream` does",
          "[batch][realdata]") {
  const fs::path data = ORTHOFRONT_DATASETS_DIR;
  const fs::path tornado = data / "tornado" / "1.vec";
  if (!fs::exists(tornado)) {
    WARN("skipped: " << tornado.string() << " not found");
    return;
  }
  TempDir dir("batch-tornado");
  write_text(dir / "job.toml", "[job]\nfield = " + nlohmann::json(tornado.string()).dump() +
                                   "\n[[surface]]\nname = \"t\"\nkind = \"stream\"\n"
                                   "seed = \"line:30,24,10:30,24,30\"\nsteps = 60\n");
  const auto r = run("batch " + quoted(dir / "job.toml") + " --out " + quoted(dir / "out") +
                     " --quiet");
  INFO(r.output);
  REQUIRE(r.status == 0);
  REQUIRE(run("stream --field " + quoted(tornado) +
              " --seed line:30,24,10:30,24,30 --steps 60 --quiet --out " + quoted(dir / "t.vtp"))
              .status == 0);
  CHECK(read_text(dir / "out" / "t.vtp") == read_text(dir / "t.vtp"));
  const auto report = nlohmann::json::parse(read_text(dir / "out" / "t.json"));
  CHECK(report["edge_source"] == "grid cell");
  CHECK(report["edge"] == 1.0);
}
