// OSUFlow .vec reader: synthetic files read back exactly, bad files rejected, the tornado data.
#include <cmath>

#include "io/grid_test_support.h"
#include "orthofront/io/error.h"
#include "orthofront/io/grid_file.h"
#include "orthofront/io/vec_reader.h"

using Catch::Matchers::Contains;
using orthofront::Vec3;
using orthofront::VectorGrid;
using orthofront::io::FormatError;
using orthofront::io::IoError;
using orthofront::io::read_vec;
using namespace grid_test;

namespace {

std::string vec_file(std::int32_t nx, std::int32_t ny, std::int32_t nz,
                     const std::vector<float>& values) {
  std::string bytes;
  put(bytes, nx, true);
  put(bytes, ny, true);
  put(bytes, nz, true);
  return bytes + float_bytes(values, true);
}

}  // namespace

TEST_CASE("vec: a synthetic file reads back exactly, unit spacing at 0 by default", "[vec]") {
  TempDir dir("vec");
  const VectorGrid expected = sample_grid(5, 4, 3, 3, true);
  write_file(dir / "a.vec", vec_file(5, 4, 3, expected.values));
  const VectorGrid grid = read_vec(dir / "a.vec");
  CHECK(grid.geometry.dimension == 3);
  CHECK(grid.geometry.size == std::array<std::int64_t, 3>{5, 4, 3});
  CHECK(grid.components == 3);
  CHECK(grid.geometry.origin == Vec3::Zero());
  CHECK(grid.geometry.spacing == Vec3::Ones());
  CHECK_FALSE(grid.geometry.rectilinear());
  CHECK(same_values(grid.values, expected.values));
  CHECK(std::isnan(grid.values[3]));  // NaN kept as NaN

  // A placement, and the format dispatch by extension.
  orthofront::io::VecPlacement placement;
  placement.origin = Vec3(1, 2, 3);
  placement.spacing = Vec3(0.5, 0.25, 2);
  const VectorGrid placed = read_vec(dir / "a.vec", placement);
  CHECK(placed.geometry.origin == Vec3(1, 2, 3));
  CHECK(placed.geometry.spacing == Vec3(0.5, 0.25, 2));
  CHECK(same_values(orthofront::io::read_vector_grid(dir / "a.vec").values, expected.values));
}

TEST_CASE("vec: bad files are rejected naming the file and the value", "[vec]") {
  TempDir dir("vec");
  const VectorGrid grid = sample_grid(4, 4, 4);

  SECTION("truncated data") {
    std::string bytes = vec_file(4, 4, 4, grid.values);
    bytes.resize(bytes.size() - 7);
    write_file(dir / "short.vec", bytes);
    const std::string message = thrown<FormatError>([&] { read_vec(dir / "short.vec"); });
    CHECK_THAT(message, Contains("short.vec") && Contains("truncated") && Contains("4 x 4 x 4") &&
                            Contains(std::to_string(bytes.size())));
  }
  SECTION("header sizes that do not match the data") {
    write_file(dir / "dims.vec", vec_file(4, 4, 3, grid.values));
    CHECK_THAT(thrown<FormatError>([&] { read_vec(dir / "dims.vec"); }),
               Contains("dims.vec") && Contains("4 x 4 x 3"));
  }
  SECTION("a non-positive size") {
    write_file(dir / "neg.vec", vec_file(4, -4, 4, grid.values));
    CHECK_THAT(thrown<FormatError>([&] { read_vec(dir / "neg.vec"); }),
               Contains("neg.vec") && Contains("-4"));
  }
  SECTION("shorter than the header") {
    write_file(dir / "tiny.vec", "abc");
    CHECK_THAT(thrown<FormatError>([&] { read_vec(dir / "tiny.vec"); }),
               Contains("tiny.vec") && Contains("truncated"));
  }
  SECTION("a missing file") {
    CHECK_THAT(thrown<IoError>([&] { read_vec(dir / "none.vec"); }), Contains("none.vec"));
  }
}

TEST_CASE("vec: the tornado time steps", "[vec][realdata]") {
  const fs::path dir = datasets_dir("tornado");
  if (dir.empty()) return;
  for (int step = 1; step <= 10; ++step) {
    const VectorGrid grid = read_vec(dir / (std::to_string(step) + ".vec"));
    INFO("step " << step);
    REQUIRE(grid.geometry.size == std::array<std::int64_t, 3>{48, 48, 48});
    REQUIRE(grid.components == 3);
    double lo = INFINITY;
    double hi = 0;
    for (std::size_t p = 0; p < grid.geometry.point_count(); ++p) {
      const double m = std::hypot(grid.values[3 * p], grid.values[3 * p + 1], grid.values[3 * p + 2]);
      REQUIRE(std::isfinite(m));
      lo = std::min(lo, m);
      hi = std::max(hi, m);
    }
    // A swirl of moderate speed everywhere (no zero vectors, no fill values).
    CHECK(lo > 0.01);
    CHECK(hi < 1.0);
    if (step == 1) {
      // The speed range 1.vti records (RangeMin / RangeMax of its array).
      CHECK(lo == Approx(0.029834362748).epsilon(1e-6));
      CHECK(hi == Approx(0.31268415955).epsilon(1e-6));
      CHECK(grid.values[0] == Approx(-0.00603248).epsilon(1e-5));
      CHECK(grid.values[1] == Approx(-0.0966396).epsilon(1e-5));
      CHECK(grid.values[2] == Approx(-0.000732792).epsilon(1e-4));
    }
  }
}
