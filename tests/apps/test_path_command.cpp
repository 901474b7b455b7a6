#include <hdf5.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>

#include "orthofront/field/unsteady.h"
#include "orthofront/io/hdf5_layout.h"
#include "orthofront/io/mesh_io.h"
#include "orthofront/quality/quality.h"
#include "orthofront/spacetime/sampled_series.h"
#include "temp_dir.h"

namespace fs = std::filesystem;
using test_support::read_text;
using namespace orthofront;

namespace {

fs::path fresh_dir() {
  std::random_device rd;
  const fs::path dir = fs::temp_directory_path() / ("orthofront-path-" + std::to_string(rd()));
  fs::create_directories(dir);
  return dir;
}

int run(const std::string& args, const fs::path& log) {
  const std::string command =
      std::string(ORTHOFRONT_BINARY) + " " + args + " > " + log.string() + " 2>&1";
  return WEXITSTATUS(std::system(command.c_str()));
}

// A double-gyre time series on disk, in the project's HDF5 layout.
fs::path write_gyre(const fs::path& dir, std::size_t steps) {
  const auto flow = make_unsteady_field("double-gyre");
  spacetime::SampledTimeSeries series(
      *flow, spacetime::uniform_grid(flow->domain(), 2, 81),
      spacetime::uniform_times(0, 0.1 * static_cast<double>(steps - 1), steps - 1));
  const fs::path file = dir / "gyre.h5";
  io::Hdf5WriteOptions o;
  o.gzip_level = 1;
  o.zero_is_no_data = false;
  std::vector<double> times;
  for (std::size_t k = 0; k < series.step_count(); ++k) times.push_back(series.time(k));
  io::Hdf5SeriesWriter writer(file, series.geometry(), 3, times, o);
  std::vector<float> values(series.step_floats());
  for (std::size_t k = 0; k < series.step_count(); ++k) {
    series.sample(k, values.data());
    writer.write_step(values);
  }
  writer.commit();
  return file;
}

}  // namespace

TEST_CASE("path command: analytic field, report with c and the time band", "[apps][path]") {
  const fs::path dir = fresh_dir();
  const fs::path out = dir / "gyre.vtp", report = dir / "gyre.json";
  REQUIRE(run("path --field double-gyre --seed line:0.3,0.25,0:0.9,0.7,0 --seed-count 8 --t0 0 "
              "--t1 4 --edge 0.05 --out " +
                  out.string() + " --report " + report.string(),
              dir / "log") == 0);
  const nlohmann::json j = nlohmann::json::parse(read_text(report));
  CHECK(j["complete"] == true);
  CHECK(j["zero_vectors"] == "flow");  // an analytic flow's zeros are stagnation points
  // The summary gives the quality figures of the report.
  char quads[64];
  std::snprintf(quads, sizeof quads, "%.1f%% quads",
                100.0 * j["quality"]["quad_share"].get<double>());
  const std::string summary = read_text(dir / "log");
  CHECK(summary.find(quads) != std::string::npos);
  CHECK(summary.find(std::to_string(j["quality"]["folds"].get<std::size_t>()) + " folds") !=
        std::string::npos);
  CHECK(j["path"]["time_scale_source"] == "median seed speed");
  CHECK(j["path"]["time_scale"].get<double>() > 0.1);
  CHECK(j["path"]["time_reached"].get<double>() == Approx(4.0).epsilon(1e-3));
  CHECK(j["path"]["band"].size() == j["steps"].get<std::size_t>());
  const Mesh mesh = io::read_mesh(out);
  REQUIRE(mesh.vertex_count() == j["counts"]["vertices"].get<std::size_t>());
  const double c = j["path"]["time_scale"].get<double>();
  double tmax = 0;
  for (std::size_t i = 0; i < mesh.vertex_count(); ++i) {
    CHECK(mesh.positions[i][2] == Approx(c * mesh.time[i]).margin(1e-9));  // (x, y, c t)
    tmax = std::max(tmax, mesh.time[i]);
  }
  CHECK(tmax > 3.97);  // path lines end within one front step of t1
  CHECK(tmax <= 4.0 + 1e-9);
  // A 2D flow's surface, written as the surface that was built: the quality of the file as
  // written is the report's.
  CHECK(j["path"]["positions"] == "x, y, c t");
  const QualityReport written = measure_quality(mesh);
  CHECK(written.folds == j["quality"]["folds"].get<std::size_t>());
  CHECK(written.quad_angles_within_10 ==
        Approx(j["quality"]["quad_angles_within_10deg"].get<double>()).margin(1e-3));
  // --flat presses it into the plane, and says so; the same vertices otherwise.
  const fs::path flat = dir / "flat.vtp", flat_report = dir / "flat.json";
  REQUIRE(run("path --field double-gyre --seed line:0.3,0.25,0:0.9,0.7,0 --seed-count 8 --t0 0 "
              "--t1 4 --edge 0.05 --flat --out " +
                  flat.string() + " --report " + flat_report.string(),
              dir / "log") == 0);
  CHECK(nlohmann::json::parse(read_text(flat_report))["path"]["positions"] == "x, y, 0 (flat)");
  const Mesh pressed = io::read_mesh(flat);
  REQUIRE(pressed.vertex_count() == mesh.vertex_count());
  for (std::size_t i = 0; i < mesh.vertex_count(); ++i) {
    CHECK(pressed.positions[i][2] == 0);
    CHECK(pressed.positions[i].head<2>() == mesh.positions[i].head<2>());
  }
  CHECK(run("path --field double-gyre --seed line:0.3,0.25,0:0.9,0.7,0 --t1 1 --flat "
            "--spacetime-out --out " + flat.string(),
            dir / "log") != 0);
  // --time-scale overrides and is reported.
  REQUIRE(run("path --field double-gyre --seed line:0.3,0.25,0:0.9,0.7,0 --seed-count 8 --t1 1 "
              "--edge 0.05 --time-scale 0.5 --out " +
                  out.string() + " --report " + report.string(),
              dir / "log") == 0);
  CHECK(nlohmann::json::parse(read_text(report))["path"]["time_scale"] == 0.5);
  fs::remove_all(dir);
}

// (No ";" in test names: catch_discover_tests splits the name there and the halves match nothing.)
TEST_CASE("path command: HDF5 series through the cache, and errors that leave no file",
          "[apps][path]") {
  const fs::path dir = fresh_dir();
  const fs::path h5 = write_gyre(dir, 41);
  const fs::path out = dir / "s.ply", report = dir / "s.json";
  REQUIRE(run("path --field " + h5.string() +
                  " --seed line:0.3,0.25,0:0.9,0.7,0 --seed-count 8 --t1 3 --edge 0.05 "
                  "--cache-budget 2MiB --out " +
                  out.string() + " --report " + report.string(),
              dir / "log") == 0);
  const nlohmann::json j = nlohmann::json::parse(read_text(report));
  CHECK(j["path"]["streamed"] == true);
  CHECK(j["stop_reason"] == "end_time");  // t1 reached: not "left the domain"
  // The 41 steps end at t = 4: a t1 past them stops there, and says so.
  const fs::path short_out = dir / "short.vtp", short_report = dir / "short.json";
  CHECK(run("path --field " + h5.string() +
                " --seed line:0.3,0.25,0:0.9,0.7,0 --seed-count 8 --t0 3 --t1 5 --edge 0.05 --out " +
                short_out.string() + " --report " + short_report.string(),
            dir / "log_short") != 0);
  const nlohmann::json shortened = nlohmann::json::parse(read_text(short_report));
  CHECK(shortened["complete"] == false);
  CHECK_THAT(shortened["message"].get<std::string>(),
             Catch::Contains("the data end at t = 4") && Catch::Contains("before t1 = 5"));
  CHECK_THAT(read_text(dir / "log_short"), Catch::Contains("the data end at t = 4"));
  CHECK(j["path"]["cache"]["peak_bytes"].get<std::size_t>() <= (2u << 20));
  CHECK(j["path"]["cache"]["loads"].get<std::size_t>() >= 31);
  CHECK(j["path"]["time_reached"].get<double>() == Approx(3.0).epsilon(1e-3));
  CHECK(io::read_mesh(out).vertex_count() == j["counts"]["vertices"].get<std::size_t>());

  const fs::path none = dir / "none.vtp";
  CHECK(run("path --field " + h5.string() +
                " --seed line:0.3,0.25,0:0.9,0.7,0 --t1 3 --cache-budget 100KiB --out " +
                none.string(),
            dir / "log2") == 2);
  CHECK_THAT(read_text(dir / "log2"), Catch::Contains("cache budget 100 KiB is too small"));
  CHECK_FALSE(fs::exists(none));
  CHECK(run("path --field nothing-here --seed line:0,0,0:1,1,0 --out " + none.string(),
            dir / "log3") == 2);
  CHECK_THAT(read_text(dir / "log3"), Catch::Contains("'nothing-here'"));
  CHECK_FALSE(fs::exists(none));
  fs::remove_all(dir);
}

TEST_CASE("path command: a ParaView collection and a glob of its files are read directly, as "
          "their HDF5 conversion is",
          "[apps][path]") {
  test_support::TempDir dir;
  // Eleven steps of the double gyre on 41 x 21 points as inline-ascii .vti, listed by a .pvd.
  const auto gyre = make_unsteady_field("double-gyre");
  std::string collection = "<VTKFile type=\"Collection\" version=\"0.1\"><Collection>\n";
  for (int step = 0; step <= 10; ++step) {
    const double t = 0.2 * step;
    std::string text =
        "<VTKFile type=\"ImageData\"><ImageData WholeExtent=\"0 40 0 20 0 0\" Origin=\"0 0 0\" "
        "Spacing=\"0.05 0.05 1\"><Piece Extent=\"0 40 0 20 0 0\"><PointData><DataArray "
        "type=\"Float32\" Name=\"v\" NumberOfComponents=\"3\" format=\"ascii\">";
    for (int j = 0; j <= 20; ++j)
      for (int i = 0; i <= 40; ++i) {
        Vec3 v;
        REQUIRE(gyre->velocity(Vec3(0.05 * i, 0.05 * j, 0), t, v) == FieldStatus::inside);
        text += std::to_string(v.x()) + " " + std::to_string(v.y()) + " 0 ";
      }
    text += "</DataArray></PointData></Piece></ImageData></VTKFile>";
    const std::string name = "s" + std::to_string(step) + ".vti";
    std::ofstream(dir / name) << text;
    collection +=
        "<DataSet timestep=\"" + std::to_string(t) + "\" part=\"0\" file=\"" + name + "\"/>\n";
  }
  std::ofstream(dir / "gyre.pvd") << collection + "</Collection></VTKFile>\n";
  const std::string surface =
      " --seed line:0.3,0.25,0:0.9,0.7,0 --seed-count 8 --t1 1.6 --edge 0.05 --cache-budget 1MiB";
  REQUIRE(run("path --field " + (dir / "gyre.pvd").string() + surface + " --out " +
                  (dir / "pvd.vtp").string(),
              dir / "log1") == 0);
  REQUIRE(run("convert " + (dir / "gyre.pvd").string() + " --out " + (dir / "gyre.h5").string(),
              dir / "log2") == 0);
  REQUIRE(run("path --field " + (dir / "gyre.h5").string() + surface + " --out " +
                  (dir / "h5.vtp").string(),
              dir / "log3") == 0);
  INFO(read_text(dir / "log1"));
  CHECK(io::read_mesh(dir / "pvd.vtp").vertex_count() > 100);
  CHECK(test_support::vtp_geometry_text(dir / "pvd.vtp") ==
        test_support::vtp_geometry_text(dir / "h5.vtp"));
  // The same files as a glob, one step a file at i dt: the same surface (t = 3 dt may differ
  // from the collection's decimal 0.6 in the last bit, so positions are compared to 1e-9).
  REQUIRE(run("path --field '" + (dir / "s*.vti").string() + ":dt=0.2'" + surface + " --out " +
                  (dir / "glob.vtp").string(),
              dir / "log4") == 0);
  INFO(read_text(dir / "log4"));
  const Mesh from_pvd = io::read_mesh(dir / "pvd.vtp");
  const Mesh from_glob = io::read_mesh(dir / "glob.vtp");
  REQUIRE(from_glob.vertex_count() == from_pvd.vertex_count());
  CHECK(from_glob.faces == from_pvd.faces);
  double largest = 0;
  for (std::size_t i = 0; i < from_pvd.vertex_count(); ++i)
    largest = std::max(largest, (from_glob.positions[i] - from_pvd.positions[i]).norm());
  CHECK(largest < 1e-9);
}

TEST_CASE("path command: a step deleted from a per-step series keeps the surface up to it",
          "[apps][path]") {
  const fs::path dir = fresh_dir();
  const fs::path h5 = dir / "gyre.h5", out = dir / "gyre.vtp", report = dir / "gyre.json",
                 log = dir / "log.txt";
  REQUIRE(run("generate --field double-gyre --resolution 41,21 --steps 80 --t1 8 --layout per-step "
              "--out " +
                  h5.string(),
              log) == 0);
  {
    const hid_t f = H5Fopen(h5.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    REQUIRE(f >= 0);
    REQUIRE(H5Ldelete(f, "/steps/000020", H5P_DEFAULT) >= 0);
    H5Fclose(f);
  }
  const int status = run("path --field " + h5.string() +
                             " --seed line:0.3,0.25,0:0.9,0.7,0 --t0 0 --t1 6 --edge 0.05"
                             " --out " +
                             out.string() + " --report " + report.string(),
                         log);
  const std::string text = read_text(log);
  INFO(text);
  CHECK(status == 2);
  CHECK(text.find("no dataset '/steps/000020' (step 20 of 80)") != std::string::npos);
  CHECK(text.find("gyre.h5") != std::string::npos);
  REQUIRE(fs::exists(out));  // the partial surface
  const auto r = nlohmann::json::parse(read_text(report));
  CHECK_FALSE(r["complete"].get<bool>());
  CHECK(r["path"]["time_reached"].get<double>() <= 2.0 + 1e-9);
  CHECK(r["path"]["time_reached"].get<double>() > 1.0);
  CHECK(io::read_mesh(out).vertex_count() > 20);
  fs::remove_all(dir);
}
