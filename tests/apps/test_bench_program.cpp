// The benchmarks live in their own program: `orthofront --help` shows only what users choose.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <string>

#include "apps/cli_run.h"
#include "temp_dir.h"

TEST_CASE("orthofront lists the user's commands and no benchmark", "[apps][bench]") {
  const auto r = cli_test::run("--help");
  INFO(r.output);
  REQUIRE(r.status == 0);
  for (const char* command : {"stream", "path", "streak", "batch", "fields", "generate",
                              "convert", "info", "demo"})
    CHECK(r.output.find(std::string("  ") + command) != std::string::npos);
  CHECK(r.output.find("bench-") == std::string::npos);
  CHECK(r.output.find("Benchmark") == std::string::npos);
  CHECK(r.output.find("orthofront-bench") != std::string::npos);  // where they went
}

TEST_CASE("orthofront-bench lists every benchmark and each has its help", "[apps][bench]") {
  const auto r = cli_test::run_bench("--help");
  INFO(r.output);
  REQUIRE(r.status == 0);
  for (const char* bench : {"stream", "path", "streak", "gpu-streak", "batch", "grid", "gpu",
                            "front"}) {
    CHECK(r.output.find(std::string("  ") + bench) != std::string::npos);
    const auto help = cli_test::run_bench(std::string(bench) + " --help");
    INFO(bench << ": " << help.output);
    CHECK(help.status == 0);
    CHECK(help.output.find("--") != std::string::npos);
  }
}

TEST_CASE("a benchmark asked of orthofront says where the benchmarks are", "[apps][bench]") {
  const auto r = cli_test::run("bench-streak");
  INFO(r.output);
  CHECK(r.status == 2);
  CHECK(r.output.find("orthofront-bench --help") != std::string::npos);
}

TEST_CASE("orthofront-bench batch runs the orthofront beside it and every way builds the same meshes",
          "[apps][bench]") {
  test_support::TempDir dir;
  const std::string json = (dir.path() / "bench.json").string();
  const auto r = cli_test::run_bench(
      "batch --surfaces 2 --resolution 16,8,4 --steps 11 --t1 2 --edge 0.2 --cache-budget 1MiB "
      "--work " + (dir.path() / "work").string() + " --json " + json);
  INFO(r.output);
  REQUIRE(r.status == 0);
  const auto j = nlohmann::json::parse(test_support::read_text(json));
  REQUIRE(j["rows"].size() >= 3);
  for (const auto& row : j["rows"]) {
    INFO(row.dump());
    CHECK(row["identical_meshes"] == 2);
  }
}
