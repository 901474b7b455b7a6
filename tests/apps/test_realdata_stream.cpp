// Stream surfaces on real data files (bubble chamber, tornado step 1) read straight from their
// formats. [realdata]: skipped visibly when ../shared/datasets is absent.
#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "orthofront/io/mesh_io.h"
#include "orthofront/quality/quality.h"

namespace fs = std::filesystem;

namespace {

struct Surface {
  orthofront::QualityReport quality;
  nlohmann::json report;
};

Surface stream(const fs::path& field, const std::string& args, const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("orthofront-realdata-stream-" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string command = std::string(ORTHOFRONT_BINARY) + " stream --field '" +
                              field.string() + "' " + args + " --out '" +
                              (dir / "s.vtp").string() + "' --report '" +
                              (dir / "s.json").string() + "' > '" + (dir / "log").string() +
                              "' 2>&1 < /dev/null";
  const int status = WEXITSTATUS(std::system(command.c_str()));
  std::ifstream log(dir / "log"), report(dir / "s.json");
  std::stringstream log_text, report_text;
  log_text << log.rdbuf();
  report_text << report.rdbuf();
  INFO(log_text.str());
  REQUIRE(status == 0);
  Surface s;
  s.report = nlohmann::json::parse(report_text.str());
  const orthofront::Mesh mesh = orthofront::io::read_mesh(dir / "s.vtp");
  for (const auto& p : mesh.positions) REQUIRE(p.allFinite());
  s.quality = orthofront::measure_quality(mesh);
  // The report carries the same quality figures as an independent measurement of the file.
  CHECK(s.report["quality"]["folds"].get<std::size_t>() == s.quality.folds);
  CHECK(s.report["quality"]["quads"].get<std::size_t>() == s.quality.quads);
  // ... and says why fronts waited and why insertions fell back, cause by cause.
  const nlohmann::json& counts = s.report["counts"];
  std::size_t clamped = 0, fallbacks = 0;
  for (const auto& [cause, n] : counts["clamped_alpha_by_cause"].items())
    clamped += n.get<std::size_t>();
  for (const auto& [cause, n] : counts["insertion_fallbacks_by_cause"].items())
    fallbacks += n.get<std::size_t>();
  CHECK(clamped == counts["clamped_alpha"].get<std::size_t>());
  CHECK(fallbacks == counts["insertion_fallbacks"].get<std::size_t>());
  // ... and where every triangle of the file came from.
  std::size_t triangles = 0;
  for (const auto& [cause, n] : counts["triangles_by_cause"].items())
    triangles += n.get<std::size_t>();
  CHECK(triangles == s.quality.triangles);
  WARN(name << ": clamped alpha by cause " << counts["clamped_alpha_by_cause"].dump()
            << " of " << counts["vertex_steps"] << " vertex-steps; insertion fallbacks by cause "
            << counts["insertion_fallbacks_by_cause"].dump() << ", "
            << counts["streamline_insertions"] << " stream-line insertions; triangles by cause "
            << counts["triangles_by_cause"].dump());
  return s;
}

/// No folds, non-manifold edges, T-junctions or degenerate faces in the written surface.
void check_valid(const Surface& s) {
  CHECK(s.quality.folds == 0);
  CHECK(s.quality.non_manifold_edges == 0);
  CHECK(s.quality.t_junctions == 0);
  CHECK(s.quality.degenerate_faces == 0);
}

}  // namespace

TEST_CASE("stream surfaces on the bubble chamber and tornado step 1", "[apps][stream][realdata]") {
  const fs::path data = ORTHOFRONT_DATASETS_DIR;
  if (!fs::exists(data / "tornado" / "1.vec")) {
    WARN("skipped: " << data.string() << " not found");
    return;
  }
  const Surface tornado = stream(data / "tornado" / "1.vec",
                                 "--seed line:30,24,10:30,24,30 --seed-count 20 --edge 0.5 "
                                 "--steps 200",
                                 "tornado");
  CHECK(tornado.quality.faces > 5000);
  check_valid(tornado);
  CHECK(tornado.quality.quad_angles_within_10 > 0.95);

  // Walls (zero vectors) stop the surface: fronts split there and no NaN reaches a vertex.
  const Surface bubble = stream(data / "bubble-chamber" / "BubbleChamber_11x11x10_T0.am",
                                "--seed line:0,-0.03,0.02:0,0.03,0.02 --seed-count 20 "
                                "--edge 0.004 --steps 100",
                                "bubble");
  CHECK(bubble.quality.faces > 1000);
  CHECK(bubble.quality.non_manifold_edges == 0);
  CHECK(bubble.quality.t_junctions == 0);
  CHECK(bubble.quality.degenerate_faces == 0);
  CHECK(bubble.quality.folds == 0);  // 1 before the fold guard
  WARN("bubble chamber: " << bubble.quality.faces << " faces, " << bubble.quality.folds
                          << " folds; tornado: " << tornado.quality.faces << " faces");
}

TEST_CASE("the fold guard on real data: the tornado across its core, the square cylinder",
          "[apps][stream][realdata][fold]") {
  const fs::path data = ORTHOFRONT_DATASETS_DIR;
  if (!fs::exists(data / "tornado" / "1.vec")) {
    WARN("skipped: " << data.string() << " not found");
    return;
  }
  // A horizontal seed through the vortex core: the front wraps the core with a crease sharper
  // than 90° (8 folds along one stream line from step 246 without the guard, 55 without row
  // skipping). The guard takes the crease vertex out once and the rest stays whole. (With the
  // stall cut, the default, the vertices there have left the front before it creases.)
  const Surface tornado = stream(data / "tornado" / "1.vec",
                                 "--seed line:10,24,24:38,24,24 --seed-count 20 --edge 0.5 "
                                 "--steps 300 --stall-steps 0",
                                 "tornado-across");
  CHECK(tornado.quality.faces > 20000);
  check_valid(tornado);
  CHECK(tornado.report["counts"]["fold_rips"].get<std::size_t>() >= 1);
  CHECK(tornado.report["counts"]["folds_left_by_guard"].get<std::size_t>() == 0);
  CHECK(tornado.quality.quad_share > 0.9);

  const Surface by_default = stream(data / "tornado" / "1.vec",
                                    "--seed line:10,24,24:38,24,24 --seed-count 20 --edge 0.5 "
                                    "--steps 300",
                                    "tornado-across-default");
  check_valid(by_default);
  CHECK(by_default.report["counts"]["stall_cuts"].get<std::size_t>() > 0);
  // Waiting runs of up to 16 vertices beside moving ones move with them once they have gone a
  // twentieth of the skip distance: about half the triangles at waiting vertices go, and the
  // quad share rises past 95 % (docs/benchmarks/engine-options.md, row skipping).
  CHECK(by_default.quality.quad_share >= 0.95);
  // A lower join fraction trades more of them for short edges (docs/benchmarks/engine-options.md,
  // row skipping).
  const Surface joined = stream(data / "tornado" / "1.vec",
                                "--seed line:10,24,24:38,24,24 --seed-count 20 --edge 0.5 "
                                "--steps 300 --join-fraction 0.3",
                                "tornado-across-joined");
  check_valid(joined);
  CHECK(joined.quality.quad_share > by_default.quality.quad_share);
  CHECK(joined.report["counts"]["triangles_by_cause"]["waiting_vertices"].get<std::size_t>() <
        by_default.report["counts"]["triangles_by_cause"]["waiting_vertices"].get<std::size_t>());
  CHECK(joined.quality.edge_spread_median > by_default.quality.edge_spread_median);
  CHECK(by_default.report["counts"]["skipped_vertex_steps"].get<std::size_t>() <
        tornado.report["counts"]["skipped_vertex_steps"].get<std::size_t>());

  const fs::path cylinder = data / "square-cylinder-2d" / "sqflow2D-3928.nrrd";
  const Surface wake = stream(cylinder,
                              "--seed line:-10,-3,0:-10,3,0 --seed-count 20 --edge 0.1 "
                              "--steps 400",
                              "square-cylinder");
  CHECK(wake.quality.faces > 20000);
  CHECK(wake.quality.folds == 0);
  CHECK(wake.quality.non_manifold_edges == 0);
  CHECK(wake.quality.degenerate_faces == 0);
}

TEST_CASE("the gap behind the square cylinder closes where its sides come within the distance",
          "[apps][stream][realdata][gaps]") {
  const fs::path cylinder =
      fs::path(ORTHOFRONT_DATASETS_DIR) / "square-cylinder-2d" / "sqflow2D-1608.nrrd";
  if (!fs::exists(cylinder)) {
    WARN("skipped: " << cylinder.string() << " not found");
    return;
  }
  // The seed is cut where it meets the cylinder; its halves run on side by side 3 to 4 ℓ apart.
  const std::string seed = "--seed line:-10,-3,0:-10,3,0 --seed-count 20 --edge 0.1 --steps 400";
  const Surface open = stream(cylinder, seed + " --no-close-gaps", "cylinder-gap-open");
  const Surface within_2l = stream(cylinder, seed, "cylinder-gap-default");
  const Surface closed = stream(cylinder, seed + " --gap-distance 4", "cylinder-gap-closed");
  // Within 2 ℓ (the default) the sides never come: nothing changes.
  CHECK(within_2l.quality.faces == open.quality.faces);
  CHECK(within_2l.report["counts"]["gaps_closed"]["faces"].get<std::size_t>() == 0);
  // Within 4 ℓ most of the wake's gap closes: 183 faces; the boundary loses 352 edges.
  const auto& gaps = closed.report["counts"]["gaps_closed"];
  CHECK(gaps["faces"].get<std::size_t>() > 150);
  CHECK(closed.quality.faces == open.quality.faces + gaps["faces"].get<std::size_t>());
  CHECK(closed.quality.boundary_edges + 300 < open.quality.boundary_edges);
  check_valid(closed);
  CHECK(closed.quality.inconsistent_edges == 0);

  // At twice the edge the same halves run 1.5 to 2 ℓ apart: the default closes them where they
  // come within 2 ℓ, and within ℓ they stay open.
  const std::string coarse =
      "--seed line:-10,-3,0:-10,3,0 --seed-count 20 --edge 0.2 --steps 200";
  const Surface coarse_open = stream(cylinder, coarse + " --gap-distance 1", "cylinder-coarse-1");
  const Surface coarse_default = stream(cylinder, coarse, "cylinder-coarse-default");
  CHECK(coarse_open.report["counts"]["gaps_closed"]["faces"].get<std::size_t>() == 0);
  const auto& coarse_gaps = coarse_default.report["counts"]["gaps_closed"];
  CHECK(coarse_gaps["stretches"].get<std::size_t>() >= 2);
  CHECK(coarse_gaps["faces"].get<std::size_t>() > 20);
  CHECK(coarse_default.quality.faces ==
        coarse_open.quality.faces + coarse_gaps["faces"].get<std::size_t>());
  check_valid(coarse_default);
  CHECK(coarse_default.quality.inconsistent_edges == 0);
}

TEST_CASE("seed shots on a budget: the square cylinder's recirculation stops integrating its age",
          "[apps][stream][realdata][shots]") {
  const fs::path cylinder =
      fs::path(ORTHOFRONT_DATASETS_DIR) / "square-cylinder-2d" / "sqflow2D-1608.nrrd";
  if (!fs::exists(cylinder)) {
    WARN("skipped: " << cylinder.string() << " not found");
    return;
  }
  // A front circling the recirculation bubble for 700-1,100 steps: every insertion from the
  // seed integrates its whole age (up to 8,500 evaluations each without a budget).
  const std::string seed =
      "--seed line:0.8,-0.6,0:0.8,0.6,0 --seed-count 20 --edge 0.02 --steps 3000";
  const Surface unlimited = stream(cylinder, seed + " --shot-evaluations 0", "shots-unlimited");
  const Surface budget = stream(cylinder, seed, "shots-budget");
  const nlohmann::json& u = unlimited.report["counts"];
  const nlohmann::json& b = budget.report["counts"];
  CHECK(u["seed_shots_over_budget"].get<std::size_t>() == 0);
  CHECK(u["seed_shot_time_limit"].is_null());
  CHECK(b["seed_shots_over_budget"].get<std::size_t>() > 0);
  CHECK(b["seed_shot_time_limit"].get<double>() > 0);
  // The budget saves most of the field evaluations; no insertion falls back to the cubic point.
  CHECK(3 * b["field_evaluations"].get<std::size_t>() < u["field_evaluations"].get<std::size_t>());
  CHECK(b["insertion_fallbacks"].get<std::size_t>() == 0);
  check_valid(budget);
  check_valid(unlimited);
}
