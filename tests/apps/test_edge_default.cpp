// The edge length a surface takes without --edge: the grid's cell size on gridded data, as the
// `stream`, `path` and `streak` commands (and Python) resolve it.
#include <catch2/catch.hpp>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "apps/cli_run.h"
#include "jobs/edge_default.h"
#include "temp_dir.h"

namespace fs = std::filesystem;
using namespace orthofront;
using test_support::read_text;

TEST_CASE("the default edge of gridded data is its cell size", "[apps][edge]") {
  GridGeometry uniform;
  uniform.dimension = 2;
  uniform.size = {101, 51, 1};
  uniform.spacing = Vec3(0.02, 0.01, 0);  // ParaView writes a 2D image with z spacing 0
  CHECK(jobs::grid_cell_size(uniform) == 0.01);

  // Rectilinear: each axis's median width, so a few refined wall cells do not set it; in 3D
  // the middle of the three.
  GridGeometry rect;
  rect.dimension = 3;
  rect.size = {6, 2, 2};
  rect.axes[0] = {0, 0.001, 0.002, 1, 2, 3};  // widths 0.001 0.001 0.998 1 1: median 0.998
  rect.axes[1] = {0, 2};
  rect.axes[2] = {0, 1.5};
  CHECK(jobs::grid_cell_size(rect) == Approx(1.5));
  // An ocean grid in metres: 50 km x 30 km cells, 10 m layers. The layers do not set it.
  GridGeometry ocean;
  ocean.dimension = 3;
  ocean.size = {100, 100, 40};
  ocean.spacing = Vec3(50e3, 30e3, 10);
  CHECK(jobs::grid_cell_size(ocean) == 30e3);

  const jobs::EdgeChoice from_grid = jobs::choose_edge(0.05, false, &uniform);
  CHECK(from_grid.edge == 0.01);
  CHECK(from_grid.source == "grid cell");
  CHECK(jobs::edge_note(from_grid).find("0.01: the grid's cell size (--edge sets it)") !=
        std::string::npos);
  const jobs::EdgeChoice given = jobs::choose_edge(0.05, true, &uniform);
  CHECK(given.edge == 0.05);
  CHECK(given.source == "--edge");
  CHECK(jobs::edge_note(given).empty());
  const jobs::EdgeChoice analytic = jobs::choose_edge(0.05, false, nullptr);
  CHECK(analytic.edge == 0.05);
  CHECK(analytic.source == "default");
}

TEST_CASE("stream, path and streak without --edge take the grid's cell size, and say so",
          "[apps][edge]") {
  test_support::TempDir dir;
  // A double gyre on [0, 2] x [0, 1] sampled at 0.02 over [0, 4]: the old default edges
  // (0.1 and 0.05) are 5 and 2.5 cells.
  const fs::path h5 = dir.path() / "gyre.h5";
  REQUIRE(cli_test::run("generate --field double-gyre --resolution 101,51 --steps 41 --t1 4 "
                        "--out " + h5.string() + " --quiet")
              .status == 0);
  const std::string seed = " --seed line:0.3,0.3,0:0.3,0.45,0";
  const auto edge_of = [&](const std::string& command, const fs::path& report) {
    const auto r = cli_test::run(command + " --report " + report.string());
    INFO(r.output);
    REQUIRE(r.status == 0);
    CHECK(r.output.find("Edge length 0.02: the grid's cell size (--edge sets it)") !=
          std::string::npos);
    const auto j = nlohmann::json::parse(read_text(report));
    CHECK(j["edge_source"] == "grid cell");
    return j["edge"].get<double>();
  };
  CHECK(edge_of("streak --field " + h5.string() + seed + " --release 0:1 --frames 1 --out " +
                    (dir.path() / "s.pvd").string(),
                dir.path() / "s.json") == Approx(0.02));
  CHECK(edge_of("path --field " + h5.string() + seed + " --t0 0 --t1 0.5 --out " +
                    (dir.path() / "p.vtp").string(),
                dir.path() / "p.json") == Approx(0.02));
  // A steady grid: the saddle on [-3, 3]² sampled at 0.05 (the old default, 0.1, is 2 cells).
  const fs::path steady = dir.path() / "saddle.h5";
  REQUIRE(cli_test::run("generate --field saddle --resolution 121,121 --out " + steady.string() +
                        " --quiet")
              .status == 0);
  const auto r = cli_test::run("stream --field " + steady.string() +
                               " --seed line:-2,1,0:-2,2,0 --steps 20 --out " +
                               (dir.path() / "f.vtp").string() + " --report " +
                               (dir.path() / "f.json").string());
  INFO(r.output);
  REQUIRE(r.status == 0);
  CHECK(r.output.find("Edge length 0.05: the grid's cell size (--edge sets it)") !=
        std::string::npos);
  const auto f = nlohmann::json::parse(read_text(dir.path() / "f.json"));
  CHECK(f["edge_source"] == "grid cell");
  CHECK(f["edge"].get<double>() == Approx(0.05));
  // Given, it is kept, and nothing is said about it.
  const auto given = cli_test::run("streak --field " + h5.string() + seed +
                                   " --release 0:1 --frames 1 --edge 0.03 --out " +
                                   (dir.path() / "g.pvd").string() + " --report " +
                                   (dir.path() / "g.json").string());
  REQUIRE(given.status == 0);
  CHECK(given.output.find("Edge length") == std::string::npos);
  const auto j = nlohmann::json::parse(read_text(dir.path() / "g.json"));
  CHECK(j["edge"] == 0.03);
  CHECK(j["edge_source"] == "--edge");
}
