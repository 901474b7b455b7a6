// `orthofront generate`, `info` and `stream --field FILE.h5`, run as a user runs them.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "temp_dir.h"
#include "apps/cli_run.h"

namespace fs = std::filesystem;

using cli_test::Run;
using cli_test::run;

namespace {

using test_support::TempDir;

std::string at(const TempDir& dir, const std::string& name) { return (dir / name).string(); }

nlohmann::json read_json(const std::string& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

}  // namespace

TEST_CASE("generate writes a steady field that info describes", "[apps][generate]") {
  TempDir dir;
  const Run g =
      run("generate --field saddle3d --resolution 17,9,5 --units-length m --out " + at(dir, "s.h5"));
  INFO(g.output);
  REQUIRE(g.status == 0);
  CHECK(fs::exists(at(dir, "s.h5")));
  // The default codec (Blosc lz4) is one ParaView's HDF5 cannot decode: no sidecar, and why.
  CHECK_FALSE(fs::exists(at(dir, "s.xmf")));
  CHECK_THAT(g.output, Catch::Contains("no .xmf: ParaView's HDF5 cannot decode Blosc lz4"));

  const Run info = run("info " + at(dir, "s.h5"));
  INFO(info.output);
  REQUIRE(info.status == 0);
  CHECK_THAT(info.output, Catch::Contains("uniform 3D, 17 x 9 x 5 points") &&
                              Catch::Contains("components:   3") &&
                              Catch::Contains("steps:        steady") &&
                              Catch::Contains("bounds:       [-4, 4] x [-4, 4] x [-4, 4]") &&
                              Catch::Contains("length m") &&
                              Catch::Contains("v_x [-4, 4] v_y [-4, 4] v_z [-4, 4]") &&
                              Catch::Contains("bytes/step:   9180 "));

  const Run json = run("info --json " + at(dir, "s.h5") + " > " + at(dir, "info.json"));
  REQUIRE(json.status == 0);
  const nlohmann::json j = read_json(at(dir, "info.json"));
  CHECK(j["grid"]["size"] == nlohmann::json{17, 9, 5});
  CHECK(j["components"] == 3);
  CHECK(j["missing_points"] == 0);
}

TEST_CASE("generate streams time series of unsteady fields in both layouts", "[apps][generate]") {
  TempDir dir;
  for (const char* layout : {"chunked", "per-step"}) {
    const std::string file = at(dir, (std::string(layout) + ".h5"));
    const Run g = run(std::string("generate --field double-gyre --resolution 41,21,1 --steps 5 "
                                  "--t0 0 --t1 2 --compress gzip:3 --layout ") +
                      layout + " --group /dg --out " + file);
    INFO(g.output);
    REQUIRE(g.status == 0);
    const Run info = run("info " + file + ":/dg");
    INFO(info.output);
    REQUIRE(info.status == 0);
    CHECK_THAT(info.output, Catch::Contains("uniform 2D, 41 x 21 points") &&
                                Catch::Contains("components:   2") &&
                                Catch::Contains("steps:        5, times 0 0.5 1 1.5 2") &&
                                Catch::Contains(std::string("storage:      ") + layout) &&
                                Catch::Contains("shuffle + gzip level 3"));
  }
  const Run g3 = run("generate --field unsteady-abc --resolution 16,16,16 --steps 3 --t1 1 --out " +
                     at(dir, "abc.h5"));
  INFO(g3.output);
  REQUIRE(g3.status == 0);
  const Run info = run("info " + at(dir, "abc.h5"));
  CHECK_THAT(info.output, Catch::Contains("16 x 16 x 16") && Catch::Contains("steps:        3"));
}

TEST_CASE("stream on a sampled field matches the analytic field", "[apps][generate][stream]") {
  TempDir dir;
  REQUIRE(run("generate --field saddle3d --resolution 81,81,81 --out " + at(dir, "s.h5")).status == 0);
  const std::string common =
      " --seed line:-1,2,0.1:1,2,0.1 --seed-count 21 --edge 0.1 --steps 60 --quiet ";
  const Run grid = run("stream --field " + at(dir, "s.h5") + common + "--out " + at(dir, "g.ply") +
                       " --report " + at(dir, "g.json"));
  INFO(grid.output);
  REQUIRE(grid.status == 0);
  const Run exact = run("stream --field saddle3d" + common + "--out " + at(dir, "e.ply") +
                        " --report " + at(dir, "e.json"));
  REQUIRE(exact.status == 0);
  const double v_grid = read_json(at(dir, "g.json"))["counts"]["vertices"].get<double>();
  const double v_exact = read_json(at(dir, "e.json"))["counts"]["vertices"].get<double>();
  CHECK(v_grid > 1000);
  CHECK(v_grid == Approx(v_exact).epsilon(0.02));
}

TEST_CASE("bad paths and values fail with a message naming them", "[apps][generate][errors]") {
  TempDir dir;
  SECTION("info on a missing file") {
    const Run r = run("info " + at(dir, "missing.h5"));
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains("missing.h5") && Catch::Contains("no such file"));
  }
  SECTION("info on a file that is not HDF5") {
    std::ofstream(at(dir, "text.h5")) << "not hdf5";
    const Run r = run("info " + at(dir, "text.h5"));
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains("text.h5 is not an HDF5 file"));
  }
  SECTION("info on an unknown format") {
    const Run r = run("info " + at(dir, "field.xyz"));
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains("field.xyz") && Catch::Contains(".h5"));
  }
  SECTION("stream on a missing file and on a missing group") {
    Run r = run("stream --field " + at(dir, "missing.h5") + " --seed line:0,0,0:1,1,1 --out " +
                at(dir, "x.ply"));
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains("missing.h5"));
    REQUIRE(run("generate --field saddle3d --resolution 5,5,5 --out " + at(dir, "s.h5")).status == 0);
    r = run("stream --field " + at(dir, "s.h5:/nope") + " --seed line:0,0,0:1,1,1 --out " +
            at(dir, "x.ply"));
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains("s.h5: no group or dataset '/nope'"));
  }
  SECTION("generate into a missing folder leaves nothing") {
    const Run r = run("generate --field saddle3d --resolution 5,5,5 --out " + at(dir, "no/s.h5"));
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains("no/s.h5"));
    CHECK(dir.empty());
  }
  SECTION("generate of a grid that cannot fit in memory is refused before allocating") {
    const Run r = run("generate --field saddle3d --resolution 100000,100000,100000 --out " +
                      at(dir, "huge.h5"));
    CHECK(r.status == 2);
    CHECK_THAT(r.output, Catch::Contains("--resolution 100000,100000,100000") &&
                             Catch::Contains("more than half of the") &&
                             Catch::Contains("huge.h5 was not written"));
    CHECK(dir.empty());
  }
  SECTION("generate with bad values leaves nothing") {
    for (const std::string& args :
         {std::string("--field nosuch --resolution 5,5,5"),
          std::string("--field saddle3d --resolution 5,x,5"),
          std::string("--field saddle3d --resolution 5,5,5 --compress lzf"),
          std::string("--field saddle3d --resolution 5,5,5 --steps 3"),
          std::string("--field double-gyre --resolution 5,5,1"),
          std::string("--field double-gyre --resolution 5,5,1 --steps 3 --t0 1 --t1 0"),
          std::string("--field unsteady-abc --resolution 5,5,5 --steps 2 --t0 -1 --t1 1")}) {
      const Run r = run("generate " + args + " --out " + at(dir, "s.h5"));
      INFO(args << "\n" << r.output);
      CHECK(r.status == 2);
      CHECK_THAT(r.output, Catch::Contains("error"));
    }
    CHECK(dir.empty());
  }
}

TEST_CASE("ParaView's XDMF reader opens generate's files through their .xmf: arrays, geometry, "
          "times",
          "[apps][generate][paraview]") {
  if (std::system("command -v pvpython > /dev/null 2>&1") != 0) {
    WARN("skipped: pvpython not found (Debian: paraview, python3-paraview)");
    return;
  }
  TempDir dir;
  // A 2D series (gzip) and a 3D steady field (no compression), as a user writes them.
  const Run g2 = run("generate --field double-gyre --resolution 21,11 --steps 3 --t1 2 "
                     "--compress gzip --out " + at(dir, "g.h5"));
  INFO(g2.output);
  REQUIRE(g2.status == 0);
  CHECK_THAT(g2.output, Catch::Contains("and " + at(dir, "g.xmf")));
  REQUIRE(run("generate --field abc --resolution 9,8,7 --compress none --out " + at(dir, "a.h5") +
              " --quiet")
              .status == 0);
  const fs::path script = dir / "open.py";
  std::ofstream(script) << R"PY(
import sys
from paraview.simple import XDMFReader, servermanager
for name in sys.argv[1:]:
    reader = XDMFReader(FileNames=[name])
    reader.UpdatePipeline()
    data = servermanager.Fetch(reader)
    array = data.GetPointData().GetArray('velocity')
    bounds = ' '.join('%g' % b for b in data.GetBounds())
    times = ' '.join('%g' % t for t in reader.TimestepValues) if reader.TimestepValues else '-'
    print('%s points %d bounds %s components %d max %.6f times %s' % (
        name.split('/')[-1], data.GetNumberOfPoints(), bounds, array.GetNumberOfComponents(),
        array.GetRange(-1)[1], times))
)PY";
  const fs::path out = dir / "open.out";
  const int status = std::system(("pvpython '" + script.string() + "' '" + at(dir, "g.xmf") +
                                  "' '" + at(dir, "a.xmf") + "' > '" + out.string() +
                                  "' 2>&1")
                                     .c_str());
  const std::string text = test_support::read_text(out);
  INFO(text);
  REQUIRE(status == 0);
  // The gyre on [0, 2] x [0, 1] in the z = 0 plane, its three steps; |v| peaks at pi A = 0.314
  // (the reader pads 2-vectors to three components).
  CHECK_THAT(text, Catch::Contains("g.xmf points 231 bounds 0 2 0 1 0 0 components 3 max "
                                   "0.314159 times 0 1 2"));
  // ABC on [-2pi, 4pi]^3 (steady: no times).
  CHECK_THAT(text, Catch::Contains("a.xmf points 504 bounds -6.28319 12.5664 -6.28319 12.5664 "
                                   "-6.28319 12.5664 components 3"));
  CHECK_THAT(text, Catch::Contains("times -"));
}
