// Batch checkpoint states cannot lie: every single-bit change of a state file is refused.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "apps/cli_run.h"
#include "cli/batch_checkpoint.h"
#include "orthofront/error.h"
#include "orthofront/io/error.h"
#include "temp_dir.h"

namespace fs = std::filesystem;
using cli_test::quoted;
using test_support::read_text;

TEST_CASE("batch checkpoint: every single-bit flip of a state file is refused", "[batch]") {
  test_support::TempDir dir("checkpoint-bits");
  {
    std::ofstream(dir / "job.toml") << "[job]\nfield = \"saddle3d\"\n[[surface]]\nname = \"s\"\n"
                                       "kind = \"stream\"\nseed = \"line:-3,1,1:-3,1,3\"\n"
                                       "seed_count = 4\nsteps = 400\nedge = 0.5\n";
  }
  const fs::path out = dir / "out";
  REQUIRE(cli_test::run("batch " + quoted(dir / "job.toml") + " --out " + quoted(out) +
                        " --checkpoint-every 0.000001 --quiet --fail-after-steps 3")
              .status == 9);
  const fs::path folder = out / ".checkpoint";
  const std::string job = nlohmann::json::parse(read_text(folder / "job.id"))["job"];
  const orthofront::cli::CheckpointFolder checkpoints(folder, std::stoull(job, nullptr, 16));
  const std::string bytes = read_text(folder / "s.state");
  REQUIRE(checkpoints.load_state("s").has_value());  // the state as written loads
  INFO(bytes.size() << " bytes");
  std::size_t refused = 0, flips = 0;
  for (std::size_t i = 0; i < bytes.size(); ++i)
    for (int bit = 0; bit < 8; ++bit) {
      std::string flipped = bytes;
      flipped[i] = static_cast<char>(flipped[i] ^ (1 << bit));
      std::ofstream(folder / "s.state", std::ios::binary | std::ios::trunc) << flipped;
      ++flips;
      try {
        (void)checkpoints.load_state("s");
      } catch (const orthofront::Error&) {
        ++refused;
      }
    }
  CHECK(refused == flips);
}
