// Streak surfaces through real time series: the 10 tornado steps and the 6 POP steps, converted
// to the HDF5 layout and streamed one step interval at a time. [realdata]: skipped visibly when
// ../shared/datasets is absent.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "apps/realdata_support.h"
#include "orthofront/io/mesh_io.h"
#include "orthofront/quality/quality.h"

namespace fs = std::filesystem;

namespace {

using realdata_test::fresh_dir;
using realdata_test::run;
using realdata_test::text_of;

// Runs `streak` with interpolated insertion and checks: a complete run, every frame on disk and
// listed, each step read once, and every frame a valid mesh (manifold, no T-junctions, no
// degenerate faces, consistent orientation, finite positions, ages within the run).
void check_streak(const fs::path& dir, const fs::path& h5, const std::string& args,
                  std::size_t frames) {
  const fs::path pvd = dir / "streak.pvd", report = dir / "report.json", log = dir / "log.txt";
  const int status = run(std::string(ORTHOFRONT_BINARY) + " streak --field '" + h5.string() +
                             "' " + args + " --insert interpolate --out '" + pvd.string() +
                             "' --report '" + report.string() + "'",
                         log);
  INFO(text_of(log));
  REQUIRE(status == 0);
  const auto r = nlohmann::json::parse(text_of(report));
  CHECK(r["complete"].get<bool>());
  CHECK(r["cache"]["max_reads_of_a_unit"].get<int>() == 1);
  REQUIRE(r["frames"].size() == frames);
  for (std::size_t f = 0; f < frames; ++f) {
    char name[32];
    std::snprintf(name, sizeof name, "streak_%04zu.vtp", f);
    const orthofront::Mesh mesh = orthofront::io::read_mesh(dir / "streak" / name);
    INFO("frame " << f);
    REQUIRE(mesh.face_count() > 0);
    CHECK(mesh.vertex_count() == r["frames"][f]["vertices"].get<std::size_t>());
    const orthofront::QualityReport q = orthofront::measure_quality(mesh);
    CHECK(q.non_manifold_edges == 0);
    CHECK(q.t_junctions == 0);
    CHECK(q.degenerate_faces == 0);
    CHECK(q.inconsistent_edges == 0);
    for (std::size_t i = 0; i < mesh.vertex_count(); ++i) {
      REQUIRE(mesh.positions[i].allFinite());
      CHECK(mesh.age[i] >= 0);
    }
  }
  const auto& last = r["frames"].back();
  WARN("streak surface, last frame: " << last["vertices"] << " vertices, "
                                      << last["quality"]["quad_share"] << " quads, "
                                      << last["quality"]["folds"] << " folds");
}

}  // namespace

TEST_CASE("a streak surface through the 10 tornado steps", "[apps][streak][realdata]") {
  const fs::path data = fs::path(ORTHOFRONT_DATASETS_DIR) / "tornado";
  if (!fs::exists(data / "10.vec")) {
    WARN("skipped: " << data.string() << " not found");
    return;
  }
  const fs::path dir = fresh_dir("streak-tornado");
  const fs::path h5 = dir / "tornado.h5";
  std::string inputs;
  for (int i = 1; i <= 10; ++i) inputs += " '" + (data / (std::to_string(i) + ".vec")).string() + "'";
  REQUIRE(run(std::string(ORTHOFRONT_BINARY) + " convert" + inputs + " --dt 10 --out '" +
                  h5.string() + "'",
              dir / "convert.txt") == 0);
  check_streak(dir, h5,
               "--seed line:14,24,5:34,24,5 --release 0:40 --frames 10:90:9 --edge 0.5 "
               "--cache-budget 64MiB",
               9);
}

#ifdef ORTHOFRONT_POP_CONVERT  // builds that read NetCDF
TEST_CASE("a streak surface through the 6 POP steps, land as no data", "[apps][streak][realdata]") {
  const fs::path data = fs::path(ORTHOFRONT_DATASETS_DIR) / "pop-southern-ocean";
  if (!fs::exists(data)) {
    WARN("skipped: " << data.string() << " not found");
    return;
  }
  const fs::path dir = fresh_dir("streak-pop");
  const fs::path h5 = dir / "pop.h5";
  // The files carry no time: 30 days between steps (a monthly series) is an assumption.
  REQUIRE(run(std::string("'") + ORTHOFRONT_POP_CONVERT + "' " + (data / "*.nc").string() +
                  " --dt 2592000 --out '" + h5.string() + "'",
              dir / "convert.txt") == 0);
  check_streak(dir, h5,
               "--seed line:60,-50,-10:80,-50,-10 --release 0:6.48e6 --frames 2.592e6:1.296e7:5 "
               "--edge 0.3 --cache-budget 128MiB",
               5);
}
#endif

TEST_CASE("a remeshed streak surface of the backward-facing step over its whole series "
          "(ParaView's .pvd as written)",
          "[apps][streak][realdata]") {
  const fs::path pvd_in = fs::path(ORTHOFRONT_DATASETS_DIR) / "pitzdaily-les" / "step.pvd";
  if (!fs::exists(pvd_in)) {
    WARN("skipped: " << pvd_in.string() << " not found");
    return;
  }
  const fs::path dir = fresh_dir("streak-step");
  const fs::path pvd = dir / "streak.pvd", report = dir / "report.json", log = dir / "log.txt";
  // A 6 mm line across the inlet's boundary layer 2 mm before the step's edge, released over
  // the whole series (0.04 s, more than one flow-through); ℓ two cells.
  const double edge = 0.001;
  const std::size_t frames = 8;
  const int status =
      run(std::string(ORTHOFRONT_BINARY) + " streak --field '" + pvd_in.string() +
              "' --seed line:-0.002,0.0003,0:-0.002,0.0063,0 --release 0.03:0.07 "
              "--frames 0.035:0.07:8 --edge 0.001 --out '" + pvd.string() + "' --report '" +
              report.string() + "'",
          log);
  INFO(text_of(log));
  REQUIRE(status == 0);
  const auto r = nlohmann::json::parse(text_of(report));
  CHECK(r["complete"].get<bool>());
  CHECK(r["mesh"].get<std::string>() == "remeshed");
  REQUIRE(r["frames"].size() == frames);
  double pruned_before = 0;
  for (std::size_t f = 0; f < frames; ++f) {
    const auto& fr = r["frames"][f];
    INFO("frame " << f << ": " << fr.dump());
    char name[32];
    std::snprintf(name, sizeof name, "streak_%04zu.vtp", f);
    const orthofront::Mesh mesh = orthofront::io::read_mesh(dir / "streak" / name);
    REQUIRE(mesh.face_count() > 0);
    // Measured independently on the file as written.
    const orthofront::QualityReport q = orthofront::measure_quality(mesh);
    CHECK(q.folds == 0);
    CHECK(q.non_manifold_edges == 0);
    CHECK(q.t_junctions == 0);
    CHECK(q.degenerate_faces == 0);
    CHECK(q.inconsistent_edges == 0);
    CHECK(q.longest_edge <= 2 * edge);
    CHECK(q.triangle_min_angle_p05 >= 20);
    // Bounded by the area: within 3 x what well-shaped triangles of edge ℓ need.
    CHECK(static_cast<double>(mesh.vertex_count()) <= 3 * fr["vertex_estimate"].get<double>());
    for (const auto& p : mesh.positions) {
      CHECK(p.x() >= -0.0207);
      CHECK(p.x() <= 0.2901);
    }
    // Pruning only ever adds up, and takes less of the dye than it leaves.
    const double pruned = fr["area_pruned"].get<double>();
    CHECK(pruned >= pruned_before);
    CHECK(pruned < fr["area"].get<double>());
    pruned_before = pruned;
  }
  // A 2D flow: most splits lie inside the dye, where the midpoint needs no path.
  CHECK(r["refinement"]["flat_insertions"].get<double>() >
        r["refinement"]["exact_insertions"].get<double>());
  const auto& last = r["frames"].back();
  WARN("step streak surface, last frame: " << last["vertices"] << " vertices (estimate "
                                           << last["vertex_estimate"] << "), " << last["pieces"]
                                           << " pieces, p05 min angle "
                                           << last["quality"]["triangle_min_angle_p05_deg"]
                                           << ", area pruned " << last["area_pruned"] << " of "
                                           << last["area"] << ", " << r["seconds"]["total"]
                                           << " s");
}
