// Every input that once made a fuzz target fail (fuzz/regressions/TARGET/*) is replayed through the
// same code the target runs: it must now end in a result or in one of the project's own errors.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "exercise.h"
#include "temp_dir.h"

namespace fs = std::filesystem;

TEST_CASE("inputs that once failed a fuzz target are read or refused with a message", "[fuzz]") {
  // Some inputs made OpenVDB loop: their first read (in a child) is cut at 2 s instead of 10.
  ::setenv("ORTHOFRONT_READ_TIMEOUT", "2", 1);
  const fs::path regressions = fs::path(ORTHOFRONT_SOURCE_DIR) / "fuzz" / "regressions";
  REQUIRE(fs::is_directory(regressions));
  std::size_t replayed = 0;
  for (const char* target : orthofront::fuzz::kTargets) {
    const fs::path folder = regressions / target;
    if (!fs::is_directory(folder)) continue;
    for (const auto& entry : fs::directory_iterator(folder)) {
      std::ifstream in(entry.path(), std::ios::binary);
      std::ostringstream bytes;
      bytes << in.rdbuf();
      const std::string input = bytes.str();
      INFO(target << ": " << entry.path().filename().string());
      bool consistent = false;
      REQUIRE_NOTHROW(consistent = orthofront::fuzz::exercise(target, input));
      CHECK(consistent);
      ++replayed;
    }
  }
  // The corpus of findings is part of the repository; an empty replay would test nothing.
  CHECK(replayed > 0);
}

TEST_CASE("the fuzz exercise refuses a target it does not have", "[fuzz]") {
  CHECK_THROWS_AS(orthofront::fuzz::exercise("no_such_target", ""), std::invalid_argument);
  // A valid input of each text syntax passes.
  CHECK(orthofront::fuzz::exercise("parse_seed", "line:0,0,0:1,1,1"));
  CHECK(orthofront::fuzz::exercise("parse_bytes", "512MiB"));
  CHECK(orthofront::fuzz::exercise("parse_field", "saddle"));
  // The targets of several files: each valid input is read through, each damaged one refused.
  using orthofront::fuzz::exercise;
  CHECK(exercise("pvd", "<VTKFile type=\"Collection\"><Collection><DataSet timestep=\"0\" "
                        "file=\"a.vti\"/><DataSet timestep=\"1\" file=\"b.vti\"/></Collection>"
                        "</VTKFile>"));
  CHECK(exercise("pvd", "<VTKFile type=\"Collection\"><Collection><DataSet timestep=\"0\" "
                        "file=\"../../etc/none.vti\"/>"));
  std::string nhdr = "NRRD0004\ntype: float\ndimension: 4\nsizes: 3 2 2 2\nencoding: raw\n"
                     "endian: little\ndata file: data.raw\n";
  nhdr.push_back('\0');
  nhdr.append(3 * 8 * sizeof(float), '\0');
  CHECK(exercise("grid_nhdr", nhdr));
  CHECK(exercise("grid_nhdr", nhdr.substr(0, nhdr.size() - 5)));  // data cut short
  CHECK(exercise("job_file", "[job]\nfield = \"saddle3d\"\n[[surface]]\nname = \"a\"\n"
                             "kind = \"stream\"\nseed = \"line:0,0,0:1,0,0\"\n"));
  CHECK(exercise("job_file", "[[surface]\nname = "));
  CHECK(exercise("checkpoint", std::string("\x05\0\0\0\0\0\0\0abc", 11)));
  CHECK(exercise("netcdf", "CDF\x01\0\0\0\0"));
}

namespace {

std::string read_bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

// One to four of libFuzzer's simplest mutations: flip a bit, set a byte, erase a run, repeat a
// run, insert random bytes.
std::string mutated(std::string input, std::mt19937_64& random) {
  const auto below = [&](std::size_t n) { return n == 0 ? 0 : random() % n; };
  const std::size_t count = 1 + below(4);
  for (std::size_t m = 0; m < count; ++m) {
    const std::size_t at = below(input.size() + 1);
    switch (below(5)) {
      case 0:
        if (at < input.size()) input[at] = static_cast<char>(input[at] ^ (1 << below(8)));
        break;
      case 1:
        if (at < input.size()) input[at] = static_cast<char>(below(256));
        break;
      case 2:
        input.erase(at, below(16) + 1);
        break;
      case 3:
        if (at < input.size()) input.insert(at, input.substr(at, below(32) + 1));
        break;
      default:
        for (std::size_t k = below(8) + 1; k > 0; --k)
          input.insert(input.begin() + static_cast<std::ptrdiff_t>(at), static_cast<char>(below(256)));
    }
  }
  return input;
}

}  // namespace

TEST_CASE("every fuzz target over its seed corpus and mutations of it ends in a result or an error",
          "[fuzz]") {
  // The build has no libFuzzer (that is fuzz/run.sh's clang build): this runs each target over
  // the seed corpus fuzz/make_corpus.sh writes and a fixed sequence of mutations of it, in every
  // build and so under the sanitizers too.
  ::setenv("ORTHOFRONT_READ_TIMEOUT", "2", 1);
  test_support::TempDir dir("fuzz-corpus");
  const std::string make = "ORTHOFRONT='" + std::string(ORTHOFRONT_BINARY) + "' bash '" +
                           ORTHOFRONT_SOURCE_DIR + "/fuzz/make_corpus.sh' '" +
                           (dir / "corpus").string() + "' > '" + (dir / "log").string() +
                           "' 2>&1";
  INFO(make);
  REQUIRE(std::system(make.c_str()) == 0);
  std::size_t targets = 0, runs = 0;
  for (const char* target : orthofront::fuzz::kTargets) {
    std::vector<std::string> inputs;
    for (const auto& entry : fs::directory_iterator(dir / "corpus" / target))
      inputs.push_back(read_bytes(entry.path()));
    if (inputs.empty()) continue;
    ++targets;
    // Targets that read each input in a child process (HDF5, OpenVDB, NetCDF) take longer each.
    const std::string name = target;
    const bool forks =
        name == "hdf5" || name == "vdb_file" || name == "grid_vdb" || name == "netcdf";
    const std::size_t mutations = forks ? 12 : 300;
    std::mt19937_64 random(std::hash<std::string>{}(name));
    for (std::size_t k = 0; k < inputs.size() + mutations; ++k) {
      const std::string input =
          k < inputs.size() ? inputs[k] : mutated(inputs[random() % inputs.size()], random);
      bool consistent = false;
      try {
        consistent = orthofront::fuzz::exercise(target, input);
      } catch (const std::exception& e) {
        const fs::path kept = fs::current_path() / ("fuzz-failure-" + name);
        std::ofstream(kept, std::ios::binary) << input;
        FAIL(target << " input " << k << " threw " << e.what() << " (kept as " << kept << ")");
      }
      INFO(target << " input " << k);
      CHECK(consistent);
      ++runs;
    }
  }
  INFO(runs << " runs");
  CHECK(targets >= 15);
}
