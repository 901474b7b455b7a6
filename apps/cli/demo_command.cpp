// `orthofront demo`: the default job. A few analytic cases, each with the flow-orthogonal method
// and the timeline baseline, plus a path surface of the double gyre; writes .vtp meshes and JSON
// reports and prints a side-by-side quality table.
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "cli/commands.h"
#include "cli/pictures.h"
#include "jobs/streak_report.h"
#include "cli/surface_job.h"
#include "orthofront/error.h"
#include "orthofront/field/unsteady.h"
#include "orthofront/io/error.h"
#include "orthofront/io/mesh_io.h"
#include "orthofront/io/mesh_series.h"
#include "orthofront/io/report_json.h"
#include "orthofront/seed/seed_curve.h"
#include "orthofront/spacetime/path_command_json.h"
#include "orthofront/spacetime/path_surface.h"
#include "orthofront/spacetime/streak_surface.h"

namespace orthofront::cli {

using namespace jobs;

namespace {

struct DemoCase {
  const char* name;
  const char* field;
  const char* seed;
  int seed_count;
  double edge;
  int steps;
};

// The paper's synthetic cases (Section 7.1) at sizes that run in well under a second each.
constexpr DemoCase kCases[] = {
    {"sinus", "sinus", "line:-1,0,0:1,0,0", 20, 0.05, 200},
    {"saddle", "saddle", "line:-1,1,0:1,1,0", 20, 0.05, 240},
    {"saddle3d", "saddle3d", "line:-1,2,0.1:1,2,0.1", 20, 0.1, 100},
    {"focus-sink", "focus-sink", "line:1,0,-1:1,0,1", 20, 0.05, 200},
    {"stalling", "stalling", "line:-2.5,-1,0:-2.5,1,0", 20, 0.05, 300},
    // The stable manifold of the origin: a circle in the stable eigenplane of the reversed flow.
    {"lorenz", "lorenz:reverse=1", "circle:0,0,0:1.2830,1,0:1", 10, 0.5, 500},
};

void print_row(const char* name, const char* method, const SurfaceReport& r) {
  const QualityReport& q = r.quality;
  std::printf("%-11s %-10s %8zu %7.1f %8.1f %7.3f %6zu %6zu %6zu %8.3f\n", name, method, r.vertices,
              100.0 * q.quad_share, 100.0 * q.quad_angles_within_10, q.edge_spread_median, q.folds,
              q.non_manifold_edges + q.t_junctions, q.degenerate_faces, r.times.total);
}

}  // namespace

void add_demo_command(CLI::App& app) {
  auto out_dir = std::make_shared<std::string>("orthofront-demo");
  CLI::App* c = app.add_subcommand("demo",
                                   "Default job: analytic stream surfaces (orthogonal vs "
                                   "timeline), a path surface and a streak surface");
  c->add_option("--out-dir", *out_dir, "Folder for the meshes and reports")->capture_default_str();
  c->callback([out_dir]() {
    const std::filesystem::path dir = *out_dir;
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec)
      throw io::IoError("cannot create output folder '" + dir.string() + "': " + ec.message());
    // Every surface gets a picture and every report its histograms, drawn together at the end.
    PictureRequest pictures;
    const auto add_pictures = [&](const std::filesystem::path& mesh,
                                  const std::filesystem::path& report) {
      std::filesystem::path png = report;  // NAME.png beside NAME.json
      pictures.renders.push_back({mesh, png.replace_extension(".png"), {}});
      pictures.plots.push_back({report, histograms_path(report)});
    };
    std::printf("%-11s %-10s %8s %7s %8s %7s %6s %6s %6s %8s\n", "case", "method", "vertices",
                "quads%", "ang±10%", "spread", "folds", "nm+tj", "degen", "time s");
    for (const DemoCase& dc : kCases) {
      for (const Method method : {Method::orthogonal, Method::timeline}) {
        SurfaceJob job;
        job.field = dc.field;
        job.seed = dc.seed;
        job.seed_count = dc.seed_count;
        job.options.edge = dc.edge;
        job.options.max_steps = dc.steps;
        job.options.method = method;
        // The timeline baseline refines without bound where the flow speeds up: cap it.
        job.options.max_vertices = 150'000;
        const SurfaceResult result = run_surface(job, false);
        const std::string stem = std::string(dc.name) + "-" + to_string(method);
        io::write_mesh(result.mesh, dir / (stem + ".vtp"));
        nlohmann::json report = io::to_json(result.report);
        report["field"] = dc.field;
        report["seed"] = dc.seed;
        io::write_json(report, dir / (stem + ".json"));
        add_pictures(dir / (stem + ".vtp"), dir / (stem + ".json"));
        print_row(dc.name, to_string(method), result.report);
      }
    }
    // A path surface of the unsteady double gyre (the space-time lift of Section 4).
    spacetime::PathSurfaceOptions path;
    path.engine.edge = 0.02;
    path.engine.max_steps = 100'000;
    path.t0 = 0;
    path.t1 = 10;
    const auto gyre = make_unsteady_field("double-gyre");
    const spacetime::PathSurfaceResult pr = spacetime::build_path_surface(
        *gyre, SeedCurve::line(Vec3(0.1, 0.5, 0), Vec3(0.6, 0.5, 0)), 20, path);
    io::write_mesh(pr.mesh, dir / "double-gyre-path.vtp");
    nlohmann::json path_report = io::to_json(pr.report);
    path_report["field"] = "double-gyre";
    path_report["path"] = spacetime::to_json(pr.path);
    io::write_json(path_report, dir / "double-gyre-path.json");
    add_pictures(dir / "double-gyre-path.vtp", dir / "double-gyre-path.json");
    print_row("dbl-gyre", "path", pr.report);
    // A streak surface of the same flow: dye released from a line for 4 time units, seen at 8
    // times, written as a ParaView animation.
    spacetime::StreakOptions streak;
    streak.release_begin = 0;
    streak.release_end = 4;
    streak.frames = {1, 2, 3, 4, 5, 6, 7, 8};
    streak.edge = 0.02;
    io::MeshSeriesWriter animation(dir / "double-gyre-streak.pvd");
    spacetime::StreakFrameRecord last;
    std::filesystem::path last_frame;
    const spacetime::StreakReport sr = spacetime::build_streak_surface(
        *gyre, SeedCurve::line(Vec3(0.3, 0.3, 0), Vec3(0.3, 0.45, 0)), streak,
        [&](const spacetime::StreakFrame& f) { last_frame = animation.add_frame(f.mesh, f.time); });
    if (!sr.frames.empty()) last = sr.frames.back();
    nlohmann::json streak_report = streak_report_json(sr);
    streak_report["field"] = "double-gyre";
    io::write_json(streak_report, dir / "double-gyre-streak.json");
    if (!last_frame.empty()) add_pictures(last_frame, dir / "double-gyre-streak.json");
    std::printf("%-11s %-10s %8zu %7.1f %8.1f %7.3f %6zu %6zu %6zu %8.3f  (last of %zu frames)\n",
                "dbl-gyre", "streak", last.vertices, 100.0 * last.quality.quad_share,
                100.0 * last.quality.quad_angles_within_10, last.quality.edge_spread_median,
                last.quality.folds, last.quality.non_manifold_edges + last.quality.t_junctions,
                last.quality.degenerate_faces, sr.total_seconds, animation.frames());
    std::printf(
        "\nColumns: quads%% = quads among faces; ang±10%% = quad angles within 90±10°; spread = "
        "median |1 - l_i/l_avg| of quad edges; nm+tj = non-manifold edges + T-junctions.\n"
        "Wrote %zu meshes (.vtp, open in ParaView), their JSON reports and a streak-surface "
        "animation (double-gyre-streak.pvd) to %s\n",
        2 * std::size(kCases) + 1, std::filesystem::absolute(dir).string().c_str());
    std::fflush(stdout);
    if (const std::string why = draw_pictures(pictures); !why.empty())
      std::fprintf(stderr, "orthofront: warning: no pictures: %s\n", why.c_str());
    else
      std::printf("Wrote a picture of every surface (NAME.png beside NAME.json; the streak "
                  "surface's shows its last frame) and the quality histograms of every report "
                  "(NAME.histograms.svg) to %s\n",
                  std::filesystem::absolute(dir).string().c_str());
  });
}

}  // namespace orthofront::cli
