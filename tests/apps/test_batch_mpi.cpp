// `mpirun -np 2 orthofront batch`: the ranks share the surfaces (rank 0 hands them out) and write
// the files of the serial run; killed and resumed under MPI, the same files again. Registered only
// in builds with MPI.
#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

#include "cli_run.h"
#include "temp_dir.h"

namespace fs = std::filesystem;
using cli_test::quoted;
using test_support::read_text;
using test_support::TempDir;

namespace {

// mpirun with two ranks on this machine, whatever its core count, as root too (CI).
cli_test::Run mpirun(const std::string& args) {
  return cli_test::run_shell(
      "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 '" ORTHOFRONT_MPIEXEC
      "' -np 2 --oversubscribe '" ORTHOFRONT_BINARY "' " +
      args);
}

const char* kJob = R"([job]
field = "double-gyre"
[defaults]
edge = 0.04
seed_count = 12
t0 = 0.0
t1 = 4.0
[[rake]]
name = "r"
seed = "line:0.15,0.2,0:0.15,0.8,0"
count = 6
offset = [0.3, 0.0]
[[surface]]
name = "saddle"
kind = "stream"
field = "saddle3d"
seed = "line:-3,1,1:-3,1,3"
edge = 0.1
steps = 60
)";

}  // namespace

TEST_CASE("batch under MPI: two ranks write the serial run's files", "[batch][mpi]") {
  TempDir dir("batch-mpi");
  {
    std::ofstream out(dir / "job.toml");
    out << kJob;
  }
  const auto serial = cli_test::run("batch " + quoted(dir / "job.toml") + " --out " +
                                    quoted(dir / "serial") + " --quiet");
  REQUIRE(serial.status == 0);
  const auto parallel =
      mpirun("batch " + quoted(dir / "job.toml") + " --out " + quoted(dir / "mpi") + " --quiet");
  INFO(parallel.output);
  REQUIRE(parallel.status == 0);
  const nlohmann::json s = nlohmann::json::parse(read_text(dir / "mpi" / "summary.json"));
  CHECK(s["ranks"] == 2);
  std::set<int> ranks;
  for (const auto& p : s["passes"]) ranks.insert(p["rank"].get<int>());
  CHECK(ranks.size() == 2);  // both ranks built surfaces
  for (const auto& row : s["surfaces"]) {
    const std::string name = row["name"];
    INFO(name);
    CHECK(row["status"] == "done");
    CHECK(read_text(dir / "mpi" / (name + ".vtp")) == read_text(dir / "serial" / (name + ".vtp")));
  }

  // Killed (one rank exits as if by SIGKILL; mpirun stops the other) and resumed under MPI.
  const auto killed =
      mpirun("batch " + quoted(dir / "job.toml") + " --out " + quoted(dir / "killed") +
             " --quiet --checkpoint-every 0.000001 --fail-after-steps 20");
  CHECK(killed.status != 0);
  CHECK_FALSE(fs::exists(dir / "killed" / "summary.json"));
  const auto resumed = mpirun("batch " + quoted(dir / "job.toml") + " --out " +
                              quoted(dir / "killed") + " --quiet --resume");
  INFO(resumed.output);
  REQUIRE(resumed.status == 0);
  const nlohmann::json r = nlohmann::json::parse(read_text(dir / "killed" / "summary.json"));
  bool continued = false;
  for (const auto& row : r["surfaces"]) {
    const std::string name = row["name"];
    INFO(name);
    CHECK(read_text(dir / "killed" / (name + ".vtp")) ==
          read_text(dir / "serial" / (name + ".vtp")));
    continued = continued || row.value("resumed_at_step", -1) > 0 || row.contains("resumed");
  }
  CHECK(continued);
}
