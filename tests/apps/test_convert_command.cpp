// `orthofront convert`, `info` on the real-data formats, `stream --field FILE.am|.vdb` and
// `stream --exr`, run as a user runs them.
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>

#include "apps/cli_run.h"
#include "io/grid_test_support.h"
#include "orthofront/io/grid_file.h"
#include "orthofront/io/hdf5_layout.h"
#include "orthofront/io/vdb_grid.h"

using Catch::Matchers::Contains;
using cli_test::quoted;
using orthofront::VectorGrid;
using namespace grid_test;

using cli_test::Run;
using cli_test::run;

namespace {

nlohmann::json info_json(const fs::path& file) {
  const Run r = run("info --json " + quoted(file));
  INFO(r.output);
  REQUIRE(r.status == 0);
  return nlohmann::json::parse(r.output);
}

/// A legacy VTK file of `grid` (ASCII), the simplest to write here.
void write_vtk(const fs::path& path, const VectorGrid& grid) {
  const auto& n = grid.geometry.size;
  std::string text =
      "# vtk DataFile Version 3.0\nstep\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS " +
      std::to_string(n[0]) + " " + std::to_string(n[1]) + " " + std::to_string(n[2]) +
      "\nORIGIN 0 0 0\nSPACING 1 1 1\nPOINT_DATA " + std::to_string(grid.geometry.point_count()) +
      "\nVECTORS v float\n";
  for (const float v : grid.values) text += std::to_string(v) + "\n";
  write_file(path, text);
}

std::vector<float> read_h5_step(const fs::path& file, std::size_t step) {
  orthofront::io::Hdf5ReadOptions options;
  options.steady_as_single_step = true;
  const auto series = orthofront::io::open_hdf5_series(file, "/", options);
  std::vector<float> values(series->step_floats());
  series->read(step, values);
  return values;
}

}  // namespace

TEST_CASE("convert: several files make a time series in natural order", "[apps][convert]") {
  TempDir dir("convert");
  std::vector<VectorGrid> steps;
  for (int s = 0; s < 11; ++s) {
    VectorGrid g = sample_grid(4, 3, 2);
    for (float& v : g.values) v += static_cast<float>(s);
    write_vtk(dir / ("step" + std::to_string(s) + ".vtk"), g);
    steps.push_back(g);
  }
  // A glob, expanded and sorted by convert itself: step2 before step10.
  const Run r = run("convert " + quoted(dir / "step*.vtk") +
                    " --dt 0.5 --t0 1 --compress gzip --out " + quoted(dir / "s.h5"));
  INFO(r.output);
  REQUIRE(r.status == 0);
  CHECK_THAT(r.output, Contains("11 steps at t = 1 .. 6"));
  const nlohmann::json j = info_json(dir / "s.h5");
  CHECK(j["steps"] == 11);
  CHECK(j["times"][10].get<double>() == 6.0);
  CHECK(j["grid"]["size"] == nlohmann::json{4, 3, 2});
  for (const std::size_t s : {std::size_t{0}, std::size_t{2}, std::size_t{10}})
    CHECK(same_values(read_h5_step(dir / "s.h5", s), steps[s].values));

  // Explicit times, and to OpenVDB and back.
  const Run v = run("convert " + quoted(dir / "step0.vtk") + " " + quoted(dir / "step1.vtk") + " " +
                    quoted(dir / "step2.vtk") + " --times 0,0.25,1 --out " + quoted(dir / "s.vdb"));
  INFO(v.output);
  REQUIRE(v.status == 0);
  const Run back =
      run("convert " + quoted(dir / "s.vdb") + " --out " + quoted(dir / "from_vdb.h5"));
  INFO(back.output);
  REQUIRE(back.status == 0);
  const nlohmann::json k = info_json(dir / "from_vdb.h5");
  CHECK(k["times"] == nlohmann::json{0.0, 0.25, 1.0});
  CHECK(same_values(read_h5_step(dir / "from_vdb.h5", 1), steps[1].values));

  // A steady input with --origin/--spacing.
  const Run steady = run("convert " + quoted(dir / "step3.vtk") +
                         " --origin 1,2,3 --spacing 0.5,0.5,2 --out " + quoted(dir / "one.h5"));
  INFO(steady.output);
  REQUIRE(steady.status == 0);
  const nlohmann::json o = info_json(dir / "one.h5");
  CHECK(o["steady"] == true);
  CHECK(o["grid"]["origin"] == nlohmann::json{1.0, 2.0, 3.0});
  CHECK(o["grid"]["spacing"] == nlohmann::json{0.5, 0.5, 2.0});
}

TEST_CASE("convert keeps the input's rule for zero vectors", "[apps][convert]") {
  TempDir dir("convert-zeros");
  write_vtk(dir / "a.vtk", sample_grid(4, 3, 2));
  write_vtk(dir / "b.vtk", sample_grid(4, 3, 2));
  const auto zeros_are_no_data = [](const fs::path& file) {
    orthofront::io::Hdf5ReadOptions options;
    options.steady_as_single_step = true;
    return orthofront::io::open_hdf5_series(file, "/", options)->zero_is_no_data();
  };
  // Grid files: zeros are solid or land; so in the conversion.
  REQUIRE(run("convert " + quoted(dir / "a.vtk") + " " + quoted(dir / "b.vtk") + " --out " +
              quoted(dir / "grid.h5")).status == 0);
  CHECK(zeros_are_no_data(dir / "grid.h5"));
  // An HDF5 file whose zeros are flow stays so when converted again (to another compression).
  REQUIRE(run("convert " + quoted(dir / "grid.h5") + " --zeros-are-flow --out " +
              quoted(dir / "flow.h5")).status == 0);
  CHECK_FALSE(zeros_are_no_data(dir / "flow.h5"));
  REQUIRE(run("convert " + quoted(dir / "flow.h5") + " --compress gzip --out " +
              quoted(dir / "again.h5")).status == 0);
  CHECK_FALSE(zeros_are_no_data(dir / "again.h5"));
  // And one whose zeros are no data stays so.
  REQUIRE(run("convert " + quoted(dir / "grid.h5") + " --compress gzip --out " +
              quoted(dir / "kept.h5")).status == 0);
  CHECK(zeros_are_no_data(dir / "kept.h5"));
}

TEST_CASE("convert: bad arguments are refused with a message", "[apps][convert]") {
  TempDir dir("convert");
  write_vtk(dir / "a.vtk", sample_grid(3, 3, 3));
  write_vtk(dir / "b.vtk", sample_grid(3, 3, 3));
  write_vtk(dir / "c.vtk", sample_grid(4, 3, 3));
  Run r = run("convert " + quoted(dir / "a.vtk") + " " + quoted(dir / "b.vtk") +
              " --times 0,1,2 --out " + quoted(dir / "x.h5"));
  CHECK(r.status == 2);
  CHECK_THAT(r.output, Contains("3 times for 2 input files"));
  r = run("convert " + quoted(dir / "a.vtk") + " " + quoted(dir / "c.vtk") + " --out " +
          quoted(dir / "x.h5"));
  CHECK(r.status == 2);
  CHECK_THAT(r.output, Contains("c.vtk") && Contains("differs from the first step"));
  r = run("convert " + quoted(dir / "a.txt") + " --out " + quoted(dir / "x.h5"));
  CHECK(r.status == 2);
  CHECK_THAT(r.output, Contains("a.txt") && Contains("unknown extension"));
  r = run("convert " + quoted(dir / "a.vtk") + " --out " + quoted(dir / "x.png"));
  CHECK(r.status == 2);
  CHECK_THAT(r.output, Contains("must end in .h5, .hdf5 or .vdb"));
  r = run("convert " + quoted(dir / "nothing*.vtk") + " --out " + quoted(dir / "x.h5"));
  CHECK(r.status == 2);
  CHECK_THAT(r.output, Contains("matches no file"));
  CHECK_FALSE(fs::exists(dir / "x.h5"));
}

TEST_CASE("writing .vdb or .h5 on a full disk fails naming the cause, leaving no file",
          "[apps][convert][diskfull]") {
  TempDir dir("fulldisk");
  const fs::path small = dir / "small";
  fs::create_directories(small);
  // A 300 KiB tmpfs: needs root (CAP_SYS_ADMIN); said and skipped otherwise.
  if (std::system(
          ("mount -t tmpfs -o size=300k tmpfs " + quoted(small) + " 2>/dev/null").c_str()) != 0) {
    WARN("skipped: cannot mount a small tmpfs here (needs root)");
    return;
  }
  const Run g = run("generate --field lorenz --resolution 40,40,40 --out " + quoted(dir / "lz.h5"));
  REQUIRE(g.status == 0);
  const Run r = run("convert " + quoted(dir / "lz.h5") + " --out " + quoted(small / "x.vdb"));
  const bool left = fs::exists(small / "x.vdb");
  const Run h =
      run("generate --field lorenz --resolution 40,40,40 --out " + quoted(small / "y.h5"));
  std::size_t litter = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(small)) ++litter;
  std::system(("umount " + quoted(small)).c_str());
  INFO(r.output << h.output);
  CHECK(r.status == 2);
  CHECK_THAT(r.output, Contains("x.vdb") && Contains("disk full"));
  CHECK_FALSE(left);
  CHECK(h.status == 2);  // the HDF5 writer says why too
  CHECK_THAT(h.output, Contains("y.h5") && Contains("disk full"));
  CHECK(litter == 0);
}

TEST_CASE("convert and info on the real data", "[apps][convert][realdata]") {
  const fs::path data = datasets_dir("");
  if (data.empty() || !fs::exists(data / "tornado")) return;
  TempDir dir("convert");
  Run r = run("convert " + quoted(data / "tornado/*.vec") + " --dt 0.1 --out " +
              quoted(dir / "tornado.h5"));
  INFO(r.output);
  REQUIRE(r.status == 0);
  const nlohmann::json j = info_json(dir / "tornado.h5");
  CHECK(j["steps"] == 10);
  CHECK(j["grid"]["size"] == nlohmann::json{48, 48, 48});
  CHECK(j["missing_points"] == 0);
  // Step 0 is 1.vec, step 9 is 10.vec (natural order).
  CHECK(same_values(read_h5_step(dir / "tornado.h5", 0),
                    orthofront::io::read_vector_grid(data / "tornado/1.vec").values));
  CHECK(same_values(read_h5_step(dir / "tornado.h5", 9),
                    orthofront::io::read_vector_grid(data / "tornado/10.vec").values));

  for (const char* file : {"bubble-chamber/BubbleChamber_11x11x10_T0.am",
                           "square-cylinder-2d/sqflow2D-1608.nrrd", "tornado/1.vti"}) {
    INFO(file);
    const nlohmann::json k = info_json(data / file);
    CHECK(k["steady"] == true);
  }
  CHECK(info_json(data / "bubble-chamber/BubbleChamber_11x11x10_T0.am")["zero_vectors"] == 400);
  CHECK(info_json(data / "square-cylinder-2d/sqflow2D-1608.nrrd")["grid"]["dimension"] == 2);
}

TEST_CASE("stream on real-data files and VDB, with a front image", "[apps][stream][realdata]") {
  const fs::path data = datasets_dir("bubble-chamber");
  if (data.empty()) return;
  TempDir dir("convert");
  const fs::path am = data / "BubbleChamber_11x11x10_T0.am";
  Run r = run("stream --field " + quoted(am) +
              " --seed line:-0.03,0,0.02:0.03,0,0.02 --edge 0.004 --steps 30 --out " +
              quoted(dir / "a.vtp") + " --exr " + quoted(dir / "a.exr") + " --quiet");
  INFO(r.output);
  REQUIRE(r.status == 0);
  CHECK(fs::exists(dir / "a.exr"));
  REQUIRE(run("convert " + quoted(am) + " --out " + quoted(dir / "b.vdb") + " --quiet").status ==
          0);
  r = run("stream --field " + quoted(dir / "b.vdb") +
          " --seed line:-0.03,0,0.02:0.03,0,0.02 --edge 0.004 --steps 30 --out " +
          quoted(dir / "b.vtp"));
  INFO(r.output);
  REQUIRE(r.status == 0);
  CHECK_THAT(r.output, Contains("b.vdb"));
  r = run("stream --field " + quoted(am) + " --seed line:0,0,0:1,1,1 --out " +
          quoted(dir / "c.vtp") + " --exr " + quoted(dir / "c.png"));
  CHECK(r.status == 2);
  CHECK_THAT(r.output, Contains("must end in .exr"));
}
