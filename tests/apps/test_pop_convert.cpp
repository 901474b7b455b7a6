// datasets-scripts/orthofront-pop-convert on the 6 POP steps: dimensions, times, land as NaN,
// ocean values finite, the resampling loss stated and small for (u, v).
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "io/grid_test_support.h"
#include "orthofront/io/hdf5_layout.h"

using Catch::Matchers::Contains;
using namespace grid_test;

#ifdef ORTHOFRONT_POP_CONVERT  // builds that read NetCDF
TEST_CASE("pop-convert: the six POP steps become a uniform HDF5 series with land as NaN",
          "[apps][pop][realdata]") {
  const fs::path data = datasets_dir("pop-southern-ocean");
  if (data.empty()) return;
  TempDir dir("pop");
  // The shell expands the glob (unquoted); the tool sorts the files itself.
  const std::string command = std::string("'") + ORTHOFRONT_POP_CONVERT + "' " + (data / "*.nc").string() +
                              " --out '" + (dir / "pop.h5").string() + "' --report '" +
                              (dir / "loss.json").string() + "' 2>&1";
  std::string output;
  FILE* pipe = ::popen(command.c_str(), "r");
  REQUIRE(pipe != nullptr);
  char buffer[4096];
  while (std::fgets(buffer, sizeof buffer, pipe) != nullptr) output += buffer;
  const int status = ::pclose(pipe);
  INFO(output);
  REQUIRE(WIFEXITED(status));
  REQUIRE(WEXITSTATUS(status) == 0);
  CHECK_THAT(output, Contains("resampling loss") && Contains("max error") && Contains("Wrote"));

  orthofront::io::Hdf5ReadOptions options;
  const auto series = orthofront::io::open_hdf5_series(dir / "pop.h5", "/", options);
  REQUIRE(series->step_count() == 6);
  CHECK(series->time(5) == 5.0);
  const auto& g = series->geometry();
  // 60 x 60 source columns -> 2 (60 - 1) + 1 samples; 20 layers of 10 m (top) to 130 m -> dz <= 10 m.
  CHECK(g.size[0] == 119);
  CHECK(g.size[1] == 119);
  CHECK(g.size[2] == 59);
  CHECK(series->components() == 3);
  CHECK(g.origin[0] == Approx(39.875));     // ULON of the first column, degrees east
  CHECK(g.origin[1] == Approx(-62.92569));  // ULAT of the first row
  CHECK(g.bounds().hi[0] == Approx(106.25));
  CHECK(g.bounds().hi[2] == Approx(-0.5 * (0 + 10.01244)));  // the top layer's centre, z up
  const auto description = orthofront::io::describe_hdf5(dir / "pop.h5");
  CHECK_THAT(description.units.velocity, Contains("deg/s"));

  std::vector<float> values(series->step_floats());
  for (std::size_t s = 0; s < 6; ++s) {
    series->read(s, values);
    std::size_t nan = 0;
    std::size_t partial = 0;  // a point is missing as a whole, never one component
    for (std::size_t p = 0; p < g.point_count(); ++p) {
      const bool missing = std::isnan(values[3 * p]);
      nan += missing ? 1 : 0;
      partial += missing != std::isnan(values[3 * p + 1]) || missing != std::isnan(values[3 * p + 2]);
    }
    INFO("step " << s);
    CHECK(partial == 0);
    // Land: the Kerguelen plateau rises into the deepest layers around source column (30, 18),
    // target column (60, 36); the bottom sample there is land.
    CHECK(std::isnan(values[3 * g.index(60, 36, 0)]));
    // Open ocean near the surface is data.
    CHECK(std::isfinite(values[3 * g.index(20, 100, g.size[2] - 1)]));
    CHECK(nan > 0);
    CHECK(nan < g.point_count() / 50);
  }
  std::ifstream in(dir / "loss.json");
  const nlohmann::json report = nlohmann::json::parse(in);
  const auto& h = report["loss"]["horizontal"];
  CHECK(h["samples"].get<std::size_t>() == 6u * (72000u - 155u));  // 155 land U points per step
  CHECK(h["relative_max"].get<double>() < 0.02);
  CHECK(h["mean_cm_s"].get<double>() < 0.05);
  CHECK(report["loss"]["vertical"]["relative_max"].get<double>() < 0.1);
}
#endif

