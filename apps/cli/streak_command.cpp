// `orthofront streak`: streak surfaces (continuous release from a seed curve), written as a
// ParaView animation: one .vtp per observation time and a .pvd collection listing them.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

#include "cli/commands.h"
#include "cli/option_flags.h"
#include "jobs/edge_default.h"
#include "jobs/engine_options.h"
#include "jobs/output_notes.h"
#include "jobs/grid_args.h"
#include "cli/pictures.h"
#include "jobs/process_memory.h"
#include "cli/progress_bar.h"
#include "jobs/seed_spec.h"
#include "jobs/streak_job.h"
#include "jobs/streak_report.h"
#include "orthofront/error.h"
#include "orthofront/io/atomic_file.h"
#include "orthofront/io/hdf5_layout.h"
#include "orthofront/io/mesh_io.h"
#include "orthofront/io/mesh_series.h"
#include "orthofront/io/open_field.h"
#include "orthofront/io/report_json.h"
#include "orthofront/io/vdb_grid.h"
#include "orthofront/spacetime/path_command_json.h"
#include "orthofront/spacetime/spacetime_streak.h"
#include "orthofront/spacetime/streak_line_field.h"
#include "orthofront/spacetime/streak_surface.h"

namespace orthofront::cli {

using namespace jobs;

namespace {

// One status line on stderr (terminals only): simulated time, frames written, particles.
class StreakStatus {
 public:
  StreakStatus() : enabled_(isatty(STDERR_FILENO) != 0) {}
  ~StreakStatus() { finish(); }
  StreakStatus(const StreakStatus&) = delete;
  StreakStatus& operator=(const StreakStatus&) = delete;
  bool update(const spacetime::StreakProgress& p) {
    if (interrupted()) return false;
    if (!enabled_ || p.elapsed_seconds - last_ < 0.1) return true;
    last_ = p.elapsed_seconds;
    std::fprintf(stderr,
                 "\rstreak: t = %.4g of %.4g  %zu of %zu frames written  %zu particles in %zu rows "
                 " RSS %s   ",
                 p.t, p.t_end, p.frames_written, p.frames, p.particles, p.rows,
                 format_memory(current_rss_bytes()).c_str());
    drawn_ = true;
    return true;
  }
  void finish() {
    if (drawn_) std::fprintf(stderr, "\n");
    drawn_ = false;
  }

 private:
  bool enabled_;
  bool drawn_ = false;
  double last_ = -1;
};


// The flow-orthogonal route: one space-time surface from a point, written as one mesh.
void run_spacetime_route(const StreakArgs& args, const PreviewFlags& preview) {
  const std::filesystem::path out = args.out;
  if (!io::is_mesh_extension(out))
    throw InvalidArgument("--route spacetime writes one mesh: --out '" + args.out +
                          "' needs the extension .vtp, .ply or .obj");
  io::check_writable(out);
  if (!args.report.empty()) io::check_writable(args.report);
  double x = 0, y = 0;
  char end = 0;
  if (std::sscanf(args.point.c_str(), "%lf,%lf%c", &x, &y, &end) != 2)
    throw InvalidArgument("--route spacetime needs --point x,y (the release point), got '" +
                          args.point + "'");
  if (!is_unsteady_field_name(args.field))
    throw InvalidArgument("--route spacetime takes an unsteady analytic 2D field, not '" +
                          args.field + "'");
  const auto flow = make_unsteady_field(args.field);
  spacetime::SpacetimeStreakOptions o;
  std::tie(o.release_begin, o.release_end) = parse_streak_release(args.release);
  o.t_end = parse_streak_frames(args.frames).back();
  o.engine.edge = args.edge;
  o.engine.max_steps = 10'000'000;
  if (args.max_vertices > 0) o.engine.max_vertices = args.max_vertices;
  const spacetime::SpacetimeStreakResult r =
      spacetime::build_spacetime_streak_surface(*flow, Vec3(x, y, 0), o);
  const io::OutputLock lock(out);
  io::AtomicFileSet outputs;
  io::write_mesh(r.mesh, out, outputs);
  if (!args.report.empty()) {
    nlohmann::json report = io::to_json(r.report);
    report["route"] = "spacetime";
    report["field"] = args.field;
    report["point"] = {x, y};
    report["time_scale"] = r.time_scale;
    report["quality_space"] = "(x, y, c t)";
    io::write_json(report, args.report, outputs);
  }
  outputs.commit();
  if (!args.quiet)
    std::printf(
        "Space-time streak surface of %s from (%g, %g), released over [%g, %g], to t = "
        "%g: %zu vertices, %zu faces, c = %g; quality in (x, y, c t): %.1f%% quads, "
        "%.1f%% of quad angles within 90±10°, edge spread %.3f, %zu folds. Time %.3f s.\n"
        "Wrote %s (positions (x, y, t); its slice at time t is the streak line at t)\n",
        args.field.c_str(), x, y, o.release_begin, o.release_end, o.t_end, r.mesh.vertex_count(),
        r.mesh.face_count(), r.time_scale, 100 * r.report.quality.quad_share,
        100 * r.report.quality.quad_angles_within_10, r.report.quality.edge_spread_median,
        r.report.quality.folds, r.report.times.total, args.out.c_str());
  std::fflush(stdout);
  draw_run_pictures(preview, out, args.report, args.quiet);
}

// The paper's route for a seed curve: at each observation time, the stream surface of the
// streak-line field over (x, y, age), written as one frame of a .pvd animation.
void run_streak_line_route(const StreakArgs& args, const SeedCurve& seed,
                           const PreviewFlags& preview) {
  if (!is_unsteady_field_name(args.field))
    throw InvalidArgument("--route streak-line takes an unsteady analytic 2D field, not '" +
                          args.field + "'");
  io::MeshSeriesWriter writer(args.out);  // checks the extension and the folder
  if (!args.report.empty()) io::check_writable(args.report);
  const auto flow = make_unsteady_field(args.field);
  spacetime::StreakLineSurfaceOptions o;
  std::tie(o.release_begin, o.release_end) = parse_streak_release(args.release);
  o.seed_count = args.seed_count;
  o.path.engine.edge = args.edge;
  o.path.engine.max_steps = 10'000'000;
  if (args.max_vertices > 0) o.path.engine.max_vertices = args.max_vertices;
  o.path.seed_name = args.seed;
  o.path.field_name = args.field;
  o.path.progress = [](const spacetime::PathProgress&) { return !interrupted(); };
  nlohmann::json frames = nlohmann::json::array();
  std::filesystem::path last_frame;
  std::size_t derived = 0, evaluations = 0;
  double seconds = 0;
  bool complete = true;
  for (const double t : parse_streak_frames(args.frames)) {
    o.observation_time = t;
    spacetime::StreakLineSurface w = spacetime::build_streak_line_surface(*flow, seed, o);
    if (!w.path.complete) {
      complete = false;
      break;
    }
    // The surface the engine built, in (x, y, age); its projection is the planar streak surface.
    w.mesh.positions.assign(w.lifted.begin(), w.lifted.end());
    last_frame = writer.add_frame(w.mesh, t);
    derived += w.derived_evaluations;
    evaluations += w.flow_evaluations;
    seconds += w.seconds;
    nlohmann::json f = io::to_json(w.report);
    f["time"] = t;
    f["first_age"] = w.first_age;
    f["time_scale"] = w.path.time_scale;
    f["streak_line_field_values"] = w.derived_evaluations;
    f["flow_evaluations"] = w.flow_evaluations;
    f["seconds"] = w.seconds;
    frames.push_back(std::move(f));
    if (!args.quiet)
      std::printf(
          "t = %g: %zu vertices, %zu faces, %.1f%% quads, %.1f%% of quad angles within "
          "90±10° in (x, y, c age), %zu folds; %zu values of the streak-line field, "
          "%.3f s\n",
          t, w.mesh.vertex_count(), w.mesh.face_count(), 100 * w.report.quality.quad_share,
          100 * w.report.quality.quad_angles_within_10, w.report.quality.folds,
          w.derived_evaluations, w.seconds);
  }
  if (!args.report.empty()) {
    const nlohmann::json report = {{"route", "streak-line"},
                                   {"field", args.field},
                                   {"seed", args.seed},
                                   {"output", args.out},
                                   {"positions", "(x, y, age)"},
                                   {"quality_space", "(x, y, c age)"},
                                   {"frames_written", writer.frames()},
                                   {"complete", complete},
                                   {"streak_line_field_values", derived},
                                   {"flow_evaluations", evaluations},
                                   {"seconds", seconds},
                                   {"frames", frames}};
    io::write_atomically(args.report, [&](std::ofstream& out) { out << report.dump(2) << '\n'; });
  }
  if (!args.quiet)
    std::printf("Wrote %s (%zu frames in %s, positions (x, y, age))%s%s\n", args.out.c_str(),
                writer.frames(), writer.frame_folder().string().c_str(),
                args.report.empty() ? "" : " and ", args.report.c_str());
  std::fflush(stdout);
  if (!last_frame.empty()) draw_run_pictures(preview, last_frame, args.report, args.quiet);
  if (!complete)
    throw Error("interrupted: the " + std::to_string(writer.frames()) +
                " frames written are listed in " + args.out);
}

}  // namespace

void add_streak_command(CLI::App& app) {
  auto args = std::make_shared<StreakArgs>();
  auto options = std::make_shared<OptionSet>();
  auto preview = std::make_shared<PreviewFlags>();
  CLI::App* c = app.add_subcommand(
      "streak",
      "Build a streak surface (dye released continuously from a seed curve) as a "
      "ParaView animation");
  c->add_option("--field", args->field,
                "Unsteady field NAME[:key=value,...] (see `orthofront fields`) or a time series: "
                "HDF5, NetCDF, a .pvd collection, a glob of grid files or an OpenVDB file of "
                "timed vector grids")
      ->required();
  c->add_option("--seed", args->seed, "Seed curve (as for `stream`; 2D flows take z = 0)");
  add_streak_options(*options, *args);
  add_option_flags(*c, options);
  c->add_option("--out", args->out, "Output collection DIR/NAME.pvd (frames go to DIR/NAME/)")
      ->required();
  c->add_option("--report", args->report, "Write the JSON report here");
  add_preview_flags(*c, *preview);
  c->add_flag("--quiet", args->quiet, "No summary on stdout");
  c->callback([args, options, preview, c]() {
    check_preview(*preview);
    if (args->frames.empty()) throw InvalidArgument("--frames is required (the observation times)");
    if (args->route == "spacetime") {
      run_spacetime_route(*args, *preview);
      return;
    }
    if (args->seed.empty()) throw InvalidArgument("--seed is required (the curve the dye leaves)");
    if (args->route == "streak-line") {
      run_streak_line_route(*args, parse_seed(args->seed), *preview);
      return;
    }
    spacetime::StreakOptions o = streak_options(*options, *args);
    io::MeshSeriesWriter writer(args->out);  // checks the extension and the folder
    if (!args->report.empty()) io::check_writable(args->report);
    const SeedCurve seed = parse_seed(args->seed);
    StreakStatus status;
    o.progress = [&](const spacetime::StreakProgress& p) { return status.update(p); };
    std::filesystem::path last_frame;
    const auto sink = [&](const spacetime::StreakFrame& frame) {
      last_frame = writer.add_frame(frame.mesh, frame.time);
    };

    spacetime::StreakReport result;
    std::size_t cache_budget = 0;
    bool zero_is_no_data = false;  // the rule the data was read by (analytic flows: zeros flow)
    EdgeChoice edge = choose_edge(o.edge, c->count("--edge") > 0, nullptr);
    if (is_unsteady_field_name(args->field)) {
      if (o.device)
        throw InvalidArgument("--device: bulk advection reads gridded series; '" + args->field +
                              "' is an analytic field (sample it with `generate` first)");
      const auto flow = make_unsteady_field(args->field);
      writer.set_notes(output_notes("streak", args->field, nullptr));
      result = spacetime::build_streak_surface(*flow, seed, o, sink);
    } else {
      const std::unique_ptr<io::TimeSeries> series =
          io::open_time_series(args->field, "streak surfaces");
      edge = choose_edge(o.edge, c->count("--edge") > 0, &series->geometry());
      o.edge = edge.edge;
      spacetime::CacheOptions co;
      co.budget_bytes = streak_cache_budget(*args);
      cache_budget = co.budget_bytes;
      zero_is_no_data = series->zero_is_no_data();
      writer.set_notes(output_notes("streak", args->field, series.get()));
      spacetime::BrickCache cache(*series, co);
      result = spacetime::build_streak_surface(cache, seed, o, sink);
    }
    status.finish();
    if (!args->report.empty()) {
      nlohmann::json report = streak_report_json(result);
      report["field"] = args->field;
      report["zero_vectors"] = zero_is_no_data ? "no data" : "flow";
      report["seed"] = args->seed;
      add_edge_keys(report, edge);
      report["output"] = args->out;
      report["frames_written"] = writer.frames();
      report["limits"] = args->limits.to_json();
      if (cache_budget > 0) report["limits"]["cache_budget_bytes"] = cache_budget;
      report["process"] = {{"peak_rss_bytes", peak_rss_bytes()},
                           {"rss_bytes", current_rss_bytes()}};
      io::write_atomically(args->report,
                           [&](std::ofstream& out) { out << report.dump(2) << '\n'; });
    }
    if (!args->quiet) {
      std::fputs(edge_note(edge).c_str(), stdout);
      std::printf(
          "Streak surface of %s from %s, released over [%g, %g] in %zu rows of %zu "
          "particles: %zu of %zu frames, t reached %g, %zu particle-steps, %zu exact and "
          "%zu interpolated insertions, %.3f s (advect %.3f, refine %.3f, frames %.3f).\n",
          args->field.c_str(), args->seed.c_str(), result.release_begin, result.release_end,
          result.rows_released, result.seed_count, result.frames.size(), o.frames.size(),
          result.time_reached, result.particle_steps, result.exact_insertions,
          result.interpolated_insertions, result.total_seconds, result.advect_seconds,
          result.refine_seconds, result.frame_seconds);
      if (!result.frames.empty()) {
        const auto& f = result.frames.back();
        char shape[160];
        if (f.quality.quad_share > 0)
          std::snprintf(shape, sizeof shape, "%.1f%% quads, %.1f%% of quad angles within 90±10°",
                        100 * f.quality.quad_share, 100 * f.quality.quad_angles_within_10);
        else
          std::snprintf(shape, sizeof shape,
                        "triangles, smallest angle %.1f° (5th percentile) / %.1f° (median)",
                        f.quality.triangle_min_angle_p05, f.quality.triangle_min_angle_median);
        std::printf(
            "Last frame (t = %g): %zu vertices (%zu pieces), %zu faces, %s, edge spread %.3f, "
            "max edge %.3g (%.2f edge lengths), %zu folds, %zu T-junctions, %zu degenerate "
            "faces, %zu non-manifold edges.\n",
            f.time, f.vertices, f.pieces, f.faces, shape, f.quality.edge_spread_median, f.max_edge,
            f.max_edge / o.edge, f.quality.folds, f.quality.t_junctions,
            f.quality.degenerate_faces, f.quality.non_manifold_edges);
      }
      if (result.faces_pruned > 0 && !result.frames.empty()) {
        const auto& f = result.frames.back();
        std::printf("Pruned %zu faces of filaments thinner than %g edge lengths: %.3g (%.1f%%) of "
                    "the dye's area by the last frame (--prune 0 keeps them).\n",
                    result.faces_pruned, o.prune, f.area_pruned,
                    100 * f.area_pruned / std::max(f.area + f.area_pruned, 1e-300));
      }
      if (std::isfinite(result.coarsen_age) && !result.frames.empty()) {
        const std::string why =
            result.budget_coarsenings > 0
                ? " to keep the vertex budget of " + std::to_string(o.vertex_budget)
                : std::string();
        std::printf("Coarsened dye older than %g (edge * age / %g)%s: %zu collapses; the last "
                    "frame's longest edge is %.2f of its target length.\n",
                    result.coarsen_age, result.coarsen_age, why.c_str(), result.coarsened,
                    result.frames.back().max_edge_ratio);
      }
      if (result.left_region > 0)
        std::printf("%zu particles left the region of interest %s.\n", result.left_region,
                    args->region.c_str());
      if (result.streamed)
        std::printf("Cache: %s read (%.3fx needed), at most %zu reads of a unit, waited %.3f s.\n",
                    spacetime::format_bytes(result.cache.bytes_read).c_str(),
                    result.cache.read_amplification(), result.cache.max_reads_of_a_unit,
                    result.wait_seconds);
      std::printf("Wrote %s (%zu frames in %s)%s%s\n", args->out.c_str(), writer.frames(),
                  writer.frame_folder().string().c_str(), args->report.empty() ? "" : " and ",
                  args->report.c_str());
    }
    std::fflush(stdout);
    if (!last_frame.empty())
      draw_run_pictures(*preview, last_frame, args->report, args->quiet);
    if (!result.frames.empty() && result.frames.back().faces == 0)
      std::fprintf(stderr,
                   "orthofront: warning: the last frame has no faces: at an edge of %g the dye "
                   "from a seed %.4g long is too narrow to mesh (or it left the domain); give a "
                   "smaller --edge\n",
                   o.edge, seed.length());
    if (!result.complete) {
      if (interrupted())
        throw Error("interrupted: the " + std::to_string(writer.frames()) +
                    " frames written are listed in " + args->out);
      throw Error(result.message + " (the " + std::to_string(writer.frames()) +
                  " frames written are listed in " + args->out + ")");
    }
  });
}

}  // namespace orthofront::cli
