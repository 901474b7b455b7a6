#include <filesystem>
#include <iostream>

#include "cli/commands.h"
#include "cli/option_flags.h"
#include "jobs/edge_default.h"
#include "jobs/engine_options.h"
#include "jobs/output_notes.h"
#include "cli/pictures.h"
#include "jobs/process_memory.h"
#include "cli/quality_warnings.h"
#include "cli/surface_job.h"
#include "orthofront/advect/batch_advector.h"
#include "orthofront/error.h"
#include "orthofront/io/atomic_file.h"
#include "orthofront/io/exr_front_image.h"
#include "orthofront/spacetime/path_command_json.h"
#include "orthofront/io/mesh_io.h"
#include "orthofront/io/report_json.h"

namespace orthofront::cli {

using namespace jobs;

namespace {
struct StreamArgs {
  SurfaceJob job;
  std::string out;
  std::string report;
  std::string exr;
  int exr_bins = 0;
  bool quiet = false;
  MemoryLimits limits;
  PreviewFlags preview;
};
}  // namespace

void add_stream_command(CLI::App& app) {
  auto args = std::make_shared<StreamArgs>();
  auto options = std::make_shared<OptionSet>();
  CLI::App* c = app.add_subcommand("stream", "Build a stream surface of a steady field");
  c->add_option("--field", args->job.field, "Field: NAME[:key=value,...] (see `orthofront fields`)")
      ->required();
  c->add_option("--seed", args->job.seed,
                "Seed: line:x0,y0,z0:x1,y1,z1 | circle:c:n:r[:open] | arc:c:n:r:a0,a1 | "
                "file:PATH.csv[:closed]")
      ->required();
  add_stream_options(*options, args->job, args->limits);
  add_option_flags(*c, options);
  c->add_option("--out", args->out, "Output mesh (.vtp, .ply or .obj)")->required();
  c->add_option("--report", args->report, "Write the JSON report here");
  c->add_option("--exr", args->exr,
                "Also write the per-front quantities over (s, step) as an OpenEXR image "
                "(channels alpha, error, speed, dtime, time, front_id, coverage)");
  c->add_option("--exr-bins", args->exr_bins,
                "Columns (s bins) of the --exr image; 0: the widest front's vertex count")
      ->check(CLI::Range(0, 1 << 16))
      ->capture_default_str();
  add_preview_flags(*c, args->preview);
  c->add_flag("--quiet", args->quiet, "No summary on stdout");
  c->callback([args, options, c]() {
    apply_memory_limits(*options, args->limits, args->job.options);
    check_preview(args->preview);
    const std::filesystem::path out = args->out;
    if (!io::is_mesh_extension(out))
      throw InvalidArgument("output '" + args->out +
                            "' has an unknown extension (expected .vtp, .ply or .obj)");
    io::check_writable(out);
    if (!args->report.empty()) io::check_writable(args->report);
    if (!args->exr.empty()) {
      if (std::filesystem::path(args->exr).extension() != ".exr")
        throw InvalidArgument("--exr '" + args->exr + "' must end in .exr");
      io::check_writable(args->exr);
    }
    DeviceUse device;
    args->job.edge_given = c->count("--edge") > 0;
    SurfaceResult result = run_surface(args->job, true, &device);
    // A surface cut off by the vertex cap did not take the steps asked for: the report says so
    // (the exit status stays 0 with a warning, as before: what was built is a valid surface).
    const bool capped = result.report.stop_reason == StopReason::vertex_budget;
    std::string cap_text;
    if (capped) {
      cap_text = "stopped at " + vertex_cap_reached(args->limits, result.mesh.vertex_count()) +
                 ", after " + std::to_string(result.report.steps) + " of " +
                 std::to_string(args->job.options.max_steps) + " steps";
      result.report.complete = false;
      if (!result.report.message.empty()) result.report.message += "; ";
      result.report.message += cap_text;
    }
    // The mesh and its report are replaced together: both are written in full to temporaries
    // before either is renamed (a failure replaces neither), and a concurrent run of the same
    // outputs cannot interleave its files with these.
    result.mesh.notes = output_notes("stream", args->job.field, nullptr);
    const io::OutputLock lock(out);
    io::AtomicFileSet outputs;
    io::write_mesh(result.mesh, out, outputs);
    if (!args->report.empty()) {
      nlohmann::json report = stream_report(result.report, args->job, args->limits, device);
      report["output"] = args->out;
      report["process"] = {{"peak_rss_bytes", peak_rss_bytes()},
                           {"rss_bytes", current_rss_bytes()}};
      io::write_json(report, args->report, outputs);
    }
    if (!args->exr.empty()) {
      io::FrontImageOptions image;
      image.s_bins = args->exr_bins;
      io::write_front_image(result.mesh, args->exr, image);
    }
    outputs.commit();
    if (!args->quiet) {
      std::cout << edge_note({args->job.options.edge, args->job.edge_source})
                << summarize(args->job, result.report) << "\nWrote " << args->out;
      if (!args->report.empty()) std::cout << " and " << args->report;
      if (!args->exr.empty()) std::cout << " and " << args->exr;
      std::cout << "\n" << std::flush;
    }
    if (result.mesh.face_count() > 0)
      draw_run_pictures(args->preview, out, args->report, args->quiet);
    if (capped)
      std::cerr << "orthofront: warning: " << cap_text
                << "; the surface built so far was written to " << args->out
                << ", marked incomplete. To go further, " << args->limits.raise_advice()
                << ", or raise --edge\n";
    if (result.mesh.face_count() == 0)
      std::cerr << "orthofront: warning: the surface has no faces (stopped: "
                << to_string(result.report.stop_reason) << " after " << result.report.steps
                << " steps); check --steps, --edge and the field's speed along the seed\n";
    std::cerr << degenerate_faces_warning(result.report.quality.degenerate_faces,
                                          result.mesh.face_count());
    if (result.report.stop_reason == StopReason::cancelled)
      throw Error("interrupted: the surface built so far was written");
  });
}

}  // namespace orthofront::cli
