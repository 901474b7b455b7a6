// `orthofront path`: path surfaces of unsteady flows (analytic, or time series streamed from
// disk through the narrow-band cache).
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "cli/commands.h"
#include "cli/option_flags.h"
#include "jobs/edge_default.h"
#include "jobs/engine_options.h"
#include "jobs/output_notes.h"
#include "jobs/path_job.h"
#include "cli/pictures.h"
#include "jobs/process_memory.h"
#include "cli/quality_warnings.h"
#include "cli/progress_bar.h"
#include "jobs/seed_spec.h"
#include "jobs/time_arg.h"
#include "orthofront/error.h"
#include "orthofront/io/atomic_file.h"
#include "orthofront/io/hdf5_layout.h"
#include "orthofront/io/mesh_io.h"
#include "orthofront/io/open_field.h"
#include "orthofront/io/report_json.h"
#include "orthofront/io/vdb_grid.h"
#include "orthofront/spacetime/bulk_front_integrator.h"
#include "orthofront/spacetime/path_command_json.h"
#include "orthofront/spacetime/path_surface.h"

namespace orthofront::cli {

using namespace jobs;

namespace {

// One status line on stderr (terminals only): simulated time, vertices against the cap,
// resident memory, band, cache.
class PathStatus {
 public:
  explicit PathStatus(std::size_t vertex_cap)
      : enabled_(isatty(STDERR_FILENO) != 0), vertex_cap_(vertex_cap) {}
  ~PathStatus() { finish(); }
  PathStatus(const PathStatus&) = delete;
  PathStatus& operator=(const PathStatus&) = delete;
  bool update(const spacetime::PathProgress& p) {
    if (interrupted()) return false;
    if (!enabled_ || p.engine.elapsed_seconds - last_ < 0.1) return true;
    last_ = p.engine.elapsed_seconds;
    std::fprintf(stderr,
                 "\rpath: t = %.4g of [%g, %g]  step %d  %zu of %zu vertices  RSS %s  band "
                 "[%.4g, %.4g]",
                 p.time_reached, p.t0, p.t1, p.engine.step, p.engine.vertices, vertex_cap_,
                 format_memory(current_rss_bytes()).c_str(), p.band_begin, p.band_end);
    if (p.streamed)
      std::fprintf(stderr, "  steps %zu-%zu  cache %s resident, %zu hits %zu misses, wait %.2fs",
                   p.band_first, p.band_last,
                   spacetime::format_bytes(p.cache.resident_bytes).c_str(), p.cache.hits,
                   p.cache.misses, p.cache.wait_seconds);
    std::fprintf(stderr, "   ");
    drawn_ = true;
    return true;
  }
  void finish() {
    if (drawn_) std::fprintf(stderr, "\n");
    drawn_ = false;
  }

 private:
  bool enabled_;
  std::size_t vertex_cap_;
  bool drawn_ = false;
  double last_ = -1;
};

}  // namespace

void add_path_command(CLI::App& app) {
  auto args = std::make_shared<PathArgs>();
  auto options = std::make_shared<OptionSet>();
  auto preview = std::make_shared<PreviewFlags>();
  CLI::App* c = app.add_subcommand(
      "path", "Build a path surface of an unsteady flow (analytic, or a time series from files)");
  c->add_option("--field", args->field,
                "Unsteady field NAME[:key=value,...] (see `orthofront fields`) or a time series: "
                "HDF5, NetCDF, a .pvd collection or a glob of grid files")
      ->required();
  c->add_option("--seed", args->seed, "Seed curve at t0 (as for `stream`; 2D flows take z = 0)")
      ->required();
  add_path_options(*options, *args);
  add_option_flags(*c, options);
  c->add_option("--out", args->out, "Output mesh (.vtp, .ply or .obj)")->required();
  c->add_option("--report", args->report, "Write the JSON report here");
  add_preview_flags(*c, *preview);
  c->add_flag("--quiet", args->quiet, "No summary on stdout");
  c->callback([args, options, preview, c]() {
    apply_memory_limits(*options, args->limits, args->options);
    check_preview(*preview);
    const std::filesystem::path out = args->out;
    if (!io::is_mesh_extension(out))
      throw InvalidArgument("output '" + args->out +
                            "' has an unknown extension (expected .vtp, .ply or .obj)");
    io::check_writable(out);
    if (!args->report.empty()) io::check_writable(args->report);
    check_seed_count(args->seed_count, args->options.max_vertices);
    const SeedCurve seed = parse_seed(args->seed);
    spacetime::PathSurfaceOptions o = path_options(*args);
    PathStatus status(args->options.max_vertices);
    o.progress = [&](const spacetime::PathProgress& p) { return status.update(p); };

    spacetime::PathSurfaceResult result;
    std::size_t cache_budget = 0;  // streamed runs only
    bool zero_is_no_data = false;  // the rule the data was read by (analytic flows: zeros flow)
    const auto resolve_times = [&](const io::TimeSeries* series) {
      args->t0 = resolve_time(args->t0_text, "--t0", series ? series->time(0) : 0.0, series);
      args->t1 = resolve_time(args->t1_text, "--t1", args->t0, series);
      o.t0 = args->t0;
      o.t1 = args->t1;
    };
    EdgeChoice edge = choose_edge(o.engine.edge, c->count("--edge") > 0, nullptr);
    MeshNotes notes = output_notes("path", args->field, nullptr);
    if (is_unsteady_field_name(args->field)) {
      if (o.device)
        throw InvalidArgument("--device: bulk advection reads gridded series; '" + args->field +
                              "' is an analytic field (sample it with `generate` first)");
      resolve_times(nullptr);
      const auto flow = make_unsteady_field(args->field);
      result = spacetime::build_path_surface(*flow, seed, args->seed_count, o);
    } else {
      const std::unique_ptr<io::TimeSeries> series =
          io::open_time_series(args->field, "path surfaces");
      resolve_times(series.get());
      notes = output_notes("path", args->field, series.get());
      edge = choose_edge(o.engine.edge, c->count("--edge") > 0, &series->geometry());
      o.engine.edge = edge.edge;
      const spacetime::CacheOptions co = path_cache_options(*args);
      cache_budget = co.budget_bytes;
      zero_is_no_data = series->zero_is_no_data();
      spacetime::BrickCache cache(*series, co);
      if (args->warm) {
        spacetime::PathSurfaceOptions cold = o;
        cold.progress = {};
        const auto first = spacetime::build_path_surface(cache, seed, args->seed_count, cold);
        if (!first.path.complete)
          throw Error("--warm: the first build stopped: " + first.path.message);
      }
      result = spacetime::build_path_surface(cache, seed, args->seed_count, o);
    }
    status.finish();
    // Cut off by the vertex cap before t1: say what was reached and which flag raises the cap
    // (the library's message names --max-vertices only; --memory is this command's).
    const bool capped =
        !result.path.complete && result.report.stop_reason == StopReason::vertex_budget;
    if (capped) {
      char reached[128];
      std::snprintf(reached, sizeof reached, "stopped at t = %.6g of t1 = %g (step %d): reached ",
                    result.path.time_reached, args->t1, result.report.steps);
      const std::string text =
          reached + vertex_cap_reached(args->limits, result.mesh.vertex_count());
      std::string& note = result.report.message;
      if (const auto at = note.rfind(result.path.message); at != std::string::npos)
        note.replace(at, result.path.message.size(), text);
      else
        note += (note.empty() ? "" : "; ") + text;
      result.path.message = text;
    }
    spacetime::place_for_output(result, args->flat);
    Mesh& mesh = result.mesh;
    mesh.notes = std::move(notes);
    // The mesh and its report are replaced together: both are written in full to temporaries
    // before either is renamed (a failure replaces neither), and a concurrent run of the same
    // outputs cannot interleave its files with these.
    const io::OutputLock lock(out);
    io::AtomicFileSet outputs;
    io::write_mesh(mesh, out, outputs);
    if (!args->report.empty()) {
      nlohmann::json report = io::to_json(result.report);
      report["field"] = args->field;
      report["zero_vectors"] = zero_is_no_data ? "no data" : "flow";
      report["seed"] = args->seed;
      report["seed_count"] = args->seed_count;
      add_edge_keys(report, edge);
      report["output"] = args->out;
      report["complete"] = result.report.complete;
      report["path"] = spacetime::to_json(result.path);
      report["path"]["positions"] = spacetime::path_positions(result, args->flat);
      report["limits"] = args->limits.to_json();
      if (cache_budget > 0) report["limits"]["cache_budget_bytes"] = cache_budget;
      report["process"] = {{"peak_rss_bytes", peak_rss_bytes()},
                           {"rss_bytes", current_rss_bytes()}};
      io::write_json(report, args->report, outputs);
    }
    outputs.commit();
    const spacetime::PathReport& pr = result.path;
    if (!args->quiet) {
      std::fputs(edge_note(edge).c_str(), stdout);
      std::printf(
          "Path surface of %s from %s: %zu vertices, %zu faces, positions (%s), t from %g to %g "
          "(reached %g), c = %g (%s), %d steps, stopped: %s%s. Quality (2D flows in (x, y, c t), "
          "3D in space): %.1f%% quads, %.1f%% of quad angles within 90±10°, edge spread %.3f, "
          "%zu folds, %zu non-manifold edges, %zu degenerate faces. Time %.3f s",
          args->field.c_str(), args->seed.c_str(), mesh.vertex_count(), mesh.face_count(),
          spacetime::path_positions(result, args->flat), pr.t0, pr.t1, pr.time_reached, pr.time_scale, pr.time_scale_source.c_str(), result.report.steps,
          to_string(result.report.stop_reason), pr.complete ? "" : " (incomplete)",
          100.0 * result.report.quality.quad_share,
          100.0 * result.report.quality.quad_angles_within_10,
          result.report.quality.edge_spread_median, result.report.quality.folds,
          result.report.quality.non_manifold_edges, result.report.quality.degenerate_faces,
          pr.total_seconds);
      if (pr.streamed)
        std::printf(
            " (waited %.3f s for data; read %.3f s, decode %.3f s in the pipeline); "
            "cache: %zu units of %s touched, %zu hits, %zu misses, %zu late prefetches, "
            "%s read (%.3fx needed), peak %s",
            pr.wait_seconds, pr.io_seconds, pr.decode_seconds, pr.cache.units_touched,
            spacetime::format_bytes(pr.cache.unit_bytes).c_str(), pr.cache.hits, pr.cache.misses,
            pr.cache.late_prefetches, spacetime::format_bytes(pr.cache.bytes_read).c_str(),
            pr.cache.read_amplification(), spacetime::format_bytes(pr.cache.peak_bytes).c_str());
      if (!pr.device.empty())
        std::printf("; front advance on %s: %zu calls, %zu particles, %.3f s (compute %.3f s, "
                    "uploads %.3f s, %s up)",
                    pr.device.c_str(), pr.device_calls, pr.device_statistics.particles,
                    pr.device_statistics.total_seconds, pr.device_statistics.compute_seconds,
                    pr.device_statistics.upload_seconds,
                    spacetime::format_bytes(pr.device_statistics.bytes_uploaded).c_str());
      std::printf(".\nWrote %s%s%s\n", args->out.c_str(), args->report.empty() ? "" : " and ",
                  args->report.c_str());
    }
    std::fflush(stdout);
    if (mesh.face_count() > 0) draw_run_pictures(*preview, out, args->report, args->quiet);
    if (mesh.face_count() == 0)
      std::fprintf(stderr,
                   "orthofront: warning: the surface has no faces (stopped: %s after %d "
                   "steps); check --t1, --steps, --edge and the flow along the seed\n",
                   to_string(result.report.stop_reason), result.report.steps);
    std::fputs(degenerate_faces_warning(result.report.quality.degenerate_faces, mesh.face_count())
                   .c_str(),
               stderr);
    if (!pr.complete) {
      if (interrupted()) throw Error("interrupted: the surface built so far was written");
      if (capped)
        throw Error(pr.message + "; the surface built so far was written to " + args->out +
                    ", marked incomplete. To go further, " + args->limits.raise_advice() +
                    ", or raise --edge");
      throw Error(pr.message + " (the surface built so far was written to " + args->out +
                  ", marked incomplete)");
    }
  });
}

}  // namespace orthofront::cli
