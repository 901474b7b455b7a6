// The option schema (apps/jobs/option_set.h): each kind's options are written once, and the
// command line takes exactly them, with their defaults and checks.
#include <catch2/catch.hpp>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <memory>
#include <set>
#include <string>

#include "cli/batch_job.h"
#include "cli/option_flags.h"
#include "jobs/option_set.h"
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
    // Baselines are accepted but not shown.
    CHECK(option->get_group().empty() == (spec.group == jobs::OptionGroup::baseline));
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

TEST_CASE("option schema: a job file's surface keys are the kinds' option names", "[apps][options]") {
  // The union of the three kinds' options, as job files spell them ('_' for '-').
  std::set<std::string> options;
  jobs::SurfaceJob job;
  jobs::MemoryLimits limits;
  jobs::PathArgs path;
  jobs::StreakArgs streak;
  jobs::OptionSet stream_set, path_set, streak_set;
  jobs::add_stream_options(stream_set, job, limits);
  jobs::add_path_options(path_set, path);
  jobs::add_streak_options(streak_set, streak);
  for (const jobs::OptionSet* set : {&stream_set, &path_set, &streak_set})
    for (const jobs::OptionSpec& spec : set->specs()) {
      std::string key = spec.name;
      std::replace(key.begin(), key.end(), '-', '_');
      options.insert(key);
    }
  const std::set<std::string> own{"name", "kind", "field", "seed", "format"};
  for (const std::string& key : cli::batch_surface_keys()) {
    INFO(key);
    CHECK((own.count(key) == 1 || options.count(key) == 1));
  }
  // Each kind's spelling: streak surfaces take insert, the others insertion.
  CHECK(streak_set.find("insert") != nullptr);
  CHECK(stream_set.find("insertion") != nullptr);
  CHECK(cli::batch_surface_keys().count("insert") == 1);
}
