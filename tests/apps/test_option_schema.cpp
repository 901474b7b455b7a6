// The option schema (apps/jobs/option_set.h): each kind's options are written once, and the
// command line takes exactly them, with their defaults and checks.
#include <catch2/catch.hpp>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>
#include <string>

#include "cli/batch_job.h"
#include "cli/option_flags.h"
#include "jobs/option_set.h"
#include "jobs/option_spelling.h"
#include "jobs/path_job.h"
#include "jobs/streak_job.h"
#include "jobs/stream_job.h"
#include "orthofront/error.h"

using namespace orthofront;

namespace {

// A kind's options as a set and as the command line registers them.
struct Registered {
  std::shared_ptr<jobs::OptionSet> set = std::make_shared<jobs::OptionSet>();
  CLI::App app{"test"};
};

void check_command_line_matches(Registered& r) {
  std::set<std::string> names;
  for (const jobs::OptionSpec& spec : r.set->specs()) {
    INFO(spec.name);
    names.insert(spec.name);
    CHECK_FALSE(spec.doc.empty());
    const CLI::Option* option = r.app.get_option("--" + spec.name);
    REQUIRE(option != nullptr);
    CHECK(option->get_description() == spec.doc);
    if (spec.type == jobs::OptionType::flag) {
      CHECK(option->get_expected_max() == 0);
    } else if (spec.show_default) {
      CHECK(option->get_default_str() == spec.current());
    }
    // Every option is shown, under its group's title.
    CHECK(option->get_group() == jobs::group_title(spec.group));
    CHECK(option->get_required() == spec.required);
  }
  // Nothing else: every flag but --help comes from the schema.
  for (const CLI::Option* option : r.app.get_options())
    for (const std::string& name : option->get_lnames())
      if (name != "help") CHECK(names.count(name) == 1);
}

}  // namespace

TEST_CASE("option schema: stream, path and streak flags are their schemas", "[apps][options]") {
  SECTION("stream") {
    Registered r;
    jobs::SurfaceJob job;
    jobs::MemoryLimits limits;
    jobs::add_stream_options(*r.set, job, limits);
    cli::add_option_flags(r.app, r.set);
    check_command_line_matches(r);
    CHECK(r.set->find("edge")->current() == "0.1");
  }
  SECTION("path") {
    Registered r;
    jobs::PathArgs args;
    jobs::add_path_options(*r.set, args);
    cli::add_option_flags(r.app, r.set);
    check_command_line_matches(r);
    CHECK(r.set->find("steps")->current() == "1000000");
  }
  SECTION("streak") {
    Registered r;
    jobs::StreakArgs args;
    jobs::add_streak_options(*r.set, args);
    cli::add_option_flags(r.app, r.set);
    check_command_line_matches(r);
    CHECK(r.set->find("flat-split")->current() == "0.01");
    CHECK(r.set->find("release")->required);
  }
}

TEST_CASE("option schema: values parse into the members, are checked, and are recorded as given",
          "[apps][options]") {
  jobs::StreakArgs args;
  auto set = std::make_shared<jobs::OptionSet>();
  jobs::add_streak_options(*set, args);
  CLI::App app("streak");
  cli::add_option_flags(app, set);
  app.parse("--release 0:1 --flat-split 0.25 --seed-count 7 --insert interpolate "
            "--vertex-budget 1000",
            false);
  CHECK(args.release == "0:1");
  CHECK(args.flat_split == 0.25);
  CHECK(args.seed_count == 7);
  CHECK(args.insertion == "interpolate");
  CHECK(args.vertex_budget == 1000);
  CHECK(set->given("flat-split"));
  CHECK_FALSE(set->given("prune"));
  CHECK(args.prune == 0.75);  // untouched

  // Refusals name the flag and the value.
  const auto refused = [](const std::string& line) {
    jobs::StreakArgs a;
    auto s = std::make_shared<jobs::OptionSet>();
    jobs::add_streak_options(*s, a);
    CLI::App command("streak");
    cli::add_option_flags(command, s);
    try {
      command.parse("--release 0:1 " + line, false);
    } catch (const CLI::ValidationError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK(refused("--flat-split -1") == "--flat-split: -1 is below 0");
  CHECK(refused("--flat-split abc") == "--flat-split: 'abc' is not a number");
  CHECK(refused("--insert sideways") == "--insert: 'sideways' is not one of exact, interpolate");
  CHECK(refused("--seed-count 2.5") == "--seed-count: '2.5' is not an integer");
  CHECK(refused("--vertex-budget -3") == "--vertex-budget: '-3' is not a whole number >= 0");
  CHECK(refused("--flat-split nan") == "--flat-split: 'nan' is not a number");

  // A required option left out.
  jobs::StreakArgs a;
  jobs::OptionSet s;
  jobs::add_streak_options(s, a);
  CHECK(s.missing() == std::vector<std::string>{"release"});
  CHECK_THROWS_AS(s.set("no-such-option", "1"), InvalidArgument);
}

TEST_CASE("option schema: choices ignore case, switches set their member either way",
          "[apps][options]") {
  jobs::SurfaceJob job;
  jobs::MemoryLimits limits;
  jobs::OptionSet set;
  jobs::add_stream_options(set, job, limits);
  set.set("method", "TimeLine");
  CHECK(job.options.method == Method::timeline);
  CHECK(set.find("method")->current() == "timeline");
  CHECK(job.options.rip);
  set.set("no-rip", "true");
  CHECK_FALSE(job.options.rip);
  set.set("no-rip", "false");
  CHECK(job.options.rip);
  CHECK_THROWS_WITH(set.set("join-fraction", "1.5"), "1.5 is not in the range 0 to 1");
  CHECK_THROWS_WITH(set.set("time-budget", "0"), "0 is not a positive number");
  // Defaults are shown as the shortest text that reads back as the same number.
  CHECK(set.find("tolerance")->current() == "1e-09");
}

namespace {

std::string job_key(std::string option) {
  std::replace(option.begin(), option.end(), '-', '_');
  return option;
}

void write_job(const std::filesystem::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary);
  out << text;
}

}  // namespace

TEST_CASE("option schema: a job file's surface keys are each kind's options, with its defaults",
          "[apps][options]") {
  const std::set<std::string> own{"name", "kind", "field", "seed", "format"};
  for (const cli::SurfaceKind kind :
       {cli::SurfaceKind::stream, cli::SurfaceKind::path, cli::SurfaceKind::streak}) {
    INFO(cli::to_string(kind));
    jobs::SurfaceJob job;
    jobs::MemoryLimits limits;
    jobs::PathArgs path;
    jobs::StreakArgs streak;
    jobs::OptionSet set;
    if (kind == cli::SurfaceKind::stream) jobs::add_stream_options(set, job, limits);
    if (kind == cli::SurfaceKind::path) jobs::add_path_options(set, path);
    if (kind == cli::SurfaceKind::streak) jobs::add_streak_options(set, streak);
    const std::set<std::string> keys = cli::batch_surface_keys(kind);
    // Every option shown to users is a key, or the job's own with the reason why.
    std::size_t options = 0;
    for (const jobs::OptionSpec& spec : set.specs()) {
      INFO(spec.name);
      const char* job_level = cli::batch_job_level(kind, spec.name);
      CHECK(keys.count(job_key(spec.name)) == (job_level ? 0u : 1u));
      options += job_level ? 0 : 1;
    }
    // Nothing else but the job's own keys (a streak surface's format is its .pvd).
    std::size_t others = 0;
    for (const std::string& key : keys) {
      INFO(key);
      if (own.count(key)) {
        ++others;
        continue;
      }
      std::string option = key;
      std::replace(option.begin(), option.end(), '_', '-');
      CHECK(set.find(option) != nullptr);
    }
    CHECK(others == (kind == cli::SurfaceKind::streak ? 4u : 5u));
    CHECK(keys.size() == options + others);
  }
  CHECK(cli::batch_surface_keys(cli::SurfaceKind::streak).count("insert") == 1);
  CHECK(cli::batch_surface_keys(cli::SurfaceKind::stream).count("insertion") == 1);
  CHECK(cli::batch_surface_keys(cli::SurfaceKind::streak).count("flat_split") == 1);
  CHECK(cli::batch_surface_keys(cli::SurfaceKind::path).count("band_ramp") == 1);
}

TEST_CASE("option schema: a job file's surface without keys takes the command's defaults, and a "
          "key the flag's value",
          "[apps][options]") {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "orthofront-job-keys";
  std::filesystem::create_directories(dir);
  write_job(dir / "job.toml",
            "[job]\nfield = \"double-gyre\"\n"
            "[[surface]]\nname = \"a\"\nkind = \"stream\"\nseed = \"line:0,0,0:1,0,0\"\n"
            "[[surface]]\nname = \"b\"\nkind = \"path\"\nseed = \"line:0,0,0:1,0,0\"\n"
            "[[surface]]\nname = \"c\"\nkind = \"streak\"\nseed = \"line:0,0,0:1,0,0\"\n"
            "release = \"0:1\"\nframes = \"1\"\n"
            "[[surface]]\nname = \"d\"\nkind = \"stream\"\nseed = \"line:0,0,0:1,0,0\"\n"
            "gap_distance = 3\nno_rip = true\nmethod = \"timeline\"\n"
            "[[surface]]\nname = \"e\"\nkind = \"path\"\nseed = \"line:0,0,0:1,0,0\"\n"
            "band_ramp = 0.25\nt0 = 0.5\nt1 = 2\n"
            "[[surface]]\nname = \"f\"\nkind = \"streak\"\nseed = \"line:0,0,0:1,0,0\"\n"
            "release = \"0:1\"\nframes = \"1\"\nflat_split = 0.25\ncollapse = 0.5\n");
  const cli::BatchJob job = cli::read_batch_job(dir / "job.toml");
  REQUIRE(job.surfaces.size() == 6);

  // Untouched: every option as the command's set shows its default.
  const auto same_defaults = [](const jobs::OptionSet& fresh, const jobs::OptionSet& replayed) {
    for (const jobs::OptionSpec& spec : fresh.specs()) {
      INFO(spec.name);
      // The vertex cap's default follows the memory available at the moment it is read, which
      // other processes change between the two reads.
      if (spec.name == "max-vertices") continue;
      CHECK(replayed.find(spec.name)->current() == spec.current());
    }
  };
  {
    const jobs::SurfaceJob a = cli::stream_arguments(job.surfaces[0]);
    jobs::SurfaceJob fresh_job, copy = a;
    jobs::MemoryLimits l1, l2;
    jobs::OptionSet fresh, replayed;
    jobs::add_stream_options(fresh, fresh_job, l1);
    jobs::add_stream_options(replayed, copy, l2);
    same_defaults(fresh, replayed);
  }
  {
    const jobs::PathArgs b = cli::path_arguments(job.surfaces[1]);
    jobs::PathArgs fresh_args, copy = b;
    jobs::OptionSet fresh, replayed;
    jobs::add_path_options(fresh, fresh_args);
    jobs::add_path_options(replayed, copy);
    same_defaults(fresh, replayed);
  }
  {
    jobs::StreakArgs args;
    args.release = "0:1";
    args.frames = "1";
    jobs::OptionSet set;
    jobs::add_streak_options(set, args);
    set.mark_given("release");
    const spacetime::StreakOptions expected = jobs::streak_options(set, args);
    const spacetime::StreakOptions c = cli::streak_arguments(job.surfaces[2]);
    CHECK(c.mesh == expected.mesh);
    CHECK(c.edge == expected.edge);
    CHECK(c.flat_split == expected.flat_split);
    CHECK(c.prune == expected.prune);
    CHECK(c.collapse == expected.collapse);
    CHECK(c.seed_count == expected.seed_count);
    CHECK(c.insertion == expected.insertion);
  }
  // Given: the member the flag sets.
  const jobs::SurfaceJob d = cli::stream_arguments(job.surfaces[3]);
  CHECK(d.options.gap_distance == 3);
  CHECK_FALSE(d.options.rip);
  CHECK(d.options.method == Method::timeline);
  const jobs::PathArgs e = cli::path_arguments(job.surfaces[4]);
  CHECK(e.band_ramp == 0.25);
  CHECK(e.t0 == 0.5);
  CHECK(e.t1 == 2);
  const spacetime::StreakOptions f = cli::streak_arguments(job.surfaces[5]);
  CHECK(f.flat_split == 0.25);
  CHECK(f.collapse == 0.5);
  std::filesystem::remove_all(dir);
}

TEST_CASE("option schema: messages name options as Python and ParaView spell them",
          "[apps][options]") {
  using orthofront::jobs::OptionSpelling;
  using orthofront::jobs::spell_options;
  const std::string message =
      "the band needs 3 steps (4 MiB); raise --cache-budget or --max-vertices, not --frobnicate; "
      "--field 'x.h5': bad --seed-count. A range 1--2 and a-b--flat-split stay.";
  CHECK(spell_options(message, OptionSpelling::command_line) == message);
  CHECK(spell_options(message, OptionSpelling::python) ==
        "the band needs 3 steps (4 MiB); raise cache_budget or max_vertices, not --frobnicate; "
        "field 'x.h5': bad seed_count. A range 1--2 and a-b--flat-split stay.");
  CHECK(spell_options(message, OptionSpelling::paraview) ==
        "the band needs 3 steps (4 MiB); raise Cache Budget or Max Vertices, not --frobnicate; "
        "the input 'x.h5': bad Seed Count. A range 1--2 and a-b--flat-split stay.");
}
