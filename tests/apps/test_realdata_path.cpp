// Path surfaces through real time series: all 10 tornado steps and the 6 POP steps, converted to
// the HDF5 layout and streamed through the time-step cache. [realdata]: skipped visibly when
// ../shared/datasets is absent.
#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <nlohmann/json.hpp>
#include <string>

#include "apps/realdata_support.h"
#include "orthofront/io/mesh_io.h"
#include "orthofront/quality/quality.h"

namespace fs = std::filesystem;

namespace {

using realdata_test::fresh_dir;
using realdata_test::run;
using realdata_test::text_of;

/// Runs `path` on `h5` and checks what holds for any path surface through real data: a complete
/// run, every brick read exactly once, a manifold mesh without T-junctions or degenerate
/// faces, finite positions, vertex times inside [t0, t1]. Folds are reported, not asserted: a
/// path surface seen in space folds where a material line turns tangent to the flow.
void check_path(const fs::path& dir, const fs::path& h5, const std::string& args, double t0,
                double t1, std::size_t steps) {
  const fs::path out = dir / "surface.vtp", report = dir / "report.json", log = dir / "log.txt";
  const int status = run(std::string(ORTHOFRONT_BINARY) + " path --field '" + h5.string() + "' " +
                             args + " --out '" + out.string() + "' --report '" +
                             report.string() + "'",
                         log);
  INFO(text_of(log));
  REQUIRE(status == 0);
  const auto r = nlohmann::json::parse(text_of(report));
  CHECK(r["complete"].get<bool>());
  const auto& reads = r["path"]["cache"]["units_read_per_step"];
  REQUIRE(reads.size() == steps);
  for (const auto& n : reads) CHECK(n.get<int>() >= 1);
  CHECK(r["path"]["cache"]["max_reads_of_a_unit"].get<int>() == 1);
  const orthofront::Mesh mesh = orthofront::io::read_mesh(out);
  REQUIRE(mesh.vertex_count() > 500);
  const orthofront::QualityReport q = orthofront::measure_quality(mesh);
  CHECK(q.non_manifold_edges == 0);
  CHECK(q.t_junctions == 0);
  CHECK(q.degenerate_faces == 0);
  CHECK(q.inconsistent_edges == 0);
  CHECK(q.quad_share > 0.9);
  double t_max = t0;
  for (std::size_t i = 0; i < mesh.vertex_count(); ++i) {
    REQUIRE(mesh.positions[i].allFinite());
    // The last front step may overshoot t1 by a fraction of a step (seen: 4e-4 of the span).
    CHECK(mesh.time[i] >= t0 - 1e-9 * (t1 - t0));
    CHECK(mesh.time[i] <= t1 + 1e-3 * (t1 - t0));
    t_max = std::max(t_max, mesh.time[i]);
  }
  CHECK(t_max > t0 + 0.5 * (t1 - t0));
  WARN("path surface: " << mesh.vertex_count() << " vertices, " << q.quad_share * 100
                        << "% quads, " << q.folds << " folds in the spatial projection");
}

}  // namespace

TEST_CASE("a path surface through all 10 tornado steps", "[apps][path][realdata]") {
  const fs::path data = fs::path(ORTHOFRONT_DATASETS_DIR) / "tornado";
  if (!fs::exists(data / "10.vec")) {
    WARN("skipped: " << data.string() << " not found");
    return;
  }
  const fs::path dir = fresh_dir("tornado");
  const fs::path h5 = dir / "tornado.h5";
  std::string inputs;
  for (int i = 1; i <= 10; ++i) inputs += " '" + (data / (std::to_string(i) + ".vec")).string() + "'";
  REQUIRE(run(std::string(ORTHOFRONT_BINARY) + " convert" + inputs + " --dt 10 --out '" +
                  h5.string() + "'",
              dir / "convert.txt") == 0);
  check_path(dir, h5,
             "--seed line:14,24,5:34,24,5 --seed-count 20 --t0 0 --t1 90 --edge 0.5 "
             "--cache-budget 64MiB",
             0, 90, 10);
}

#ifdef ORTHOFRONT_POP_CONVERT  // builds that read NetCDF
TEST_CASE("a path surface through the 6 POP steps, land as no data", "[apps][path][realdata]") {
  const fs::path data = fs::path(ORTHOFRONT_DATASETS_DIR) / "pop-southern-ocean";
  if (!fs::exists(data)) {
    WARN("skipped: " << data.string() << " not found");
    return;
  }
  const fs::path dir = fresh_dir("pop");
  const fs::path h5 = dir / "pop.h5";
  // The files carry no time: 30 days between steps (a monthly series) is an assumption.
  REQUIRE(run(std::string("'") + ORTHOFRONT_POP_CONVERT + "' " + (data / "*.nc").string() +
                  " --dt 2592000 --out '" + h5.string() + "'",
              dir / "convert.txt") == 0);
  check_path(dir, h5,
             "--seed line:60,-50,-10:80,-50,-10 --seed-count 40 --t0 0 --t1 1.296e7 --edge 0.3 "
             "--cache-budget 128MiB",
             0, 1.296e7, 6);
}
#endif

TEST_CASE("a path surface of the backward-facing step over its whole series, written in "
          "(x, y, c t)",
          "[apps][path][realdata]") {
  const fs::path pvd = fs::path(ORTHOFRONT_DATASETS_DIR) / "pitzdaily-les" / "step.pvd";
  if (!fs::exists(pvd)) {
    WARN("skipped: " << pvd.string() << " not found");
    return;
  }
  const fs::path dir = fresh_dir("path-step");
  const fs::path out = dir / "surface.vtp", report = dir / "report.json", log = dir / "log.txt";
  // The streak test's seed, its particles followed from 0.03 to 0.07; ℓ four cells.
  const double edge = 0.002;
  const int status =
      run(std::string(ORTHOFRONT_BINARY) + " path --field '" + pvd.string() +
              "' --seed line:-0.002,0.0003,0:-0.002,0.0063,0 --seed-count 7 --t0 0.03 --t1 0.07 "
              "--edge 0.002 --out '" + out.string() + "' --report '" + report.string() + "'",
          log);
  INFO(text_of(log));
  REQUIRE(status == 0);
  const auto r = nlohmann::json::parse(text_of(report));
  CHECK(r["complete"].get<bool>());
  CHECK(r["path"]["positions"] == "x, y, c t");
  CHECK(r["zero_vectors"] == "no data");  // the step's wall, as the .vti files have it
  CHECK(r["path"]["cache"]["max_reads_of_a_unit"].get<int>() == 1);
  const double c = r["path"]["time_scale"].get<double>();
  const orthofront::Mesh mesh = orthofront::io::read_mesh(out);
  REQUIRE(mesh.vertex_count() > 1000);
  // Measured on the file as written: the surface the engine built.
  const orthofront::QualityReport q = orthofront::measure_quality(mesh);
  CHECK(q.folds == 0);
  CHECK(q.non_manifold_edges == 0);
  CHECK(q.t_junctions == 0);
  CHECK(q.degenerate_faces == 0);
  CHECK(q.inconsistent_edges == 0);
  CHECK(q.longest_edge <= 2 * edge);
  CHECK(q.quad_angles_within_10 > 0.9);
  double t_max = 0;
  for (std::size_t i = 0; i < mesh.vertex_count(); ++i) {
    REQUIRE(mesh.positions[i].allFinite());
    CHECK(mesh.positions[i].z() == Approx(c * mesh.time[i]).margin(1e-9));
    CHECK(mesh.positions[i].x() <= 0.2901);
    t_max = std::max(t_max, mesh.time[i]);
  }
  CHECK(t_max == Approx(0.07).margin(1e-4));
  WARN("step path surface: " << mesh.vertex_count() << " vertices, " << q.quad_share * 100
                             << "% quads, " << q.quad_angles_within_10 * 100
                             << "% of quad angles within 90±10° as written, " << q.folds
                             << " folds, " << r["times_s"]["total"] << " s");
}
