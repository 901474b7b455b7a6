#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "apps/cli_run.h"
#include "orthofront/io/mesh_io.h"
#include "temp_dir.h"

namespace fs = std::filesystem;
using orthofront::Mesh;
using test_support::read_text;

namespace {

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

}  // namespace

TEST_CASE("streak command: an analytic field as a .pvd animation with its report",
          "[apps][streak]") {
  test_support::TempDir dir;
  const fs::path pvd = dir.path() / "gyre.pvd", report = dir.path() / "gyre.json";
  const auto r = cli_test::run(
      "streak --field double-gyre --seed line:0.3,0.3,0:0.3,0.45,0 "
      "--release 0:3 --frames 1:4:4 --edge 0.03 --flat-split 0 --out " +
      pvd.string() + " --report " + report.string());
  INFO(r.output);
  REQUIRE(r.status == 0);
  CHECK(r.output.find("4 of 4 frames") != std::string::npos);
  const std::string collection = read_text(pvd);
  CHECK(count(collection, "<DataSet ") == 4);
  CHECK(collection.find("file=\"gyre/gyre_0003.vtp\"") != std::string::npos);
  const Mesh last = orthofront::io::read_mesh(dir.path() / "gyre" / "gyre_0003.vtp");
  CHECK(last.face_count() > 0);
  CHECK(last.particle_id.size() == last.vertex_count());
  CHECK(last.release_time.size() == last.vertex_count());
  const auto j = nlohmann::json::parse(read_text(report));
  CHECK(j["complete"] == true);
  CHECK(j["frames_written"] == 4);
  REQUIRE(j["frames"].size() == 4);
  CHECK(j["frames"][3]["vertices"] == last.vertex_count());
  CHECK(j["frames"][3]["quality"]["t_junctions"] == 0);
  CHECK(j["refinement"]["interpolated_insertions"] == 0);
  CHECK(j["refinement"]["flat_insertions"] == 0);
  CHECK(j["refinement"]["coarsen_age"].is_null());
  CHECK(j["particles"]["left_region"] == 0);
  REQUIRE(last.on_path.size() == last.vertex_count());
  CHECK(std::count(last.on_path.begin(), last.on_path.end(), 1) ==
        static_cast<std::ptrdiff_t>(last.vertex_count()));
}

TEST_CASE("streak command: a vertex budget and a region of interest, kept and counted",
          "[apps][streak]") {
  test_support::TempDir dir;
  const fs::path pvd = dir.path() / "gyre.pvd", report = dir.path() / "gyre.json";
  const std::string common =
      "streak --field double-gyre --seed line:0.3,0.3,0:0.3,0.45,0 --release 0:6 --frames "
      "2:8:4 --edge 0.02 --out " + pvd.string() + " --report " + report.string();
  {
    // Unbounded, the frames have 99, 186, 263 and 243 vertices.
    const auto r = cli_test::run(common + " --vertex-budget 200");
    INFO(r.output);
    REQUIRE(r.status == 0);
    CHECK(r.output.find("Coarsened dye older than") != std::string::npos);
    CHECK(r.output.find("to keep the vertex budget of 200") != std::string::npos);
    const auto j = nlohmann::json::parse(read_text(report));
    CHECK(j["complete"] == true);
    CHECK(j["refinement"]["budget_coarsenings"].get<int>() >= 1);
    CHECK(j["refinement"]["coarsened"].get<int>() > 0);
    CHECK(j["refinement"]["coarsen_age"].is_number());
    CHECK(j["particles"]["max"].get<int>() <= 200);
    REQUIRE(j["frames"].size() == 4);
    for (int f = 0; f < 4; ++f) {
      INFO("frame " << f);
      CHECK(j["frames"][f]["vertices"].get<int>() <= 200);
      CHECK(j["frames"][f]["quality"]["folds"] == 0);
      CHECK(j["frames"][f]["max_edge_ratio"].get<double>() <= 1.5 + 1e-9);
    }
  }
  {
    const auto r = cli_test::run(common + " --region 0,0:0.6,1");
    INFO(r.output);
    REQUIRE(r.status == 0);
    CHECK(r.output.find("left the region of interest 0,0:0.6,1") != std::string::npos);
    const auto j = nlohmann::json::parse(read_text(report));
    CHECK(j["particles"]["left_region"].get<int>() > 0);
    CHECK(j["particles"]["left_domain"] == 0);
    CHECK(j["refinement"]["coarsen_age"].is_null());
    for (int f = 0; f < 4; ++f) {
      const Mesh m = orthofront::io::read_mesh(dir.path() / "gyre" /
                                               ("gyre_000" + std::to_string(f) + ".vtp"));
      for (const auto& p : m.positions) CHECK(p.x() <= 0.6);
    }
  }
  for (const std::string& bad : {std::string("--region 0.6,0:0,1"),
                                 std::string("--mesh rows --region 0,0:0.6,1"),
                                 std::string("--mesh rows --vertex-budget 10")}) {
    const auto b = cli_test::run(
        "streak --field double-gyre --seed line:0.3,0.3,0:0.3,0.45,0 --release 0:1 --frames 1 " +
        bad + " --out " + (dir.path() / "bad.pvd").string());
    INFO(bad << "\n" << b.output);
    CHECK(b.status == 2);
    CHECK((b.output.find("max below min along x") != std::string::npos ||
           b.output.find("applies to --mesh remeshed only") != std::string::npos));
    CHECK(!fs::exists(dir.path() / "bad.pvd"));
  }
}

TEST_CASE("streak command: bad input exits 2 naming the value and leaves no collection",
          "[apps][streak]") {
  test_support::TempDir dir;
  const fs::path pvd = dir.path() / "bad.pvd";
  const std::string common =
      "streak --seed line:0.3,0.3,0:0.3,0.45,0 --edge 0.03 --out " + pvd.string();
  struct Case {
    std::string args, message;
  };
  const Case cases[] = {
      {"--field double-gyre:eps=0.1 --release 0:3 --frames 1:4:0", "COUNT must be a whole number"},
      {"--field double-gyre --release 0:3 --frames 1,x", "'x' is not a finite number"},
      {"--field double-gyre --release 3:1 --frames 4", "release interval 3:1"},
      {"--field double-gyre --release 0:3 --frames 0", "not after the release begin"},
      {"--field unsteady-abc --release -1:3 --frames 4", "time range"},
      {"--field nosuch.h5 --release 0:1 --frames 1", "neither an unsteady field name"},
  };
  for (const Case& c : cases) {
    const auto r = cli_test::run(common + " " + c.args);
    INFO(c.args << "\n" << r.output);
    CHECK(r.status == 2);
    CHECK(r.output.find(c.message) != std::string::npos);
    CHECK(!fs::exists(pvd));
    CHECK(!fs::exists(dir.path() / "bad"));
  }
  const auto r = cli_test::run(
      "streak --field double-gyre --seed line:0.3,0.3,0:0.3,0.45,0 "
      "--release 0:1 --frames 1 --out " +
      (dir.path() / "no" / "a.pvd").string());
  CHECK(r.status == 2);
  CHECK(r.output.find("does not exist") != std::string::npos);
  const auto wrong = cli_test::run(
      "streak --field double-gyre --seed line:0.3,0.3,0:0.3,0.45,0 "
      "--release 0:1 --frames 1 --out " +
      (dir.path() / "a.vtp").string());
  CHECK(wrong.status == 2);
  CHECK(wrong.output.find(".pvd") != std::string::npos);
}

TEST_CASE("streak command: an HDF5 series streamed under a small budget, each step read once",
          "[apps][streak]") {
  test_support::TempDir dir;
  const fs::path h5 = dir.path() / "gyre.h5";
  const auto g = cli_test::run(
      "generate --field double-gyre --resolution 101,51 --steps 41 "
      "--t1 4 --brick 16 --out " +
      h5.string() + " --quiet");
  REQUIRE(g.status == 0);
  const fs::path pvd = dir.path() / "s.pvd", report = dir.path() / "s.json";
  const auto r = cli_test::run("streak --field " + h5.string() +
                               " --seed line:0.3,0.3,0:0.3,0.45,0 --release 0:2 --frames 1:4:3 "
                               "--edge 0.03 --insert interpolate --cache-budget 1MiB --out " +
                               pvd.string() + " --report " + report.string());
  INFO(r.output);
  REQUIRE(r.status == 0);
  const auto j = nlohmann::json::parse(read_text(report));
  CHECK(j["streamed"] == true);
  CHECK(j["frames_written"] == 3);
  CHECK(j["cache"]["max_reads_of_a_unit"] == 1);
  CHECK(j["cache"]["peak_bytes"].get<std::size_t>() <= (std::size_t{1} << 20));
  CHECK(count(read_text(pvd), "<DataSet ") == 3);
  // The same series as an OpenVDB file (timed grids, read leaf-wise) gives the same frames.
  const fs::path vdb = dir.path() / "gyre.vdb";
  REQUIRE(cli_test::run("convert " + h5.string() + " --out " + vdb.string() + " --quiet").status ==
          0);
  const fs::path vpvd = dir.path() / "v.pvd";
  const auto v = cli_test::run("streak --field " + vdb.string() +
                               " --seed line:0.3,0.3,0:0.3,0.45,0 --release 0:2 --frames 1:4:3 "
                               "--edge 0.03 --insert interpolate --cache-budget 1MiB --out " +
                               vpvd.string());
  INFO(v.output);
  REQUIRE(v.status == 0);
  CHECK(test_support::vtp_geometry_text(dir.path() / "v" / "v_0002.vtp") ==
        test_support::vtp_geometry_text(dir.path() / "s" / "s_0002.vtp"));
  // Past the series' last time: refused before anything is written.
  const auto late = cli_test::run("streak --field " + h5.string() +
                                  " --seed line:0.3,0.3,0:0.3,0.45,0 --release 0:2 --frames 5 "
                                  "--out " +
                                  (dir.path() / "late.pvd").string());
  CHECK(late.status == 2);
  CHECK(late.output.find("[0, 4]") != std::string::npos);
  CHECK(!fs::exists(dir.path() / "late.pvd"));
}

TEST_CASE("streak command: SIGINT keeps the frames written, and the .pvd lists exactly those",
          "[apps][streak][signals]") {
  test_support::TempDir dir;
  const fs::path pvd = dir.path() / "long.pvd", report = dir.path() / "long.json";
  const fs::path log = dir.path() / "log.txt";
  // A long run: a seed across the gyres' boundary stretches exponentially; 200 frames.
  const std::vector<std::string> args{
      "streak",    "--field", "double-gyre", "--seed",      "line:0.9,0.2,0:0.9,0.8,0",
      "--release", "0:10",    "--frames",    "0.05:10:200", "--edge",
      "0.01",      "--out",   pvd.string(),  "--report",    report.string()};
  const pid_t pid = cli_test::start(args, log.string());
  ::usleep(2'000'000);
  ::kill(pid, SIGINT);
  int status = 0;
  ::waitpid(pid, &status, 0);
  INFO(read_text(log));
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 2);
  CHECK(read_text(log).find("interrupted") != std::string::npos);
  std::size_t on_disk = 0;
  for (const auto& entry : fs::directory_iterator(dir.path() / "long")) {
    CHECK(entry.path().extension() == ".vtp");  // no temporary left
    ++on_disk;
  }
  const std::string collection = read_text(pvd);
  CHECK(on_disk > 0);
  CHECK(on_disk < 200);
  CHECK(count(collection, "<DataSet ") == on_disk);
  const auto j = nlohmann::json::parse(read_text(report));
  CHECK(j["complete"] == false);
  CHECK(j["frames_written"] == on_disk);
  char last[64];
  std::snprintf(last, sizeof last, "long_%04zu.vtp", on_disk - 1);
  CHECK(orthofront::io::read_mesh(dir.path() / "long" / last).face_count() > 0);
}

TEST_CASE("streak command: the space-time route writes one surface in (x, y, t)",
          "[apps][streak]") {
  test_support::TempDir dir;
  const fs::path out = dir.path() / "st.vtp";
  const auto r = cli_test::run(
      "streak --route spacetime --field double-gyre --point 0.3,0.375 "
      "--release 0:3 --frames 5 --edge 0.02 --out " +
      out.string());
  INFO(r.output);
  REQUIRE(r.status == 0);
  const Mesh mesh = orthofront::io::read_mesh(out);
  REQUIRE(mesh.face_count() > 100);
  double t_min = 1e9, t_max = -1e9;
  for (const auto& p : mesh.positions)
    t_min = std::min(t_min, p.z()), t_max = std::max(t_max, p.z());
  CHECK(t_min >= 0);
  CHECK(t_min < 0.01);
  CHECK(t_max <= 5 + 1e-9);
  CHECK(t_max > 4.9);
  const auto pvd = cli_test::run(
      "streak --route spacetime --field double-gyre --point 0.3,0.375 "
      "--release 0:3 --frames 5 --out " +
      (dir.path() / "a.pvd").string());
  CHECK(pvd.status == 2);
  CHECK(pvd.output.find(".vtp, .ply or .obj") != std::string::npos);
  const auto three_d = cli_test::run(
      "streak --route spacetime --field unsteady-abc --point 1,1 "
      "--release 0:3 --frames 5 --out " +
      out.string());
  CHECK(three_d.status == 2);
  CHECK(three_d.output.find("needs a 2D flow") != std::string::npos);
}

TEST_CASE("streak command: the streak-line route writes one surface in (x, y, age) per frame",
          "[apps][streak]") {
  test_support::TempDir dir;
  const fs::path pvd = dir.path() / "wt.pvd", report = dir.path() / "wt.json";
  const auto r = cli_test::run(
      "streak --route streak-line --field double-gyre --seed line:0.3,0.3,0:0.3,0.45,0 "
      "--release 0:3 --frames 2,4 --edge 0.03 --out " +
      pvd.string() + " --report " + report.string());
  INFO(r.output);
  REQUIRE(r.status == 0);
  CHECK(count(read_text(pvd), "<DataSet ") == 2);
  const auto j = nlohmann::json::parse(read_text(report));
  CHECK(j["route"] == "streak-line");
  CHECK(j["complete"] == true);
  REQUIRE(j["frames"].size() == 2);
  for (int k = 0; k < 2; ++k) {
    const double t = k == 0 ? 2.0 : 4.0;
    const Mesh m =
        orthofront::io::read_mesh(dir.path() / "wt" / ("wt_000" + std::to_string(k) + ".vtp"));
    CHECK(j["frames"][k]["quality"]["vertices"] == m.vertex_count());
    CHECK(j["frames"][k]["quality"]["folds"] == 0);
    CHECK(j["frames"][k]["quality"]["t_junctions"] == 0);
    REQUIRE(m.release_time.size() == m.vertex_count());
    // z is the age: observation time minus release time, within the release interval.
    for (std::size_t i = 0; i < m.vertex_count(); ++i) {
      REQUIRE(m.positions[i].z() == Approx(t - m.release_time[i]).margin(1e-12));
      REQUIRE(m.release_time[i] >= -1e-9);
      REQUIRE(m.release_time[i] <= std::min(t, 3.0) + 1e-9);
    }
  }
  // Gridded series and 3D flows are refused, naming what was given.
  const auto three_d = cli_test::run(
      "streak --route streak-line --field unsteady-abc --seed line:1,1,1:1,2,1 --release 0:3 "
      "--frames 2 --out " +
      (dir.path() / "b.pvd").string());
  CHECK(three_d.status == 2);
  CHECK(three_d.output.find("needs a 2D flow") != std::string::npos);
  const auto series = cli_test::run(
      "streak --route streak-line --field nothing.h5 --seed line:1,1,1:1,2,1 --release 0:3 "
      "--frames 2 --out " +
      (dir.path() / "c.pvd").string());
  CHECK(series.status == 2);
  CHECK(series.output.find("takes an unsteady analytic 2D field, not 'nothing.h5'") !=
        std::string::npos);
  CHECK(!fs::exists(dir.path() / "b.pvd"));
  CHECK(!fs::exists(dir.path() / "c.pvd"));
}

TEST_CASE(
    "streak command: --device moves particles by bulk advection, the same frames under any "
    "budget, and names what it cannot do",
    "[apps][streak][advect]") {
  test_support::TempDir dir;
  const fs::path h5 = dir.path() / "gyre.h5";
  REQUIRE(cli_test::run("generate --field double-gyre --resolution 101,51 --steps 41 --t1 4 "
                        "--brick 16 --out " +
                        h5.string() + " --quiet")
              .status == 0);
  const auto streak = [&](const std::string& name, const std::string& extra) {
    return cli_test::run("streak --field " + h5.string() +
                         " --seed line:0.3,0.3,0:0.3,0.45,0 --release 0:2 --frames 1:4:3 "
                         "--edge 0.03 --insert interpolate --mesh rows --out " +
                         (dir.path() / (name + ".pvd")).string() + " --report " +
                         (dir.path() / (name + ".json")).string() + " " + extra);
  };
  const auto big = streak("big", "--device cpu");
  INFO(big.output);
  REQUIRE(big.status == 0);
  const auto small = streak("small", "--device cpu --cache-budget 1MiB");
  INFO(small.output);
  REQUIRE(small.status == 0);
  for (const char* frame : {"_0000.vtp", "_0001.vtp", "_0002.vtp"})
    CHECK(read_text(dir.path() / "big" / (std::string("big") + frame)) ==
          read_text(dir.path() / "small" / (std::string("small") + frame)));
  const auto j = nlohmann::json::parse(read_text(dir.path() / "small.json"));
  CHECK(j["device"]["backend"] == "cpu");
  CHECK(j["device"]["slabs"].get<std::size_t>() > 0);
  CHECK(j["device"]["particle_steps"].get<std::size_t>() > 0);
  CHECK(j["frames_written"] == 3);
  // An analytic field has no grid to move through.
  const auto analytic = cli_test::run(
      "streak --field double-gyre --seed line:0.3,0.3,0:0.3,0.45,0 --release 0:2 --frames 1:4:3 "
      "--device cpu --out " +
      (dir.path() / "a.pvd").string());
  CHECK(analytic.status == 2);
  CHECK(analytic.output.find("--device") != std::string::npos);
  CHECK(!fs::exists(dir.path() / "a.pvd"));
  // Without a CUDA device (or a CUDA build), --device cuda says why and writes nothing.
  // With one, its frames are the CPU backend's, byte for byte.
  const auto cuda = streak("cuda", "--device cuda");
  if (cuda.status != 0) {
    CHECK(cuda.status == 2);
    CHECK(cuda.output.find("--device cuda:") != std::string::npos);
    CHECK(!fs::exists(dir.path() / "cuda.pvd"));
  } else {
    for (const char* frame : {"_0000.vtp", "_0001.vtp", "_0002.vtp"})
      CHECK(read_text(dir.path() / "big" / (std::string("big") + frame)) ==
            read_text(dir.path() / "cuda" / (std::string("cuda") + frame)));
  }
  // Rows released between breaks (four releases a break) go there in a call of their own: the
  // same on both backends too.
  const auto cpu4 = streak("cpu4", "--device cpu --releases-per-break 4");
  INFO(cpu4.output);
  REQUIRE(cpu4.status == 0);
  CHECK(read_text(dir.path() / "cpu4" / "cpu4_0002.vtp") != read_text(dir.path() / "big" / "big_0002.vtp"));
  if (cuda.status == 0) {
    const auto cuda4 = streak("cuda4", "--device cuda --releases-per-break 4");
    REQUIRE(cuda4.status == 0);
    for (const char* frame : {"_0000.vtp", "_0001.vtp", "_0002.vtp"})
      CHECK(read_text(dir.path() / "cpu4" / (std::string("cpu4") + frame)) ==
            read_text(dir.path() / "cuda4" / (std::string("cuda4") + frame)));
  }
}

TEST_CASE(
    "path command: --device advances the front by bulk advection, the same mesh under any "
    "budget, and names what it cannot do",
    "[apps][path][advect]") {
  test_support::TempDir dir;
  const fs::path h5 = dir.path() / "abc.h5";
  REQUIRE(cli_test::run("generate --field unsteady-abc --resolution 24,24,24 --box 0,0,0:6.3,6.3,6.3 "
                        "--steps 21 --t1 2 --brick 8 --out " +
                        h5.string() + " --quiet")
              .status == 0);
  const auto path = [&](const std::string& name, const std::string& extra) {
    return cli_test::run("path --field " + h5.string() +
                         " --seed line:1,1,2:5,5,2 --t1 1.5 --edge 0.1 --out " +
                         (dir.path() / (name + ".ply")).string() + " --report " +
                         (dir.path() / (name + ".json")).string() + " " + extra);
  };
  const auto big = path("big", "--device cpu");
  INFO(big.output);
  REQUIRE(big.status == 0);
  const auto small = path("small", "--device cpu --cache-budget 2MiB");
  INFO(small.output);
  REQUIRE(small.status == 0);
  CHECK(read_text(dir.path() / "big.ply") == read_text(dir.path() / "small.ply"));
  const auto j = nlohmann::json::parse(read_text(dir.path() / "small.json"));
  CHECK(j["path"]["device"]["backend"] == "cpu");
  CHECK(j["path"]["device"]["calls"].get<std::size_t>() >= j["steps"].get<std::size_t>());
  CHECK(j["path"]["device"]["particle_steps"].get<std::size_t>() > 0);
  CHECK(j["path"]["complete"] == true);
  // auto without a front of the break-even size: the per-vertex surface.
  REQUIRE(path("auto", "--device auto").status == 0);
  REQUIRE(path("plain", "").status == 0);
  CHECK(read_text(dir.path() / "auto.ply") == read_text(dir.path() / "plain.ply"));
  // An analytic field has no grid to move through.
  const auto analytic = cli_test::run("path --field unsteady-abc --seed line:1,1,2:5,5,2 --t1 0.5 "
                                      "--device cpu --out " + (dir.path() / "a.ply").string());
  CHECK(analytic.status == 2);
  CHECK(analytic.output.find("--device") != std::string::npos);
  CHECK(!fs::exists(dir.path() / "a.ply"));
  // Without a CUDA device (or a CUDA build), --device cuda says why and writes nothing.
  const auto cuda = path("cuda", "--device cuda");
  if (cuda.status != 0) {
    CHECK(cuda.status == 2);
    CHECK(cuda.output.find("--device cuda:") != std::string::npos);
    CHECK(!fs::exists(dir.path() / "cuda.ply"));
  }
}
