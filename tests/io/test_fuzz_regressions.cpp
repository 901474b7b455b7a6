// Every input that once made a fuzz target fail (fuzz/regressions/TARGET/*) is replayed through the
// same code the target runs: it must now end in a result or in one of the project's own errors.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "exercise.h"

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
